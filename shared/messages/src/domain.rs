//! From domain values to wire messages and back, for what estimators publish
//! and hand over: the outputs and snapshots of the roles. (The other
//! direction for inputs, wire to checked domain values, is [`crate::checked`].)
//! The header's `seq`, `source` and `instance` are the publisher's to fill in.

use nauta_estimation::AttitudeStateSnapshot;
use nauta_estimation::attitude_core::AttitudeReport;

use crate::{AttitudeEstimate, AttitudeSnapshot, Header, Role, calibration};

impl From<&AttitudeReport> for AttitudeEstimate {
    fn from(r: &AttitudeReport) -> Self {
        let mut bits = if r.aligned {
            calibration::ALIGNED
        } else {
            calibration::NONE
        };
        if r.magnetometer_calibrated {
            bits |= calibration::MAGNETOMETER;
        }
        AttitudeEstimate {
            header: Header::new(r.stamp_ns, 0, Role::Attitude, 0),
            quat_nb: r.estimate.q_nb.to_wxyz(),
            std_rad: r.estimate.std_rad.to_array(),
            gyro_bias_rad_s: r.estimate.gyro_bias.to_array(),
            calibration: bits,
            pad: 0,
        }
    }
}

impl AttitudeSnapshot {
    /// The snapshot message of `state`, the estimator's state after its
    /// input stamped `stamp_ns`.
    pub fn of_state(state: &AttitudeStateSnapshot, stamp_ns: u64) -> Self {
        AttitudeSnapshot {
            header: Header::new(stamp_ns, 0, Role::Attitude, 0),
            quat_nb: state.q,
            gyro_bias_rad_s: state.gyro_bias,
            covariance: state.covariance,
            calibration: state.calibration,
            pad: 0,
        }
    }

    /// The estimator's state this message carries (checked by the estimator
    /// that restores it).
    pub fn state(&self) -> AttitudeStateSnapshot {
        AttitudeStateSnapshot {
            q: self.quat_nb,
            gyro_bias: self.gyro_bias_rad_s,
            covariance: self.covariance,
            calibration: self.calibration,
        }
    }
}
