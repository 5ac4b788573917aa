//! Paper 004's post-mission smoother: the fixed-interval Rauch-Tung-Striebel
//! smoother (eqs. 7-9) over the steps a forward Kalman pass recorded.
//!
//! - [`step`]: [`ForwardStep`], what the forward pass records at each
//!   instant (prior, posterior and the transition matrix between them), and
//!   [`SmoothedStep`], what the backward pass returns.

pub mod step;

pub use step::{ForwardStep, SmoothedStep};
