//! `site.toml` of `nauta import csv`: where the log was taken and what the
//! acoustic channels need.
//!
//! ```toml
//! latitude_deg = 38.6               # the origin: where dead reckoning starts
//! longitude_deg = -9.3              #   until a GPS fix, and the local frame's
//! magnetic_declination_deg = -0.98  # east positive; 0 if headings are true
//! sound_speed_m_s = 1500.0          # optional: needed for range_m columns
//! turnaround_s = 0.0125             # optional: every transponder's
//!
//! [[transponders]]                  # optional: needed for lbl.csv
//! id = 1
//! north_m = 0.0                     # of the origin, m
//! east_m = 0.0
//! depth_m = 30.0
//! turnaround_s = 0.0125             # optional: this one's, over the above
//! ```
//!
//! Unknown keys are refused; errors name the file, the line and the key.

use std::path::Path;

use anyhow::bail;
use serde::Deserialize;
use toml::Spanned;

/// One transponder, validated: the run's own type (`nauta_log::run`), the
/// one a recording's readers build from its site metadata.
pub use nauta_log::run::Transponder;

/// A validated `site.toml`.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvSite {
    /// Origin latitude, degrees.
    pub latitude_deg: f64,
    /// Origin longitude, degrees.
    pub longitude_deg: f64,
    /// Magnetic declination, degrees east.
    pub magnetic_declination_deg: f64,
    /// Sound speed, m/s, if given.
    pub sound_speed_m_s: Option<f64>,
    /// Every transponder's turnaround delay, s, if given.
    pub turnaround_s: Option<f64>,
    /// The transponders (unique ids).
    pub transponders: Vec<Transponder>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSite {
    latitude_deg: Spanned<f64>,
    longitude_deg: Spanned<f64>,
    magnetic_declination_deg: Spanned<f64>,
    #[serde(default)]
    sound_speed_m_s: Option<Spanned<f64>>,
    #[serde(default)]
    turnaround_s: Option<Spanned<f64>>,
    #[serde(default)]
    transponders: Vec<RawTransponder>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTransponder {
    id: Spanned<i64>,
    north_m: Spanned<f64>,
    east_m: Spanned<f64>,
    depth_m: Spanned<f64>,
    #[serde(default)]
    turnaround_s: Option<Spanned<f64>>,
}

/// Sound speeds accepted, m/s (sea water is 1400-1570 m/s; fresh water at
/// 0 °C is 1403 m/s).
pub const SOUND_SPEED_RANGE_M_S: (f64, f64) = (1300.0, 1800.0);

impl CsvSite {
    /// Reads and checks `path`.
    pub fn read(path: &Path) -> anyhow::Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| {
            anyhow::anyhow!(
                "cannot read {}: {e} (it gives the origin, the declination and the acoustics; see the README)",
                path.display()
            )
        })?;
        let name = path.display().to_string();
        let Ok(text) = std::str::from_utf8(&bytes) else {
            bail!("{name}: not UTF-8 text");
        };
        Self::parse(&name, text)
    }

    /// [`CsvSite::read`] of text already read; `name` is the file's name for errors.
    pub fn parse(name: &str, text: &str) -> anyhow::Result<Self> {
        let raw: RawSite = toml::from_str(text)
            .map_err(|e| anyhow::anyhow!("{name}: {}", e.to_string().trim_end()))?;
        let line = |span: std::ops::Range<usize>| {
            1 + text
                .get(..span.start)
                .map_or(0, |t| t.bytes().filter(|b| *b == b'\n').count())
        };
        // Written so that NaN fails (STYLE 7).
        let check = |v: &Spanned<f64>, key: &str, lo: f64, hi: f64| -> anyhow::Result<f64> {
            let x = *v.get_ref();
            if !(lo..=hi).contains(&x) {
                bail!(
                    "{name}:{}: {key} = {x} is outside [{lo}, {hi}]",
                    line(v.span())
                );
            }
            Ok(x)
        };
        let turnaround = |v: &Spanned<f64>, key: &str| check(v, key, 0.0, 10.0);
        let mut transponders: Vec<Transponder> = Vec::new();
        for (i, t) in raw.transponders.iter().enumerate() {
            let k = |f: &str| format!("transponders[{i}].{f}");
            let id = *t.id.get_ref();
            let Ok(id_u32) = u32::try_from(id) else {
                bail!(
                    "{name}:{}: {} = {id} is not an id (0 to {})",
                    line(t.id.span()),
                    k("id"),
                    u32::MAX
                );
            };
            if transponders.iter().any(|o| o.id == id_u32) {
                bail!(
                    "{name}:{}: {} = {id} is given twice",
                    line(t.id.span()),
                    k("id")
                );
            }
            transponders.push(Transponder {
                id: id_u32,
                north_m: check(&t.north_m, &k("north_m"), -1e6, 1e6)?,
                east_m: check(&t.east_m, &k("east_m"), -1e6, 1e6)?,
                depth_m: check(&t.depth_m, &k("depth_m"), 0.0, 11_000.0)?,
                turnaround_s: t
                    .turnaround_s
                    .as_ref()
                    .map(|v| turnaround(v, &k("turnaround_s")))
                    .transpose()?,
            });
        }
        let (c_lo, c_hi) = SOUND_SPEED_RANGE_M_S;
        Ok(CsvSite {
            latitude_deg: check(&raw.latitude_deg, "latitude_deg", -90.0, 90.0)?,
            longitude_deg: check(&raw.longitude_deg, "longitude_deg", -180.0, 180.0)?,
            magnetic_declination_deg: check(
                &raw.magnetic_declination_deg,
                "magnetic_declination_deg",
                -180.0,
                180.0,
            )?,
            sound_speed_m_s: raw
                .sound_speed_m_s
                .as_ref()
                .map(|v| check(v, "sound_speed_m_s", c_lo, c_hi))
                .transpose()?,
            turnaround_s: raw
                .turnaround_s
                .as_ref()
                .map(|v| turnaround(v, "turnaround_s"))
                .transpose()?,
            transponders,
        })
    }

    /// Transponder `id`, if the site has it.
    pub fn transponder(&self, id: u32) -> Option<&Transponder> {
        self.transponders.iter().find(|t| t.id == id)
    }

    /// The site as a TOML document (for the recording's metadata, where
    /// `nauta_log::run` finds the transponders and the sound speed).
    pub fn to_toml(&self) -> String {
        let mut s = format!(
            "latitude_deg = {:?}\nlongitude_deg = {:?}\nmagnetic_declination_deg = {:?}\n",
            self.latitude_deg, self.longitude_deg, self.magnetic_declination_deg
        );
        if let Some(c) = self.sound_speed_m_s {
            s += &format!("sound_speed_m_s = {c:?}\n");
        }
        if let Some(t) = self.turnaround_s {
            s += &format!("turnaround_s = {t:?}\n");
        }
        for t in &self.transponders {
            s += &format!(
                "\n[[transponders]]\nid = {}\nnorth_m = {:?}\neast_m = {:?}\ndepth_m = {:?}\n",
                t.id, t.north_m, t.east_m, t.depth_m
            );
            if let Some(ta) = t.turnaround_s.or(self.turnaround_s) {
                s += &format!("turnaround_s = {ta:?}\n");
            }
        }
        s
    }
}
