//! The particle filter's parameters: [`PfParams`] as a manifest writes them
//! (datasheet units, every field defaulted, unknown keys refused) and
//! [`PfConfig`], the checked SI values the filter uses.

use crate::params::{nonneg, positive};
use serde::Deserialize;
use thiserror::Error;

/// Standard gravity g₀, m/s², to convert µg.
const STANDARD_GRAVITY_M_S2: f64 = 9.806_65;

/// Particle-filter parameters as written in a manifest
/// (`variants.pf.filter = { ... }`).
///
/// Noise densities make the filter's behaviour independent of the sampling
/// rate: a per-sample standard deviation is the density divided by `√Δt`.
/// In the limit of a linear, Gaussian problem the filter behaves like a
/// Kalman filter whose tilt follows the accelerometer with a time constant
/// of about `tilt_noise / gyro_noise` (both in the same angle unit) and
/// whose heading follows the magnetometer with `heading_noise / gyro_noise`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PfParams {
    /// Number of particles N (paper 000 eq. 43). Default 700 (our choice,
    /// BENCHMARKS.md "Attitude PF speed", 2026-12-02: on BROAD's
    /// development trials a mean total RMSE of 2.34° / 2.33° / 2.34° with
    /// seeds 0 / 1 / 2, against 2.32° / 2.43° / 2.48° with 1,000, and on its
    /// 18 held-out trials 1.888° against 1.897° (seed 0, measured
    /// 2026-12-01 with the same arithmetic); 30 % less work per sample than
    /// 1,000. With 300 the simulator's pitch-and-roll condition gave
    /// 0.23°/0.30° roll/pitch RMS instead of 0.08°/0.09°).
    pub particles: usize,
    /// Seed of the filter's generator (xoshiro128++ streams, `pf/noise.rs`):
    /// the same seed and inputs give the same estimates, bit for bit.
    /// Default 0.
    pub seed: u64,
    /// Process noise density of the prediction (eq. 28), °/s/√Hz: the
    /// gyro's angle random walk plus what the gyro model leaves out (scale
    /// factor, axis misalignment, quantisation, timing), taken as white. It
    /// Default 0.1 (our choice: an MTi-30 is specified at 0.03 and BROAD's
    /// IMU measures 0.006 at rest, but with 0.03 the particle cloud is
    /// narrower than a hand-held IMU's real attitude error and the filter
    /// corrects too slowly: BROAD mean 2.74° against 2.41°; 0.3 gives 3.17°;
    /// `shared/bench/src/attitude.rs`).
    pub gyro_noise_deg_s_rt_hz: f64,
    /// Gyro bias random walk, °/h/√h (the rate random walk K). Default 20
    /// (our choice: an MTi-30 bias wanders ~18 °/h within an hour; faster than
    /// the physics so that the particles keep some spread in bias).
    pub gyro_bias_walk_deg_h_rt_h: f64,
    /// Accelerometer white-noise density, µg/√Hz. Default 80 (MTi 10-series,
    /// as the simulator).
    pub accel_noise_ug_rt_hz: f64,
    /// Magnetometer white noise, 1σ per axis and sample, µT. Default 0.05
    /// (Xsens MTi 10-series, as the simulator). It enters the heading noise as
    /// `σ_m / H` rad per sample, H the horizontal field.
    pub mag_noise_ut: f64,
    /// Tilt aiding noise density, °·√s: the unmodelled part of the
    /// low-passed specific force's direction (accelerations that do not
    /// average out), taken as white. With the default process noise the tilt
    /// follows the accelerometer with a time constant of about 1 s (after the
    /// 3 s low-pass). Default 0.1 (our choice: on BROAD 0.03 to 0.3 give a
    /// mean total RMSE of 2.15° to 2.61°, on the simulator 0.03 and 0.1 both
    /// stay within 0.2° in roll and pitch; sweep in
    /// `shared/bench/src/attitude.rs`).
    pub tilt_noise_deg_rt_s: f64,
    /// Heading aiding noise density, °·√s: the residual magnetic distortion
    /// of the tilt-compensated heading, taken as white. With the default
    /// process noise, a heading time constant of about 2 s. Default 0.2 (our
    /// choice: on BROAD 0.1 to 0.6 give 2.10° to 2.41° with the default tilt
    /// noise).
    pub heading_noise_deg_rt_s: f64,
    /// Time constant of the low-pass filter applied to the specific force in
    /// the navigation frame before it aids the tilt, s (0: none). Default 3
    /// (our choice, VQF's τ_acc; Laidig & Seel 2023): accelerations that come
    /// and go within seconds, and the centripetal acceleration of a turn,
    /// average out there.
    pub accel_lowpass_s: f64,
    /// Resampling threshold N_th as a fraction of N (paper 000 eq. 46: resample
    /// when N_eff < N_th). Default 0.5 (our choice; the paper determines it
    /// "experimentally" and does not give it).
    pub resample_threshold: f64,
    /// Gate on the low-passed specific force: when `| |f_lp| − g |` is above
    /// this, m/s², the accelerometer gives no tilt weight. Default 2.0 (our
    /// choice). Below the gate the tilt noise grows with the deviation
    /// (adaptive weighting).
    pub accel_gate_m_s2: f64,
    /// Gate on the field norm: a sample with `| |m| / |m_ref| − 1 |` above
    /// this gives no heading weight. Default 0.15 (as the `mekf`).
    pub mag_norm_gate: f64,
    /// Gate on the dip angle, degrees: a sample whose dip differs from the
    /// reference by more than this gives no heading weight. Default 10 (as the
    /// `mekf`).
    pub mag_dip_gate_deg: f64,
    /// Rest detection: the gyro may deviate from its 0.5 s low-pass mean by at
    /// most this, °/s, and the low-pass mean from the bias estimate too.
    /// Default 2 (our choice, VQF's default threshold).
    pub rest_gyro_deg_s: f64,
    /// Rest detection: the specific force may deviate from its low-pass mean
    /// by at most this, m/s². Default 0.5 (our choice, VQF's).
    pub rest_accel_m_s2: f64,
    /// Rest detection: how long both conditions must hold before the gyro is
    /// taken as a bias measurement, s. Default 1.5 (our choice, VQF's).
    pub rest_min_s: f64,
    /// Initial roll and pitch 1σ of the particle cloud, degrees. Default 5.
    pub initial_tilt_std_deg: f64,
    /// Initial heading 1σ, degrees. Default 10.
    pub initial_heading_std_deg: f64,
    /// Initial gyro bias 1σ per axis, °/s. Default 0.5 (MEMS turn-on bias;
    /// the MTi-30's is 0.2).
    pub initial_bias_std_deg_s: f64,
}

impl Default for PfParams {
    fn default() -> Self {
        Self {
            particles: 700,
            seed: 0,
            gyro_noise_deg_s_rt_hz: 0.1,
            gyro_bias_walk_deg_h_rt_h: 20.0,
            accel_noise_ug_rt_hz: 80.0,
            mag_noise_ut: 0.05,
            tilt_noise_deg_rt_s: 0.1,
            heading_noise_deg_rt_s: 0.2,
            accel_lowpass_s: 3.0,
            resample_threshold: 0.5,
            accel_gate_m_s2: 2.0,
            mag_norm_gate: 0.15,
            mag_dip_gate_deg: 10.0,
            rest_gyro_deg_s: 2.0,
            rest_accel_m_s2: 0.5,
            rest_min_s: 1.5,
            initial_tilt_std_deg: 5.0,
            initial_heading_std_deg: 10.0,
            initial_bias_std_deg_s: 0.5,
        }
    }
}

/// Why [`PfParams`] cannot be used.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum PfParamsError {
    /// A value is NaN, infinite or outside its range.
    #[error("PF parameter {name} = {value} is out of range ({range})")]
    OutOfRange {
        /// The field's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range, in words.
        range: &'static str,
    },
}

/// Checked parameters in SI units and radians; built from [`PfParams`] with
/// [`TryFrom`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PfConfig {
    pub(super) particles: usize,
    pub(super) seed: u64,
    pub(super) gyro_noise_rad_rt_s: f64,
    pub(super) gyro_bias_walk_rad_s_rt_s: f64,
    pub(super) accel_noise_m_s2_rt_hz: f64,
    pub(super) mag_noise_ut: f64,
    pub(super) tilt_noise_rad_rt_s: f64,
    pub(super) heading_noise_rad_rt_s: f64,
    pub(super) accel_lowpass_s: f64,
    pub(super) resample_threshold: f64,
    pub(super) accel_gate_m_s2: f64,
    pub(super) mag_norm_gate: f64,
    pub(super) mag_dip_gate_rad: f64,
    pub(super) rest_gyro_rad_s: f64,
    pub(super) rest_accel_m_s2: f64,
    pub(super) rest_min_s: f64,
    pub(super) initial_tilt_std_rad: f64,
    pub(super) initial_heading_std_rad: f64,
    pub(super) initial_bias_std_rad_s: f64,
}

/// Largest particle count accepted (memory: 64 bytes a particle).
pub const MAX_PARTICLES: usize = 1_000_000;

impl From<crate::params::OutOfRange> for PfParamsError {
    fn from(e: crate::params::OutOfRange) -> Self {
        Self::OutOfRange {
            name: e.name,
            value: e.value,
            range: e.range,
        }
    }
}

impl TryFrom<&PfParams> for PfConfig {
    type Error = PfParamsError;

    fn try_from(p: &PfParams) -> Result<Self, Self::Error> {
        if !(2..=MAX_PARTICLES).contains(&p.particles) {
            return Err(PfParamsError::OutOfRange {
                name: "particles",
                value: p.particles as f64,
                range: "[2, 1000000]",
            });
        }
        let gyro_noise = positive("gyro_noise_deg_s_rt_hz", p.gyro_noise_deg_s_rt_hz)?;
        let bias_walk = nonneg("gyro_bias_walk_deg_h_rt_h", p.gyro_bias_walk_deg_h_rt_h)?;
        let accel_noise = nonneg("accel_noise_ug_rt_hz", p.accel_noise_ug_rt_hz)?;
        let mag_noise = nonneg("mag_noise_ut", p.mag_noise_ut)?;
        let tilt = positive("tilt_noise_deg_rt_s", p.tilt_noise_deg_rt_s)?;
        let heading = positive("heading_noise_deg_rt_s", p.heading_noise_deg_rt_s)?;
        let lowpass = nonneg("accel_lowpass_s", p.accel_lowpass_s)?;
        let threshold = crate::params::in_range(
            "resample_threshold",
            p.resample_threshold,
            0.0,
            1.0,
            false,
            "[0, 1]",
        )?;
        let accel_gate = positive("accel_gate_m_s2", p.accel_gate_m_s2)?;
        let norm_gate = positive("mag_norm_gate", p.mag_norm_gate)?;
        let dip_gate = crate::params::in_range(
            "mag_dip_gate_deg",
            p.mag_dip_gate_deg,
            0.0,
            180.0,
            true,
            "(0, 180]",
        )?;
        let rest_gyro = nonneg("rest_gyro_deg_s", p.rest_gyro_deg_s)?;
        let rest_accel = nonneg("rest_accel_m_s2", p.rest_accel_m_s2)?;
        let rest_min = positive("rest_min_s", p.rest_min_s)?;
        let tilt_std = positive("initial_tilt_std_deg", p.initial_tilt_std_deg)?;
        let heading_std = positive("initial_heading_std_deg", p.initial_heading_std_deg)?;
        let bias_std = positive("initial_bias_std_deg_s", p.initial_bias_std_deg_s)?;
        Ok(Self {
            particles: p.particles,
            seed: p.seed,
            gyro_noise_rad_rt_s: gyro_noise.to_radians(),
            // °/h/√h → rad/s/√s: (°→rad) / 3600 (per h → per s) / 60 (√h → √s).
            gyro_bias_walk_rad_s_rt_s: bias_walk.to_radians() / 3600.0 / 60.0,
            accel_noise_m_s2_rt_hz: accel_noise * 1e-6 * STANDARD_GRAVITY_M_S2,
            mag_noise_ut: mag_noise,
            tilt_noise_rad_rt_s: tilt.to_radians(),
            heading_noise_rad_rt_s: heading.to_radians(),
            accel_lowpass_s: lowpass,
            resample_threshold: threshold,
            accel_gate_m_s2: accel_gate,
            mag_norm_gate: norm_gate,
            mag_dip_gate_rad: dip_gate.to_radians(),
            rest_gyro_rad_s: rest_gyro.to_radians(),
            rest_accel_m_s2: rest_accel,
            rest_min_s: rest_min,
            initial_tilt_std_rad: tilt_std.to_radians(),
            initial_heading_std_rad: heading_std.to_radians(),
            initial_bias_std_rad_s: bias_std.to_radians(),
        })
    }
}

impl PfConfig {
    /// Number of particles.
    pub fn particles(&self) -> usize {
        self.particles
    }

    /// Gyro white-noise density, rad/√s.
    pub fn gyro_noise_rad_rt_s(&self) -> f64 {
        self.gyro_noise_rad_rt_s
    }

    /// Gyro bias random walk, rad/s/√s.
    pub fn gyro_bias_walk_rad_s_rt_s(&self) -> f64 {
        self.gyro_bias_walk_rad_s_rt_s
    }

    /// Initial gyro bias 1σ per axis, rad/s.
    pub fn initial_bias_std_rad_s(&self) -> f64 {
        self.initial_bias_std_rad_s
    }
}
