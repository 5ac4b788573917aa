//! `[process.sensor.params]` of a manifest, as the sensor process reads it
//! (and the tools that need the run's sensors: export, calibration): the scenario ([`ScenarioParams`], every key
//! optional), a `sensors` table laid over the scenario's sensor preset
//! ([`ScenarioParams::sensors_preset`]; any value of [`SuiteConfig`] can be
//! changed, e.g. `--set sensor.params.sensors.dvl.noise.spike_probability=0.01`),
//! and the LBL synchronisation rate.

use anyhow::{Context as _, bail};

use crate::scenario::ScenarioParams;
use crate::suite::SuiteConfig;

/// Default rate of the LBL synchronisation points, Hz (the `lbl/nav` rate of
/// DESIGN §4).
pub const DEFAULT_LBL_SYNC_HZ: f64 = 10.0;

/// Everything the sensor process reads from its manifest section.
#[derive(Debug, Clone)]
pub struct SensorParams {
    /// The scenario.
    pub scenario: ScenarioParams,
    /// The sensors: the preset with the manifest's `sensors` table over it.
    pub sensors: SuiteConfig,
    /// In `sim` clock with an interrogator, how often (Hz of simulated time)
    /// the sensor waits for the interrogator's watermark (see `lbl_link`).
    pub lbl_sync_hz: f64,
}

impl SensorParams {
    /// Parses the parameter table; `place` names it in errors
    /// (`launch/lbl.toml: process.sensor.params`).
    pub fn from_table(mut table: toml::Table, place: &str) -> anyhow::Result<Self> {
        let sensors = table.remove("sensors");
        let lbl_sync_hz = match table.remove("lbl_sync_hz") {
            None => DEFAULT_LBL_SYNC_HZ,
            Some(v) => v
                .as_float()
                .or_else(|| v.as_integer().map(|i| i as f64))
                .with_context(|| format!("{place}.lbl_sync_hz: expected a number, got {v}"))?,
        };
        if !(lbl_sync_hz.is_finite() && lbl_sync_hz > 0.0) {
            bail!("{place}.lbl_sync_hz: must be positive, got {lbl_sync_hz}");
        }
        let scenario: ScenarioParams = table
            .try_into()
            .map_err(|e| anyhow::anyhow!("{place}: {}", e.to_string().trim_end()))?;
        scenario
            .validate()
            .map_err(|e| anyhow::anyhow!("{place}: {e}"))?;
        let preset = scenario.sensors_preset();
        let sensors = match sensors {
            None => preset,
            Some(toml::Value::Table(over)) => {
                let mut merged = toml::Table::try_from(&preset)
                    .context("cannot express the sensor preset as TOML")?;
                overlay(&mut merged, over);
                merged
                    .try_into()
                    .map_err(|e| anyhow::anyhow!("{place}.sensors: {}", e.to_string().trim_end()))?
            }
            Some(other) => bail!("{place}.sensors: expected a table, got {other}"),
        };
        sensors
            .validate()
            .map_err(|e| anyhow::anyhow!("{place}.sensors: {e}"))?;
        Ok(Self {
            scenario,
            sensors,
            lbl_sync_hz,
        })
    }
}

impl SensorParams {
    /// The parameters of a sensor section as `nauta-logger` records it
    /// (`sensor_config.<process>` of `nauta.run`: TOML with `params`, the
    /// `variant` and each `variants.V` table): the chosen variant's table laid
    /// over `params`, as the manifest is read.
    pub fn from_recorded_section(text: &str, place: &str) -> anyhow::Result<Self> {
        let section: toml::Table = toml::from_str(text)
            .map_err(|e| anyhow::anyhow!("{place}: {}", e.to_string().trim_end()))?;
        let mut params = match section.get("params") {
            Some(toml::Value::Table(t)) => t.clone(),
            None => toml::Table::new(),
            Some(other) => bail!("{place}.params: expected a table, got {other}"),
        };
        if let Some(v) = section.get("variant").and_then(toml::Value::as_str)
            && let Some(toml::Value::Table(over)) = section.get(&format!("variants.{v}"))
        {
            overlay(&mut params, over.clone());
        }
        Self::from_table(params, place)
    }
}

/// Lays `over` onto `base`: tables merge key by key, anything else replaces.
pub fn overlay(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => overlay(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::ScenarioKind;

    fn parse(text: &str) -> anyhow::Result<SensorParams> {
        SensorParams::from_table(text.parse::<toml::Table>()?, "process.sensor.params")
    }

    #[test]
    fn defaults_are_the_survey() {
        let p = parse("").unwrap();
        assert_eq!(p.scenario.scenario, ScenarioKind::Survey);
        assert_eq!(p.sensors, SuiteConfig::survey());
        assert_eq!(p.lbl_sync_hz, DEFAULT_LBL_SYNC_HZ);
    }

    #[test]
    fn sensor_values_lay_over_the_scenario_preset() {
        let p = parse(
            r#"
scenario = "lbl"
lbl_layout = "Four"
sensors.dvl.rate_hz = 4.0
sensors.lbl.noise.multipath_probability = 0.2
"#,
        )
        .unwrap();
        assert_eq!(p.scenario.scenario, ScenarioKind::Lbl);
        // The LBL preset stays (LBL on, four transponders, DVL off) ...
        assert!(p.sensors.lbl.enabled && !p.sensors.dvl.enabled);
        assert_eq!(p.sensors.lbl.transponders.len(), 4);
        // ... with the two values changed and nothing else.
        assert_eq!(p.sensors.dvl.rate_hz, 4.0);
        assert_eq!(p.sensors.lbl.noise.multipath_probability, 0.2);
        assert_eq!(
            p.sensors.lbl.noise.clock_resolution,
            SuiteConfig::lbl(crate::suite::LblLayout::Four)
                .lbl
                .noise
                .clock_resolution
        );
    }

    #[test]
    fn errors_name_the_key() {
        for (text, key) in [
            ("speed = 3", "speed"),
            ("scenario = \"moon\"", "moon"),
            ("sensors.dvl.colour = 1", "colour"),
            ("sensors.dvl.rate_hz = -5.0", "dvl.rate_hz"),
            ("survey.legs = 0", "survey.legs"),
            // Values that parsed and then overflowed or ate the memory.
            ("survey.legs = 9223372036854775807", "survey.legs"),
            ("survey.legs = 100000000", "survey.legs"),
            ("survey.leg_length_m = 1e300", "survey.leg_length_m"),
            ("survey.speed_m_s = 1e-300", "survey.speed_m_s"),
            ("lbl_sync_hz = 0", "lbl_sync_hz"),
            ("sensors = 3", "sensors"),
        ] {
            let e = format!("{:#}", parse(text).unwrap_err());
            assert!(e.contains(key), "{text}: {e}");
            assert!(e.contains("process.sensor.params"), "{text}: {e}");
        }
    }
}
