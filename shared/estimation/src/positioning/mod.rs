//! The positioning role (`nauta-positioning`, DESIGN §2; paper 000
//! §III-B-2): the vehicle's horizontal position from the one-way time of
//! flight of the surface buoy's broadcasts and the aided INS's velocity,
//! published as `positioning/fix` for the aided INS's position filter.
//!
//! - [`geometry`]: eqs. 51-53 (haversine, slant range) and the range of a
//!   time of flight.
//! - [`frame`]: eq. 50's dead-reckoned centre and the offsets the filters
//!   hold about it.
//! - [`pf`]: the paper's particle filter (eqs. 48-58).
//! - [`ekf`]: a range-only EKF, for comparison.
//! - [`process`]: the random walk both add to eq. 50 between messages.
//! - [`core`]: the estimator both run in: depth, the surface rule, the
//!   gate, the fixes it publishes and its snapshot.
//! - [`params`]: the manifest's parameters.

pub mod core;
pub mod ekf;
pub mod frame;
pub mod geometry;
pub mod params;
pub mod pf;
pub mod process;

pub use self::core::{Positioning, PositioningState, PositioningStats, Saved};
pub use params::{PositioningEkfParams, PositioningPfParams, RangeModel};

use crate::readings::{BuoyRangeReading, Depth, Gps, Nav};
use crate::role::Stamped;

/// The variants of the positioning role; the first is the default.
pub const VARIANTS: [&str; 2] = ["pf", "ekf"];

/// The values of [`crate::readings::Fix::source`] (`PositionFix.fix_source`).
pub mod source {
    /// No range used for the role's `silence_s`: the position carried by
    /// the navigation's velocity alone (the aided INS ignores it).
    pub const NONE: u32 = 0;
    /// A buoy range.
    pub const BUOY: u32 = 1;
    /// A GPS fix at the surface.
    pub const GPS: u32 = 2;
}

/// One checked input of the positioning role.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PositioningInput {
    /// `ains/nav`.
    Nav(Nav),
    /// `sensor/depth`.
    Depth(Depth),
    /// `sensor/gps`.
    Gps(Gps),
    /// `sensor/modem`.
    Modem(BuoyRangeReading),
}

impl Stamped for PositioningInput {
    fn stamp_ns(&self) -> u64 {
        match self {
            PositioningInput::Nav(m) => m.stamp_ns,
            PositioningInput::Depth(m) => m.stamp_ns,
            PositioningInput::Gps(m) => m.stamp_ns,
            PositioningInput::Modem(m) => m.stamp_ns,
        }
    }
}

impl Stamped for crate::readings::Fix {
    fn stamp_ns(&self) -> u64 {
        self.stamp_ns
    }
}

/// A distribution of the filters' state about the centre
/// ([`process`]'s `x`: the offset north and east, m, the correction of
/// the navigation's north and east velocity, m/s, the sound-speed, scale
/// and heading errors); and the particle filter's effective count (0 for
/// the EKF).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Gaussian {
    /// Mean.
    pub mean: [f64; process::DIM],
    /// Covariance, row-major.
    pub cov: [[f64; process::DIM]; process::DIM],
    /// Effective particle count (eq. 46).
    pub effective_particles: f64,
}
