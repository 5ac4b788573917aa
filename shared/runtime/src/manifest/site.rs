//! `[site]`: the operating area, and where its declination comes from.

use serde::Deserialize;

/// `[site]` as written.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSite {
    pub(super) latitude_deg: f64,
    pub(super) longitude_deg: f64,
    #[serde(default)]
    pub(super) magnetic_declination_deg: Option<f64>,
}

/// `[site]`: where the mission takes place.
#[derive(Debug, Clone, Copy)]
pub struct Site {
    /// Latitude of the operating area, degrees.
    pub latitude_deg: f64,
    /// Longitude of the operating area, degrees.
    pub longitude_deg: f64,
    /// Magnetic declination, degrees, east positive (true = magnetic +
    /// declination): the manifest's `magnetic_declination_deg`, else the
    /// World Magnetic Model's at the site today ([`Site::declination_from`]).
    pub magnetic_declination_deg: f64,
    /// Where the declination came from.
    pub declination_from: DeclinationSource,
}

/// Where a site's declination came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeclinationSource {
    /// The manifest's `[site] magnetic_declination_deg`.
    Manifest,
    /// The World Magnetic Model at the site on this (UTC) date, from the
    /// system clock, when the manifest gives none.
    Wmm {
        /// Year.
        year: i32,
        /// Day of the year, 1-based.
        day_of_year: u16,
    },
}

impl Site {
    /// Logs where the declination came from when the manifest gave none
    /// (an estimator calls it once as it builds its core).
    pub fn log_declination(&self) {
        if let DeclinationSource::Wmm { year, day_of_year } = self.declination_from {
            tracing::info!(
                declination_deg = self.magnetic_declination_deg,
                year,
                day_of_year,
                "[site] gives no magnetic_declination_deg: the World Magnetic Model's at the site on this date"
            );
        }
    }
}

impl RawSite {
    /// The site, its declination from the WMM when the manifest gives none
    /// (on the system clock's date: the model changes by about 0.1° a year
    /// at most sites, so the day does not matter, and a manifest that names
    /// its declination stays bit for bit the same whatever the date).
    pub(super) fn resolve(self) -> Result<Site, (&'static str, String)> {
        let declination = |deg: f64, from| Site {
            latitude_deg: self.latitude_deg,
            longitude_deg: self.longitude_deg,
            magnetic_declination_deg: deg,
            declination_from: from,
        };
        if let Some(d) = self.magnetic_declination_deg {
            return Ok(declination(d, DeclinationSource::Manifest));
        }
        let (year, day_of_year) = nauta_estimation::magnetic::today_utc();
        nauta_estimation::magnetic::wmm(
            self.latitude_deg.to_radians(),
            self.longitude_deg.to_radians(),
            0.0,
            year,
            day_of_year,
        )
        .map(|f| {
            declination(
                f.declination_rad.to_degrees(),
                DeclinationSource::Wmm { year, day_of_year },
            )
        })
        .map_err(|e| {
            (
                "site.magnetic_declination_deg",
                format!("not given, and the World Magnetic Model cannot give it ({e}): write it"),
            )
        })
    }
}
