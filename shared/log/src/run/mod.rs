//! What a recording's `nauta.run` metadata says about where and how the run
//! took place: the local origin (of `lbl/nav` and of the transponders, DESIGN
//! §4 "local planar coordinates ... from a declared origin"), the LBL
//! transponders, the acoustics (sound speed, transponder turnaround) and the
//! UTC time of stamp 0. The one reader of it, for eval, report, export and the
//! smoother.
//!
//! The record is free-form text written by the logger, so it is read
//! leniently: every entry is looked at, as a plain value under a known key or
//! as a TOML or JSON document (the manifest, the sensor configuration). What
//! is found is taken in this order, an explicit [`Overrides`] value first:
//!
//! - origin: keys `origin_lat_deg`/`origin_lon_deg` (the logger writes them
//!   from the manifest's `[site]`), `site.latitude_deg`/`site.longitude_deg`,
//!   `latitude_deg`/`longitude_deg`; else a document with a `[site]` table
//!   (the recorded manifest). An origin out of range is noted and not used.
//! - transponders: the [`Resolver`]'s (the front end passes one that knows
//!   the simulator's scenarios: the layout the simulated sensor used); else
//!   any `transponders` list of tables with `id`, `north_m`, `east_m` and
//!   optionally `depth_m` and `turnaround_s`, at any depth of a document (a
//!   manifest's `[site]` or sensor override, a sensor configuration).
//! - sound speed and turnaround: keys `sound_speed_m_s` and `turnaround`;
//!   else the first such key at any depth of a document; else the resolver's.
//! - UTC start: the key `utc_start` (RFC 3339).
//!
//! The simulator's knowledge (scenario presets) stays out of this crate: it
//! comes in as a [`Resolver`].

use std::collections::{BTreeMap, BTreeSet};

use nauta_estimation::local;
use serde_json::Value;

use crate::utc::UtcTime;

#[cfg(test)]
mod tests;

/// A local origin: local north/east metres map to latitude/longitude on the
/// exact local tangent plane at the origin (`nauta_estimation::local`), the
/// mapping the simulator's missions, eval, report and export all use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoOrigin {
    /// Geodetic latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
}

impl GeoOrigin {
    /// An origin from degrees; latitude within ±90°, longitude within ±180°.
    pub fn from_degrees(lat_deg: f64, lon_deg: f64) -> Result<Self, String> {
        if !(-90.0..=90.0).contains(&lat_deg) {
            return Err(format!(
                "origin latitude must be within ±90°, got {lat_deg}"
            ));
        }
        if !(-180.0..=180.0).contains(&lon_deg) {
            return Err(format!(
                "origin longitude must be within ±180°, got {lon_deg}"
            ));
        }
        Ok(GeoOrigin {
            lat_rad: lat_deg.to_radians(),
            lon_rad: lon_deg.to_radians(),
        })
    }

    /// Geodetic (lat, lon) of a local (north, east), rad.
    pub fn to_geodetic(&self, north_m: f64, east_m: f64) -> (f64, f64) {
        local::geodetic_of(self.lat_rad, self.lon_rad, north_m, east_m)
    }

    /// Local (north, east) of a geodetic position, m.
    pub fn to_local(&self, lat_rad: f64, lon_rad: f64) -> (f64, f64) {
        local::north_east_of(self.lat_rad, self.lon_rad, lat_rad, lon_rad)
    }
}

/// An LBL transponder in the run's local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transponder {
    /// Id (as in `sensor/lbl`).
    pub id: u32,
    /// North of the origin, m.
    pub north_m: f64,
    /// East of the origin, m.
    pub east_m: f64,
    /// Depth, m (NaN when unknown).
    pub depth_m: f64,
    /// Its own turnaround delay, s, when given (else the run's).
    pub turnaround_s: Option<f64>,
}

/// What a source that knows the simulator's scenarios adds (see [`Resolver`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Presets {
    /// The transponders the simulated sensor used.
    pub transponders: Vec<Transponder>,
    /// The simulated water's sound speed, m/s.
    pub sound_speed_m_s: Option<f64>,
    /// The simulated transponders' turnaround delay, s.
    pub turnaround_s: Option<f64>,
}

/// Resolves what the metadata leaves to the simulator: given the `nauta.run`
/// record and the origin found, the scenario's layout and acoustics.
pub type Resolver = fn(&BTreeMap<String, String>, Option<&GeoOrigin>) -> Presets;

/// Values the user gave that win over the recording's.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Overrides {
    /// The local origin (`--origin`).
    pub origin: Option<GeoOrigin>,
    /// The UTC time of stamp 0 (`--utc-start`).
    pub utc_start: Option<UtcTime>,
}

/// Where a value came from, for the notes tools print.
#[derive(Debug, Clone, PartialEq)]
pub struct Found<T> {
    /// The value.
    pub value: T,
    /// `nauta.run` key, document or `--origin`, for the user.
    pub source: String,
}

/// What the metadata says about the run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunInfo {
    /// The local origin, if known.
    pub origin: Option<Found<GeoOrigin>>,
    /// LBL transponders (unique ids, finite positions), if known.
    pub transponders: Vec<Transponder>,
    /// Sound speed, m/s.
    pub sound_speed_m_s: Option<f64>,
    /// Transponder turnaround delay, s.
    pub turnaround_s: Option<f64>,
    /// UTC time of stamp 0, if known.
    pub utc_start: Option<UtcTime>,
    /// What was found but could not be used, one line each.
    pub notes: Vec<String>,
}

impl RunInfo {
    /// Reads the `nauta.run` record (`None`: the file has none).
    pub fn read(
        meta: Option<&BTreeMap<String, String>>,
        overrides: &Overrides,
        presets: Option<Resolver>,
    ) -> RunInfo {
        let mut notes = Vec::new();
        let empty = BTreeMap::new();
        let meta = meta.unwrap_or(&empty);
        let docs: Vec<(&str, Value)> = meta
            .iter()
            .filter_map(|(k, v)| parse_document(v).map(|d| (k.as_str(), d)))
            .collect();
        let num = |k: &str| meta.get(k).and_then(|v| v.trim().parse::<f64>().ok());

        let origin = match overrides.origin {
            Some(o) => Some(Found {
                value: o,
                source: "--origin".to_owned(),
            }),
            None => recorded_origin(&num, &docs, &mut notes),
        };

        let presets = presets
            .map(|f| f(meta, origin.as_ref().map(|o| &o.value)))
            .unwrap_or_default();
        let mut transponders = presets.transponders;
        if transponders.is_empty() {
            for (_, d) in &docs {
                find_transponders(d, &mut transponders);
            }
        }
        let mut seen = BTreeSet::new();
        transponders.retain(|t| seen.insert(t.id) && t.north_m.is_finite() && t.east_m.is_finite());

        let in_docs = |key: &str| {
            docs.iter()
                .find_map(|(_, d)| find_key(d, key).and_then(Value::as_f64))
        };
        let sound_speed_m_s = num("sound_speed_m_s")
            .or_else(|| in_docs("sound_speed_m_s"))
            .filter(|c| c.is_finite() && *c > 0.0)
            .or(presets.sound_speed_m_s);
        let turnaround_s = num("turnaround")
            .or_else(|| in_docs("turnaround"))
            .filter(|t| t.is_finite() && *t >= 0.0)
            .or(presets.turnaround_s);

        let utc_start = overrides.utc_start.or_else(|| {
            let text = meta.get("utc_start")?;
            UtcTime::parse(text)
                .map_err(|e| notes.push(format!("ignoring the recorded utc_start: {e}")))
                .ok()
        });
        RunInfo {
            origin,
            transponders,
            sound_speed_m_s,
            turnaround_s,
            utc_start,
            notes,
        }
    }

    /// [`RunInfo::read`] of a manifest's text, as the logger would record it
    /// (for a running pipeline, which has no recording yet).
    pub fn of_manifest(manifest_toml: &str, presets: Option<Resolver>) -> RunInfo {
        let meta = BTreeMap::from([("manifest".to_owned(), manifest_toml.to_owned())]);
        RunInfo::read(Some(&meta), &Overrides::default(), presets)
    }
}

fn recorded_origin(
    num: &dyn Fn(&str) -> Option<f64>,
    docs: &[(&str, Value)],
    notes: &mut Vec<String>,
) -> Option<Found<GeoOrigin>> {
    let keys = [
        ("origin_lat_deg", "origin_lon_deg"),
        ("site.latitude_deg", "site.longitude_deg"),
        ("latitude_deg", "longitude_deg"),
    ];
    let from_keys = keys.iter().find_map(|(lat_k, lon_k)| {
        Some((
            num(lat_k)?,
            num(lon_k)?,
            format!("nauta.run {lat_k}/{lon_k}"),
        ))
    });
    let from_docs = || {
        docs.iter().find_map(|(key, d)| {
            let site = d.get("site")?;
            Some((
                site.get("latitude_deg")?.as_f64()?,
                site.get("longitude_deg")?.as_f64()?,
                format!("nauta.run {key} [site]"),
            ))
        })
    };
    let (lat, lon, source) = from_keys.or_else(from_docs)?;
    match GeoOrigin::from_degrees(lat, lon) {
        Ok(value) => Some(Found { value, source }),
        Err(e) => {
            notes.push(format!("ignoring the recorded origin ({source}): {e}"));
            None
        }
    }
}

/// A metadata value as a document, when it is a TOML table or a JSON object
/// or array.
fn parse_document(text: &str) -> Option<Value> {
    let t = text.trim_start();
    if (t.starts_with('{') || t.starts_with('['))
        && let Ok(v) = serde_json::from_str::<Value>(t)
    {
        return Some(v);
    }
    if !t.contains('=') {
        return None;
    }
    let table: toml::Table = toml::from_str(text).ok()?;
    serde_json::to_value(table).ok()
}

/// The first value under `key`, depth first.
fn find_key<'a>(v: &'a Value, key: &str) -> Option<&'a Value> {
    match v {
        Value::Object(m) => m
            .get(key)
            .or_else(|| m.values().find_map(|c| find_key(c, key))),
        Value::Array(a) => a.iter().find_map(|c| find_key(c, key)),
        _ => None,
    }
}

/// Collects every `transponders` list found in `v`.
fn find_transponders(v: &Value, out: &mut Vec<Transponder>) {
    match v {
        Value::Object(m) => {
            for (k, child) in m {
                if k == "transponders"
                    && let Value::Array(items) = child
                {
                    out.extend(items.iter().filter_map(transponder));
                } else {
                    find_transponders(child, out);
                }
            }
        }
        Value::Array(items) => items.iter().for_each(|i| find_transponders(i, out)),
        _ => {}
    }
}

fn transponder(t: &Value) -> Option<Transponder> {
    Some(Transponder {
        id: u32::try_from(t.get("id")?.as_u64()?).ok()?,
        north_m: t.get("north_m")?.as_f64()?,
        east_m: t.get("east_m")?.as_f64()?,
        depth_m: t.get("depth_m").and_then(Value::as_f64).unwrap_or(f64::NAN),
        turnaround_s: t
            .get("turnaround_s")
            .and_then(Value::as_f64)
            .filter(|t| t.is_finite() && *t >= 0.0),
    })
}
