//! From domain values to wire messages and back, for what estimators publish
//! and hand over: the outputs and snapshots of the roles. (The other
//! direction for inputs, wire to checked domain values, is [`crate::checked`].)
//! The header's `seq`, `source` and `instance` are the publisher's to fill in.

use nauta_estimation::AttitudeStateSnapshot;
use nauta_estimation::ains::AinsState;
use nauta_estimation::attitude_core::AttitudeReport;
use nauta_estimation::readings::Nav;

use crate::{
    AinsSnapshot, AttitudeEstimate, AttitudeSnapshot, Header, NavSolution, Role, calibration,
    codec, fixed_str, to_fixed_str,
};

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

impl From<&Nav> for NavSolution {
    fn from(n: &Nav) -> Self {
        NavSolution {
            header: Header::new(n.stamp_ns, 0, Role::Ains, 0),
            lat_rad: n.lat_rad,
            lon_rad: n.lon_rad,
            depth_m: n.depth_m,
            vel_ned_m_s: n.vel_ned_m_s.to_array(),
            // The wire's zero quaternion: no attitude in this solution.
            quat_nb: n.attitude.map_or([0.0; 4], |q| q.to_wxyz()),
            pos_std_ned_m: n.pos_std_ned_m.to_array(),
            vel_std_ned_m_s: n.vel_std_ned_m_s.to_array(),
            predicted_drift_m: n.predicted_drift_m,
            aiding_mode: n.aiding_mode,
            advisory: n.advisory,
        }
    }
}

/// Bytes an [`AinsSnapshot`] holds of a variant's state.
pub const AINS_STATE_BYTES: usize = 9 * 32 * 8;

impl AinsSnapshot {
    /// The snapshot message of `state`, after the input stamped `stamp_ns`.
    /// A state that does not fit (it cannot: the test below bounds every
    /// variant's) is sent empty, and refused by whoever restores it.
    pub fn of_state(state: &AinsState, stamp_ns: u64) -> Self {
        let bytes = match state {
            AinsState::Dr(s) => bincode::serde::encode_to_vec(s.as_ref(), codec::config()),
            AinsState::Pf(s) => bincode::serde::encode_to_vec(s.as_ref(), codec::config()),
            AinsState::Ekf(s) => bincode::serde::encode_to_vec(s.as_ref(), codec::config()),
            AinsState::Unreadable { .. } => Ok(Vec::new()),
        }
        .ok()
        .filter(|b| b.len() <= AINS_STATE_BYTES)
        .unwrap_or_default();
        let mut m = AinsSnapshot {
            header: Header::new(stamp_ns, 0, Role::Ains, 0),
            variant: to_fixed_str(state.variant()),
            state_len: bytes.len() as u32,
            pad: 0,
            state: [[0; 32]; 9],
        };
        pack(&bytes, &mut m.state);
        m
    }

    /// The variant's state this message carries (checked by the instance
    /// that restores it; what does not decode is [`AinsState::Unreadable`]).
    pub fn state(&self) -> AinsState {
        let variant = fixed_str(&self.variant);
        let unreadable = |reason: String| AinsState::Unreadable {
            variant: variant.clone(),
            reason,
        };
        let len = self.state_len as usize;
        if len == 0 || len > AINS_STATE_BYTES {
            return unreadable(format!("it holds {len} bytes of state"));
        }
        let bytes = unpack(&self.state, len);
        let decoded = match variant.as_str() {
            "dr" => decode(&bytes).map(|s| AinsState::Dr(Box::new(s))),
            "pf" => decode(&bytes).map(|s| AinsState::Pf(Box::new(s))),
            "ekf" => decode(&bytes).map(|s| AinsState::Ekf(Box::new(s))),
            other => Err(format!("no variant {other:?}")),
        };
        decoded.unwrap_or_else(unreadable)
    }
}

/// `bytes` into the words of an opaque snapshot, little-endian, the rest
/// zero (the caller checked that they fit).
pub(crate) fn pack<const R: usize>(bytes: &[u8], words: &mut [[u64; 32]; R]) {
    for (i, chunk) in bytes.chunks(8).enumerate().take(R * 32) {
        let mut word = [0u8; 8];
        word[..chunk.len()].copy_from_slice(chunk);
        words[i / 32][i % 32] = u64::from_le_bytes(word);
    }
}

/// The first `len` bytes of an opaque snapshot's words.
pub(crate) fn unpack(words: &[[u64; 32]], len: usize) -> Vec<u8> {
    words
        .iter()
        .flatten()
        .flat_map(|w| w.to_le_bytes())
        .take(len)
        .collect()
}

/// A state decoded from all of `bytes` (trailing bytes are an error).
pub(crate) fn decode<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> Result<T, String> {
    match bincode::serde::decode_from_slice(bytes, codec::config()) {
        Ok((s, used)) if used == bytes.len() => Ok(s),
        Ok((_, used)) => Err(format!("{} trailing bytes", bytes.len() - used)),
        Err(e) => Err(e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use nauta_estimation::ains::dr::{DrParams, Site};
    use nauta_estimation::ains::{AinsCore, AinsInput, AinsParams, AinsState};
    use nauta_estimation::frames::Vector;
    use nauta_estimation::readings::{Ahrs, Dvl, Gps, Imu};
    use nauta_estimation::{Estimator, Stamped as _};

    use super::*;

    /// A `dr` that has run a while: every part of its state set.
    fn running_dr() -> AinsCore {
        running(&AinsParams::Dr(DrParams::default()))
    }

    /// A variant that has run a while on IMU, AHRS, DVL and GPS.
    fn running(params: &AinsParams) -> AinsCore {
        let site = Site {
            lat_rad: 0.67,
            lon_rad: -0.16,
            declination_rad: -0.017,
        };
        let mut core = AinsCore::new(params, site).expect("variant");
        let mut out = Vec::new();
        for k in 0..200u64 {
            let t = k * 100_000_000;
            let mut inputs: Vec<AinsInput> = (1..=10u64)
                .filter(|_| k > 0)
                .map(|j| {
                    AinsInput::Imu(Imu {
                        stamp_ns: t - 100_000_000 + j * 10_000_000 - 1,
                        interval_s: 0.01,
                        gyro_rad_s: Vector::new(0.0, 0.0, 0.0),
                        accel_m_s2: Vector::new(0.0, 0.0, -9.80),
                        mag_ut: Vector::new(20.0, 0.0, 40.0),
                    })
                })
                .collect();
            inputs.push(AinsInput::Ahrs(Ahrs {
                stamp_ns: t,
                roll_rad: 0.01,
                pitch_rad: -0.02,
                heading_mag_rad: 1.0,
            }));
            if k % 2 == 0 {
                inputs.push(AinsInput::Dvl(Dvl {
                    stamp_ns: t,
                    velocity_body_m_s: Vector::new(1.5, 0.01, 0.0),
                    altitude_m: 20.0,
                    beams_valid: 0b1111,
                    bottom_lock: true,
                }));
            }
            if k < 20 {
                inputs.push(AinsInput::Gps(Gps {
                    stamp_ns: t,
                    lat_rad: 0.67,
                    lon_rad: -0.16,
                    height_m: 0.0,
                    horizontal_std_m: 2.0,
                    quality: 1,
                    velocity: None,
                }));
            }
            inputs.sort_by_key(|i| i.stamp_ns());
            for i in &inputs {
                // A variant may gate a measurement of this made-up run;
                // the state is what is tested.
                let _ = core.on_input(i, &mut out);
            }
        }
        core
    }

    #[test]
    fn every_variants_state_fits_the_snapshot_message_and_comes_back() {
        use nauta_estimation::ains::ekf::EkfParams;
        use nauta_estimation::ains::pf::AinsPfParams;
        for params in [
            AinsParams::Pf(AinsPfParams::default()),
            AinsParams::Dr(DrParams::default()),
            AinsParams::Ekf(EkfParams::default()),
        ] {
            let core = running(&params);
            let state = core
                .snapshot()
                .unwrap_or_else(|| panic!("{}: no state", core.variant()));
            let m = AinsSnapshot::of_state(&state, 42);
            assert!(m.state_len > 0, "{}: the state did not fit", core.variant());
            assert_eq!(fixed_str(&m.variant), core.variant());
            let m: AinsSnapshot =
                codec::decode(&codec::encode(&m).expect("encode")).expect("decode");
            assert_eq!(m.state(), state, "{}", core.variant());
            eprintln!(
                "{}: {} of {AINS_STATE_BYTES} bytes",
                core.variant(),
                m.state_len
            );
        }
    }

    #[test]
    fn a_dr_state_fits_the_snapshot_message_and_comes_back_exactly() {
        let core = running_dr();
        let state = core.snapshot().expect("a state");
        let m = AinsSnapshot::of_state(&state, 42);
        assert!(m.state_len > 0, "the state did not fit");
        assert!((m.state_len as usize) < AINS_STATE_BYTES);
        assert_eq!(fixed_str(&m.variant), "dr");
        // Through the wire encoding too.
        let m: AinsSnapshot = codec::decode(&codec::encode(&m).expect("encode")).expect("decode");
        assert_eq!(m.state(), state);
    }

    #[test]
    fn a_damaged_or_foreign_snapshot_is_unreadable_and_refused() {
        let state = running_dr().snapshot().expect("a state");
        let mut m = AinsSnapshot::of_state(&state, 42);
        m.state_len = 7;
        let AinsState::Unreadable { variant, reason } = m.state() else {
            panic!("a cut state decoded");
        };
        assert_eq!(variant, "dr");
        assert!(!reason.is_empty());
        let mut core = running_dr();
        let e = core.restore(&m.state(), 42).expect_err("refused");
        assert_eq!(e.kind, "snapshot-unreadable");
        m.variant = to_fixed_str("pf");
        assert!(matches!(m.state(), AinsState::Unreadable { .. }));
    }
}
