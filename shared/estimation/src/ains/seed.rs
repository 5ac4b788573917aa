//! The part of an aided INS state every variant understands: a navigation
//! solution with its uncertainty ([`NavSeed`]), for a hot swap from one
//! variant to another (`nauta swap ains ekf` while `dr` runs).
//!
//! A swap within a variant continues from the exact state (`dr`, `ekf`: bit
//! for bit; `pf`: from its moments). Across variants the states have
//! nothing else in common: `dr` has an error predictor, `ekf` an 18-state
//! covariance, `pf` particle clouds. So the new variant starts from the old
//! one's position, depth, velocity and attitude and their standard
//! deviations, and from the depth gauge's tare; its own error states
//! (biases, the heading source's error, the clouds' spread of drift) start
//! at their priors, and its cross-covariances at zero. Without this the new
//! variant started cold: `pf` and `ekf` waited for a GPS fix, so a swap in
//! a dive published nothing until the vehicle surfaced.

use crate::ains::dr::DrSnapshot;
use crate::ains::ekf::EkfSnapshot;
use crate::ains::ekf::filter::Filter;
use crate::ains::ekf::model::{POS, VEL};
use crate::ains::pf::AinsPfSnapshot;
use crate::ains::tare::TareState;
use crate::local::flat;

/// A navigation solution with its uncertainty, from any variant's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavSeed {
    /// Latitude, longitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Depth, m (tared).
    pub depth_m: f64,
    /// Velocity over ground, NED, m/s.
    pub vel_ned_m_s: [f64; 3],
    /// Position σ north, east, down, m.
    pub pos_std_ned_m: [f64; 3],
    /// Velocity σ per axis, m/s, when the state has one (`dr`'s depends
    /// on the motion; the new variant then takes its own prior).
    pub vel_std_m_s: Option<[f64; 3]>,
    /// Attitude body → NED, `[w, x, y, z]`, when the state has one.
    pub attitude_wxyz: Option<[f64; 4]>,
    /// The depth gauge's tare.
    pub tare: TareState,
}

impl NavSeed {
    /// Whether every number is finite, the position on the planet and the
    /// σ not negative (a seed from a checked snapshot always is).
    pub fn is_valid(&self) -> bool {
        let finite = [self.lat_rad, self.lon_rad, self.depth_m]
            .iter()
            .chain(&self.vel_ned_m_s)
            .chain(&self.pos_std_ned_m)
            .chain(self.vel_std_m_s.iter().flatten())
            .chain(self.attitude_wxyz.iter().flatten())
            .all(|x| x.is_finite());
        finite
            && self.lat_rad.abs() <= std::f64::consts::FRAC_PI_2
            && self.pos_std_ned_m.iter().all(|s| *s >= 0.0)
            && self.vel_std_m_s.iter().flatten().all(|s| *s >= 0.0)
    }

    /// A `dr` state's solution: eq. 1's position and velocity, the error
    /// predictor's position σ (paper 002 eqs. 14-17).
    pub fn from_dr(s: &DrSnapshot) -> Option<Self> {
        s.check().ok()?;
        let n = &s.nav;
        let (lat, lon) =
            flat::to_geodetic(n.origin_rad[0], n.origin_rad[1], n.p_ned_m[0], n.p_ned_m[1]);
        let seed = Self {
            lat_rad: lat,
            lon_rad: crate::attitude::wrap_pi(lon),
            depth_m: n.p_ned_m[2],
            vel_ned_m_s: n.v_ned_m_s,
            pos_std_ned_m: [0, 1, 2].map(|i| s.covariance[i][i].max(0.0).sqrt()),
            vel_std_m_s: None,
            attitude_wxyz: n
                .euler_rad
                .map(|e| crate::frames::Rotation::from_euler(e[0], e[1], e[2]).to_wxyz()),
            tare: s.tare,
        };
        seed.is_valid().then_some(seed)
    }

    /// An `ekf` state's solution (`None` before it initialised).
    pub fn from_ekf(s: &EkfSnapshot) -> Option<Self> {
        s.check().ok()?;
        let f = Filter::from_state(s.filter.as_ref()?)?;
        let sd = |i: usize| f.p[(i, i)].max(0.0).sqrt();
        let seed = Self {
            lat_rad: f.nav.lat_rad,
            lon_rad: f.nav.lon_rad,
            depth_m: f.nav.depth_m(),
            vel_ned_m_s: f.nav.v_ned_m_s.to_array(),
            pos_std_ned_m: [sd(POS), sd(POS + 1), sd(POS + 2)],
            vel_std_m_s: Some([sd(VEL), sd(VEL + 1), sd(VEL + 2)]),
            attitude_wxyz: Some(f.nav.q_nb.to_wxyz()),
            tare: s.tare,
        };
        seed.is_valid().then_some(seed)
    }

    /// A `pf` state's solution: the clouds' means and standard deviations
    /// (paper 000 eqs. 26-27).
    pub fn from_pf(s: &AinsPfSnapshot) -> Option<Self> {
        s.check().ok()?;
        let p = &s.position;
        let (lat, lon) = flat::to_geodetic(s.origin_rad[0], s.origin_rad[1], p.mean[0], p.mean[1]);
        let seed = Self {
            lat_rad: lat,
            lon_rad: crate::attitude::wrap_pi(lon),
            depth_m: p.mean[2],
            vel_ned_m_s: s.velocity.mean,
            pos_std_ned_m: p.std,
            vel_std_m_s: Some(s.velocity.std),
            attitude_wxyz: Some(s.attitude_wxyz),
            tare: s.tare,
        };
        seed.is_valid().then_some(seed)
    }
}
