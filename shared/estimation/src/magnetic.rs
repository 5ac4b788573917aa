//! The main geomagnetic field from the NOAA World Magnetic Model (WMM2025
//! for 2025-2029, WMM2020 before) through the `world_magnetic_model` crate
//! (Chulliat et al. 2025, "The US/UK World Magnetic Model for 2025-2030",
//! NOAA NCEI technical report): the simulator's field, and the declination
//! an estimator takes when its manifest gives none (issue 13: "the site's
//! declination, from the manifest, else the WMM").
//!
//! The crate evaluates the model in `f32`; the model's own accuracy (about
//! 0.3-0.4° in declination and 150 nT in intensity, 1σ) is far coarser.
//! Crustal anomalies and disturbances are not modelled.

use thiserror::Error;
use world_magnetic_model::GeomagneticField;
use world_magnetic_model::time::Date;
use world_magnetic_model::uom::si::angle::{degree, radian};
use world_magnetic_model::uom::si::f32::{Angle, Length};
use world_magnetic_model::uom::si::length::meter;
use world_magnetic_model::uom::si::magnetic_flux_density::nanotesla;

/// The model's field at one place and date.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geomagnetic {
    /// Field in NED (north X, east Y, down Z), tesla.
    pub ned_t: [f64; 3],
    /// Declination (east of true north positive), rad.
    pub declination_rad: f64,
    /// Inclination (dip, below the horizontal positive), rad.
    pub inclination_rad: f64,
}

/// Why the model could not be evaluated.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum WmmError {
    /// The date does not exist (e.g. day 366 of a common year).
    #[error("invalid date: year {year}, day of year {day_of_year}")]
    InvalidDate {
        /// Year.
        year: i32,
        /// Day of the year, 1-based.
        day_of_year: u16,
    },
    /// A latitude beyond ±90° or a non-finite coordinate.
    #[error("not a position: latitude {lat_rad} rad, longitude {lon_rad} rad, height {height_m} m")]
    NotAPosition {
        /// Latitude, rad.
        lat_rad: f64,
        /// Longitude, rad.
        lon_rad: f64,
        /// Height, m.
        height_m: f64,
    },
    /// The model refused the place or date (outside its epoch, say).
    #[error("world magnetic model: {0}")]
    Model(String),
}

/// Evaluates the model at geodetic latitude and longitude (rad) and height
/// above the WGS84 ellipsoid (m; a depth `d` is `-d`) on day `day_of_year`
/// (1-based) of `year`.
pub fn wmm(
    lat_rad: f64,
    lon_rad: f64,
    height_m: f64,
    year: i32,
    day_of_year: u16,
) -> Result<Geomagnetic, WmmError> {
    if !(lat_rad.abs() <= std::f64::consts::FRAC_PI_2
        && lon_rad.is_finite()
        && height_m.is_finite())
    {
        return Err(WmmError::NotAPosition {
            lat_rad,
            lon_rad,
            height_m,
        });
    }
    let date = Date::from_ordinal_date(year, day_of_year)
        .map_err(|_| WmmError::InvalidDate { year, day_of_year })?;
    let lon = crate::attitude::wrap_pi(lon_rad);
    let f = GeomagneticField::new(
        Length::new::<meter>(height_m as f32),
        Angle::new::<radian>(lat_rad as f32),
        Angle::new::<radian>(lon as f32),
        date,
    )
    .map_err(|e| WmmError::Model(e.to_string()))?;
    let nt = 1e-9;
    Ok(Geomagnetic {
        ned_t: [
            f64::from(f.x().get::<nanotesla>()) * nt,
            f64::from(f.y().get::<nanotesla>()) * nt,
            f64::from(f.z().get::<nanotesla>()) * nt,
        ],
        declination_rad: f64::from(f.declination().get::<degree>()).to_radians(),
        inclination_rad: f64::from(f.inclination().get::<degree>()).to_radians(),
    })
}

/// Today's date in UTC from the system clock: (year, day of the year).
pub fn today_utc() -> (i32, u16) {
    let days = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() / 86_400);
    // The Unix epoch is Julian day 2,440,588.
    let date = i32::try_from(days)
        .ok()
        .and_then(|d| Date::from_julian_day(2_440_588 + d).ok())
        .unwrap_or(Date::MIN);
    (date.year(), date.ordinal())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Off Lisbon on 2026-06-21 (the shipped manifests' site and day): the
    /// model's declination is the −0.98° the manifests carry.
    #[test]
    fn lisbon_2026() {
        let f = wmm(38.6f64.to_radians(), (-9.3f64).to_radians(), 0.0, 2026, 172).expect("wmm");
        assert!(
            (f.declination_rad.to_degrees() + 0.98).abs() < 0.01,
            "{f:?}"
        );
        assert!(f.inclination_rad.to_degrees() > 50.0, "{f:?}");
    }

    #[test]
    fn bad_dates_and_places_are_errors() {
        assert!(matches!(
            wmm(0.0, 0.0, 0.0, 2026, 366),
            Err(WmmError::InvalidDate { .. })
        ));
        assert!(matches!(
            wmm(2.0, 0.0, 0.0, 2026, 1),
            Err(WmmError::NotAPosition { .. })
        ));
        assert!(matches!(
            wmm(0.0, f64::NAN, 0.0, 2026, 1),
            Err(WmmError::NotAPosition { .. })
        ));
    }

    #[test]
    fn today_is_a_date() {
        let (year, day) = today_utc();
        assert!(year >= 2024 && (1..=366).contains(&day), "{year} {day}");
    }
}
