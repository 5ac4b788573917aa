//! The LBL role (`nauta-lbl`, DESIGN §2; paper 003 §V, paper 004 §III):
//! the vehicle's horizontal position and the water current from acoustic
//! ranges to long-baseline transponders and dead reckoning by propeller
//! speed (or a DVL) and the AHRS, published as `lbl/nav` at 10 Hz; and the
//! interrogations that ask the transponders for those ranges
//! (`lbl/interrogate`).
//!
//! - [`layout`]: the transponders of the site, checked, and the named
//!   layouts of the simulator's `lbl` scenario.
//! - [`params`]: the manifest's parameters (paper 003's symbols).
//! - [`model`]: eqs. 1-4 of paper 004 and their exact discretisation.
//! - [`kalman`]: `E`, `P`, the prediction and the Joseph-form update.
//! - [`range`]: the range of a round trip and `r*`, `H` at the middle of the
//!   round trip (paper 003 §V-C).
//! - [`history`]: the last steps' inputs, to move the state back there.
//! - [`selection`]: the figure of merit `m_k` and round robin (§V-D).
//! - [`baseline`]: the two-transponder side ambiguity (§III).
//! - [`ellipse`]: the uncertainty ellipse of `P_xy` (§V-A).
//! - [`core`]: the estimator: steps, replies, gate, re-acquisition, GPS,
//!   interrogations, snapshot.
//! - [`state`]: the snapshot's state and the counters.
//! - [`forward`]: the forward pass's steps for the smoother (paper 004
//!   eqs. 7-9) and the offline entry point.

pub mod baseline;
pub mod core;
pub mod ellipse;
pub mod forward;
pub mod history;
pub mod kalman;
pub mod layout;
pub mod model;
pub mod params;
pub mod range;
pub mod selection;
pub mod state;

pub use self::core::{Lbl, LblSite};
pub use forward::{ForwardPass, ForwardStep, ForwardSteps, forward_pass};
pub use layout::{Layout, LayoutError, Transponder};
pub use params::{LblParams, Selection, VelocitySource};
pub use state::{LblSaved, LblState, LblStats};

use crate::readings::{Ahrs, Depth, Dvl, Gps, LblNav, LblReplyReading, Propeller};
use crate::role::Stamped;

/// The variants of the LBL role; the first is the default.
pub const VARIANTS: [&str; 1] = ["ekf"];

/// One checked input of the LBL role. The service declares them in this
/// order (ties at one stamp are taken in it): the AHRS first, so that the
/// step at a grid point is taken before any other input of that stamp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LblInput {
    /// `sensor/ahrs`.
    Ahrs(Ahrs),
    /// `sensor/depth`.
    Depth(Depth),
    /// `sensor/propeller`.
    Propeller(Propeller),
    /// `sensor/dvl` (used with `velocity_source = "dvl"`).
    Dvl(Dvl),
    /// `sensor/lbl`.
    Reply(LblReplyReading),
    /// `sensor/gps`.
    Gps(Gps),
}

impl Stamped for LblInput {
    fn stamp_ns(&self) -> u64 {
        match self {
            LblInput::Ahrs(m) => m.stamp_ns,
            LblInput::Depth(m) => m.stamp_ns,
            LblInput::Propeller(m) => m.stamp_ns,
            LblInput::Dvl(m) => m.stamp_ns,
            LblInput::Reply(m) => m.stamp_ns,
            LblInput::Gps(m) => m.stamp_ns,
        }
    }
}

/// A request to interrogate one transponder (`lbl/interrogate`), sent at
/// `stamp_ns`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ping {
    /// When, ns.
    pub stamp_ns: u64,
    /// Which transponder.
    pub transponder_id: u32,
}

/// One output of the LBL role.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LblOutput {
    /// `lbl/nav`.
    Nav(LblNav),
    /// `lbl/interrogate`.
    Ping(Ping),
}

impl Stamped for LblOutput {
    fn stamp_ns(&self) -> u64 {
        match self {
            LblOutput::Nav(n) => n.stamp_ns,
            LblOutput::Ping(p) => p.stamp_ns,
        }
    }
}
