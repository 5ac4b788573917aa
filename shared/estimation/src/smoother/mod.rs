//! Paper 004's post-mission smoother: the fixed-interval Rauch-Tung-Striebel
//! smoother (eqs. 7-9) over the steps a forward Kalman pass recorded. Pure:
//! no IPC, no files.
//!
//! - [`step`]: [`ForwardStep`], what the forward pass records at each
//!   instant (prior, posterior and the transition matrix between them), and
//!   [`SmoothedStep`], what the backward pass returns.
//! - [`rts`]: the backward pass ([`smooth`], [`smooth_into`]).
//! - [`discretise`]: `φ_i`, `Q_i`, `b_i` of the linearised dynamics over one
//!   step ([`Discretised`]).
//! - [`linear`]: a linear Kalman filter's forward pass that records its
//!   steps ([`LinearForward`]).
//! - [`error`]: why a forward pass was refused ([`SmoothError`]).

pub mod discretise;
pub mod error;
pub mod linear;
pub mod rts;
pub mod step;

#[cfg(test)]
mod tests;

pub use discretise::{DiscretiseError, Discretised};
pub use error::{SmoothError, StepField};
pub use linear::{LinearForward, LinearUpdateError};
pub use rts::{is_restart, smooth, smooth_bridged, smooth_into};
pub use step::{ForwardStep, SmoothedStep};
