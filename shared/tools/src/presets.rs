//! What the simulator knows about a recorded run that its `nauta.run`
//! metadata does not spell out: the LBL layout, the transponders' turnaround
//! and the water's sound speed of the scenario the sensor ran. Passed to
//! [`nauta_log::run::RunInfo::read`] as its [`nauta_log::run::Resolver`], so
//! the one reader of run metadata stays free of the simulator.
//!
//! The sensor's parameters are found, as the sensor reads them (the scenario's
//! preset with the `sensors` table laid over it, [`SensorParams`]), in:
//! - a `sensor_config.<process>` entry (the logger's copy of the sensor's
//!   manifest section: `params`, `variant`, `variants.V`); else
//! - a manifest document with a `[process.<name>]` whose `params` name a
//!   `scenario`.

use std::collections::BTreeMap;

use nauta_log::run::{GeoOrigin, Presets, Transponder};
use nauta_sim::mission::Origin;
use nauta_sim::params::{SensorParams, overlay};

/// The [`nauta_log::run::Resolver`] of simulated runs.
pub fn simulated(meta: &BTreeMap<String, String>, origin: Option<&GeoOrigin>) -> Presets {
    let Some(params) = sensor_params(meta) else {
        return Presets::default();
    };
    let lbl = &params.sensors.lbl;
    let sound_speed_m_s = params.sensors.sound_speed_m_s.or_else(|| {
        // The suite's own default (shared/sim/src/suite/mod.rs, `new`): the
        // water column's speed at 10 m, at the mission's place and date.
        let o = origin?;
        let env = params
            .scenario
            .environment(Origin {
                lat_rad: o.lat_rad,
                lon_rad: o.lon_rad,
            })
            .ok()?;
        Some(env.water.sound_speed_m_s(10.0))
    });
    Presets {
        transponders: if lbl.enabled {
            lbl.transponders
                .iter()
                .map(|t| Transponder {
                    id: t.id,
                    north_m: t.north_m,
                    east_m: t.east_m,
                    depth_m: t.depth_m,
                    turnaround_s: Some(t.turnaround_s),
                })
                .collect()
        } else {
            Vec::new()
        },
        sound_speed_m_s,
        // Each transponder has its own; the run's is the first one's.
        turnaround_s: lbl
            .enabled
            .then(|| lbl.transponders.first().map(|t| t.turnaround_s))
            .flatten(),
    }
}

/// The sensor's parameters from the run's metadata, if it ran the simulator.
fn sensor_params(meta: &BTreeMap<String, String>) -> Option<SensorParams> {
    let from_section = meta
        .iter()
        .filter(|(k, _)| k.starts_with("sensor_config."))
        .find_map(|(_, v)| SensorParams::from_recorded_section(v, "sensor_config").ok());
    from_section.or_else(|| meta.values().find_map(|v| of_manifest(v)))
}

/// The parameters of the first process of a manifest that runs a scenario.
fn of_manifest(text: &str) -> Option<SensorParams> {
    let manifest: toml::Table = text.parse().ok()?;
    manifest.get("process")?.as_table()?.values().find_map(|p| {
        let p = p.as_table()?;
        let mut params = p.get("params")?.as_table()?.clone();
        params.get("scenario")?;
        if let Some(variant) = p.get("variant").and_then(toml::Value::as_str)
            && let Some(over) = p
                .get("variants")
                .and_then(|v| v.get(variant))
                .and_then(toml::Value::as_table)
        {
            overlay(&mut params, over.clone());
        }
        SensorParams::from_table(params, "manifest").ok()
    })
}

#[cfg(test)]
mod tests {
    use nauta_log::run::{Overrides, RunInfo};

    use super::*;

    fn meta(entries: &[(&str, &str)]) -> BTreeMap<String, String> {
        entries
            .iter()
            .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
            .collect()
    }

    fn read(m: &BTreeMap<String, String>) -> RunInfo {
        RunInfo::read(Some(m), &Overrides::default(), Some(simulated))
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
        let info = read(&meta(&[("manifest", manifest)]));
        assert_eq!(info.transponders.len(), 4);
        assert_eq!(info.transponders[1].north_m, 550.0);
        assert_eq!(info.turnaround_s, Some(12.5e-3));
        let c = info.sound_speed_m_s.expect("sound speed");
        assert!((1400.0..1600.0).contains(&c), "{c}");
        // As nauta-logger writes it: the origin, and the sensor's section alone.
        let section = "variant = \"sim\"\n[params]\nscenario = \"lbl\"\n";
        let info = read(&meta(&[
            ("origin_lat_deg", "38.6"),
            ("origin_lon_deg", "-9.3"),
            ("sensor_config.sensor", section),
        ]));
        assert_eq!(info.transponders.len(), 2);
        assert!(info.sound_speed_m_s.is_some());
    }

    #[test]
    fn a_survey_has_no_transponders() {
        let section = "variant = \"sim\"\n[params]\nscenario = \"survey\"\n";
        let info = read(&meta(&[("sensor_config.sensor", section)]));
        assert!(info.transponders.is_empty());
        assert_eq!(info.turnaround_s, None);
    }

    #[test]
    fn a_sensors_override_moves_a_transponder() {
        let section = "variant = \"sim\"\n[params]\nscenario = \"lbl\"\n\
             [params.sensors.lbl]\ntransponders = [{ id = 5, north_m = 1.0, east_m = 2.0, depth_m = 3.0 }]\n";
        let info = read(&meta(&[("sensor_config.sensor", section)]));
        assert_eq!(info.transponders.len(), 1);
        assert_eq!(info.transponders[0].id, 5);
    }
}
