//! The `ekf` variant's parameters as a manifest writes them
//! (`[process.ains.variants.ekf]`, every field defaulted, unknown keys
//! refused) and their check.
//!
//! The sensor figures default to the simulator's survey suite (an Xsens
//! MTi-30 class IMU, a Workhorse-class DVL, a pressure gauge, a stand-alone
//! GPS; `nauta_sim::suite::SuiteConfig::survey`), which is what the
//! vehicle carries; a manifest for other sensors sets them.

use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;

use crate::params::{OutOfRange, in_range, nonneg, positive};

/// Parameters of the error-state Kalman filter.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EkfParams {
    /// Use `positioning/fix` position fixes. Default true; false is paper
    /// 000's "DVL-aided INS" (GPS at the surface is still used).
    pub position_aiding: bool,
    /// Gyro white noise (angle random walk), rad/√s. Default 5.2e-4
    /// (0.03 °/s/√Hz, MTi-30 class).
    pub gyro_noise_rad_s_rt_s: f64,
    /// Accelerometer white noise (velocity random walk), m/s/√s. Default
    /// 7.8e-4 (80 µg/√Hz).
    pub accel_noise_m_s2_rt_s: f64,
    /// Gyro bias random walk, rad/s/√s. Default 1e-5 (an 18 °/h bias
    /// instability over about 150 s; our choice).
    pub gyro_bias_walk_rad_s_rt_s: f64,
    /// Accelerometer bias random walk, m/s²/√s. Default 5e-5 (40 µg over
    /// about 120 s; our choice).
    pub accel_bias_walk_m_s2_rt_s: f64,
    /// Initial gyro bias σ per axis, rad/s. Default 3.5e-3 (0.2 °/s turn-on
    /// bias).
    pub initial_gyro_bias_std_rad_s: f64,
    /// Initial accelerometer bias σ per axis, m/s². Default 0.03.
    pub initial_accel_bias_std_m_s2: f64,
    /// Initial velocity σ per axis, m/s (the filter starts at rest).
    /// Default 0.5.
    pub initial_velocity_std_m_s: f64,
    /// Without a first position (no GPS fix, no `positioning/fix`), the
    /// filter starts at the site's position this long after the first IMU
    /// sample with a heading, s (a GPS that never comes, a launch
    /// submerged). Default 30 (our choice: a surfaced receiver gives a fix
    /// within seconds).
    pub position_wait_s: f64,
    /// Initial σ north and east when started at the site, m. Default 1000
    /// (as `dr`).
    pub initial_position_std_m: f64,
    /// The surfacing advisory ([`crate::ains::advisory::SURFACE`], and the
    /// shell's `surfacing_advised` run event) is raised while
    /// `predicted_drift_m`, the covariance's horizontal RMS, is above this,
    /// m. Default 50 (as `dr`'s predictor).
    pub surfacing_threshold_m: f64,
    /// Initial roll and pitch σ when the AHRS initialises the attitude,
    /// rad. Default 0.0087 (0.5°).
    pub initial_tilt_std_rad: f64,
    /// The heading source's slowly varying error (magnetic disturbance,
    /// the attitude filter's own drift): a first-order Gauss-Markov state
    /// of this stationary σ, rad. Default 0.035 (2°).
    pub heading_bias_std_rad: f64,
    /// ... and this correlation time, s. Default 600.
    pub heading_bias_time_s: f64,
    /// The stationary σ of that state while the attitude estimate is the
    /// heading source, rad. Default 0.0052 (0.3°, our choice: the
    /// attitude role's `mekf` with a calibrated magnetometer publishes a
    /// yaw σ of about 0.1° on the survey, and its realised error is
    /// correlated over minutes and at times twice that).
    pub attitude_heading_bias_std_rad: f64,
    /// ... and its correlation time, s. Default 300 (our choice).
    pub attitude_heading_bias_time_s: f64,
    /// The heading source's one-cycle deviation (a residual hard iron):
    /// prior σ of each coefficient, rad. Default 0.0052 (0.3°, our choice:
    /// a compass calibrated to a few tenths of a degree).
    pub heading_deviation_std_rad: f64,
    /// White noise of the AHRS heading, rad. Default 0.0175 (1°).
    pub ahrs_heading_std_rad: f64,
    /// Smallest white noise σ of the attitude estimate's yaw, rad (its
    /// published σ is used when larger). Default 0.0017 (0.1°).
    pub attitude_heading_std_floor_rad: f64,
    /// The heading source's error in a manoeuvre, rad of heading per rad
    /// of the manoeuvre's tilt angle `|ω × v| / g` (held and falling over
    /// `heading_manoeuvre_time_s`), added in quadrature to the white σ,
    /// times the headings used within that time (the error is one bias
    /// over the manoeuvre, [`crate::ains::manoeuvre_var`]). An
    /// attitude filter or AHRS that takes the accelerometer for gravity
    /// tilts by about that angle in a turn (the centripetal acceleration),
    /// and its magnetic heading, tilt-compensated with the wrong tilt,
    /// errs by about `tan(inclination)` times that; the error outlasts the
    /// turn by as long as the filter takes to recover. Default 1.0 (the
    /// attitude role's `pf` on the survey, seed 7: 1.1° of roll and 1.2°
    /// of yaw error in 10°/s turns at 1.5 m/s, a tilt angle of 1.5°, while
    /// its published σ stays 0.1-0.14°; our choice). 0 leaves it out.
    pub heading_manoeuvre_factor: f64,
    /// The squared angle is held at its peak and falls with this time
    /// constant, s: how long the source's error outlasts the manoeuvre
    /// ([`crate::ains::Manoeuvre`]). Default 3 (as the `pf`'s
    /// `attitude_manoeuvre_time_s`: the attitude `pf`'s yaw error falls
    /// from 1.2° to 0.2° in the 8 s after a turn on the survey, seed 7;
    /// the `ekf`'s velocity RMS there is within 0.0002 m/s of each other
    /// with 3, 5 and 10 s).
    pub heading_manoeuvre_time_s: f64,
    /// A heading measurement is used at most once per this interval, s
    /// (the measurement's error is correlated: more frequent updates would
    /// only add weight). Default 1.
    pub heading_interval_s: f64,
    /// DVL velocity noise σ per axis, m/s. Default 0.012 (0.01 white plus
    /// the scale factor's 0.2 % at 1.5 m/s, our choice).
    pub dvl_std_m_s: f64,
    /// DVL position in the body (FRD) from the IMU, m. Default zero.
    pub dvl_lever_arm_m: [f64; 3],
    /// The DVL's axes in the body as roll, pitch, yaw (ZYX) of the DVL
    /// frame relative to FRD, rad. Default zero (identity).
    pub dvl_misalignment_rad: [f64; 3],
    /// A locked DVL speed above this is refused as bad input, m/s.
    /// Default 10.
    pub max_speed_m_s: f64,
    /// Depth gauge noise σ, m. Default 0.03.
    pub depth_std_m: f64,
    /// Tare: a depth reading is a surface reading when a GPS fix came
    /// within this, s. Default 1.5.
    pub surface_window_s: f64,
    /// ... and the vertical speed is below this, m/s. Default 0.05.
    pub tare_max_vertical_speed_m_s: f64,
    /// Surface readings the tare averages. Default 20.
    pub tare_samples: u64,
    /// Smallest GPS horizontal σ per axis used, m (the published one when
    /// larger). Default 1.
    pub gps_std_floor_m: f64,
    /// Normalised-innovation gates (χ² quantiles) for measurements of 1,
    /// 2 and 3 dimensions. Default 99.9 %: 10.83, 13.82, 16.27.
    pub gate_chi2: [f64; 3],
    /// After this many consecutive rejections of one kind the next
    /// measurement of that kind re-anchors the filter (resets that part of
    /// the state and covariance to it). Default 10.
    pub max_consecutive_rejections: u32,
    /// An aiding kind counts in `aiding_mode` while its last used
    /// measurement is at most this old, s. Default 1.5.
    pub aiding_timeout_s: f64,
    /// The covariance is propagated every this many IMU samples with the
    /// block's mean transition (and before every measurement). Default 10.
    pub covariance_decimation: u32,
}

impl Default for EkfParams {
    fn default() -> Self {
        Self {
            position_aiding: true,
            gyro_noise_rad_s_rt_s: 5.2e-4,
            accel_noise_m_s2_rt_s: 7.8e-4,
            gyro_bias_walk_rad_s_rt_s: 1e-5,
            accel_bias_walk_m_s2_rt_s: 5e-5,
            initial_gyro_bias_std_rad_s: 3.5e-3,
            initial_accel_bias_std_m_s2: 0.03,
            initial_velocity_std_m_s: 0.5,
            position_wait_s: 30.0,
            initial_position_std_m: 1000.0,
            surfacing_threshold_m: 50.0,
            initial_tilt_std_rad: 0.0087,
            heading_bias_std_rad: 0.035,
            heading_bias_time_s: 600.0,
            attitude_heading_bias_std_rad: 0.0052,
            attitude_heading_bias_time_s: 300.0,
            heading_deviation_std_rad: 0.0052,
            ahrs_heading_std_rad: 0.0175,
            attitude_heading_std_floor_rad: 0.0017,
            heading_manoeuvre_factor: 1.0,
            heading_manoeuvre_time_s: 3.0,
            heading_interval_s: 1.0,
            dvl_std_m_s: 0.012,
            dvl_lever_arm_m: [0.0; 3],
            dvl_misalignment_rad: [0.0; 3],
            max_speed_m_s: 10.0,
            depth_std_m: 0.03,
            surface_window_s: 1.5,
            tare_max_vertical_speed_m_s: 0.05,
            tare_samples: 20,
            gps_std_floor_m: 1.0,
            gate_chi2: [10.83, 13.82, 16.27],
            max_consecutive_rejections: 10,
            aiding_timeout_s: 1.5,
            covariance_decimation: 10,
        }
    }
}

/// Why [`EkfParams`] cannot be used.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum EkfParamsError {
    /// A value is NaN, infinite or outside its range.
    #[error("ekf parameter {name} = {value} is out of range ({range})")]
    OutOfRange {
        /// The field's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range, in words.
        range: &'static str,
    },
}

impl From<OutOfRange> for EkfParamsError {
    fn from(e: OutOfRange) -> Self {
        Self::OutOfRange {
            name: e.name,
            value: e.value,
            range: e.range,
        }
    }
}

/// The checked parameters, SI units, ns for time windows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EkfConfig {
    pub(super) position_aiding: bool,
    pub(super) gyro_noise: f64,
    pub(super) accel_noise: f64,
    pub(super) gyro_bias_walk: f64,
    pub(super) accel_bias_walk: f64,
    pub(super) initial_gyro_bias_std: f64,
    pub(super) initial_accel_bias_std: f64,
    pub(super) initial_velocity_std: f64,
    pub(super) position_wait_ns: u64,
    pub(super) initial_position_std: f64,
    pub(super) surfacing_threshold: f64,
    pub(super) initial_tilt_std: f64,
    pub(super) heading_bias_std: f64,
    pub(super) heading_bias_time_s: f64,
    pub(super) attitude_heading_bias_std: f64,
    pub(super) attitude_heading_bias_time_s: f64,
    pub(super) heading_deviation_std: f64,
    pub(super) ahrs_heading_std: f64,
    pub(super) attitude_heading_std_floor: f64,
    pub(super) heading_manoeuvre_factor: f64,
    pub(super) heading_manoeuvre_time_s: f64,
    pub(super) heading_interval_ns: u64,
    pub(super) dvl_std: f64,
    pub(super) dvl_lever_arm: Vector3<f64>,
    /// DVL frame → body.
    pub(super) dvl_to_body: Matrix3<f64>,
    pub(super) max_speed_m_s: f64,
    pub(super) depth_std: f64,
    pub(super) surface_window_ns: u64,
    pub(super) tare_max_vertical_speed_m_s: f64,
    pub(super) tare_samples: u64,
    pub(super) gps_std_floor: f64,
    pub(super) gate_chi2: [f64; 3],
    pub(super) max_consecutive_rejections: u32,
    pub(super) aiding_timeout_ns: u64,
    pub(super) covariance_decimation: u32,
}

fn ns(s: f64) -> u64 {
    (s * 1e9).round() as u64
}

fn count(
    name: &'static str,
    v: u64,
    lo: u64,
    hi: u64,
    range: &'static str,
) -> Result<u64, EkfParamsError> {
    if (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(EkfParamsError::OutOfRange {
            name,
            value: v as f64,
            range,
        })
    }
}

impl EkfParams {
    /// The checked configuration; a bad value is refused by name.
    pub fn validate(&self) -> Result<EkfConfig, EkfParamsError> {
        let day = 86_400.0;
        let angle = |name, v| in_range(name, v, 0.0, 1.0, true, "(0, 1] rad");
        for (name, v) in [
            ("dvl_lever_arm_m", self.dvl_lever_arm_m),
            ("dvl_misalignment_rad", self.dvl_misalignment_rad),
        ] {
            for x in v {
                in_range(name, x, -10.0, 10.0, false, "[-10, 10] per component")?;
            }
        }
        let [r, p, y] = self.dvl_misalignment_rad;
        let dvl_to_body = crate::attitude::from_euler(r, p, y)
            .to_rotation_matrix()
            .into_inner();
        let mut gate = [0.0; 3];
        for (g, v) in gate.iter_mut().zip(self.gate_chi2) {
            *g = positive("gate_chi2", v)?;
        }
        Ok(EkfConfig {
            position_aiding: self.position_aiding,
            gyro_noise: positive("gyro_noise_rad_s_rt_s", self.gyro_noise_rad_s_rt_s)?,
            accel_noise: positive("accel_noise_m_s2_rt_s", self.accel_noise_m_s2_rt_s)?,
            gyro_bias_walk: nonneg("gyro_bias_walk_rad_s_rt_s", self.gyro_bias_walk_rad_s_rt_s)?,
            accel_bias_walk: nonneg("accel_bias_walk_m_s2_rt_s", self.accel_bias_walk_m_s2_rt_s)?,
            initial_gyro_bias_std: nonneg(
                "initial_gyro_bias_std_rad_s",
                self.initial_gyro_bias_std_rad_s,
            )?,
            initial_accel_bias_std: nonneg(
                "initial_accel_bias_std_m_s2",
                self.initial_accel_bias_std_m_s2,
            )?,
            initial_velocity_std: positive(
                "initial_velocity_std_m_s",
                self.initial_velocity_std_m_s,
            )?,
            position_wait_ns: ns(in_range(
                "position_wait_s",
                self.position_wait_s,
                0.0,
                day,
                false,
                "[0, 86400]",
            )?),
            initial_position_std: in_range(
                "initial_position_std_m",
                self.initial_position_std_m,
                0.0,
                1e6,
                true,
                "(0, 1e6]",
            )?,
            surfacing_threshold: in_range(
                "surfacing_threshold_m",
                self.surfacing_threshold_m,
                0.0,
                1e7,
                true,
                "(0, 1e7]",
            )?,
            initial_tilt_std: angle("initial_tilt_std_rad", self.initial_tilt_std_rad)?,
            heading_bias_std: in_range(
                "heading_bias_std_rad",
                self.heading_bias_std_rad,
                0.0,
                1.0,
                false,
                "[0, 1] rad",
            )?,
            heading_bias_time_s: in_range(
                "heading_bias_time_s",
                self.heading_bias_time_s,
                0.0,
                f64::INFINITY,
                true,
                "(0, inf] s",
            )?,
            attitude_heading_bias_std: in_range(
                "attitude_heading_bias_std_rad",
                self.attitude_heading_bias_std_rad,
                0.0,
                1.0,
                false,
                "[0, 1] rad",
            )?,
            attitude_heading_bias_time_s: in_range(
                "attitude_heading_bias_time_s",
                self.attitude_heading_bias_time_s,
                0.0,
                f64::INFINITY,
                true,
                "(0, inf] s",
            )?,
            heading_deviation_std: in_range(
                "heading_deviation_std_rad",
                self.heading_deviation_std_rad,
                0.0,
                1.0,
                false,
                "[0, 1] rad",
            )?,
            ahrs_heading_std: angle("ahrs_heading_std_rad", self.ahrs_heading_std_rad)?,
            attitude_heading_std_floor: angle(
                "attitude_heading_std_floor_rad",
                self.attitude_heading_std_floor_rad,
            )?,
            heading_manoeuvre_factor: in_range(
                "heading_manoeuvre_factor",
                self.heading_manoeuvre_factor,
                0.0,
                100.0,
                false,
                "[0, 100]",
            )?,
            heading_manoeuvre_time_s: in_range(
                "heading_manoeuvre_time_s",
                self.heading_manoeuvre_time_s,
                0.0,
                day,
                true,
                "(0, 86400] s",
            )?,
            heading_interval_ns: ns(in_range(
                "heading_interval_s",
                self.heading_interval_s,
                0.0,
                day,
                false,
                "[0, 86400] s",
            )?),
            dvl_std: positive("dvl_std_m_s", self.dvl_std_m_s)?,
            dvl_lever_arm: Vector3::from(self.dvl_lever_arm_m),
            dvl_to_body,
            max_speed_m_s: in_range(
                "max_speed_m_s",
                self.max_speed_m_s,
                0.0,
                100.0,
                true,
                "(0, 100]",
            )?,
            depth_std: positive("depth_std_m", self.depth_std_m)?,
            surface_window_ns: ns(in_range(
                "surface_window_s",
                self.surface_window_s,
                0.0,
                day,
                false,
                "[0, 86400] s",
            )?),
            tare_max_vertical_speed_m_s: in_range(
                "tare_max_vertical_speed_m_s",
                self.tare_max_vertical_speed_m_s,
                0.0,
                10.0,
                false,
                "[0, 10]",
            )?,
            tare_samples: count(
                "tare_samples",
                self.tare_samples,
                1,
                1_000_000,
                "[1, 1000000]",
            )?,
            gps_std_floor: positive("gps_std_floor_m", self.gps_std_floor_m)?,
            gate_chi2: gate,
            max_consecutive_rejections: count(
                "max_consecutive_rejections",
                self.max_consecutive_rejections as u64,
                0,
                1_000_000,
                "[0, 1000000]",
            )? as u32,
            aiding_timeout_ns: ns(in_range(
                "aiding_timeout_s",
                self.aiding_timeout_s,
                0.0,
                day,
                true,
                "(0, 86400] s",
            )?),
            covariance_decimation: count(
                "covariance_decimation",
                self.covariance_decimation as u64,
                1,
                1000,
                "[1, 1000]",
            )? as u32,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_parse_and_bad_values_are_refused_by_name() {
        let p: EkfParams = toml::from_str("").expect("defaults");
        assert_eq!(p, EkfParams::default());
        assert!(p.validate().is_ok());
        let p: EkfParams =
            toml::from_str("position_aiding = false\ndvl_lever_arm_m = [0.5, 0.0, 0.2]")
                .expect("valid");
        assert!(!p.position_aiding);
        assert_eq!(p.dvl_lever_arm_m, [0.5, 0.0, 0.2]);
        assert!(toml::from_str::<EkfParams>("nope = 1").is_err());
        for (p, name) in [
            (
                EkfParams {
                    dvl_std_m_s: f64::NAN,
                    ..Default::default()
                },
                "dvl_std_m_s",
            ),
            (
                EkfParams {
                    covariance_decimation: 0,
                    ..Default::default()
                },
                "covariance_decimation",
            ),
            (
                EkfParams {
                    heading_manoeuvre_time_s: 0.0,
                    ..Default::default()
                },
                "heading_manoeuvre_time_s",
            ),
            (
                EkfParams {
                    gate_chi2: [1.0, -1.0, 1.0],
                    ..Default::default()
                },
                "gate_chi2",
            ),
            (
                EkfParams {
                    dvl_misalignment_rad: [0.0, f64::INFINITY, 0.0],
                    ..Default::default()
                },
                "dvl_misalignment_rad",
            ),
        ] {
            match p.validate() {
                Err(EkfParamsError::OutOfRange { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{name}: {other:?}"),
            }
        }
        let e = EkfParams {
            heading_bias_time_s: 0.0,
            ..Default::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("heading_bias_time_s"), "{e}");
    }
}
