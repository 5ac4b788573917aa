//! A torpedo-shaped AUV of the REMUS-100 class (Isurus, paper 003, is one; so is
//! paper 000's emulated vehicle), as a kinematic model with first-order surge,
//! yaw-rate and pitch-rate dynamics.
//!
//! This is not a hydrodynamic model (no added mass, lift or drag coefficients):
//! it is the smallest model that gives smooth, bounded, realistic motion for
//! sensor simulation. All constants are **our choice**, picked to look like a
//! REMUS-100 class vehicle (Hydroid REMUS 100 brochure: max speed ~2.3 m/s
//! (4.5 kn), cruise ~1.5 m/s (3 kn)); the time constants are of the order of the
//! values identified for REMUS by Prestero (2001, MIT MS thesis, "Verification of
//! a six-degree of freedom simulation model for the REMUS AUV").
//!
//! # Equations (state [`VehicleState`], commands [`Commands`])
//!
//! ```text
//! u̇ = (u_c - u) / τ_u                         surge speed through the water
//! ψ̇ = r,     ṙ = (r_c - r) / τ_r              yaw, yaw rate (|r_c| ≤ r_max)
//! θ̇ = q,     q̇ = (k_θ (θ_c - θ) - q) / τ_q    pitch, pitch rate (|θ_c| ≤ θ_max)
//! φ(t) = A_φ sin(2π t / T_φ + φ₀)             roll: a configured small oscillation
//! v^n = C_b^n [u, 0, 0]ᵀ + c^n(t) + [0, 0, -w_b max(0, 1 - u/u_lift)]ᵀ
//! L̇ = v_N / (R_N + h),  λ̇ = v_E / ((R_E + h) cos L),  ḋ = v_D  (h = -d)
//! ```
//!
//! No sideslip or angle of attack: the body moves through the water along its
//! x axis. `ψ, θ, φ` are the ZYX Euler angles of `q_nb`
//! ([`nauta_estimation::attitude::from_euler`]); `C_b^n [u,0,0]ᵀ = u [cθcψ, cθsψ, -sθ]`.
//! The pitch loop `k_θ τ_q ≤ 1/4` is critically or over-damped, so pitch is a
//! positively weighted average of past commands and never exceeds `θ_max`; the
//! yaw-rate lag of a clamped command never exceeds `r_max`.
//!
//! Buoyancy: the vehicle is slightly positively buoyant (our choice, a REMUS is
//! trimmed a few hundred grams light). Under way the hull's lift holds it; below
//! `u_lift` it rises at up to `w_b`. At the surface the depth is clamped at 0
//! (no downward-negative velocity while `d ≤ 0`).
//!
//! Propeller (papers 003/004: the LBL filter's dead reckoning uses the shaft
//! speed): steady-state `ω_prop = u / k_prop` (paper 004 eq. 2: `u = k ω`), with
//! `k_prop` = [`PROPELLER_ADVANCE_M_PER_RAD`].

use nalgebra::{UnitQuaternion, Vector3};
use nauta_estimation::attitude::from_euler;
use nauta_estimation::earth::{meridian_radius, transverse_radius};

/// Steady-state advance per radian of propeller shaft rotation, m/rad (our
/// choice: 1.5 m/s at 143 rad/s ≈ 1370 rpm, of the order of a REMUS-100).
pub const PROPELLER_ADVANCE_M_PER_RAD: f64 = 0.0105;

/// The vehicle's parameters. Every default is our choice (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleParams {
    /// Maximum speed through the water, m/s (REMUS-100: ~2.3 m/s).
    pub max_speed_m_s: f64,
    /// Cruise speed, m/s (REMUS-100: ~1.5 m/s).
    pub cruise_speed_m_s: f64,
    /// Surge time constant `τ_u`, s (5 s).
    pub surge_time_constant_s: f64,
    /// Yaw-rate time constant `τ_r`, s (1 s).
    pub yaw_rate_time_constant_s: f64,
    /// Pitch-rate time constant `τ_q`, s (1 s).
    pub pitch_rate_time_constant_s: f64,
    /// Pitch loop gain `k_θ`, 1/s (0.2; with `τ_q` = 1 s the loop is over-damped).
    pub pitch_gain_per_s: f64,
    /// Maximum yaw rate `r_max`, rad/s (10°/s).
    pub max_yaw_rate_rad_s: f64,
    /// Maximum pitch `θ_max`, rad (30°).
    pub max_pitch_rad: f64,
    /// Roll oscillation amplitude `A_φ`, rad (1.5°; zero for none).
    pub roll_amplitude_rad: f64,
    /// Roll oscillation period `T_φ`, s (7 s).
    pub roll_period_s: f64,
    /// Free rise speed from positive buoyancy `w_b`, m/s (0.05 m/s).
    pub buoyancy_rise_m_s: f64,
    /// Speed above which hull lift cancels buoyancy `u_lift`, m/s (0.5 m/s).
    pub lift_speed_m_s: f64,
}

impl Default for VehicleParams {
    fn default() -> Self {
        Self::remus100()
    }
}

impl VehicleParams {
    /// REMUS-100 class defaults (our choice; see the field docs).
    pub fn remus100() -> Self {
        Self {
            max_speed_m_s: 2.3,
            cruise_speed_m_s: 1.5,
            surge_time_constant_s: 5.0,
            yaw_rate_time_constant_s: 1.0,
            pitch_rate_time_constant_s: 1.0,
            pitch_gain_per_s: 0.2,
            max_yaw_rate_rad_s: 10f64.to_radians(),
            max_pitch_rad: 30f64.to_radians(),
            roll_amplitude_rad: 1.5f64.to_radians(),
            roll_period_s: 7.0,
            buoyancy_rise_m_s: 0.05,
            lift_speed_m_s: 0.5,
        }
    }

    /// Roll at time `t_s` for an oscillation phase `phase_rad`, rad.
    pub fn roll_rad(&self, t_s: f64, phase_rad: f64) -> f64 {
        self.roll_amplitude_rad
            * (std::f64::consts::TAU * t_s / self.roll_period_s + phase_rad).sin()
    }
}

/// What the controllers ask of the vehicle, held over one control interval.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Commands {
    /// Speed through the water, m/s (clamped to [0, max speed]).
    pub speed_m_s: f64,
    /// Yaw rate, rad/s (clamped to ±max yaw rate).
    pub yaw_rate_rad_s: f64,
    /// Pitch, rad (clamped to ±max pitch).
    pub pitch_rad: f64,
}

/// The integrated state of the vehicle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleState {
    /// Geodetic latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad (not wrapped while integrating).
    pub lon_rad: f64,
    /// Depth below the ellipsoid (sea surface), m.
    pub depth_m: f64,
    /// Surge speed through the water, m/s.
    pub speed_m_s: f64,
    /// Yaw (heading), rad, unwrapped.
    pub yaw_rad: f64,
    /// Yaw rate `ψ̇`, rad/s.
    pub yaw_rate_rad_s: f64,
    /// Pitch, rad.
    pub pitch_rad: f64,
    /// Pitch rate `θ̇`, rad/s.
    pub pitch_rate_rad_s: f64,
    /// Horizontal distance travelled over ground, m.
    pub distance_m: f64,
}

const N: usize = 9;

impl VehicleState {
    /// At rest at the surface at (`lat_rad`, `lon_rad`) heading `yaw_rad`.
    pub fn at_rest(lat_rad: f64, lon_rad: f64, depth_m: f64, yaw_rad: f64) -> Self {
        Self {
            lat_rad,
            lon_rad,
            depth_m,
            speed_m_s: 0.0,
            yaw_rad,
            yaw_rate_rad_s: 0.0,
            pitch_rad: 0.0,
            pitch_rate_rad_s: 0.0,
            distance_m: 0.0,
        }
    }

    fn to_array(self) -> [f64; N] {
        [
            self.lat_rad,
            self.lon_rad,
            self.depth_m,
            self.speed_m_s,
            self.yaw_rad,
            self.yaw_rate_rad_s,
            self.pitch_rad,
            self.pitch_rate_rad_s,
            self.distance_m,
        ]
    }

    fn from_array(a: [f64; N]) -> Self {
        Self {
            lat_rad: a[0],
            lon_rad: a[1],
            depth_m: a[2],
            speed_m_s: a[3],
            yaw_rad: a[4],
            yaw_rate_rad_s: a[5],
            pitch_rad: a[6],
            pitch_rate_rad_s: a[7],
            distance_m: a[8],
        }
    }

    /// Attitude `q_nb` with roll `roll_rad`.
    pub fn attitude(&self, roll_rad: f64) -> UnitQuaternion<f64> {
        from_euler(roll_rad, self.pitch_rad, self.yaw_rad)
    }

    /// Propeller shaft speed in steady state, rad/s (`u / k_prop`).
    pub fn propeller_rad_s(&self) -> f64 {
        self.speed_m_s / PROPELLER_ADVANCE_M_PER_RAD
    }
}

/// The vehicle model: parameters plus the equations of the module docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vehicle {
    /// Parameters.
    pub params: VehicleParams,
}

impl Vehicle {
    /// A vehicle with parameters `params`.
    pub fn new(params: VehicleParams) -> Self {
        Self { params }
    }

    /// Velocity over ground, NED, m/s, for state `s` in current `current_ned`.
    pub fn velocity_ned(&self, s: &VehicleState, current_ned: &Vector3<f64>) -> Vector3<f64> {
        let p = &self.params;
        let (sp, cp) = s.pitch_rad.sin_cos();
        let (sy, cy) = s.yaw_rad.sin_cos();
        let u = s.speed_m_s;
        let rise = p.buoyancy_rise_m_s * (1.0 - u / p.lift_speed_m_s).max(0.0);
        let mut v = Vector3::new(u * cp * cy, u * cp * sy, -u * sp - rise) + current_ned;
        if s.depth_m <= 0.0 && v.z < 0.0 {
            v.z = 0.0;
        }
        v
    }

    /// Clamps commands to the vehicle's limits.
    pub fn clamp(&self, c: &Commands) -> Commands {
        let p = &self.params;
        Commands {
            speed_m_s: c.speed_m_s.clamp(0.0, p.max_speed_m_s),
            yaw_rate_rad_s: c
                .yaw_rate_rad_s
                .clamp(-p.max_yaw_rate_rad_s, p.max_yaw_rate_rad_s),
            pitch_rad: c.pitch_rad.clamp(-p.max_pitch_rad, p.max_pitch_rad),
        }
    }

    fn derivative(&self, a: &[f64; N], c: &Commands, current_ned: &Vector3<f64>) -> [f64; N] {
        let p = &self.params;
        let s = VehicleState::from_array(*a);
        let v = self.velocity_ned(&s, current_ned);
        let h = -s.depth_m;
        let lat_dot = v.x / (meridian_radius(s.lat_rad) + h);
        let lon_dot = v.y / ((transverse_radius(s.lat_rad) + h) * s.lat_rad.cos());
        let q_cmd = p.pitch_gain_per_s * (c.pitch_rad - s.pitch_rad);
        [
            lat_dot,
            lon_dot,
            v.z,
            (c.speed_m_s - s.speed_m_s) / p.surge_time_constant_s,
            s.yaw_rate_rad_s,
            (c.yaw_rate_rad_s - s.yaw_rate_rad_s) / p.yaw_rate_time_constant_s,
            s.pitch_rate_rad_s,
            (q_cmd - s.pitch_rate_rad_s) / p.pitch_rate_time_constant_s,
            v.x.hypot(v.y),
        ]
    }

    /// One classical fourth-order Runge-Kutta step of `dt_s` from `s` at time
    /// `t_s`, commands `c` held (clamped first), current from `current(t)`. The
    /// depth is clamped at the surface afterwards.
    pub fn rk4_step(
        &self,
        s: &VehicleState,
        c: &Commands,
        t_s: f64,
        dt_s: f64,
        current: impl Fn(f64) -> Vector3<f64>,
    ) -> VehicleState {
        let c = self.clamp(c);
        let y = s.to_array();
        let add = |y: &[f64; N], k: &[f64; N], f: f64| {
            let mut o = *y;
            for i in 0..N {
                o[i] += f * k[i];
            }
            o
        };
        let c_mid = current(t_s + 0.5 * dt_s);
        let k1 = self.derivative(&y, &c, &current(t_s));
        let k2 = self.derivative(&add(&y, &k1, 0.5 * dt_s), &c, &c_mid);
        let k3 = self.derivative(&add(&y, &k2, 0.5 * dt_s), &c, &c_mid);
        let k4 = self.derivative(&add(&y, &k3, dt_s), &c, &current(t_s + dt_s));
        let mut out = y;
        for i in 0..N {
            out[i] += dt_s / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        let mut s1 = VehicleState::from_array(out);
        if s1.depth_m < 0.0 {
            s1.depth_m = 0.0;
        }
        s1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(c: Commands, seconds: f64) -> (VehicleState, f64, f64) {
        let v = Vehicle::new(VehicleParams::remus100());
        let mut s = VehicleState::at_rest(0.67, -0.16, 10.0, 0.0);
        let dt = 0.01;
        let (mut max_r, mut max_p) = (0.0f64, 0.0f64);
        let n = (seconds / dt) as usize;
        for k in 0..n {
            s = v.rk4_step(&s, &c, k as f64 * dt, dt, |_| Vector3::zeros());
            max_r = max_r.max(s.yaw_rate_rad_s.abs());
            max_p = max_p.max(s.pitch_rad.abs());
        }
        (s, max_r, max_p)
    }

    #[test]
    fn first_order_surge_reaches_the_command() {
        let (s, _, _) = run(
            Commands {
                speed_m_s: 1.5,
                ..Commands::default()
            },
            5.0,
        );
        // One time constant: 1 - 1/e of the step.
        assert!((s.speed_m_s - 1.5 * (1.0 - (-1.0f64).exp())).abs() < 1e-6);
        assert!((s.propeller_rad_s() - s.speed_m_s / PROPELLER_ADVANCE_M_PER_RAD).abs() < 1e-12);
    }

    #[test]
    fn limits_are_respected() {
        let (s, max_r, max_p) = run(
            Commands {
                speed_m_s: 5.0,
                yaw_rate_rad_s: 1.0,
                pitch_rad: -1.2,
            },
            60.0,
        );
        let p = VehicleParams::remus100();
        assert!(max_r <= p.max_yaw_rate_rad_s + 1e-12, "{max_r}");
        assert!(max_p <= p.max_pitch_rad + 1e-9, "{max_p}");
        assert!((s.pitch_rad + p.max_pitch_rad).abs() < 1e-3);
        assert!(s.speed_m_s <= p.max_speed_m_s + 1e-12);
        assert!(s.depth_m > 10.0);
    }

    #[test]
    fn floats_up_and_stays_at_the_surface() {
        let v = Vehicle::new(VehicleParams::remus100());
        let mut s = VehicleState::at_rest(0.67, -0.16, 1.0, 0.0);
        for k in 0..10_000 {
            s = v.rk4_step(&s, &Commands::default(), k as f64 * 0.01, 0.01, |_| {
                Vector3::zeros()
            });
            assert!(s.depth_m >= 0.0);
        }
        assert_eq!(s.depth_m, 0.0);
    }
}
