//! The checks of an input before the filter sees it (module docs of
//! [`super`], "Bad input"): an input that fails is refused with an
//! [`EstimatorError`] and the state is kept. The IMU sample is checked by
//! the strapdown itself.

use super::{Ekf, err};
use crate::ains::AinsInput;
use crate::role::EstimatorError;
use crate::strapdown::MAX_ABS_LATITUDE_RAD;

impl Ekf {
    /// Refuses an input the filter cannot use.
    pub(super) fn validate(&self, input: &AinsInput) -> Result<(), EstimatorError> {
        let lat_ok = |l: f64| l.abs() <= MAX_ABS_LATITUDE_RAD;
        match input {
            AinsInput::Imu(_) => {} // the strapdown checks it
            AinsInput::Dvl(d) => {
                let speed = d.velocity_body_m_s.norm();
                if d.bottom_lock && !(speed <= self.config.max_speed_m_s) {
                    return Err(err(
                        "dvl-out-of-range",
                        format!(
                            "DVL speed {speed} m/s above max_speed_m_s = {}",
                            self.config.max_speed_m_s
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
                if !(lat_ok(g.lat_rad) && g.lon_rad.is_finite()) {
                    return Err(err(
                        "gps-out-of-range",
                        format!("GPS latitude {} rad is beyond ±89°", g.lat_rad),
                    ));
                }
                if !(g.horizontal_std_m >= 0.0 && g.horizontal_std_m.is_finite()) {
                    return Err(err(
                        "gps-bad-std",
                        format!("GPS horizontal σ {} m", g.horizontal_std_m),
                    ));
                }
                if let Some((v, s)) = &g.velocity
                    && !(v.is_finite() && *s > 0.0 && s.is_finite() && v.norm() <= 100.0)
                {
                    return Err(err("gps-bad-velocity", format!("GPS velocity {v:?} σ {s}")));
                }
            }
            AinsInput::Fix(x) => {
                if !(lat_ok(x.lat_rad)
                    && x.lon_rad.is_finite()
                    && x.std_north_m > 0.0
                    && x.std_north_m.is_finite()
                    && x.std_east_m > 0.0
                    && x.std_east_m.is_finite()
                    && x.corr_ne.abs() < 1.0)
                {
                    return Err(err("fix-out-of-range", format!("{x:?}")));
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
            AinsInput::Attitude(a) => {
                if !(a.std_rad.is_finite() && a.std_rad.iter().all(|s| *s >= 0.0)) {
                    return Err(err("attitude-bad-std", format!("{:?}", a.std_rad)));
                }
            }
        }
        Ok(())
    }
}
