//! The checks every input passes before the filter uses it (module docs
//! of [`super`], "Bad input"): an input that fails gets an
//! [`EstimatorError`] and the state is kept.

use super::AinsPfConfig;
use crate::ains::AinsInput;
use crate::role::EstimatorError;

fn err(kind: &'static str, detail: impl std::fmt::Display) -> EstimatorError {
    EstimatorError::new(kind, detail)
}

/// Checks `input` against the ranges of the module docs and `config`.
pub(super) fn check_input(config: &AinsPfConfig, input: &AinsInput) -> Result<(), EstimatorError> {
    let bad_lat =
        |lat: f64, lon: f64| !(lat.abs() <= std::f64::consts::FRAC_PI_2 && lon.is_finite());
    match input {
        AinsInput::Imu(m) => {
            if !(m.interval_s > 0.0 && m.interval_s <= 1.0) {
                return Err(err(
                    "imu-interval",
                    format!("IMU interval {} s is not in (0, 1]", m.interval_s),
                ));
            }
            if !(m.accel_m_s2.norm() <= 200.0 && m.gyro_rad_s.norm().is_finite()) {
                return Err(err(
                    "imu-out-of-range",
                    format!(
                        "specific force {} m/s², rate {} rad/s",
                        m.accel_m_s2.norm(),
                        m.gyro_rad_s.norm()
                    ),
                ));
            }
        }
        AinsInput::Dvl(d) => {
            let speed = d.velocity_body_m_s.norm();
            if d.bottom_lock && !(speed <= config.max_speed) {
                return Err(err(
                    "dvl-out-of-range",
                    format!(
                        "DVL speed {speed} m/s above max_speed_m_s = {}",
                        config.max_speed
                    ),
                ));
            }
        }
        AinsInput::Depth(d) => {
            if !(-10.0..=11_000.0).contains(&d.depth_m) {
                return Err(err(
                    "depth-out-of-range",
                    format!("depth {} m is not in [-10, 11000]", d.depth_m),
                ));
            }
        }
        AinsInput::Gps(g) => {
            if g.quality == 0 {
                return Err(err("gps-no-fix", "GPS fix of quality 0 (no fix)"));
            }
            if bad_lat(g.lat_rad, g.lon_rad) {
                return Err(err(
                    "gps-out-of-range",
                    format!("GPS latitude {} rad is not a latitude", g.lat_rad),
                ));
            }
            if !(g.horizontal_std_m >= 0.0 && g.horizontal_std_m.is_finite()) {
                return Err(err(
                    "gps-bad-std",
                    format!("GPS horizontal σ {} m", g.horizontal_std_m),
                ));
            }
            if let Some((v, s)) = &g.velocity
                && !(v.norm() <= config.max_speed && *s >= 0.0 && s.is_finite())
            {
                return Err(err(
                    "gps-bad-velocity",
                    format!("GPS velocity {v:?} m/s, σ {s} m/s"),
                ));
            }
        }
        AinsInput::Fix(f) => {
            if bad_lat(f.lat_rad, f.lon_rad) {
                return Err(err(
                    "fix-out-of-range",
                    format!("fix latitude {} rad is not a latitude", f.lat_rad),
                ));
            }
            if !(f.std_north_m >= 0.0
                && f.std_north_m.is_finite()
                && f.std_east_m >= 0.0
                && f.std_east_m.is_finite())
            {
                return Err(err(
                    "fix-bad-std",
                    format!("fix σ {} / {} m", f.std_north_m, f.std_east_m),
                ));
            }
        }
        AinsInput::Ahrs(a) => {
            if ![a.roll_rad, a.pitch_rad, a.heading_mag_rad]
                .iter()
                .all(|v| v.is_finite())
                || a.pitch_rad.abs() > std::f64::consts::FRAC_PI_2
            {
                return Err(err("ahrs-out-of-range", format!("{a:?}")));
            }
        }
        AinsInput::Attitude(_) => {}
    }
    Ok(())
}
