//! `[site]`: the operating area, where its declination comes from, and what
//! the vehicle knows of its acoustic field: the LBL transponders and the
//! sound speed it assumes.
//!
//! The transponders are `[[site.transponders]]` (id, north_m, east_m,
//! depth_m, turnaround_s), or, when `[site]` lists none, the named layout of
//! a process parameter `lbl_layout` (`"Two"`, `"Four"`: the simulator's
//! `lbl` scenario, `nauta_estimation::lbl::layout::preset`), so that
//! `--set sensor.params.lbl_layout=Four` changes them for every process of
//! the run at once. Both at once is refused: one list, one source.

use nauta_estimation::lbl::{Layout, LblSite, Transponder};
use serde::Deserialize;

/// `[site]` as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSite {
    pub(super) latitude_deg: f64,
    pub(super) longitude_deg: f64,
    #[serde(default)]
    pub(super) magnetic_declination_deg: Option<f64>,
    #[serde(default)]
    pub(super) sound_speed_m_s: Option<f64>,
    #[serde(default)]
    pub(super) transponders: Option<Vec<Transponder>>,
}

/// Sound speeds accepted, m/s (sea water is 1400-1570 m/s; fresh water at
/// 0 °C is 1403 m/s).
pub const SOUND_SPEED_RANGE_M_S: (f64, f64) = (1300.0, 1800.0);

/// Where a site's transponders came from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TranspondersSource {
    /// None are known.
    None,
    /// `[[site.transponders]]`.
    Manifest,
    /// The named layout of `process.NAME.params.lbl_layout`.
    Layout {
        /// The process whose parameter named it.
        process: String,
        /// The layout's name.
        name: String,
    },
}

/// `[site]`: where the mission takes place.
#[derive(Debug, Clone)]
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
    /// The sound speed the vehicle assumes (from a CTD cast), m/s.
    pub sound_speed_m_s: Option<f64>,
    /// The LBL transponders (a checked layout when not empty).
    pub transponders: Vec<Transponder>,
    /// Where they came from.
    pub transponders_from: TranspondersSource,
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

impl Site {
    /// The transponders as a checked layout; `None` when there are none.
    pub fn layout(&self) -> Option<Layout> {
        Layout::new(self.transponders.clone()).ok()
    }

    /// What the LBL role knows of its site (`nauta-lbl`, and whatever runs
    /// its estimator offline): the origin, the declination, the sound
    /// speed the vehicle assumes and the transponders; the error says
    /// which of the last two the site lacks.
    pub fn lbl_site(&self) -> anyhow::Result<LblSite> {
        let layout = self.layout().ok_or_else(|| {
            anyhow::anyhow!(
                "[site] has no transponders (site.transponders, or a process's lbl_layout)"
            )
        })?;
        let sound_speed_m_s = self.sound_speed_m_s.ok_or_else(|| {
            anyhow::anyhow!(
                "[site] has no sound_speed_m_s (the sound speed the vehicle assumes, m/s)"
            )
        })?;
        Ok(LblSite {
            origin_lat_rad: self.latitude_deg.to_radians(),
            origin_lon_rad: self.longitude_deg.to_radians(),
            declination_rad: self.magnetic_declination_deg.to_radians(),
            sound_speed_m_s,
            layout,
        })
    }

    /// Checks the acoustics (the sound speed's range, the transponders as a
    /// layout) and takes the transponders from a process's `lbl_layout`
    /// when `[site]` lists none: `named` is the first (process, layout
    /// name) of the manifest. The error names the key.
    pub(super) fn resolve_acoustics(
        &mut self,
        named: Option<(String, String)>,
    ) -> Result<(), (String, String)> {
        if let Some(c) = self.sound_speed_m_s {
            let (lo, hi) = SOUND_SPEED_RANGE_M_S;
            if !(c >= lo && c <= hi) {
                return Err((
                    "site.sound_speed_m_s".into(),
                    format!("must be within [{lo}, {hi}] m/s, got {c}"),
                ));
            }
        }
        match (&self.transponders_from, named) {
            (TranspondersSource::Manifest, Some((process, name))) => {
                return Err((
                    format!("process.{process}.params.lbl_layout"),
                    format!(
                        "names the transponders ({name:?}), and [site] lists them too: keep one (docs/design-notes.md, \"LBL navigation\")"
                    ),
                ));
            }
            (TranspondersSource::None, Some((process, name))) => {
                let Some(t) = nauta_estimation::lbl::layout::preset(&name) else {
                    return Err((
                        format!("process.{process}.params.lbl_layout"),
                        format!(
                            "unknown layout {name:?}; the named layouts are {:?}",
                            nauta_estimation::lbl::layout::PRESETS
                        ),
                    ));
                };
                self.transponders = t;
                self.transponders_from = TranspondersSource::Layout { process, name };
            }
            _ => {}
        }
        if !self.transponders.is_empty() {
            Layout::new(self.transponders.clone())
                .map_err(|e| ("site.transponders".to_owned(), e.to_string()))?;
        }
        Ok(())
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
            sound_speed_m_s: self.sound_speed_m_s,
            transponders: self.transponders.clone().unwrap_or_default(),
            transponders_from: if self.transponders.is_some() {
                TranspondersSource::Manifest
            } else {
                TranspondersSource::None
            },
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
