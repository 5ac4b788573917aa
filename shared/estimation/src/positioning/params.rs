//! The positioning role's parameters as a manifest writes them
//! (`[process.positioning.variants.pf]` and `.ekf`, every field defaulted,
//! unknown keys refused) and their checks. Paper 000 gives the filter's
//! structure but none of its numbers: every default is our choice, from
//! the simulator's modem (DESIGN §10) unless it says otherwise.

use serde::Deserialize;

use crate::params::{OutOfRange, in_range, nonneg, positive};
use crate::positioning::process::{BE, BN, CE, CN, DIM, E, HEADING, N, SCALE, SOUND, UE, UN, Walk};

/// Largest particle count.
pub const MAX_PARTICLES: usize = 65_536;

/// What both variants share: the range's error model, the state's priors
/// and random walks ([`super::process`]), the gate and the surface rule.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RangeModel {
    /// The range's own noise, m: the sound speed times the modem clocks'
    /// synchronisation jitter (1 ms at 1500 m/s). Default 1.5.
    pub range_sigma_m: f64,
    /// σ of the relative error of the sound speed the buoy reports at a
    /// start (the prior of the state `s`: a measured range is `(1 + s)`
    /// times the geometric one). Default 0.003.
    pub sound_speed_rel_sigma: f64,
    /// `q_s`, random walk of that error, 1/√s. Default 0.
    pub sound_speed_walk_rt_s: f64,
    /// The error of the buoy's GPS position in its broadcast, m per
    /// horizontal axis, independent between broadcasts. Default 2.5.
    pub buoy_sigma_m: f64,
    /// Track the buoy ([`super::process`]'s `b`, `u`) with its broadcasts
    /// as measurements; `false` takes each broadcast position as it comes,
    /// its error a part of eq. 54's σ_d (paper 000). Default: true for
    /// `ekf`, false for `pf` ([`Self::tracks_buoy`]): in the particles the
    /// buoy's four values starve the set (survey, development seeds 7-9,
    /// `posdev`: the `pf`'s horizontal error 4.5-6.0 m with them, 2.0-2.4
    /// m without, particle seeds 0-2; the `ekf`'s 1.7 m with, 1.9 m
    /// without; BENCHMARKS.md, "error budget").
    pub track_buoy: Option<bool>,
    /// `q_b`, random walk of the buoy's position, m/√s (its wandering
    /// about a steady drift: waves, wind, a mooring's swing). Default 0.05
    /// (the simulator's buoy).
    pub buoy_walk_m_rt_s: f64,
    /// σ of the buoy's drift at its first broadcast, m/s per axis.
    /// Default 0.05.
    pub buoy_drift_m_s: f64,
    /// `q_u`, random walk of that drift, m/s/√s. Default 1e-4 (0.005 m/s
    /// over a 40-minute dive).
    pub buoy_drift_walk_m_s_rt_s: f64,
    /// `q_p`, random walk of the vehicle's position between messages,
    /// m/√s ([`super::process`]): the navigation's white velocity error,
    /// integrated (eq. 50 has no noise; without it the set collapses).
    /// Default 0.02.
    pub position_walk_m_rt_s: f64,
    /// σ of the correction of the navigation's velocity fixed in NED at a
    /// start, m/s per axis. Default 0.005 (a 0.2° heading deviation at 1.5
    /// m/s): the aided INS `pf` on the survey's development seeds 7-9 errs
    /// by −0.0012, −0.0085 and −0.0018 m/s east over the dive, the same on
    /// legs of opposite direction ([`super::process`]); the former 0.002,
    /// measured on seed 7 alone, put seed 8's at 4σ and let its east error
    /// grow to 4 m before the ranges caught up.
    pub velocity_error_m_s: f64,
    /// `q_c`, random walk of that correction, m/s/√s. Default 1e-5.
    pub velocity_walk_m_s_rt_s: f64,
    /// σ of the navigation's velocity scale error at a start (the state
    /// `k`). Default 0.
    pub scale_error: f64,
    /// `q_k`, its random walk, 1/√s. Default 0.
    pub scale_walk_rt_s: f64,
    /// σ of the navigation's heading error at a start (the state `ψ`),
    /// rad. Default 0.
    pub heading_error_rad: f64,
    /// `q_ψ`, its random walk, rad/√s. Default 0.
    pub heading_walk_rad_rt_s: f64,
    /// The gate: a range whose innovation is more than this many of its σ
    /// (eq. 54's σ_d with the filter's own spread) is refused and counted
    /// (multipath, clock jumps). Default 4.
    pub gate_sigmas: f64,
    /// Paper 000's rule: at a depth below this the vehicle is at the
    /// surface and takes its position from the GPS, m. Default 4.
    pub surface_depth_m: f64,
    /// Half-width of the square of eq. 48's uniform set around a GPS fix,
    /// m (and the EKF's σ, its uniform equivalent). Default 5.
    pub init_half_width_m: f64,
    /// Submerged and no range used for this long: a fix stamped now with
    /// source [`super::source::NONE`] says so (and again after as long),
    /// s. Default 90 (three of the buoy's 30 s broadcasts).
    pub silence_s: f64,
}

impl Default for RangeModel {
    fn default() -> Self {
        Self {
            range_sigma_m: 1.5,
            sound_speed_rel_sigma: 0.003,
            sound_speed_walk_rt_s: 0.0,
            buoy_sigma_m: 2.5,
            track_buoy: None,
            buoy_walk_m_rt_s: 0.05,
            buoy_drift_m_s: 0.05,
            buoy_drift_walk_m_s_rt_s: 1e-4,
            position_walk_m_rt_s: 0.02,
            velocity_error_m_s: 0.005,
            velocity_walk_m_s_rt_s: 1e-5,
            scale_error: 0.0,
            scale_walk_rt_s: 0.0,
            heading_error_rad: 0.0,
            heading_walk_rad_rt_s: 0.0,
            gate_sigmas: 4.0,
            surface_depth_m: 4.0,
            init_half_width_m: 5.0,
            silence_s: 90.0,
        }
    }
}

impl RangeModel {
    /// Whether the buoy is tracked (unset: yes; the `pf` variant sets it
    /// to no when it is unset).
    pub fn tracks_buoy(&self) -> bool {
        self.track_buoy.unwrap_or(true)
    }

    /// Eq. 54's σ_d² of one range, m²: its own noise, and the buoy's GPS
    /// when the buoy is not tracked (the sound speed's share is the state
    /// `s`, the tracked buoy's the states `b`).
    pub fn range_var_m2(&self) -> f64 {
        let buoy = if self.tracks_buoy() {
            0.0
        } else {
            self.buoy_sigma_m.powi(2)
        };
        self.range_sigma_m.powi(2) + buoy
    }

    /// The variance of the buoy's broadcast position per axis, m² (at
    /// least a centimetre's).
    pub fn buoy_var_m2(&self) -> f64 {
        self.buoy_sigma_m.max(0.01).powi(2)
    }

    /// σ of each value of the state at a start with the position uniform in
    /// a square of half-width `half_width_m` (σ `h/√3`), the buoy at its
    /// broadcast position (zero when it is not tracked).
    pub fn prior_sigma(&self, half_width_m: f64) -> [f64; DIM] {
        let p = half_width_m / 3f64.sqrt();
        let mut s = [0.0; DIM];
        s[N] = p;
        s[E] = p;
        s[CN] = self.velocity_error_m_s;
        s[CE] = self.velocity_error_m_s;
        s[SOUND] = self.sound_speed_rel_sigma;
        s[SCALE] = self.scale_error;
        s[HEADING] = self.heading_error_rad;
        if self.tracks_buoy() {
            s[BN] = self.buoy_sigma_m.max(0.01);
            s[BE] = s[BN];
            s[UN] = self.buoy_drift_m_s;
            s[UE] = self.buoy_drift_m_s;
        }
        s
    }

    /// The random walks (the buoy's zero when it is not tracked).
    pub fn walk(&self) -> Walk {
        Walk {
            position_m_rt_s: self.position_walk_m_rt_s,
            velocity_m_s_rt_s: self.velocity_walk_m_s_rt_s,
            sound_speed_rt_s: self.sound_speed_walk_rt_s,
            scale_rt_s: self.scale_walk_rt_s,
            heading_rad_rt_s: self.heading_walk_rad_rt_s,
            buoy_m_rt_s: if self.tracks_buoy() {
                self.buoy_walk_m_rt_s
            } else {
                0.0
            },
            buoy_drift_m_s_rt_s: if self.tracks_buoy() {
                self.buoy_drift_walk_m_s_rt_s
            } else {
                0.0
            },
        }
    }

    fn check(&self) -> Result<(), OutOfRange> {
        positive("range_sigma_m", self.range_sigma_m)?;
        in_range(
            "sound_speed_rel_sigma",
            self.sound_speed_rel_sigma,
            0.0,
            0.5,
            false,
            "[0, 0.5]",
        )?;
        in_range(
            "sound_speed_walk_rt_s",
            self.sound_speed_walk_rt_s,
            0.0,
            0.01,
            false,
            "[0, 0.01]",
        )?;
        nonneg("buoy_sigma_m", self.buoy_sigma_m)?;
        in_range(
            "buoy_walk_m_rt_s",
            self.buoy_walk_m_rt_s,
            0.0,
            100.0,
            false,
            "[0, 100]",
        )?;
        in_range(
            "buoy_drift_m_s",
            self.buoy_drift_m_s,
            0.0,
            10.0,
            false,
            "[0, 10]",
        )?;
        in_range(
            "buoy_drift_walk_m_s_rt_s",
            self.buoy_drift_walk_m_s_rt_s,
            0.0,
            1.0,
            false,
            "[0, 1]",
        )?;
        nonneg("position_walk_m_rt_s", self.position_walk_m_rt_s)?;
        in_range(
            "velocity_error_m_s",
            self.velocity_error_m_s,
            0.0,
            10.0,
            false,
            "[0, 10]",
        )?;
        in_range(
            "velocity_walk_m_s_rt_s",
            self.velocity_walk_m_s_rt_s,
            0.0,
            1.0,
            false,
            "[0, 1]",
        )?;
        in_range("scale_error", self.scale_error, 0.0, 0.5, false, "[0, 0.5]")?;
        in_range(
            "scale_walk_rt_s",
            self.scale_walk_rt_s,
            0.0,
            0.01,
            false,
            "[0, 0.01]",
        )?;
        in_range(
            "heading_error_rad",
            self.heading_error_rad,
            0.0,
            0.5,
            false,
            "[0, 0.5]",
        )?;
        in_range(
            "heading_walk_rad_rt_s",
            self.heading_walk_rad_rt_s,
            0.0,
            0.01,
            false,
            "[0, 0.01]",
        )?;
        in_range(
            "gate_sigmas",
            self.gate_sigmas,
            1.0,
            100.0,
            false,
            "[1, 100]",
        )?;
        in_range(
            "surface_depth_m",
            self.surface_depth_m,
            0.0,
            100.0,
            false,
            "[0, 100]",
        )?;
        positive("init_half_width_m", self.init_half_width_m)?;
        positive("silence_s", self.silence_s)?;
        Ok(())
    }
}

/// `pf`: paper 000 §III-B-2's particle filter.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PositioningPfParams {
    /// `N`, particles (eq. 48). Default 1000.
    pub particles: usize,
    /// Seed of the filter's random numbers (the same seed and inputs give
    /// the same outputs, bit for bit). Default 0.
    pub seed: u64,
    /// `N_th / N`: resample when the effective particle count (eq. 46)
    /// falls below this share of `N`. Default 0.5.
    pub resample_threshold: f64,
    /// The completion of the set after eq. 55's reproduction draws
    /// particles around the best particle, uniform in a box of this many
    /// of the reproduced set's σ in the set's own axes (its covariance's
    /// Cholesky factor times a uniform of half-width `√3` times this).
    /// Default 1.
    pub fill_spread: f64,
    /// The range model, gate and surface rule.
    pub model: RangeModel,
}

impl Default for PositioningPfParams {
    fn default() -> Self {
        Self {
            particles: 1000,
            seed: 0,
            resample_threshold: 0.5,
            fill_spread: 1.0,
            model: RangeModel::default(),
        }
    }
}

impl PositioningPfParams {
    /// Checks every field.
    pub fn validate(&self) -> anyhow::Result<()> {
        if !(2..=MAX_PARTICLES).contains(&self.particles) {
            anyhow::bail!(
                "particles = {} is outside [2, {MAX_PARTICLES}]",
                self.particles
            );
        }
        let r = (|| {
            in_range(
                "resample_threshold",
                self.resample_threshold,
                0.0,
                1.0,
                false,
                "[0, 1]",
            )?;
            in_range("fill_spread", self.fill_spread, 0.0, 10.0, false, "[0, 10]")?;
            self.model.check()
        })();
        r.map_err(out_of_range)
    }
}

/// `ekf`: a range-only extended Kalman filter of the horizontal position.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PositioningEkfParams {
    /// The range model, gate and surface rule.
    pub model: RangeModel,
}

impl PositioningEkfParams {
    /// Checks every field.
    pub fn validate(&self) -> anyhow::Result<()> {
        self.model.check().map_err(out_of_range)
    }
}

fn out_of_range(e: OutOfRange) -> anyhow::Error {
    anyhow::anyhow!("{} = {} is outside {}", e.name, e.value, e.range)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_pass_and_bad_values_are_named() {
        PositioningPfParams::default().validate().expect("defaults");
        PositioningEkfParams::default()
            .validate()
            .expect("defaults");
        let mut p = PositioningPfParams::default();
        p.model.gate_sigmas = f64::NAN;
        let e = p.validate().expect_err("NaN gate").to_string();
        assert!(e.contains("gate_sigmas"), "{e}");
        p = PositioningPfParams {
            particles: 1,
            ..Default::default()
        };
        assert!(p.validate().is_err());
        let t: PositioningPfParams =
            toml::from_str("particles = 50\n[model]\nbuoy_sigma_m = 5.0").expect("toml");
        assert_eq!((t.particles, t.model.buoy_sigma_m), (50, 5.0));
        assert!(toml::from_str::<PositioningPfParams>("particle = 50").is_err());
    }
}
