//! The MEKF's parameters: [`MekfParams`] as a manifest writes them (datasheet
//! units, every field defaulted, unknown keys refused) and [`MekfConfig`], the
//! checked SI values the filter uses.

use crate::params::{nonneg, positive};
use serde::Deserialize;
use thiserror::Error;

/// Standard gravity g₀, m/s², to convert µg (the same constant as the simulator's
/// `noise::units`).
const STANDARD_GRAVITY_M_S2: f64 = 9.806_65;

/// Ratio of the flicker floor of an Allan deviation to the bias instability B
/// (IEEE Std 952-1997, Annex C: σ_min = B √(2 ln 2 / π) ≈ 0.664 B).
const FLICKER_FLOOR_FACTOR: f64 = 0.664;

/// MEKF parameters as written in a manifest (`variants.mekf.filter = { ... }`).
///
/// Defaults are of the Xsens MTi-30 class, the IMU of the papers (the same
/// datasheet figures as the simulator's `InertialAxisSpec::mti30_gyro` and
/// `mti30_accel` in `shared/sim/src/noise/inertial.rs`, "as remembered, to be
/// checked against the PDF"), except where a field says "our choice".
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MekfParams {
    /// Gyro white-noise density (angle random walk) N, °/s/√Hz. Default 0.03
    /// (MTi-30 rate noise density; = 1.8 °/√h).
    pub gyro_noise_deg_s_rt_hz: f64,
    /// Gyro in-run bias instability B, °/h. Default 18 (MTi-30). The filter models
    /// the bias as a random walk; see [`gyro_bias_walk_time_s`](Self::gyro_bias_walk_time_s).
    pub gyro_bias_instability_deg_h: f64,
    /// Averaging time τ_B, s, at which the bias random walk's Allan deviation
    /// equals the flicker floor `0.664 B`: the random-walk coefficient is
    /// `σ_u = 0.664 B √(3 / τ_B)` (rad/s/√s = rad/s²/√Hz), since a random walk of
    /// coefficient K has Allan deviation `K √(τ/3)` (IEEE Std 952-1997 Annex C).
    /// Default 1000 s (our choice: the upper end of the flat part of the MTi-30's
    /// Allan curve, which the simulator reproduces between 10 s and 1000 s); it
    /// gives `σ_u ≈ 3.2e-6 rad/s/√s`.
    pub gyro_bias_walk_time_s: f64,
    /// Accelerometer white-noise density, µg/√Hz. Default 60 (the MTi 100-series
    /// figure; the simulator uses the 10-series 80 µg/√Hz). Its share of the
    /// gravity-direction noise is `N_a / (g √Δt)` rad per sample, ~6e-4 rad at
    /// 100 Hz: far below the vehicle's own accelerations, see the next field.
    pub accel_noise_ug_rt_hz: f64,
    /// Unmodelled specific force (the vehicle's own accelerations, waves),
    /// 1σ per axis, m/s², added to the gravity-direction noise as `σ / g` rad.
    /// Default 0.3 (our choice, tuned with the two turn parameters below on the
    /// simulator's survey and attitude motions: a larger σ makes the tilt lean
    /// longer on the gyro, whose noise then dominates when still; a smaller one
    /// lets accelerations tilt it).
    pub accel_dynamic_sigma_m_s2: f64,
    /// Speed v_t, m/s, at which a turn is assumed to be made: a turn at rate ω_D
    /// about the vertical then carries a centripetal acceleration `ω_D v_t`
    /// that the norm gate cannot see (it is perpendicular to gravity) and that
    /// lasts the whole turn. It enters the gravity-direction noise as white noise
    /// of the same effect over the turn's duration τ_t, `(ω_D v_t)² τ_t / Δt`
    /// (a constant error over τ_t weighs in a Kalman filter's average like white
    /// noise of that variance). A 10 °/s turn at 1.5 m/s is 0.26 m/s² of
    /// centripetal acceleration, 1.5° of tilt if the filter followed it; it
    /// changes the norm of the specific force by only 0.004 m/s². Default 1.5
    /// (our choice: the survey's speed; 0 turns this off, right for an IMU that
    /// turns in place, e.g. on a turntable).
    pub turn_speed_m_s: f64,
    /// Duration τ_t, s, of the centripetal acceleration of a turn (see
    /// [`turn_speed_m_s`](Self::turn_speed_m_s)). Default 10 (our choice: the
    /// survey's 180° turns last about 18 s at 10 °/s).
    pub turn_duration_s: f64,
    /// Gate on the specific force: a sample with `| |f| − g |` above this, m/s²,
    /// is not used. Default 0.5 (our choice, 5 % of g).
    pub accel_gate_m_s2: f64,
    /// Heading measurement noise, 1σ, degrees: residual magnetic distortion and
    /// noise of one magnetometer sample's heading. Default 2 (our choice; the
    /// MTi-30 datasheet quotes 1° heading in a homogeneous field).
    pub mag_heading_sigma_deg: f64,
    /// Gate on the field norm: a sample with `| |m| / |m_ref| − 1 |` above this is
    /// not used. Default 0.15 (our choice: 15 %, above the −5 % to +6 % that the
    /// simulator's default hard and soft iron give over all headings with ±20°
    /// of roll and ±15° of pitch).
    pub mag_norm_gate: f64,
    /// Gate on the dip angle: a sample whose dip (angle of the field below the
    /// estimated horizontal) differs from the reference by more than this,
    /// degrees, is not used. Default 10 (our choice: the simulator's default
    /// hard and soft iron move the dip by −3° to +4.5° over all headings with
    /// ±20° of roll and ±15° of pitch, relative to an alignment anywhere in that
    /// range by up to ~7°).
    pub mag_dip_gate_deg: f64,
    /// Initial roll and pitch (north and east attitude error) 1σ, degrees.
    /// Default 2 (our choice; a still static alignment is good to a few tenths).
    pub initial_tilt_std_deg: f64,
    /// Initial heading (down attitude error) 1σ, degrees. Default 5 (our choice).
    pub initial_heading_std_deg: f64,
    /// Initial gyro bias 1σ per axis, °/s, when the bias is not measured at
    /// start. Default 0.2 (MTi-30 bias repeatability, the simulator's turn-on
    /// bias 1σ).
    pub initial_bias_std_deg_s: f64,
}

impl Default for MekfParams {
    fn default() -> Self {
        Self {
            gyro_noise_deg_s_rt_hz: 0.03,
            gyro_bias_instability_deg_h: 18.0,
            gyro_bias_walk_time_s: 1000.0,
            accel_noise_ug_rt_hz: 60.0,
            accel_dynamic_sigma_m_s2: 0.3,
            turn_speed_m_s: 1.5,
            turn_duration_s: 10.0,
            accel_gate_m_s2: 0.5,
            mag_heading_sigma_deg: 2.0,
            mag_norm_gate: 0.15,
            mag_dip_gate_deg: 10.0,
            initial_tilt_std_deg: 2.0,
            initial_heading_std_deg: 5.0,
            initial_bias_std_deg_s: 0.2,
        }
    }
}

/// Why [`MekfParams`] cannot be used.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum MekfParamsError {
    /// A value is NaN, infinite or outside its range.
    #[error("MEKF parameter {name} = {value} is out of range ({range})")]
    OutOfRange {
        /// The field's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range, in words.
        range: &'static str,
    },
}

/// Checked MEKF parameters in SI units and radians; built from [`MekfParams`]
/// with [`TryFrom`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MekfConfig {
    pub(super) gyro_noise_rad_rt_s: f64,
    pub(super) gyro_bias_instability_rad_s: f64,
    pub(super) gyro_bias_walk_rad_s_rt_s: f64,
    pub(super) accel_noise_m_s2_rt_hz: f64,
    pub(super) accel_dynamic_sigma_m_s2: f64,
    pub(super) turn_speed_m_s: f64,
    pub(super) turn_duration_s: f64,
    pub(super) accel_gate_m_s2: f64,
    pub(super) mag_heading_sigma_rad: f64,
    pub(super) mag_norm_gate: f64,
    pub(super) mag_dip_gate_rad: f64,
    pub(super) initial_tilt_std_rad: f64,
    pub(super) initial_heading_std_rad: f64,
    pub(super) initial_bias_std_rad_s: f64,
}

impl From<crate::params::OutOfRange> for MekfParamsError {
    fn from(e: crate::params::OutOfRange) -> Self {
        Self::OutOfRange {
            name: e.name,
            value: e.value,
            range: e.range,
        }
    }
}

impl TryFrom<&MekfParams> for MekfConfig {
    type Error = MekfParamsError;

    fn try_from(p: &MekfParams) -> Result<Self, Self::Error> {
        let gyro_noise = nonneg("gyro_noise_deg_s_rt_hz", p.gyro_noise_deg_s_rt_hz)?;
        let bias_instability =
            nonneg("gyro_bias_instability_deg_h", p.gyro_bias_instability_deg_h)?;
        let walk_time = positive("gyro_bias_walk_time_s", p.gyro_bias_walk_time_s)?;
        let accel_noise = nonneg("accel_noise_ug_rt_hz", p.accel_noise_ug_rt_hz)?;
        let accel_dynamic = nonneg("accel_dynamic_sigma_m_s2", p.accel_dynamic_sigma_m_s2)?;
        let turn_speed = nonneg("turn_speed_m_s", p.turn_speed_m_s)?;
        let turn_duration = nonneg("turn_duration_s", p.turn_duration_s)?;
        let accel_gate = positive("accel_gate_m_s2", p.accel_gate_m_s2)?;
        let heading_sigma = positive("mag_heading_sigma_deg", p.mag_heading_sigma_deg)?;
        let norm_gate = positive("mag_norm_gate", p.mag_norm_gate)?;
        let dip_gate = crate::params::in_range(
            "mag_dip_gate_deg",
            p.mag_dip_gate_deg,
            0.0,
            180.0,
            true,
            "(0, 180]",
        )?;
        let tilt_std = positive("initial_tilt_std_deg", p.initial_tilt_std_deg)?;
        let heading_std = positive("initial_heading_std_deg", p.initial_heading_std_deg)?;
        let bias_std = positive("initial_bias_std_deg_s", p.initial_bias_std_deg_s)?;
        // The gravity-direction noise must not vanish (S must stay invertible).
        if accel_noise == 0.0 && accel_dynamic == 0.0 {
            return Err(MekfParamsError::OutOfRange {
                name: "accel_noise_ug_rt_hz",
                value: 0.0,
                range: "> 0 when accel_dynamic_sigma_m_s2 is 0",
            });
        }
        let bias_instability_rad_s = bias_instability.to_radians() / 3600.0;
        Ok(Self {
            gyro_noise_rad_rt_s: gyro_noise.to_radians(),
            gyro_bias_instability_rad_s: bias_instability_rad_s,
            gyro_bias_walk_rad_s_rt_s: FLICKER_FLOOR_FACTOR
                * bias_instability_rad_s
                * (3.0 / walk_time).sqrt(),
            accel_noise_m_s2_rt_hz: accel_noise * 1e-6 * STANDARD_GRAVITY_M_S2,
            accel_dynamic_sigma_m_s2: accel_dynamic,
            turn_speed_m_s: turn_speed,
            turn_duration_s: turn_duration,
            accel_gate_m_s2: accel_gate,
            mag_heading_sigma_rad: heading_sigma.to_radians(),
            mag_norm_gate: norm_gate,
            mag_dip_gate_rad: dip_gate.to_radians(),
            initial_tilt_std_rad: tilt_std.to_radians(),
            initial_heading_std_rad: heading_std.to_radians(),
            initial_bias_std_rad_s: bias_std.to_radians(),
        })
    }
}

impl MekfConfig {
    /// Gyro white-noise density N (angle random walk), rad/√s.
    pub fn gyro_noise_rad_rt_s(&self) -> f64 {
        self.gyro_noise_rad_rt_s
    }

    /// Gyro bias instability B, rad/s.
    pub fn gyro_bias_instability_rad_s(&self) -> f64 {
        self.gyro_bias_instability_rad_s
    }

    /// Gyro bias random-walk coefficient σ_u, rad/s/√s.
    pub fn gyro_bias_walk_rad_s_rt_s(&self) -> f64 {
        self.gyro_bias_walk_rad_s_rt_s
    }

    /// Initial gyro bias 1σ per axis, rad/s.
    pub fn initial_bias_std_rad_s(&self) -> f64 {
        self.initial_bias_std_rad_s
    }
}
