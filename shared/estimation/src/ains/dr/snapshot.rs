//! The `dr` estimator's state as plain data ([`DrSnapshot`]) for warm
//! restart and hot swap, and its checks.

use serde::{Deserialize, Serialize};

use super::spike::SpikeState;
use crate::ains::tare::TareState;
use crate::predictor::Covariance;

/// Counters of what the estimator did (for health).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct DrStats {
    /// DVL samples the spike filter replaced by its prediction.
    pub spikes_rejected: u64,
    /// DVL samples over the threshold trusted again after the largest
    /// number of consecutive rejections.
    pub spikes_trusted_again: u64,
    /// DVL samples without bottom lock.
    pub dvl_no_lock: u64,
    /// GPS fixes that reset the position.
    pub gps_fixes: u64,
    /// GPS fixes refused by the normalised-innovation gate.
    pub gps_gated: u64,
    /// GPS fixes taken after the largest number of consecutive gated ones
    /// (re-anchored).
    pub gps_reanchored: u64,
    /// Consecutive gated fixes so far.
    pub gps_gated_in_a_row: u32,
}

/// DVL samples a delayed DVL (`dvl_delay_s`) keeps waiting at most; a
/// ninth makes the oldest take effect at once.
pub const MAX_PENDING_DVL: usize = 8;

/// The navigation state proper.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NavState {
    /// Stamp of the last input processed, ns.
    pub last_stamp_ns: Option<u64>,
    /// Paper 002 eq. 4's origin `(L₀, λ₀)`, rad: the last GPS fix (the
    /// site before the first).
    pub origin_rad: [f64; 2],
    /// Eq. 1's `p_n`: north and east of the origin, and depth, m.
    pub p_ned_m: [f64; 3],
    /// Body velocity in use (DVL, the spike filter's prediction, or held),
    /// FRD, m/s.
    pub v_body_m_s: [f64; 3],
    /// `v_n = R_b^n(Θ) v_b` at the last integration step, NED, m/s.
    pub v_ned_m_s: [f64; 3],
    /// Stamp of the last integration step, ns.
    pub last_step_ns: Option<u64>,
    /// The AHRS's roll, pitch and true heading (magnetic + declination),
    /// rad.
    pub euler_rad: Option<[f64; 3]>,
    /// Stamp of the last AHRS sample, ns.
    pub last_ahrs_ns: Option<u64>,
    /// Stamp of the last DVL sample whose velocity was used as measured, ns.
    pub last_dvl_aid_ns: Option<u64>,
    /// DVL samples taken but not yet in use (`dvl_delay_s`): from when (ns)
    /// and the body velocity, oldest first.
    pub pending_dvl: [Option<(u64, [f64; 3])>; MAX_PENDING_DVL],
    /// Stamp of the last GPS fix, ns.
    pub last_gps_ns: Option<u64>,
    /// Stamp of the last depth sample, ns.
    pub last_depth_ns: Option<u64>,
    /// Counters.
    pub stats: DrStats,
}

impl NavState {
    /// The state before any input, eq. 1's origin at `origin_rad`
    /// (latitude, longitude, rad), at rest there.
    pub fn at(origin_rad: [f64; 2]) -> Self {
        Self {
            last_stamp_ns: None,
            origin_rad,
            p_ned_m: [0.0; 3],
            v_body_m_s: [0.0; 3],
            v_ned_m_s: [0.0; 3],
            last_step_ns: None,
            euler_rad: None,
            last_ahrs_ns: None,
            last_dvl_aid_ns: None,
            pending_dvl: [None; MAX_PENDING_DVL],
            last_gps_ns: None,
            last_depth_ns: None,
            stats: DrStats::default(),
        }
    }
}

/// Everything another `dr` instance needs to continue bit for bit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DrSnapshot {
    /// The navigation state.
    pub nav: NavState,
    /// The spike filter's state.
    pub spike: SpikeState,
    /// The depth gauge's tare.
    pub tare: TareState,
    /// The error predictor's covariance.
    pub covariance: Covariance,
}

/// Why a snapshot is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DrSnapshotError {
    /// A number is NaN or infinite.
    #[error("snapshot holds a non-finite number in {0}")]
    NonFinite(&'static str),
    /// A value is out of its range.
    #[error("snapshot value out of range: {0}")]
    OutOfRange(&'static str),
    /// The covariance is not one.
    #[error("snapshot covariance is not symmetric with a non-negative diagonal")]
    NotCovariance,
}

fn finite(name: &'static str, v: &[f64]) -> Result<(), DrSnapshotError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(DrSnapshotError::NonFinite(name))
    }
}

impl DrSnapshot {
    /// Checks every number (the covariance is checked by the predictor).
    pub fn check(&self) -> Result<(), DrSnapshotError> {
        let n = &self.nav;
        finite("origin_rad", &n.origin_rad)?;
        finite("p_ned_m", &n.p_ned_m)?;
        finite("v_body_m_s", &n.v_body_m_s)?;
        finite("v_ned_m_s", &n.v_ned_m_s)?;
        for (_, v) in n.pending_dvl.iter().flatten() {
            finite("pending_dvl", v)?;
        }
        if let Some(e) = &n.euler_rad {
            finite("euler_rad", e)?;
            if e[0].abs() > std::f64::consts::PI + 1e-9
                || e[1].abs() > std::f64::consts::FRAC_PI_2 + 1e-9
            {
                return Err(DrSnapshotError::OutOfRange("euler_rad"));
            }
        }
        if n.origin_rad[0].abs() > std::f64::consts::FRAC_PI_2 {
            return Err(DrSnapshotError::OutOfRange("origin_rad"));
        }
        if let Some(v) = &self.spike.v_ned_pred_m_s {
            finite("spike.v_ned_pred_m_s", v)?;
        }
        finite("spike.span_s", &[self.spike.span_s])?;
        if let Some(v) = &self.spike.v_body_held_m_s {
            finite("spike.v_body_held_m_s", v)?;
        }
        let t = &self.tare;
        finite("tare", &[t.offset_m, t.session_mean_m])?;
        if self.spike.span_s < 0.0 {
            return Err(DrSnapshotError::OutOfRange("spike.span_s"));
        }
        Ok(())
    }
}
