//! The sensor specifications the error predictor is fed from, as a manifest
//! writes them (`[process.ains.variants.dr.predictor.sensors]`), and their
//! checks.
//!
//! Each error of paper 002's `δv_b = (δv_x, δv_y, δv_z)` and
//! `δΘ = (δφ, δθ, δψ)` is the sum of up to three parts, by how it is
//! correlated in time:
//!
//! - white noise: σ per sample at the sensor's rate f, so a power spectral
//!   density `σ² / f` once integrated (the dead reckoning holds each sample
//!   for `1 / f`);
//! - a bias: a first-order Gauss-Markov process of stationary σ_b and
//!   correlation time τ (`τ = inf` in TOML: a constant drawn once, a
//!   turn-on bias); it starts every run from its stationary distribution;
//! - a scale factor (DVL only): `δv_b = s v_b`, `s` a constant of σ_s
//!   common to the three axes, as DVL datasheets quote one accuracy.
//!
//! The defaults are the shipped simulator's sensors (`nauta_sim`'s
//! `SuiteConfig::dr()` preset, `shared/sim/src/suite/config.rs` and
//! `shared/sim/src/noise/sensors.rs`): DVL 5 Hz, 0.01 m/s white per axis,
//! 0.2 % scale factor, no bias; AHRS 10 Hz, roll and pitch 0.2° white,
//! heading 1° white plus a 2° Gauss-Markov bias of 600 s; depth 0.02 m
//! white. They are what a manifest for those sensors writes; the predictor
//! never reads the simulator. [`SensorErrorSpec::paper_002`] gives the
//! paper's own constant-error inputs (5 % of `v_b`, 3° on each angle).

use serde::Deserialize;

use crate::params::{OutOfRange, nonneg, positive};

/// DVL velocity errors `δv_b` (each body axis alike).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DvlErrorSpec {
    /// Sample rate f, Hz. Default 5 (the simulator's).
    pub rate_hz: f64,
    /// White noise σ per axis and sample, m/s. Default 0.01 (the simulator's).
    pub noise_sigma_m_s: f64,
    /// Bias stationary σ_b per axis, m/s. Default 0 (the simulator has none).
    pub bias_sigma_m_s: f64,
    /// Bias correlation time τ, s (`inf`: constant). Default `inf`.
    pub bias_time_s: f64,
    /// Scale factor σ_s, fraction, common to the three axes. Default 0.002
    /// (the simulator's 0.2 %).
    pub scale_factor_sigma: f64,
}

impl Default for DvlErrorSpec {
    fn default() -> Self {
        Self {
            rate_hz: 5.0,
            noise_sigma_m_s: 0.01,
            bias_sigma_m_s: 0.0,
            bias_time_s: f64::INFINITY,
            scale_factor_sigma: 0.002,
        }
    }
}

/// AHRS attitude errors `δΘ`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AhrsErrorSpec {
    /// Sample rate f, Hz. Default 10 (the simulator's).
    pub rate_hz: f64,
    /// Roll and pitch white noise σ per sample, degrees. Default 0.2.
    pub roll_pitch_sigma_deg: f64,
    /// Roll and pitch bias stationary σ_b, degrees. Default 0.
    pub roll_pitch_bias_sigma_deg: f64,
    /// Roll and pitch bias correlation time τ, s (`inf`: constant). Default `inf`.
    pub roll_pitch_bias_time_s: f64,
    /// Heading white noise σ per sample, degrees. Default 1.
    pub heading_sigma_deg: f64,
    /// Heading bias stationary σ_b, degrees (what the declination and the
    /// compass's slowly varying magnetic disturbances leave). Default 2.
    pub heading_bias_sigma_deg: f64,
    /// Heading bias correlation time τ, s (`inf`: constant). Default 600.
    pub heading_bias_time_s: f64,
}

impl Default for AhrsErrorSpec {
    fn default() -> Self {
        Self {
            rate_hz: 10.0,
            roll_pitch_sigma_deg: 0.2,
            roll_pitch_bias_sigma_deg: 0.0,
            roll_pitch_bias_time_s: f64::INFINITY,
            heading_sigma_deg: 1.0,
            heading_bias_sigma_deg: 2.0,
            heading_bias_time_s: 600.0,
        }
    }
}

/// Depth gauge errors (after the surface tare).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DepthErrorSpec {
    /// White noise σ per sample, m. Default 0.02 (the simulator's).
    pub noise_sigma_m: f64,
}

impl Default for DepthErrorSpec {
    fn default() -> Self {
        Self {
            noise_sigma_m: 0.02,
        }
    }
}

/// The sensors' error specification (defaults: the shipped simulator's).
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorErrorSpec {
    /// DVL.
    pub dvl: DvlErrorSpec,
    /// AHRS.
    pub ahrs: AhrsErrorSpec,
    /// Depth gauge.
    pub depth: DepthErrorSpec,
}

/// One error channel of `[δv_x, δv_y, δv_z, δφ, δθ, δψ]`, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Channel {
    /// White noise power spectral density `σ² / f`, unit²·s.
    pub white_psd: f64,
    /// White noise variance per sample `σ²`, unit².
    pub white_var: f64,
    /// Bias stationary standard deviation σ_b, unit.
    pub bias_sigma: f64,
    /// Bias correlation time τ, s (infinite: constant).
    pub bias_time_s: f64,
}

/// The checked specification in SI units: the six channels and the rest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckedSpec {
    /// `δv_x, δv_y, δv_z` (m/s), `δφ, δθ, δψ` (rad).
    pub channels: [Channel; 6],
    /// DVL scale factor σ_s, fraction.
    pub scale_factor_sigma: f64,
    /// Depth white noise σ, m.
    pub depth_sigma_m: f64,
}

fn correlation_time(name: &'static str, value: f64) -> Result<f64, OutOfRange> {
    // `inf` (a constant) is allowed; NaN, zero and negatives are not.
    if value > 0.0 {
        Ok(value)
    } else {
        Err(OutOfRange {
            name,
            value,
            range: "(0, inf]",
        })
    }
}

impl SensorErrorSpec {
    /// The shipped simulator's sensors (the defaults; see the module docs).
    pub fn simulator() -> Self {
        Self::default()
    }

    /// Paper 002's inputs to eqs. 14-17 (§ Results): `δv_b = 5 % of v_b`
    /// and `δΘ = 3°` on each angle, both constant over a dive (no white
    /// noise), "based on manufacturers specifications and augmented by a
    /// fraction to represent other error sources".
    pub fn paper_002() -> Self {
        Self {
            dvl: DvlErrorSpec {
                noise_sigma_m_s: 0.0,
                scale_factor_sigma: 0.05,
                ..DvlErrorSpec::default()
            },
            ahrs: AhrsErrorSpec {
                roll_pitch_sigma_deg: 0.0,
                roll_pitch_bias_sigma_deg: 3.0,
                roll_pitch_bias_time_s: f64::INFINITY,
                heading_sigma_deg: 0.0,
                heading_bias_sigma_deg: 3.0,
                heading_bias_time_s: f64::INFINITY,
                ..AhrsErrorSpec::default()
            },
            depth: DepthErrorSpec::default(),
        }
    }

    /// The checked values in SI units; a NaN, a negative σ, a rate or a
    /// correlation time that is not positive is refused by name.
    pub fn check(&self) -> Result<CheckedSpec, OutOfRange> {
        let d = &self.dvl;
        let a = &self.ahrs;
        let dvl_rate = positive("dvl.rate_hz", d.rate_hz)?;
        let ahrs_rate = positive("ahrs.rate_hz", a.rate_hz)?;
        let dvl_noise = nonneg("dvl.noise_sigma_m_s", d.noise_sigma_m_s)?;
        let dvl_bias = nonneg("dvl.bias_sigma_m_s", d.bias_sigma_m_s)?;
        let dvl_tau = correlation_time("dvl.bias_time_s", d.bias_time_s)?;
        let scale = nonneg("dvl.scale_factor_sigma", d.scale_factor_sigma)?;
        let rp = nonneg("ahrs.roll_pitch_sigma_deg", a.roll_pitch_sigma_deg)?.to_radians();
        let rp_bias = nonneg(
            "ahrs.roll_pitch_bias_sigma_deg",
            a.roll_pitch_bias_sigma_deg,
        )?
        .to_radians();
        let rp_tau = correlation_time("ahrs.roll_pitch_bias_time_s", a.roll_pitch_bias_time_s)?;
        let hd = nonneg("ahrs.heading_sigma_deg", a.heading_sigma_deg)?.to_radians();
        let hd_bias = nonneg("ahrs.heading_bias_sigma_deg", a.heading_bias_sigma_deg)?.to_radians();
        let hd_tau = correlation_time("ahrs.heading_bias_time_s", a.heading_bias_time_s)?;
        let depth = nonneg("depth.noise_sigma_m", self.depth.noise_sigma_m)?;
        let channel = |sigma: f64, rate: f64, bias: f64, tau: f64| Channel {
            white_psd: sigma * sigma / rate,
            white_var: sigma * sigma,
            bias_sigma: bias,
            bias_time_s: tau,
        };
        let v = channel(dvl_noise, dvl_rate, dvl_bias, dvl_tau);
        let t = channel(rp, ahrs_rate, rp_bias, rp_tau);
        Ok(CheckedSpec {
            channels: [v, v, v, t, t, channel(hd, ahrs_rate, hd_bias, hd_tau)],
            scale_factor_sigma: scale,
            depth_sigma_m: depth,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_parse_and_unknown_keys_are_refused() {
        let s: SensorErrorSpec = toml::from_str("").expect("defaults");
        assert_eq!(s, SensorErrorSpec::simulator());
        let p: SensorErrorSpec =
            toml::from_str("ahrs = { heading_bias_time_s = inf }\ndvl = { bias_time_s = 60.0 }")
                .expect("valid");
        assert!(p.ahrs.heading_bias_time_s.is_infinite() && p.dvl.bias_time_s == 60.0);
        assert!(toml::from_str::<SensorErrorSpec>("dvl = { nope = 1.0 }").is_err());
        assert!(toml::from_str::<SensorErrorSpec>("nope = 1").is_err());
        let c = s.check().expect("valid");
        assert!((c.channels[5].bias_sigma - 2f64.to_radians()).abs() < 1e-15);
        assert_eq!(c.channels[5].bias_time_s, 600.0);
        assert!(c.channels[0].bias_time_s.is_infinite());
        assert!((c.channels[0].white_psd - 1e-4 / 5.0).abs() < 1e-18);
    }

    #[test]
    fn bad_values_are_refused_by_name() {
        let mut s = SensorErrorSpec::default();
        s.ahrs.heading_bias_time_s = 0.0;
        assert_eq!(s.check().unwrap_err().name, "ahrs.heading_bias_time_s");
        let mut s = SensorErrorSpec::default();
        s.dvl.noise_sigma_m_s = f64::NAN;
        assert_eq!(s.check().unwrap_err().name, "dvl.noise_sigma_m_s");
        let mut s = SensorErrorSpec::default();
        s.dvl.rate_hz = -5.0;
        assert_eq!(s.check().unwrap_err().name, "dvl.rate_hz");
        let mut s = SensorErrorSpec::default();
        s.ahrs.heading_bias_sigma_deg = -1.0;
        assert_eq!(s.check().unwrap_err().name, "ahrs.heading_bias_sigma_deg");
        assert!(SensorErrorSpec::paper_002().check().is_ok());
    }
}
