//! The attitude-estimator role (STYLE item 4): one trait so that variants (gyro
//! integration, particle filter, MEKF, ...) are interchangeable behind the
//! `attitude` service, and a fixed-size snapshot for warm start and hot swap
//! (DESIGN §5).

use thiserror::Error;

use crate::frames::{Frd, Ned, Rotation, Vector, WxyzError};

/// What an attitude estimator reports after each input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AttitudeOutput {
    /// Attitude, body (FRD) → NED.
    pub q_nb: Rotation<Frd, Ned>,
    /// Standard deviation of the attitude error about N, E, D, rad; zeros when the
    /// estimator has no uncertainty model (as the `AttitudeEstimate` message says).
    pub std_rad: Vector<Ned>,
    /// Gyro bias in use, FRD, rad/s.
    pub gyro_bias: Vector<Frd>,
}

/// Everything needed to warm-start an attitude estimator, in plain arrays (it maps
/// one to one onto the `AttitudeSnapshot` message, minus the header).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AttitudeStateSnapshot {
    /// Attitude quaternion body → NED, `[w, x, y, z]`.
    pub q: [f64; 4],
    /// Gyro bias, FRD, rad/s.
    pub gyro_bias: [f64; 3],
    /// Error covariance, row-major: attitude error about N, E, D (rad), then gyro
    /// bias (rad/s). All zeros when the estimator has none.
    pub covariance: [[f64; 6]; 6],
    /// Calibration bits (the `calibration` constants of the messages crate; opaque
    /// here and passed through unchanged).
    pub calibration: u32,
}

/// Why [`AttitudeEstimator::restore`] refused a snapshot (the estimator keeps its
/// state).
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum AttitudeRestoreError {
    /// A number in the snapshot is NaN or infinite.
    #[error("snapshot holds a non-finite number")]
    NonFinite,
    /// The quaternion's norm is not within [`AttitudeStateSnapshot::MAX_NORM_ERROR`] of 1.
    #[error("snapshot quaternion has norm {0}, not 1")]
    NotUnit(f64),
    /// The covariance is not symmetric with a positive diagonal (an estimator
    /// that uses it refuses it; all zeros means "unknown").
    #[error("snapshot covariance is not symmetric with a positive diagonal")]
    NotCovariance,
}

impl AttitudeStateSnapshot {
    /// How far from 1 the norm of a restored quaternion may be; it is renormalised.
    pub const MAX_NORM_ERROR: f64 = 1e-6;

    /// The snapshot's quaternion and bias as domain values, checked: every number
    /// finite (covariance included) and `|q|` within [`Self::MAX_NORM_ERROR`] of 1.
    pub fn checked(&self) -> Result<(Rotation<Frd, Ned>, Vector<Frd>), AttitudeRestoreError> {
        let finite = self
            .q
            .iter()
            .chain(&self.gyro_bias)
            .chain(self.covariance.iter().flatten());
        if !finite.clone().all(|v| v.is_finite()) {
            return Err(AttitudeRestoreError::NonFinite);
        }
        let q = Rotation::from_wxyz_within(self.q, Self::MAX_NORM_ERROR).map_err(|e| match e {
            WxyzError::NonFinite => AttitudeRestoreError::NonFinite,
            WxyzError::NotUnit(norm) => AttitudeRestoreError::NotUnit(norm),
        })?;
        Ok((q, Vector::from_array(self.gyro_bias)))
    }
}

/// An attitude estimator: the pure core behind the `attitude` service.
///
/// Time is not read from any clock: `predict` is told the length of the interval
/// its gyro sample covers (DESIGN §7).
pub trait AttitudeEstimator {
    /// Propagates with one gyro sample: the average angular rate `ω_ib^b` (rad/s,
    /// FRD) over an interval of `dt_s` seconds ending now.
    fn predict(&mut self, gyro_rad_s: &Vector<Frd>, dt_s: f64);

    /// Corrects with one aiding pair: specific force (m/s², FRD) and magnetic field
    /// (µT, FRD, calibrated).
    fn update(&mut self, accel_m_s2: &Vector<Frd>, mag_ut: &Vector<Frd>);

    /// The current estimate.
    fn estimate(&self) -> AttitudeOutput;

    /// The state needed to warm-start another instance.
    fn snapshot(&self) -> AttitudeStateSnapshot;

    /// Replaces the state with a snapshot's. A snapshot that fails
    /// [`AttitudeStateSnapshot::checked`] is refused and the state kept.
    fn restore(&mut self, s: &AttitudeStateSnapshot) -> Result<(), AttitudeRestoreError>;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn snap() -> AttitudeStateSnapshot {
        AttitudeStateSnapshot {
            q: [0.5, 0.5, 0.5, 0.5],
            gyro_bias: [1e-4, 0.0, -1e-4],
            covariance: [[0.0; 6]; 6],
            calibration: 1,
        }
    }

    #[test]
    fn checked_accepts_a_valid_snapshot() {
        let (q, b) = snap().checked().expect("valid");
        assert_eq!(q.to_wxyz().map(f64::to_bits), [0.5f64; 4].map(f64::to_bits));
        assert_eq!(b, Vector::new(1e-4, 0.0, -1e-4));
    }

    #[test]
    fn checked_refuses_bad_numbers() {
        let mut s = snap();
        s.q = [1.0, 1.0, 0.0, 0.0];
        assert!(matches!(s.checked(), Err(AttitudeRestoreError::NotUnit(_))));
        let mut s = snap();
        s.gyro_bias[1] = f64::NAN;
        assert_eq!(s.checked(), Err(AttitudeRestoreError::NonFinite));
        let mut s = snap();
        s.covariance[5][5] = f64::INFINITY;
        assert_eq!(s.checked(), Err(AttitudeRestoreError::NonFinite));
        let mut s = snap();
        s.q = [f64::NAN, 0.0, 0.0, 0.0];
        assert_eq!(s.checked(), Err(AttitudeRestoreError::NonFinite));
    }
}
