//! What the recording's `nauta.run` metadata says about the mission's frame:
//! the local origin (for `lbl/nav`, DESIGN §4 "local planar coordinates ...
//! from a declared origin"), the LBL transponders and the acoustics (for the
//! range residuals of `nauta report`).
//!
//! The record is read leniently, because it is free-form text written by the
//! logger: every entry is looked at, as a plain value under a known key or as
//! a TOML or JSON document (the manifest, the sensor configuration), and what
//! is found is taken in this order:
//!
//! - origin: keys `origin_lat_deg`/`origin_lon_deg`, `site.latitude_deg`/
//!   `site.longitude_deg` or `latitude_deg`/`longitude_deg`; else a document
//!   with a `[site]` table (the manifest: the simulator's mission origin is
//!   the site, `nauta-sensor`);
//! - transponders: a document with an array `transponders` of
//!   `{id, north_m, east_m, depth_m}` at any depth (the sensor configuration,
//!   or a manifest's `sensors.lbl.transponders` override); else, in a manifest
//!   whose sensor runs the `lbl` scenario, that scenario's layout
//!   ([`ScenarioParams::sensors_preset`]);
//! - sound speed and transponder turnaround: `sound_speed_m_s` and
//!   `turnaround` (`lbl.noise.turnaround` of the sensor configuration), else
//!   those of the `lbl` scenario found in the manifest.

use std::collections::BTreeMap;

use nauta_sim::mission::Origin;
use nauta_sim::scenario::{ScenarioKind, ScenarioParams};
use nauta_sim::suite::Transponder;

/// Where a value came from, for the notes eval prints.
#[derive(Debug, Clone, PartialEq)]
pub struct Found<T> {
    /// The value.
    pub value: T,
    /// `nauta.run` key (or `truth`), for the user.
    pub source: String,
}

/// What the metadata says about the mission's frame and acoustics.
#[derive(Debug, Clone, Default)]
pub struct RunInfo {
    /// Local origin (north/east frame of `lbl/nav` and of the transponders).
    pub origin: Option<Found<Origin>>,
    /// LBL transponders, local frame.
    pub transponders: Vec<Transponder>,
    /// Sound speed, m/s.
    pub sound_speed_m_s: Option<f64>,
    /// Transponder turnaround delay, s.
    pub turnaround_s: Option<f64>,
}

/// Reads the `nauta.run` record (`None`: the file has none).
pub fn from_metadata(run: Option<&BTreeMap<String, String>>) -> RunInfo {
    let mut info = RunInfo::default();
    let Some(run) = run else {
        return info;
    };
    let num = |k: &str| run.get(k).and_then(|v| v.trim().parse::<f64>().ok());
    for (lat_k, lon_k) in [
        ("origin_lat_deg", "origin_lon_deg"),
        ("site.latitude_deg", "site.longitude_deg"),
        ("latitude_deg", "longitude_deg"),
    ] {
        if let (Some(lat), Some(lon)) = (num(lat_k), num(lon_k))
            && let Some(o) = checked_origin(lat, lon)
        {
            info.origin = Some(Found {
                value: o,
                source: format!("nauta.run {lat_k}/{lon_k}"),
            });
            break;
        }
    }
    info.sound_speed_m_s = num("sound_speed_m_s").filter(|c| *c > 0.0);
    info.turnaround_s = num("turnaround").filter(|t| *t >= 0.0);

    let docs: Vec<(&String, serde_json::Value)> = run
        .iter()
        .filter_map(|(k, v)| parse_doc(v).map(|d| (k, d)))
        .collect();
    for (key, doc) in &docs {
        if info.origin.is_none()
            && let Some(site) = doc.get("site")
            && let (Some(lat), Some(lon)) = (
                site.get("latitude_deg").and_then(serde_json::Value::as_f64),
                site.get("longitude_deg")
                    .and_then(serde_json::Value::as_f64),
            )
            && let Some(o) = checked_origin(lat, lon)
        {
            info.origin = Some(Found {
                value: o,
                source: format!("nauta.run {key} [site]"),
            });
        }
        if info.transponders.is_empty()
            && let Some(t) = find_key(doc, "transponders")
            && let Ok(t) = serde_json::from_value::<Vec<Transponder>>(t.clone())
        {
            info.transponders = t;
        }
        if info.sound_speed_m_s.is_none() {
            info.sound_speed_m_s = find_key(doc, "sound_speed_m_s")
                .and_then(serde_json::Value::as_f64)
                .filter(|c| *c > 0.0);
        }
        if info.turnaround_s.is_none() {
            info.turnaround_s = find_key(doc, "turnaround")
                .and_then(serde_json::Value::as_f64)
                .filter(|t| *t >= 0.0);
        }
    }
    // The lbl scenario's own layout and acoustics, from a manifest.
    if let Some(params) = docs.iter().find_map(|(_, d)| lbl_scenario(d)) {
        let preset = params.sensors_preset();
        if info.transponders.is_empty() {
            info.transponders = preset.lbl.transponders.clone();
        }
        if info.turnaround_s.is_none() {
            info.turnaround_s = Some(preset.lbl.noise.turnaround);
        }
        if info.sound_speed_m_s.is_none()
            && let Some(origin) = &info.origin
            && let Ok(env) = params.environment(origin.value)
        {
            // The suite's own default (shared/sim/src/suite/mod.rs, `new`):
            // the configured speed, else the water column's at 10 m.
            info.sound_speed_m_s = Some(
                preset
                    .sound_speed_m_s
                    .unwrap_or_else(|| env.water.sound_speed_m_s(10.0)),
            );
        }
    }
    info
}

fn checked_origin(lat_deg: f64, lon_deg: f64) -> Option<Origin> {
    (lat_deg.is_finite() && lon_deg.is_finite() && lat_deg.abs() < 90.0 && lon_deg.abs() <= 360.0)
        .then(|| Origin::from_degrees(lat_deg, lon_deg))
}

/// A TOML or JSON document (objects only), as JSON.
fn parse_doc(text: &str) -> Option<serde_json::Value> {
    let t = text.trim_start();
    if t.starts_with('{') {
        return serde_json::from_str::<serde_json::Value>(text)
            .ok()
            .filter(serde_json::Value::is_object);
    }
    let table: toml::Table = text.parse().ok()?;
    serde_json::to_value(table).ok()
}

/// The first value under `key`, depth first.
fn find_key<'a>(v: &'a serde_json::Value, key: &str) -> Option<&'a serde_json::Value> {
    match v {
        serde_json::Value::Object(m) => m
            .get(key)
            .or_else(|| m.values().find_map(|c| find_key(c, key))),
        serde_json::Value::Array(a) => a.iter().find_map(|c| find_key(c, key)),
        _ => None,
    }
}

/// The `lbl` scenario of a manifest (a process whose `params` say
/// `scenario = "lbl"`) or of a sensor section (`sensor_config.NAME`: the
/// process's `params` at the top).
fn lbl_scenario(doc: &serde_json::Value) -> Option<ScenarioParams> {
    let of_process = |p: &serde_json::Value| {
        let mut params = p.get("params")?.as_object()?.clone();
        if params.get("scenario")?.as_str()? != ScenarioKind::Lbl.name() {
            return None;
        }
        // Keys of the sensor process that are not scenario parameters.
        params.remove("sensors");
        params.remove("lbl_sync_hz");
        serde_json::from_value::<ScenarioParams>(serde_json::Value::Object(params)).ok()
    };
    of_process(doc).or_else(|| {
        doc.get("process")?
            .as_object()?
            .values()
            .find_map(of_process)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn meta(entries: &[(&str, &str)]) -> BTreeMap<String, String> {
        entries
            .iter()
            .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
            .collect()
    }

    #[test]
    fn origin_from_plain_keys_or_the_manifest() {
        let m = meta(&[("origin_lat_deg", "38.5"), ("origin_lon_deg", "-9.25")]);
        let o = from_metadata(Some(&m)).origin.expect("origin").value;
        assert!((o.lat_rad - 38.5f64.to_radians()).abs() < 1e-15);
        assert!((o.lon_rad + 9.25f64.to_radians()).abs() < 1e-15);

        let manifest = "[run]\nseed = 1\n[site]\nlatitude_deg = 41.0\nlongitude_deg = -8.75\n";
        let info = from_metadata(Some(&meta(&[("manifest", manifest)])));
        let o = info.origin.expect("origin");
        assert!((o.value.lat_rad - 41f64.to_radians()).abs() < 1e-15);
        assert!(o.source.contains("manifest"), "{}", o.source);
        assert!(info.transponders.is_empty());
        assert!(from_metadata(None).origin.is_none());
        assert!(
            from_metadata(Some(&meta(&[("manifest", "not = [toml")])))
                .origin
                .is_none()
        );
    }

    #[test]
    fn the_lbl_scenario_gives_its_layout_and_acoustics() {
        let manifest = r#"
[site]
latitude_deg = 38.6
longitude_deg = -9.3
[process.sensor]
bin = "nauta-sensor"
params = { scenario = "lbl", lbl_layout = "Four", lbl_sync_hz = 10.0 }
"#;
        let info = from_metadata(Some(&meta(&[("manifest", manifest)])));
        assert_eq!(info.transponders.len(), 4);
        assert_eq!(info.transponders[1].north_m, 550.0);
        assert_eq!(info.turnaround_s, Some(12.5e-3));
        let c = info.sound_speed_m_s.expect("sound speed");
        assert!((1400.0..1600.0).contains(&c), "{c}");
        // As nauta-logger writes it: the origin, and the sensor's section alone.
        let section = "variant = \"sim\"\n[params]\nscenario = \"lbl\"\n";
        let info = from_metadata(Some(&meta(&[
            ("origin_lat_deg", "38.6"),
            ("origin_lon_deg", "-9.3"),
            ("sensor_config.sensor", section),
        ])));
        assert_eq!(info.transponders.len(), 2);
        assert!(info.sound_speed_m_s.is_some());
    }

    #[test]
    fn explicit_transponders_in_a_json_configuration_win() {
        let cfg = r#"{"lbl": {"enabled": true, "transponders": [{"id": 7, "north_m": 1.0, "east_m": 2.0, "depth_m": 3.0}], "noise": {"turnaround": 0.02}}, "sound_speed_m_s": 1490.0}"#;
        let info = from_metadata(Some(&meta(&[("sensors", cfg)])));
        assert_eq!(info.transponders.len(), 1);
        assert_eq!(info.transponders[0].id, 7);
        assert_eq!(info.sound_speed_m_s, Some(1490.0));
        assert_eq!(info.turnaround_s, Some(0.02));
    }
}
