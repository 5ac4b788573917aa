//! The aided INS role (`nauta-ains`, DESIGN §2): what every variant takes in
//! and what it publishes. The variants themselves (`pf`, paper 000 §III-A;
//! `dr`, paper 002; `ekf`, an error-state Kalman filter) live in their own
//! modules and implement [`crate::Estimator`] with [`AinsInput`] in and
//! [`crate::readings::Nav`] out (`ains/nav`).
//!
//! - [`pf`]: paper 000 §III-A's velocity and position particle filters.
//! - [`dr`]: paper 002's dead reckoning with its spike filter and error
//!   predictor.
//! - [`ekf`]: an error-state Kalman filter of the INS errors and the heading
//!   source's.
//! - [`tare`]: the depth gauge's offset, tared at the surface (every variant).

pub mod dr;
pub mod ekf;
pub mod pf;
pub mod role;
pub mod tare;

pub use role::{AinsCore, AinsParams, AinsState, VARIANTS};

use crate::readings::{Ahrs, Attitude, Depth, Dvl, Fix, Gps, Imu, Nav};
use crate::role::Stamped;

/// One checked input of the aided INS, from any of its input services.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AinsInput {
    /// `sensor/imu`.
    Imu(Imu),
    /// `attitude/estimate`.
    Attitude(Attitude),
    /// `sensor/dvl`.
    Dvl(Dvl),
    /// `sensor/depth`.
    Depth(Depth),
    /// `sensor/gps`.
    Gps(Gps),
    /// `sensor/ahrs`.
    Ahrs(Ahrs),
    /// `positioning/fix`.
    Fix(Fix),
}

impl Stamped for AinsInput {
    fn stamp_ns(&self) -> u64 {
        match self {
            AinsInput::Imu(m) => m.stamp_ns,
            AinsInput::Attitude(m) => m.stamp_ns,
            AinsInput::Dvl(m) => m.stamp_ns,
            AinsInput::Depth(m) => m.stamp_ns,
            AinsInput::Gps(m) => m.stamp_ns,
            AinsInput::Ahrs(m) => m.stamp_ns,
            AinsInput::Fix(m) => m.stamp_ns,
        }
    }
}

impl Stamped for Nav {
    fn stamp_ns(&self) -> u64 {
        self.stamp_ns
    }
}

/// The bits of [`Nav::aiding_mode`] (`NavSolution.aiding_mode` on the wire):
/// which aiding the solution used within its staleness window. No bit set is
/// free inertial (or, for `dr`, dead reckoning on the last velocity).
pub mod aiding {
    /// DVL bottom-track velocity.
    pub const DVL: u32 = 1;
    /// GPS position (and velocity) at the surface.
    pub const GPS: u32 = 2;
    /// Acoustic position fixes (`positioning/fix`).
    pub const FIX: u32 = 4;
    /// Heading (the attitude estimate's yaw or the AHRS).
    pub const HEADING: u32 = 8;
    /// Depth gauge.
    pub const DEPTH: u32 = 16;
}
