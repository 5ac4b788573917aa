//! The positioning role's parameters as a manifest writes them
//! (`[process.positioning.variants.pf]` and `.ekf`, every field defaulted,
//! unknown keys refused) and their checks. Paper 000 gives the filter's
//! structure but none of its numbers: every default is our choice, from
//! the simulator's modem (DESIGN §10) unless it says otherwise.

use serde::Deserialize;

use crate::params::{OutOfRange, in_range, nonneg, positive};

/// Largest particle count.
pub const MAX_PARTICLES: usize = 65_536;

/// What both variants share: the range's error model, the gate, the
/// surface rule and the process noise between messages.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RangeModel {
    /// The range's own noise, m: the sound speed times the modem clocks'
    /// synchronisation jitter (1 ms at 1500 m/s). Default 1.5.
    pub range_sigma_m: f64,
    /// The relative error of the sound speed the buoy reports, 1σ: its
    /// share of eq. 54's σ_d grows with the range. Default 0.003.
    pub sound_speed_rel_sigma: f64,
    /// The error of the buoy's GPS position in its broadcast, m per
    /// horizontal axis. Default 2.5.
    pub buoy_sigma_m: f64,
    /// `q_p`, random walk of the vehicle's position between messages,
    /// m/√s ([`super::process`]): the navigation's white velocity error,
    /// integrated (eq. 50 has no noise; without it the set collapses).
    /// Default 0.02.
    pub position_walk_m_rt_s: f64,
    /// σ of the correction of the navigation's velocity at a start, m/s
    /// per axis. Default 0.002: the aided INS `pf` on the survey (seed 7,
    /// the development seed) errs by a mean of 0.0002 / −0.0013 m/s north /
    /// east over the dive, 0.007 m/s RMS of which integrates to only
    /// 0.3-0.4 m over 300 s (BENCHMARKS.md, "Acoustic positioning"); a
    /// looser prior (0.02 before) lets the filter follow each noisy range.
    pub velocity_error_m_s: f64,
    /// `q_v`, random walk of that correction, m/s/√s. Default 1e-5 (0.0005
    /// m/s over the 2600 s survey; development seeds 7-9).
    pub velocity_walk_m_s_rt_s: f64,
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
            buoy_sigma_m: 2.5,
            position_walk_m_rt_s: 0.02,
            velocity_error_m_s: 0.002,
            velocity_walk_m_s_rt_s: 1e-5,
            gate_sigmas: 4.0,
            surface_depth_m: 4.0,
            init_half_width_m: 5.0,
            silence_s: 90.0,
        }
    }
}

impl RangeModel {
    /// Eq. 54's σ_d² for a range of `range_m`, m².
    pub fn range_var_m2(&self, range_m: f64) -> f64 {
        let c = self.sound_speed_rel_sigma * range_m;
        self.range_sigma_m.powi(2) + c * c + self.buoy_sigma_m.powi(2)
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
        nonneg("buoy_sigma_m", self.buoy_sigma_m)?;
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
    /// Half-width of the square the set is completed in around the best
    /// particle after eq. 55's reproduction, m. Default 3.
    pub fill_half_width_m: f64,
    /// Half-width of the same completion in the velocity correction, m/s.
    /// Default 0.002 (the correction's prior σ).
    pub fill_velocity_m_s: f64,
    /// The range model, gate and surface rule.
    pub model: RangeModel,
}

impl Default for PositioningPfParams {
    fn default() -> Self {
        Self {
            particles: 1000,
            seed: 0,
            resample_threshold: 0.5,
            fill_half_width_m: 3.0,
            fill_velocity_m_s: 0.002,
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
            positive("fill_half_width_m", self.fill_half_width_m)?;
            nonneg("fill_velocity_m_s", self.fill_velocity_m_s)?;
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
