//! Where the run took place: the local origin of `lbl/nav`, the LBL
//! transponders and the UTC time of the run clock's zero, read from the
//! recording's `nauta.run` metadata or given on the command line.
//!
//! Looked up in this order:
//! - origin: `--origin`; the keys `origin_lat_deg` and `origin_lon_deg`
//!   (written by the logger from the manifest's `[site]`); a value that parses
//!   as TOML or JSON with `site.latitude_deg` and `site.longitude_deg` (the
//!   recorded manifest);
//! - transponders: the front end's resolver ([`super::ExportOptions::transponders_from_run`],
//!   which knows the simulator's layouts); else any value that parses as TOML
//!   or JSON holding, at any depth, a `transponders` list of tables with `id`,
//!   `north_m`, `east_m` and optionally `depth_m`;
//! - UTC start: `--utc-start`; the key `utc_start` (RFC 3339).

use std::collections::BTreeMap;

use nauta_estimation::local;
use serde_json::Value;

use super::{ExportOptions, UtcTime};

/// A local origin: local north/east metres map to latitude/longitude on the
/// exact local tangent plane at the origin (`nauta_estimation::local`), the
/// mapping the simulator's missions, eval and report use.
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

    /// Geodetic (lat, lon) of a local (north, east), rad: the exact local
    /// tangent plane of `nauta_estimation::local`, as every tool uses.
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
}

/// What the export knows about the run.
#[derive(Debug, Clone, Default)]
pub struct RunInfo {
    /// The local origin, if known.
    pub origin: Option<GeoOrigin>,
    /// LBL transponders, if known.
    pub transponders: Vec<Transponder>,
    /// UTC time of stamp 0, if known.
    pub utc_start: Option<UtcTime>,
}

impl RunInfo {
    /// Resolves the run's origin, transponders and UTC start from `options`
    /// and the `nauta.run` metadata; says in `notes` what it could not use.
    pub fn resolve(
        meta: Option<&BTreeMap<String, String>>,
        options: &ExportOptions,
        notes: &mut Vec<String>,
        wants_origin: bool,
    ) -> RunInfo {
        let empty = BTreeMap::new();
        let meta = meta.unwrap_or(&empty);
        let docs: Vec<(&str, Value)> = meta
            .iter()
            .filter_map(|(k, v)| parse_document(v).map(|d| (k.as_str(), d)))
            .collect();

        let origin = options.origin.or_else(|| {
            let key = |k: &str| meta.get(k).and_then(|v| v.trim().parse::<f64>().ok());
            let from_keys = match (key("origin_lat_deg"), key("origin_lon_deg")) {
                (Some(lat), Some(lon)) => Some((lat, lon, "origin_lat_deg/origin_lon_deg")),
                _ => None,
            };
            let from_docs = || {
                docs.iter().find_map(|(_, d)| {
                    let site = d.get("site")?;
                    Some((
                        site.get("latitude_deg")?.as_f64()?,
                        site.get("longitude_deg")?.as_f64()?,
                        "the manifest's [site]",
                    ))
                })
            };
            let (lat, lon, whence) = from_keys.or_else(from_docs)?;
            match GeoOrigin::from_degrees(lat, lon) {
                Ok(o) => Some(o),
                Err(e) => {
                    if wants_origin {
                        notes.push(format!("ignoring the recorded origin ({whence}): {e}"));
                    }
                    None
                }
            }
        });

        let mut transponders = options
            .transponders_from_run
            .map(|f| f(meta))
            .unwrap_or_default();
        if transponders.is_empty() {
            for (_, d) in &docs {
                find_transponders(d, &mut transponders);
            }
        }
        let mut seen = std::collections::BTreeSet::new();
        transponders.retain(|t| seen.insert(t.id) && t.north_m.is_finite() && t.east_m.is_finite());

        let utc_start = options.utc_start.or_else(|| {
            let text = meta.get("utc_start")?;
            match UtcTime::parse(text) {
                Ok(t) => Some(t),
                Err(e) => {
                    notes.push(format!("ignoring the recorded utc_start: {e}"));
                    None
                }
            }
        });
        RunInfo {
            origin,
            transponders,
            utc_start,
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

/// Collects every `transponders` list found in `v`.
fn find_transponders(v: &Value, out: &mut Vec<Transponder>) {
    match v {
        Value::Object(m) => {
            for (k, child) in m {
                if k == "transponders"
                    && let Value::Array(items) = child
                {
                    out.extend(items.iter().filter_map(|t| {
                        Some(Transponder {
                            id: u32::try_from(t.get("id")?.as_u64()?).ok()?,
                            north_m: t.get("north_m")?.as_f64()?,
                            east_m: t.get("east_m")?.as_f64()?,
                            depth_m: t.get("depth_m").and_then(Value::as_f64).unwrap_or(f64::NAN),
                        })
                    }));
                } else {
                    find_transponders(child, out);
                }
            }
        }
        Value::Array(items) => items.iter().for_each(|i| find_transponders(i, out)),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::Format;

    fn meta(pairs: &[(&str, &str)]) -> BTreeMap<String, String> {
        pairs
            .iter()
            .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
            .collect()
    }

    #[test]
    fn origin_from_keys_then_from_the_manifest() {
        let opts = ExportOptions::new(Format::Kml);
        let mut notes = Vec::new();
        let m = meta(&[("origin_lat_deg", "38.6"), ("origin_lon_deg", "-9.3")]);
        let r = RunInfo::resolve(Some(&m), &opts, &mut notes, true);
        let o = r.origin.expect("origin");
        assert!((o.lat_rad.to_degrees() - 38.6).abs() < 1e-12);
        let m = meta(&[(
            "manifest",
            "[run]\nseed = 7\n[site]\nlatitude_deg = -12.5\nlongitude_deg = 170.25\n",
        )]);
        let r = RunInfo::resolve(Some(&m), &opts, &mut notes, true);
        let o = r.origin.expect("origin from the manifest");
        assert!((o.lon_rad.to_degrees() - 170.25).abs() < 1e-12);
        assert!(
            RunInfo::resolve(None, &opts, &mut notes, true)
                .origin
                .is_none()
        );
        let m = meta(&[("origin_lat_deg", "95"), ("origin_lon_deg", "0")]);
        assert!(
            RunInfo::resolve(Some(&m), &opts, &mut notes, true)
                .origin
                .is_none()
        );
        assert!(notes.iter().any(|n| n.contains("±90")), "{notes:?}");
    }

    #[test]
    fn explicit_transponders_are_found_at_any_depth() {
        let opts = ExportOptions::new(Format::Kml);
        let m = meta(&[(
            "sensor_config.sensor",
            "[params.sensors.lbl]\nenabled = true\ntransponders = [\
             { id = 1, north_m = -50.0, east_m = -150.0, depth_m = 20.0 },\
             { id = 2, north_m = 550.0, east_m = -150.0 }]\n",
        )]);
        let r = RunInfo::resolve(Some(&m), &opts, &mut Vec::new(), true);
        assert_eq!(r.transponders.len(), 2);
        assert_eq!(r.transponders[1].id, 2);
        assert!(r.transponders[1].depth_m.is_nan());
        assert_eq!(r.transponders[0].east_m, -150.0);
    }

    #[test]
    fn local_and_geodetic_round_trip() {
        let o = GeoOrigin::from_degrees(38.6, -9.3).expect("origin");
        let (lat, lon) = o.to_geodetic(550.0, -150.0);
        let (n, e) = o.to_local(lat, lon);
        assert!((n - 550.0).abs() < 1e-6 && (e + 150.0).abs() < 1e-6);
        // 1 km north is about 0.009°.
        assert!(((lat - o.lat_rad).to_degrees() - 0.00495).abs() < 1e-4);
    }
}
