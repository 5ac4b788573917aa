//! The world the vehicle moves in: WGS84 Earth (gravity, Earth rotation, from
//! [`nauta_estimation::earth`]), the local geomagnetic field from the NOAA World
//! Magnetic Model, the speed of sound in sea water and the water current.
//!
//! Everything here is a pure function of its inputs (position, depth, time); the
//! only random choice (the phase of the current's slow variation) is made by the
//! caller, e.g. [`crate::trajectory::Simulator`] from its seed.
//!
//! Units: SI inside (m, s, rad, m/s, m/s², tesla); the magnetic field is also
//! offered in µT ([`MagneticField::ned_ut`]) because that is how the WMM and
//! datasheets quote it.

use nalgebra::Vector3;
use thiserror::Error;

use nauta_estimation::magnetic::{WmmError, wmm};

pub use nauta_estimation::earth::{
    earth_rate_ned, meridian_radius, normal_gravity, transport_rate_ned, transverse_radius, wgs84,
};

/// Why an environment could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EnvironmentError {
    /// The date does not exist (e.g. day 366 of a common year).
    #[error("invalid date: year {year}, day of year {day_of_year}")]
    InvalidDate {
        /// Calendar year.
        year: i32,
        /// Day of the year, 1-based.
        day_of_year: u16,
    },
    /// The World Magnetic Model refused the query (date outside 2020-2029, height
    /// outside -1 km … 850 km, bad latitude or longitude).
    #[error("world magnetic model: {0}")]
    Wmm(String),
    /// A configuration value is NaN, infinite or out of its range.
    #[error("invalid environment parameter {name}: {value}")]
    Invalid {
        /// Which parameter.
        name: &'static str,
        /// Its value.
        value: f64,
    },
}

fn check(name: &'static str, value: f64, ok: bool) -> Result<(), EnvironmentError> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(EnvironmentError::Invalid { name, value })
    }
}

/// Gravity vector in NED, `[0, 0, γ(L, h)]`, m/s²: WGS84 normal gravity
/// ([`normal_gravity`], Somigliana with free-air correction), gravitation plus the
/// centripetal acceleration of the Earth's rotation.
pub fn gravity_ned(lat_rad: f64, height_m: f64) -> Vector3<f64> {
    Vector3::new(0.0, 0.0, normal_gravity(lat_rad, height_m))
}

// ---------------------------------------------------------------------------
// Magnetic field
// ---------------------------------------------------------------------------

/// The geomagnetic (main, core) field at one place and date, from the NOAA World
/// Magnetic Model ([`nauta_estimation::magnetic`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagneticField {
    /// Field in NED (north X, east Y, down Z), tesla.
    pub ned_t: Vector3<f64>,
    /// Declination (east of true north positive), rad.
    pub declination_rad: f64,
    /// Inclination (dip, below the horizontal positive), rad.
    pub inclination_rad: f64,
}

impl MagneticField {
    /// Evaluates the WMM at geodetic latitude/longitude (rad), height above the
    /// WGS84 ellipsoid (m; a depth `d` is `-d`) on day `day_of_year` (1-based) of
    /// `year`.
    pub fn from_wmm(
        lat_rad: f64,
        lon_rad: f64,
        height_m: f64,
        year: i32,
        day_of_year: u16,
    ) -> Result<Self, EnvironmentError> {
        check(
            "lat_rad",
            lat_rad,
            lat_rad.abs() <= std::f64::consts::FRAC_PI_2,
        )?;
        check("lon_rad", lon_rad, true)?;
        check("height_m", height_m, true)?;
        let f = wmm(lat_rad, lon_rad, height_m, year, day_of_year).map_err(|e| match e {
            WmmError::InvalidDate { year, day_of_year } => {
                EnvironmentError::InvalidDate { year, day_of_year }
            }
            e => EnvironmentError::Wmm(e.to_string()),
        })?;
        Ok(Self {
            ned_t: Vector3::from(f.ned_t),
            declination_rad: f.declination_rad,
            inclination_rad: f.inclination_rad,
        })
    }

    /// A field given directly: total intensity (T), declination and inclination (rad).
    pub fn from_angles(total_t: f64, declination_rad: f64, inclination_rad: f64) -> Self {
        let h = total_t * inclination_rad.cos();
        Self {
            ned_t: Vector3::new(
                h * declination_rad.cos(),
                h * declination_rad.sin(),
                total_t * inclination_rad.sin(),
            ),
            declination_rad,
            inclination_rad,
        }
    }

    /// Field in NED, µT.
    pub fn ned_ut(&self) -> Vector3<f64> {
        self.ned_t * 1e6
    }

    /// Total intensity, T.
    pub fn total_t(&self) -> f64 {
        self.ned_t.norm()
    }
}

// ---------------------------------------------------------------------------
// Sea water
// ---------------------------------------------------------------------------

/// Speed of sound in sea water, m/s, by Mackenzie's nine-term equation
/// (K. V. Mackenzie 1981, "Nine-term equation for sound speed in the oceans",
/// J. Acoust. Soc. Am. 70(3):807-812), valid for 2-30 °C, 25-40 ‰ and 0-8000 m:
///
/// ```text
/// c = 1448.96 + 4.591 T - 5.304e-2 T² + 2.374e-4 T³ + 1.340 (S - 35)
///     + 1.630e-2 D + 1.675e-7 D² - 1.025e-2 T (S - 35) - 7.139e-13 T D³
/// ```
///
/// `T` in °C, `S` in practical salinity units (‰), `D` depth in m. Standard
/// error 0.07 m/s. Mackenzie's check value: 1550.744 m/s at 25 °C, 35 ‰, 1000 m.
pub fn mackenzie_sound_speed(temperature_c: f64, salinity_psu: f64, depth_m: f64) -> f64 {
    let t = temperature_c;
    let s = salinity_psu - 35.0;
    let d = depth_m;
    1448.96 + 4.591 * t - 5.304e-2 * t * t
        + 2.374e-4 * t * t * t
        + 1.340 * s
        + 1.630e-2 * d
        + 1.675e-7 * d * d
        - 1.025e-2 * t * s
        - 7.139e-13 * t * d * d * d
}

/// The water column: uniform temperature and salinity (our simplification; a
/// shallow coastal AUV mission spans tens of metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Water {
    /// Temperature, °C (default 15 °C, a temperate coastal value; our choice).
    pub temperature_c: f64,
    /// Practical salinity (default 35.5, the open Atlantic off Portugal; our choice).
    pub salinity_psu: f64,
}

impl Default for Water {
    fn default() -> Self {
        Self {
            temperature_c: 15.0,
            salinity_psu: 35.5,
        }
    }
}

impl Water {
    /// Speed of sound at `depth_m`, m/s ([`mackenzie_sound_speed`]).
    pub fn sound_speed_m_s(&self, depth_m: f64) -> f64 {
        mackenzie_sound_speed(self.temperature_c, self.salinity_psu, depth_m.max(0.0))
    }
}

/// Water current, NED, m/s: a constant plus a slow sinusoidal variation,
/// `c(t) = mean + amplitude · sin(2π t / period + phase)`, componentwise with one
/// shared phase (a tidal or inertial oscillation; the form is our choice). The
/// down component is normally zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Current {
    /// Mean current, NED, m/s.
    pub mean_ned_m_s: Vector3<f64>,
    /// Amplitude of the variation, NED, m/s.
    pub amplitude_ned_m_s: Vector3<f64>,
    /// Period of the variation, s (must be positive).
    pub period_s: f64,
    /// Phase of the variation at `t = 0`, rad.
    pub phase_rad: f64,
}

impl Default for Current {
    /// Still water.
    fn default() -> Self {
        Self::none()
    }
}

impl Current {
    /// No current.
    pub fn none() -> Self {
        Self {
            mean_ned_m_s: Vector3::zeros(),
            amplitude_ned_m_s: Vector3::zeros(),
            period_s: 3600.0,
            phase_rad: 0.0,
        }
    }

    /// The LBL scenario's current (DESIGN §10: 0.1-0.3 m/s): 0.2 m/s mean towards
    /// north-east plus 0.05 m/s varying over 30 minutes (our choice).
    pub fn lbl_default() -> Self {
        let c = 0.2 * std::f64::consts::FRAC_1_SQRT_2;
        Self {
            mean_ned_m_s: Vector3::new(c, c, 0.0),
            amplitude_ned_m_s: Vector3::new(0.05, -0.03, 0.0),
            period_s: 1800.0,
            phase_rad: 0.0,
        }
    }

    /// Checks that every number is finite and the period positive.
    pub fn validate(&self) -> Result<(), EnvironmentError> {
        for v in self.mean_ned_m_s.iter() {
            check("current.mean", *v, true)?;
        }
        for v in self.amplitude_ned_m_s.iter() {
            check("current.amplitude", *v, true)?;
        }
        check("current.period_s", self.period_s, self.period_s > 0.0)?;
        check("current.phase_rad", self.phase_rad, true)
    }

    /// Current at time `t_s`, NED, m/s.
    pub fn at(&self, t_s: f64) -> Vector3<f64> {
        let arg = std::f64::consts::TAU * t_s / self.period_s + self.phase_rad;
        self.mean_ned_m_s + self.amplitude_ned_m_s * arg.sin()
    }
}

/// The environment of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Environment {
    /// Local geomagnetic field, held constant over the mission area (over 10 km
    /// the WMM field changes by a few tens of nT, 0.1 % of its magnitude, well
    /// inside the model's own uncertainty).
    pub magnetic: MagneticField,
    /// Water column properties.
    pub water: Water,
    /// Water current.
    pub current: Current,
}

impl Environment {
    /// Still water, default water properties, the WMM field at the given place
    /// (rad, m) and date.
    pub fn at(
        lat_rad: f64,
        lon_rad: f64,
        year: i32,
        day_of_year: u16,
    ) -> Result<Self, EnvironmentError> {
        Ok(Self {
            magnetic: MagneticField::from_wmm(lat_rad, lon_rad, 0.0, year, day_of_year)?,
            water: Water::default(),
            current: Current::none(),
        })
    }

    /// Gravity in NED, m/s² ([`gravity_ned`]).
    pub fn gravity_ned(&self, lat_rad: f64, height_m: f64) -> Vector3<f64> {
        gravity_ned(lat_rad, height_m)
    }

    /// Earth rotation in NED, rad/s ([`earth_rate_ned`]).
    pub fn earth_rate_ned(&self, lat_rad: f64) -> Vector3<f64> {
        earth_rate_ned(lat_rad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lisbon area (38.6° N, 9.3° W), mid-2026: the WMM gives a small westerly
    /// declination, a dip in the low fifties and ~43-44 µT.
    #[test]
    fn wmm_lisbon_2026() {
        let f =
            MagneticField::from_wmm(38.6f64.to_radians(), (-9.3f64).to_radians(), 0.0, 2026, 182)
                .expect("valid query");
        let dec = f.declination_rad.to_degrees();
        let inc = f.inclination_rad.to_degrees();
        let total_ut = f.total_t() * 1e6;
        eprintln!(
            "Lisbon 2026: declination {dec:.3}°, inclination {inc:.3}°, F {total_ut:.3} µT, NED {:?} µT",
            f.ned_ut()
        );
        assert!((-2.0..=0.0).contains(&dec), "{dec}");
        assert!((51.5..=54.5).contains(&inc), "{inc}");
        assert!((42.5..=44.5).contains(&total_ut), "{total_ut}");
        // The NED vector agrees with the angles the crate reports.
        let n = f.ned_t;
        assert!((n.y.atan2(n.x) - f.declination_rad).abs() < 1e-5);
        assert!((n.z.atan2(n.x.hypot(n.y)) - f.inclination_rad).abs() < 1e-5);
        // from_angles rebuilds the same vector.
        let g = MagneticField::from_angles(f.total_t(), f.declination_rad, f.inclination_rad);
        assert!((g.ned_t - f.ned_t).norm() < 1e-10);
    }

    #[test]
    fn wmm_refuses_bad_queries() {
        assert!(matches!(
            MagneticField::from_wmm(0.5, 0.1, 0.0, 2026, 400),
            Err(EnvironmentError::InvalidDate { .. })
        ));
        assert!(matches!(
            MagneticField::from_wmm(0.5, 0.1, 0.0, 2040, 10),
            Err(EnvironmentError::Wmm(_))
        ));
        assert!(MagneticField::from_wmm(f64::NAN, 0.1, 0.0, 2026, 10).is_err());
    }

    #[test]
    fn mackenzie_check_value() {
        assert!((mackenzie_sound_speed(25.0, 35.0, 1000.0) - 1550.744).abs() < 1e-3);
        let c = Water::default().sound_speed_m_s(15.0);
        assert!((1500.0..1515.0).contains(&c), "{c}");
    }

    #[test]
    fn current_is_mean_plus_sinusoid() {
        let c = Current {
            mean_ned_m_s: Vector3::new(0.1, 0.2, 0.0),
            amplitude_ned_m_s: Vector3::new(0.05, 0.0, 0.0),
            period_s: 100.0,
            phase_rad: 0.0,
        };
        assert!(c.validate().is_ok());
        assert!((c.at(0.0) - c.mean_ned_m_s).norm() < 1e-15);
        assert!((c.at(25.0).x - 0.15).abs() < 1e-12);
        assert!((c.at(75.0).x - 0.05).abs() < 1e-12);
        let bad = Current {
            period_s: 0.0,
            ..Current::none()
        };
        assert!(bad.validate().is_err());
        let lbl = Current::lbl_default().at(0.0).norm();
        assert!((0.1..=0.3).contains(&lbl));
    }

    #[test]
    fn gravity_and_earth_rate_are_the_estimation_crates() {
        let g = gravity_ned(0.67, -15.0);
        assert_eq!(g.z, normal_gravity(0.67, -15.0));
        assert!((earth_rate_ned(0.0).norm() - wgs84::OMEGA_IE_RAD_S).abs() < 1e-18);
    }
}
