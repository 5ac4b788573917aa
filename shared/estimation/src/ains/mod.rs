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
//! - [`seed`]: the solution every variant's state holds, for a swap from one
//!   variant to another.

pub mod dr;
pub mod ekf;
pub mod pf;
pub mod role;
pub mod seed;
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

/// Time constant of the low-pass of [`Manoeuvre`]'s acceleration, s: it
/// removes the gyro's noise (6e-4 rad of tilt angle per 100 Hz sample at
/// 1.5 m/s, 8e-5 after it) and follows a turn's onset within a second.
pub const MANOEUVRE_SMOOTHING_S: f64 = 0.5;

/// The `pf` and `ekf` variants' measure of a manoeuvre, for their
/// attitude input's error model: the centripetal acceleration `ω × v`
/// (body frame) low-passed over [`MANOEUVRE_SMOOTHING_S`], and the squared
/// tilt angle `m = |ω × v|² / g²` it gives an accelerometer-levelled
/// attitude, held at its peak and falling over the given time (the
/// input's error outlasts the manoeuvre).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Manoeuvre {
    /// The low-passed `ω × v`, FRD, m/s².
    pub accel_m_s2: [f64; 3],
    /// `m`, rad².
    pub tilt_sq_rad2: f64,
}

impl Manoeuvre {
    /// One IMU sample of `dt` s: body rate `w` (bias-corrected), rad/s,
    /// body velocity `v_b`, m/s, gravity `g`, m/s²; `m` falls with the time
    /// constant `fall_s`.
    pub fn update(
        &mut self,
        w: &nalgebra::Vector3<f64>,
        v_b: &nalgebra::Vector3<f64>,
        g: f64,
        dt: f64,
        fall_s: f64,
    ) {
        let a = w.cross(v_b);
        let alpha = -(-dt / MANOEUVRE_SMOOTHING_S).exp_m1();
        for (s, x) in self.accel_m_s2.iter_mut().zip(a.iter()) {
            *s += alpha * (x - *s);
        }
        let lp = nalgebra::Vector3::from(self.accel_m_s2);
        let now = lp.norm_squared() / (g * g);
        self.tilt_sq_rad2 = now.max(self.tilt_sq_rad2 * (-dt / fall_s).exp());
    }

    /// Whether every number is finite and `m` not negative (a snapshot's
    /// check).
    pub fn is_valid(&self) -> bool {
        self.accel_m_s2.iter().all(|x| x.is_finite())
            && self.tilt_sq_rad2.is_finite()
            && self.tilt_sq_rad2 >= 0.0
    }
}

/// The variance an attitude (or heading) input errs by in a manoeuvre, for
/// one input used `spacing_s` after the previous one, rad²: `k² m` (`k` the
/// manoeuvre factor, `m` the squared tilt angle of [`Manoeuvre`]) times the number of inputs used within the
/// error's correlation time `time_s` (the low-pass's fall time), at least
/// one. The error is a bias over the manoeuvre, not white noise: `N` inputs
/// of one common error `e`, each taken as independent of variance `R`,
/// weigh as one of variance `R / N`, so each is given `N R` (the usual
/// inflation of time-correlated measurement noise; Groves 2013 ch. 3, the
/// Kalman filter's assumptions, equation numbers not checkable here).
pub fn manoeuvre_var(k: f64, m: f64, time_s: f64, spacing_s: Option<f64>) -> f64 {
    let n = spacing_s.map_or(1.0, |dt| time_s / dt.max(1e-3)).max(1.0);
    k * k * m * n
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

/// The bits of [`Nav::advisory`] (`NavSolution.advisory` on the wire).
pub mod advisory {
    /// Surfacing advised: the solution's predicted horizontal RMS error
    /// (`predicted_drift_m`) is above the variant's `surfacing_threshold_m`
    /// (paper 002's embedded use: "foresee the moment to emerge").
    pub const SURFACE: u32 = 1;

    /// The advisory bits of a solution whose predicted horizontal error is
    /// `predicted_m`, against `threshold_m`.
    pub fn surface(predicted_m: f64, threshold_m: f64) -> u32 {
        if predicted_m > threshold_m {
            SURFACE
        } else {
            0
        }
    }
}
