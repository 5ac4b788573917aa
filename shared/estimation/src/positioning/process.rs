//! The state both positioning filters hold and its motion between two buoy
//! messages (our addition to paper 000's eq. 50, which moves the position
//! with the navigation's velocity and nothing else).
//!
//! The state `x` ([`DIM`] values, indices below) about the dead-reckoned
//! centre of [`super::frame`]:
//!
//! - `n`, `e`: the vehicle's offset north and east of the centre, m;
//! - `c_n`, `c_e`: a correction of the navigation's velocity fixed in the
//!   north/east frame, m/s. The aided INS's velocity errs by an offset
//!   that stays put in NED while the vehicle turns: a heading error that
//!   depends on the heading once per turn (a magnetometer's residual hard
//!   iron, the deviation of a compass) rotates each leg's velocity the
//!   other way, and the two make a velocity error fixed in NED (measured
//!   on the survey, seeds 7-9: −0.0012, −0.0085, −0.0018 m/s east over
//!   the whole dive, the same on legs of opposite direction);
//! - `s`: the relative error of the sound speed the ranges are taken with
//!   (a measured range is `(1 + s)` times the geometric one): a sound
//!   speed from a table or an old cast errs by a constant over a dive,
//!   which makes every range long or short in proportion (issue 14's +1 %
//!   case);
//! - `k`, `ψ`: the navigation's velocity scale error and heading error in
//!   the vehicle's frame (a DVL's scale factor, a constant heading bias):
//!   errors that turn with the track, `δv = k v + ψ J v`, `J v = (−v_E,
//!   v_N)` (Groves 2013 §14.3.2, the dead-reckoning error model);
//! - `b_n`, `b_e`, `u_n`, `u_e`: the buoy's position north and east of a
//!   reference (its first broadcast), m, and its drift, m/s. A buoy's GPS
//!   errs by metres in each broadcast (the simulator: 2.5 m per axis,
//!   independent between broadcasts) while the buoy itself drifts slowly
//!   (the simulator: 0.02 m/s and a random walk of 0.05 m/√s): tracking
//!   it with its broadcasts as measurements (a constant-velocity model with
//!   a random walk, Bar-Shalom et al. 2001 §6.3) takes most of that error
//!   out of the ranges, and holding it in the same state keeps the
//!   correlation its estimate's error makes between successive ranges.
//!
//! Between two messages, over `Δt` with the centre moved by `D = ∫ v dt`
//! (the navigation's velocity, eq. 50):
//!
//! `n ← n + c_n Δt + k D_N − ψ D_E`, `e ← e + c_e Δt + k D_E + ψ D_N`
//! (exact for constant `c`, `k`, `ψ`), `b ← b + u Δt`, every error other
//! than the offsets a random walk, and the offsets random walks of their
//! own besides (the velocity's white error; the buoy's wandering). The position part of a random walk of `c`
//! over the interval is the integrated random walk's, exactly
//! (`q² [[Δt³/3, Δt²/2], [Δt²/2, Δt]]`; Bar-Shalom et al. 2001 §6.2); the
//! one of `k` and `ψ` the same along `D/Δt` and `J D/Δt` (exact on a
//! straight line, the survey's legs), and the one of `u` on `b` the same. The noise is `w = G u` with `u`
//! [`DRAWS`] standard normals: the particle filter draws `u`, the EKF adds
//! `G Gᵀ`, so both have the same motion.

use nalgebra::{SMatrix, SVector};

/// Values in the state.
pub const DIM: usize = 11;
/// Offset north, m.
pub const N: usize = 0;
/// Offset east, m.
pub const E: usize = 1;
/// Velocity correction north, m/s.
pub const CN: usize = 2;
/// Velocity correction east, m/s.
pub const CE: usize = 3;
/// Relative sound-speed error.
pub const SOUND: usize = 4;
/// Velocity scale error.
pub const SCALE: usize = 5;
/// Heading error, rad.
pub const HEADING: usize = 6;
/// The buoy north of its reference, m.
pub const BN: usize = 7;
/// The buoy east of its reference, m.
pub const BE: usize = 8;
/// The buoy's drift north, m/s.
pub const UN: usize = 9;
/// The buoy's drift east, m/s.
pub const UE: usize = 10;
/// The vehicle's values: [`N`] to [`HEADING`].
pub const VEHICLE: std::ops::Range<usize> = 0..BN;
/// The buoy's values: [`BN`] to [`UE`].
pub const BUOY: std::ops::Range<usize> = BN..DIM;
/// Standard normals per step of the noise.
pub const DRAWS: usize = 17;

/// The state's vector and matrices.
pub type State = SVector<f64, DIM>;
/// A `DIM × DIM` matrix.
pub type Square = SMatrix<f64, DIM, DIM>;
/// The noise's factor.
pub type Factor = SMatrix<f64, DIM, DRAWS>;

/// The random walks' densities.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Walk {
    /// `q_p`, the offset's own walk, m/√s.
    pub position_m_rt_s: f64,
    /// `q_c`, the velocity correction's, m/s/√s.
    pub velocity_m_s_rt_s: f64,
    /// `q_s`, the sound-speed error's, 1/√s.
    pub sound_speed_rt_s: f64,
    /// `q_k`, the velocity scale error's, 1/√s.
    pub scale_rt_s: f64,
    /// `q_ψ`, the heading error's, rad/√s.
    pub heading_rad_rt_s: f64,
    /// `q_b`, the buoy position's own walk, m/√s.
    pub buoy_m_rt_s: f64,
    /// `q_u`, the buoy drift's walk, m/s/√s.
    pub buoy_drift_m_s_rt_s: f64,
}

/// One step: its length and how far the centre moved in it.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Step {
    /// `Δt`, s.
    pub dt_s: f64,
    /// `D`, north and east, m.
    pub displacement_m: [f64; 2],
}

impl Step {
    /// `x ← F x` in place (module docs).
    pub fn apply(&self, x: &mut [f64; DIM]) {
        let [dn, de] = self.displacement_m;
        let dt = self.dt_s;
        x[N] += x[CN] * dt + x[SCALE] * dn - x[HEADING] * de;
        x[E] += x[CE] * dt + x[SCALE] * de + x[HEADING] * dn;
        x[BN] += x[UN] * dt;
        x[BE] += x[UE] * dt;
    }

    /// `F`.
    pub fn transition(&self) -> Square {
        let [dn, de] = self.displacement_m;
        let mut f = Square::identity();
        f[(N, CN)] = self.dt_s;
        f[(E, CE)] = self.dt_s;
        f[(N, SCALE)] = dn;
        f[(E, SCALE)] = de;
        f[(N, HEADING)] = -de;
        f[(E, HEADING)] = dn;
        f[(BN, UN)] = self.dt_s;
        f[(BE, UE)] = self.dt_s;
        f
    }

    /// `G` (module docs): the noise of this step is `G u`, `u` [`DRAWS`]
    /// standard normals.
    pub fn noise_factor(&self, w: &Walk) -> Factor {
        let mut g = Factor::zeros();
        let dt = self.dt_s;
        if dt <= 0.0 {
            return g;
        }
        let rt = dt.sqrt();
        // An integrated random walk of density q: the walk's own step
        // `q √Δt u₁` and what it adds to a position `(pn, pe)`, `q √Δt
        // Δt/2 u₁ + q √(Δt³/12) u₂`, along `dir`.
        let mut walk = |state: usize, q: f64, u: usize, pos: [usize; 2], dir: [f64; 2]| {
            g[(state, u)] = q * rt;
            for (axis, d) in pos.into_iter().zip(dir) {
                g[(axis, u)] = d * q * rt * dt / 2.0;
                g[(axis, u + 1)] = d * q * (dt * dt * dt / 12.0).sqrt();
            }
        };
        let vehicle = [N, E];
        walk(CN, w.velocity_m_s_rt_s, 0, vehicle, [1.0, 0.0]);
        walk(CE, w.velocity_m_s_rt_s, 2, vehicle, [0.0, 1.0]);
        let u = self.displacement_m.map(|d| d / dt);
        walk(SCALE, w.scale_rt_s, 6, vehicle, u);
        walk(HEADING, w.heading_rad_rt_s, 8, vehicle, [-u[1], u[0]]);
        walk(UN, w.buoy_drift_m_s_rt_s, 11, [BN, BE], [1.0, 0.0]);
        walk(UE, w.buoy_drift_m_s_rt_s, 13, [BN, BE], [0.0, 1.0]);
        g[(N, 4)] = w.position_m_rt_s * rt;
        g[(E, 5)] = w.position_m_rt_s * rt;
        g[(SOUND, 10)] = w.sound_speed_rt_s * rt;
        g[(BN, 15)] = w.buoy_m_rt_s * rt;
        g[(BE, 16)] = w.buoy_m_rt_s * rt;
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The factor gives the integrated random walk's covariance per axis,
    /// and `F` moves the offset as the errors say.
    #[test]
    fn the_factor_gives_the_covariance_and_f_the_motion() {
        let w = Walk {
            position_m_rt_s: 0.03,
            velocity_m_s_rt_s: 2e-4,
            sound_speed_rt_s: 1e-5,
            scale_rt_s: 1e-5,
            heading_rad_rt_s: 1e-5,
            buoy_m_rt_s: 0.05,
            buoy_drift_m_s_rt_s: 1e-4,
        };
        let s = Step {
            dt_s: 30.0,
            displacement_m: [45.0, 0.0],
        };
        let g = s.noise_factor(&w);
        let q = g * g.transpose();
        let dt = s.dt_s;
        let qv = w.velocity_m_s_rt_s.powi(2);
        // East: the velocity walk, the position walk and the heading walk
        // along J D = (0, 45) m over 30 s (1.5 m/s east of the line).
        let qh = w.heading_rad_rt_s.powi(2) * 1.5 * 1.5;
        let ee = (qv + qh) * dt.powi(3) / 3.0 + w.position_m_rt_s.powi(2) * dt;
        assert!((q[(E, E)] - ee).abs() < 1e-12, "{} {ee}", q[(E, E)]);
        assert!((q[(E, CE)] - qv * dt * dt / 2.0).abs() < 1e-15);
        assert!((q[(CE, CE)] - qv * dt).abs() < 1e-15);
        assert!((q[(HEADING, E)] - w.heading_rad_rt_s.powi(2) * 1.5 * dt * dt / 2.0).abs() < 1e-15);
        let mut x = [0.0; DIM];
        x[CN] = 0.01;
        x[SCALE] = 0.002;
        x[HEADING] = 0.01;
        let mut y = x;
        s.apply(&mut y);
        let fx = s.transition() * State::from(x);
        assert!(
            (y[N] - (0.3 + 0.09)).abs() < 1e-12 && (y[E] - 0.45).abs() < 1e-12,
            "{y:?}"
        );
        // The buoy: its walk and its drift's, integrated.
        let qu = w.buoy_drift_m_s_rt_s.powi(2);
        let bb = qu * dt.powi(3) / 3.0 + w.buoy_m_rt_s.powi(2) * dt;
        assert!((q[(BN, BN)] - bb).abs() < 1e-12 && q[(BN, N)] == 0.0);
        assert!((fx[N] - y[N]).abs() < 1e-12 && (fx[E] - y[E]).abs() < 1e-12);
    }
}
