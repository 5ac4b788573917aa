//! The `pf` estimator's counters ([`AinsPfStats`]) and its state as plain
//! data ([`AinsPfSnapshot`]) for warm restart and hot swap.
//!
//! The particles do not fit the `AinsSnapshot` message (2304 bytes; 128
//! particles of 18 numbers, value, companion and weight of six components,
//! are 18 kB), so a snapshot holds each component's mean and standard
//! deviation, and its companion's (the components are separate filters,
//! eqs. 13-16, so these are what the cloud says of its distribution to
//! second order), and the random generator's state; `restore` draws the
//! clouds again from them, Gaussian. A warm restart continues
//! statistically, not bit for bit. Encoded as nauta records it (bincode 2
//! serde, fixed-width integers) a snapshot takes 1335 bytes, the carried
//! attitude's filter included (`cargo test
//! --release -p nauta-estimation --test ains_pf restored -- --nocapture`).

use serde::{Deserialize, Serialize};

use crate::ains::tare::TareState;

/// Counters of one kind of aiding measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct GateStats {
    /// Measurements that weighted the particles.
    pub used: u64,
    /// Measurements refused by the normalised-innovation gate.
    pub gated: u64,
    /// Re-anchorings after `gate_max_rejections` gated ones in a row.
    pub reanchored: u64,
    /// Consecutive gated measurements so far.
    pub gated_in_a_row: u32,
}

/// Counters of what the estimator did (for health).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct AinsPfStats {
    /// DVL bottom-track velocities.
    pub dvl: GateStats,
    /// DVL samples without bottom lock (velocity from the IMU alone).
    pub dvl_no_lock: u64,
    /// GPS velocities.
    pub gps_velocity: GateStats,
    /// GPS positions.
    pub gps: GateStats,
    /// `positioning/fix` positions (counted only with `position_aiding`).
    pub fix: GateStats,
    /// Depth gauge readings.
    pub depth: GateStats,
    /// Attitude inputs that corrected the carried attitude (or re-anchored
    /// it; the decimated ones are not counted).
    pub attitude: GateStats,
    /// Resamplings of a velocity component (eq. 11).
    pub velocity_resamples: u64,
    /// Resamplings of a position component (eq. 11).
    pub position_resamples: u64,
}

/// Mean and standard deviation of each component of one filter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ComponentMoments {
    /// Per component: N, E, D.
    pub mean: [f64; 3],
    /// Per component, ≥ 0.
    pub std: [f64; 3],
}

/// Everything another `pf` instance needs to continue (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AinsPfSnapshot {
    /// Stamp of the last input processed, ns.
    pub last_stamp_ns: u64,
    /// Origin of the position filter's local N/E, rad (latitude, longitude).
    pub origin_rad: [f64; 2],
    /// The filters started at the site and no position has come since.
    pub position_from_site: bool,
    /// Velocity filter, NED, m/s.
    pub velocity: ComponentMoments,
    /// The velocity particles' acceleration errors, m/s².
    pub accel_bias: ComponentMoments,
    /// Position filter: north and east of the origin and depth, m.
    pub position: ComponentMoments,
    /// The position particles' velocity errors, m/s.
    pub drift: ComponentMoments,
    /// Attitude in use, body → NED, `[w, x, y, z]`.
    pub attitude_wxyz: [f64; 4],
    /// It came from the attitude input (not the AHRS).
    pub attitude_from_estimate: bool,
    /// The carried attitude's variance, gyro bias, manoeuvre and last
    /// correction.
    pub attitude_track: super::attitude::AttitudeTrack,
    /// Stamps of the last attitude, DVL aiding, GPS, fix and depth used, ns.
    pub last_ns: [Option<u64>; 5],
    /// The depth gauge's tare.
    pub tare: TareState,
    /// Counters.
    pub stats: AinsPfStats,
    /// The random generator's state.
    pub rng: Vec<u32>,
}

/// Why a snapshot is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum AinsPfSnapshotError {
    /// A number is NaN or infinite.
    #[error("snapshot holds a non-finite number in {0}")]
    NonFinite(&'static str),
    /// A value is out of its range.
    #[error("snapshot value out of range: {0}")]
    OutOfRange(&'static str),
}

fn finite(name: &'static str, v: &[f64]) -> Result<(), AinsPfSnapshotError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(AinsPfSnapshotError::NonFinite(name))
    }
}

impl AinsPfSnapshot {
    /// Checks every number (the generator's state is checked when it is
    /// rebuilt).
    pub fn check(&self) -> Result<(), AinsPfSnapshotError> {
        finite("origin_rad", &self.origin_rad)?;
        if self.origin_rad[0].abs() > std::f64::consts::FRAC_PI_2 {
            return Err(AinsPfSnapshotError::OutOfRange("origin_rad"));
        }
        for (name, m) in [
            ("velocity", &self.velocity),
            ("accel_bias", &self.accel_bias),
            ("position", &self.position),
            ("drift", &self.drift),
        ] {
            finite(name, &m.mean)?;
            finite(name, &m.std)?;
            if m.std.iter().any(|s| *s < 0.0) {
                return Err(AinsPfSnapshotError::OutOfRange(name));
            }
        }
        finite("attitude_wxyz", &self.attitude_wxyz)?;
        if !self.attitude_track.is_valid() {
            return Err(AinsPfSnapshotError::OutOfRange("attitude_track"));
        }
        let t = &self.tare;
        finite("tare", &[t.offset_m, t.session_mean_m])?;
        Ok(())
    }
}
