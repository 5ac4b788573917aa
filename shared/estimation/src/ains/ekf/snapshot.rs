//! The `ekf` estimator's state as plain data ([`EkfSnapshot`]) for warm
//! restart and hot swap, its counters ([`EkfStats`]), and its checks.
//!
//! The covariance is stored as its upper triangle (171 numbers for 18
//! states), so that the snapshot, bincode-encoded with fixed-width
//! integers, fits the `AinsSnapshot` message's 2304 bytes (test
//! `snapshot_fits_the_message_and_restores_bit_for_bit`).

use serde::{Deserialize, Serialize};

use super::model::{Block, Cov, N};
use crate::ains::tare::TareState;

/// Counters of one aiding kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct GateStats {
    /// Measurements used.
    pub used: u64,
    /// Measurements refused by the normalised-innovation gate.
    pub rejected: u64,
    /// Measurements that re-anchored the filter after
    /// `max_consecutive_rejections` rejections in a row.
    pub reanchored: u64,
    /// Rejections in a row so far.
    pub rejected_in_a_row: u32,
}

/// Counters of what the estimator did (for health).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct EkfStats {
    /// DVL bottom-track velocity.
    pub dvl: GateStats,
    /// Depth gauge.
    pub depth: GateStats,
    /// GPS position.
    pub gps: GateStats,
    /// GPS velocity.
    pub gps_velocity: GateStats,
    /// `positioning/fix`.
    pub fix: GateStats,
    /// Heading (attitude estimate or AHRS).
    pub heading: GateStats,
    /// DVL samples without bottom lock.
    pub dvl_no_lock: u64,
    /// `positioning/fix` inputs ignored (`position_aiding = false`).
    pub fix_ignored: u64,
    /// IMU samples integrated.
    pub imu_samples: u64,
    /// Measurements not used because their innovation covariance was not
    /// positive definite.
    pub singular: u64,
}

/// The navigation state and the filter proper (after initialisation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FilterState {
    /// Attitude `q_nb`, `[w, x, y, z]`.
    pub q_nb_wxyz: [f64; 4],
    /// Velocity, NED, m/s.
    pub v_ned_m_s: [f64; 3],
    /// Latitude, longitude, rad, and height, m.
    pub lat_lon_height: [f64; 3],
    /// Accelerometer bias estimate, FRD, m/s².
    pub accel_bias_m_s2: [f64; 3],
    /// Gyro bias estimate, FRD, rad/s.
    pub gyro_bias_rad_s: [f64; 3],
    /// Heading source's bias estimate, rad.
    pub heading_bias_rad: f64,
    /// Heading source's one-cycle deviation `[a_ψ, c_ψ]`, rad.
    pub heading_deviation_rad: [f64; 2],
    /// The last IMU sample's bias-corrected angular rate, FRD, rad/s (the
    /// DVL lever arm's rotation term).
    pub omega_b_rad_s: [f64; 3],
    /// The manoeuvre measure of the heading source's error model.
    pub manoeuvre: crate::ains::Manoeuvre,
    /// The covariance's upper triangle, row by row (`N (N+1) / 2`).
    pub p_upper: Vec<f64>,
    /// The covariance block accumulated since the last propagation.
    pub block: Block,
}

/// The last position and heading seen before initialisation.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Pending {
    /// Latitude, longitude, rad; σ north, σ east, m; correlation.
    pub position: Option<[f64; 5]>,
    /// GPS velocity NED, m/s, and its σ.
    pub velocity: Option<[f64; 4]>,
    /// The attitude estimate's `[w, x, y, z, σ_N, σ_E, σ_D]`, or the AHRS's
    /// `[roll, pitch, true heading, 0, 0, 0, 0]` (rad) when `from_ahrs`.
    pub attitude: Option<[f64; 7]>,
    /// The attitude came from the AHRS.
    pub from_ahrs: bool,
}

/// Stamps of the last input of each kind, ns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Stamps {
    /// Any input.
    pub last: Option<u64>,
    /// A DVL velocity used.
    pub dvl: Option<u64>,
    /// A depth used.
    pub depth: Option<u64>,
    /// A GPS position used.
    pub gps: Option<u64>,
    /// Any GPS fix (the surface test of the tare).
    pub gps_seen: Option<u64>,
    /// A fix used.
    pub fix: Option<u64>,
    /// A heading used.
    pub heading: Option<u64>,
    /// A heading measurement considered (the decimation).
    pub heading_tried: Option<u64>,
    /// Any attitude estimate (preferred over the AHRS while fresh).
    pub attitude_seen: Option<u64>,
    /// The first IMU sample with a heading while no position has come.
    pub waiting_since: Option<u64>,
}

/// Everything another `ekf` instance needs to continue bit for bit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EkfSnapshot {
    /// The filter, once initialised.
    pub filter: Option<FilterState>,
    /// What initialisation waits on.
    pub pending: Pending,
    /// Stamps.
    pub stamps: Stamps,
    /// The heading source in use: 0 none, 1 attitude estimate, 2 AHRS.
    pub heading_source: u8,
    /// The depth gauge's tare.
    pub tare: TareState,
    /// Counters.
    pub stats: EkfStats,
}

/// Why a snapshot is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EkfSnapshotError {
    /// A number is NaN or infinite.
    #[error("snapshot holds a non-finite number in {0}")]
    NonFinite(&'static str),
    /// A value is out of its range.
    #[error("snapshot value out of range: {0}")]
    OutOfRange(&'static str),
    /// The covariance is not one.
    #[error("snapshot covariance has {0} numbers or a negative diagonal (18 states: 171)")]
    NotCovariance(usize),
}

fn finite(name: &'static str, v: &[f64]) -> Result<(), EkfSnapshotError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(EkfSnapshotError::NonFinite(name))
    }
}

/// The upper triangle of `p`, row by row.
pub fn upper(p: &Cov) -> Vec<f64> {
    let mut v = Vec::with_capacity(N * (N + 1) / 2);
    for i in 0..N {
        for j in i..N {
            v.push(p[(i, j)]);
        }
    }
    v
}

/// The symmetric matrix of an upper triangle (checked length).
pub fn from_upper(v: &[f64]) -> Option<Cov> {
    if v.len() != N * (N + 1) / 2 {
        return None;
    }
    let mut p = Cov::zeros();
    let mut k = 0;
    for i in 0..N {
        for j in i..N {
            p[(i, j)] = v[k];
            p[(j, i)] = v[k];
            k += 1;
        }
    }
    Some(p)
}

impl FilterState {
    /// Checks every number, the attitude's norm and the covariance's shape.
    pub fn check(&self) -> Result<Cov, EkfSnapshotError> {
        finite("q_nb_wxyz", &self.q_nb_wxyz)?;
        finite("v_ned_m_s", &self.v_ned_m_s)?;
        finite("lat_lon_height", &self.lat_lon_height)?;
        finite("accel_bias_m_s2", &self.accel_bias_m_s2)?;
        finite("gyro_bias_rad_s", &self.gyro_bias_rad_s)?;
        finite("heading_bias_rad", &[self.heading_bias_rad])?;
        finite("heading_deviation_rad", &self.heading_deviation_rad)?;
        finite("omega_b_rad_s", &self.omega_b_rad_s)?;
        if !self.manoeuvre.is_valid() {
            return Err(EkfSnapshotError::OutOfRange("manoeuvre"));
        }
        finite("p_upper", &self.p_upper)?;
        finite("block", &self.block.f_dt)?;
        finite("block", &self.block.c_dt)?;
        finite("block", &self.block.w_dt)?;
        finite("block", &[self.block.t_s])?;
        let n: f64 = self.q_nb_wxyz.iter().map(|x| x * x).sum::<f64>().sqrt();
        if (n - 1.0).abs() > 1e-6 {
            return Err(EkfSnapshotError::OutOfRange("q_nb_wxyz norm"));
        }
        if self.lat_lon_height[0].abs() > crate::strapdown::MAX_ABS_LATITUDE_RAD {
            return Err(EkfSnapshotError::OutOfRange("latitude"));
        }
        let p =
            from_upper(&self.p_upper).ok_or(EkfSnapshotError::NotCovariance(self.p_upper.len()))?;
        if (0..N).any(|i| p[(i, i)] < 0.0) {
            return Err(EkfSnapshotError::NotCovariance(self.p_upper.len()));
        }
        Ok(p)
    }
}

impl EkfSnapshot {
    /// Checks every number.
    pub fn check(&self) -> Result<(), EkfSnapshotError> {
        if let Some(f) = &self.filter {
            f.check()?;
        }
        if let Some(p) = &self.pending.position {
            finite("pending.position", p)?;
        }
        if let Some(v) = &self.pending.velocity {
            finite("pending.velocity", v)?;
        }
        if let Some(a) = &self.pending.attitude {
            finite("pending.attitude", a)?;
        }
        if self.heading_source > 2 {
            return Err(EkfSnapshotError::OutOfRange("heading_source"));
        }
        let t = &self.tare;
        finite("tare", &[t.offset_m, t.session_mean_m])
    }
}
