//! Scenarios (DESIGN §10): a mission, its environment and its sensor suite
//! built from a few named parameters, and the [`Generator`] that steps the
//! truth and the sensors together. This is what `nauta-sensor` publishes and
//! what `nauta bench sim` times.
//!
//! The parameters are a manifest table (`[process.sensor.params]`); every one
//! has a default and unknown keys are refused. The sensor suite starts from the
//! scenario's preset ([`ScenarioParams::sensors_preset`]) and a manifest may
//! override any of its values.

use serde::{Deserialize, Serialize};

use crate::environment::{Current, Environment, EnvironmentError, Water};
use crate::mission::{self, AttitudeMotion, DrManoeuvre, Mission, Origin, SurveySpec};
use crate::suite::{LblLayout, Measurements, SensorSuite, SuiteConfig, SuiteError};
use crate::trajectory::{SimConfig, SimError, Simulator};

/// Which scenario to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ScenarioKind {
    /// Paper 000's parallel transects ([`mission::survey`]).
    Survey,
    /// Papers 003/004's LBL mission ([`mission::lbl`]).
    Lbl,
    /// One of paper 002's dead-reckoning manoeuvres ([`mission::dr`]).
    Dr,
    /// Paper 000's attitude test: held still.
    Still,
    /// Paper 000's attitude test: pitch-and-roll rocking.
    Rocking,
    /// Paper 000's attitude test: yaw turns.
    Yaw,
}

impl ScenarioKind {
    /// The name used in manifests.
    pub fn name(self) -> &'static str {
        match self {
            Self::Survey => "survey",
            Self::Lbl => "lbl",
            Self::Dr => "dr",
            Self::Still => "still",
            Self::Rocking => "rocking",
            Self::Yaw => "yaw",
        }
    }
}

/// The survey's shape (`survey` table; see [`SurveySpec`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SurveyParams {
    /// Number of transects.
    pub legs: usize,
    /// Transect length, m.
    pub leg_length_m: f64,
    /// Spacing between transects, m.
    pub spacing_m: f64,
    /// Depth, m.
    pub depth_m: f64,
    /// Speed through the water, m/s.
    pub speed_m_s: f64,
    /// Direction of the first transect, degrees from true north.
    pub heading_deg: f64,
}

impl Default for SurveyParams {
    fn default() -> Self {
        let s = SurveySpec::default();
        Self {
            legs: s.legs,
            leg_length_m: s.leg_length_m,
            spacing_m: s.spacing_m,
            depth_m: s.depth_m,
            speed_m_s: s.speed_m_s,
            heading_deg: s.heading_rad.to_degrees(),
        }
    }
}

/// Water current (`current` table): `mean + amplitude · sin(2π t / period + φ)`,
/// NED, m/s, φ drawn from the seed ([`Current`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurrentParams {
    /// Mean current, NED, m/s.
    pub mean_ned_m_s: [f64; 3],
    /// Amplitude of the slow variation, NED, m/s.
    #[serde(default)]
    pub amplitude_ned_m_s: [f64; 3],
    /// Period of the variation, s.
    #[serde(default = "default_current_period")]
    pub period_s: f64,
}

fn default_current_period() -> f64 {
    1800.0
}

/// The water column (`water` table; see [`Water`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WaterParams {
    /// Temperature, °C.
    pub temperature_c: f64,
    /// Practical salinity.
    pub salinity_psu: f64,
}

impl Default for WaterParams {
    fn default() -> Self {
        let w = Water::default();
        Self {
            temperature_c: w.temperature_c,
            salinity_psu: w.salinity_psu,
        }
    }
}

/// A scenario's parameters. Defaults: the survey, 10 s still at the surface
/// first, 100 Hz IMU, the WMM field of 21 June 2026.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScenarioParams {
    /// The scenario.
    pub scenario: ScenarioKind,
    /// Rest at the surface before the route starts, s (an attitude
    /// alignment's static period; waypoint scenarios only).
    pub still_s: f64,
    /// IMU and truth rate, Hz.
    pub imu_rate_hz: f64,
    /// Integration substeps per IMU interval.
    pub substeps: usize,
    /// Year of the magnetic field (WMM2025 covers 2025-2029).
    pub year: i32,
    /// Day of the year (1-based) of the magnetic field.
    pub day_of_year: u16,
    /// `survey` shape.
    pub survey: SurveyParams,
    /// `lbl` transponder layout: "Two" or "Four" (also the site's
    /// transponders when `[site]` lists none: docs/design-notes.md).
    pub lbl_layout: LblLayout,
    /// `lbl`: laps of the box (1: 2.3 km, about 32 minutes; 5: 9.5 km,
    /// over two hours).
    pub laps: u32,
    /// `dr` manoeuvre of paper 002: 1, 2 or 3.
    pub dr_manoeuvre: u8,
    /// Length of the attitude scenarios (`still`, `rocking`, `yaw`), s.
    pub attitude_duration_s: f64,
    /// Water current; default: still water, except 0.2 m/s (plus a slow
    /// 0.05 m/s variation) in the `lbl` scenario ([`Current::lbl_default`]).
    pub current: Option<CurrentParams>,
    /// Water column (sound speed).
    pub water: WaterParams,
}

impl Default for ScenarioParams {
    fn default() -> Self {
        Self {
            scenario: ScenarioKind::Survey,
            still_s: 10.0,
            imu_rate_hz: 100.0,
            substeps: 10,
            year: 2026,
            day_of_year: 172,
            survey: SurveyParams::default(),
            lbl_layout: LblLayout::Two,
            laps: 1,
            dr_manoeuvre: 1,
            attitude_duration_s: 600.0,
            current: None,
            water: WaterParams::default(),
        }
    }
}

/// Why a scenario could not be built or stepped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ScenarioError {
    /// A scenario parameter is out of range.
    #[error("scenario parameter {name} out of range: {value}")]
    Invalid {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: String,
    },
    /// The environment (magnetic model, current) could not be built.
    #[error(transparent)]
    Environment(#[from] EnvironmentError),
    /// The simulator refused its settings.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The sensor suite refused its configuration or a step.
    #[error(transparent)]
    Suite(#[from] SuiteError),
}

/// Longest still period or attitude-motion scenario, s (a week).
const MAX_DURATION_S: f64 = 7.0 * 86_400.0;
/// Most survey transects (a lawnmower of 1,000 legs is already weeks long).
const MAX_SURVEY_LEGS: usize = 1_000;
/// Most laps of the `lbl` box (100: 180 km, a week).
const MAX_LAPS: u32 = 100;
/// Longest transect and widest spacing, m.
const MAX_LEG_LENGTH_M: f64 = 100_000.0;
/// Deepest set-point, m (the deepest ocean).
const MAX_DEPTH_M: f64 = 11_000.0;
/// Slowest speed through the water, m/s (below it a mission never ends).
const MIN_SPEED_M_S: f64 = 0.01;
/// Fastest speed through the water, m/s.
const MAX_SPEED_M_S: f64 = 20.0;

fn check(name: &'static str, value: f64, ok: bool) -> Result<(), ScenarioError> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(ScenarioError::Invalid {
            name,
            value: value.to_string(),
        })
    }
}

impl ScenarioParams {
    /// The scenario's sensors: [`SuiteConfig::survey`], [`SuiteConfig::lbl`]
    /// with the layout, [`SuiteConfig::dr`]; the attitude scenarios (a still
    /// IMU at the surface) have the IMU, the AHRS and the depth sensor only.
    pub fn sensors_preset(&self) -> SuiteConfig {
        match self.scenario {
            ScenarioKind::Survey => SuiteConfig::survey(),
            ScenarioKind::Lbl => SuiteConfig::lbl(self.lbl_layout),
            ScenarioKind::Dr => SuiteConfig::dr(),
            ScenarioKind::Still | ScenarioKind::Rocking | ScenarioKind::Yaw => {
                let mut c = SuiteConfig::survey();
                c.dvl.enabled = false;
                c.gps.enabled = false;
                c.propeller.enabled = false;
                c.modem.enabled = false;
                c
            }
        }
    }

    /// Checks the values that the builders below do not check themselves.
    /// Every one has a sane range, so that a value that parses cannot make
    /// the mission builder allocate without bound (`legs = 1e8` took 12.5 GB
    /// in `nauta check`; `legs = 2^63 - 1` overflowed a capacity).
    pub fn validate(&self) -> Result<(), ScenarioError> {
        check(
            "still_s",
            self.still_s,
            (0.0..=MAX_DURATION_S).contains(&self.still_s),
        )?;
        check(
            "attitude_duration_s",
            self.attitude_duration_s,
            self.attitude_duration_s > 0.0 && self.attitude_duration_s <= MAX_DURATION_S,
        )?;
        let s = &self.survey;
        check(
            "survey.legs",
            s.legs as f64,
            (1..=MAX_SURVEY_LEGS).contains(&s.legs),
        )?;
        check(
            "survey.leg_length_m",
            s.leg_length_m,
            s.leg_length_m > 0.0 && s.leg_length_m <= MAX_LEG_LENGTH_M,
        )?;
        check(
            "survey.spacing_m",
            s.spacing_m,
            (0.0..=MAX_LEG_LENGTH_M).contains(&s.spacing_m),
        )?;
        check(
            "survey.depth_m",
            s.depth_m,
            (0.0..=MAX_DEPTH_M).contains(&s.depth_m),
        )?;
        check(
            "survey.speed_m_s",
            s.speed_m_s,
            (MIN_SPEED_M_S..=MAX_SPEED_M_S).contains(&s.speed_m_s),
        )?;
        check("survey.heading_deg", s.heading_deg, true)?;
        check(
            "water.temperature_c",
            self.water.temperature_c,
            (-2.0..=40.0).contains(&self.water.temperature_c),
        )?;
        check(
            "water.salinity_psu",
            self.water.salinity_psu,
            (0.0..=45.0).contains(&self.water.salinity_psu),
        )?;
        check(
            "laps",
            f64::from(self.laps),
            (1..=MAX_LAPS).contains(&self.laps),
        )?;
        if !(1..=3).contains(&self.dr_manoeuvre) {
            return Err(ScenarioError::Invalid {
                name: "dr_manoeuvre",
                value: self.dr_manoeuvre.to_string(),
            });
        }
        Ok(())
    }

    /// The mission from `origin`.
    pub fn mission(&self, origin: Origin) -> Mission {
        let m = match self.scenario {
            ScenarioKind::Survey => {
                let s = &self.survey;
                mission::survey(
                    origin,
                    &SurveySpec {
                        legs: s.legs,
                        leg_length_m: s.leg_length_m,
                        spacing_m: s.spacing_m,
                        depth_m: s.depth_m,
                        speed_m_s: s.speed_m_s,
                        heading_rad: s.heading_deg.to_radians(),
                    },
                )
            }
            ScenarioKind::Lbl => mission::lbl(origin, self.laps),
            ScenarioKind::Dr => mission::dr(
                origin,
                match self.dr_manoeuvre {
                    1 => DrManoeuvre::One,
                    2 => DrManoeuvre::Two,
                    _ => DrManoeuvre::Three,
                },
            ),
            ScenarioKind::Still => {
                mission::attitude(origin, AttitudeMotion::Still, self.attitude_duration_s)
            }
            ScenarioKind::Rocking => {
                mission::attitude(origin, AttitudeMotion::rocking(), self.attitude_duration_s)
            }
            ScenarioKind::Yaw => mission::attitude(
                origin,
                AttitudeMotion::yaw_turns(),
                self.attitude_duration_s,
            ),
        };
        m.with_still_s(self.still_s)
    }

    /// The environment at `origin`: the WMM field of the configured date,
    /// the water column and the current.
    pub fn environment(&self, origin: Origin) -> Result<Environment, ScenarioError> {
        let mut env = Environment::at(origin.lat_rad, origin.lon_rad, self.year, self.day_of_year)?;
        env.water = Water {
            temperature_c: self.water.temperature_c,
            salinity_psu: self.water.salinity_psu,
        };
        env.current = match (self.current, self.scenario) {
            (Some(c), _) => Current {
                mean_ned_m_s: c.mean_ned_m_s.into(),
                amplitude_ned_m_s: c.amplitude_ned_m_s.into(),
                period_s: c.period_s,
                phase_rad: 0.0,
            },
            (None, ScenarioKind::Lbl) => Current::lbl_default(),
            (None, _) => Current::none(),
        };
        env.current.validate()?;
        Ok(env)
    }
}

/// The truth and every sensor of a scenario, one simulator step at a time.
#[derive(Debug, Clone)]
pub struct Generator {
    sim: Simulator,
    suite: SensorSuite,
    end_s: f64,
}

impl Generator {
    /// A run of `params` from `origin` with `sensors`, seeded by `seed`, that
    /// ends when the mission does or after `duration_s` of simulated time,
    /// whichever comes first.
    pub fn new(
        params: &ScenarioParams,
        origin: Origin,
        sensors: SuiteConfig,
        seed: u64,
        duration_s: f64,
    ) -> Result<Self, ScenarioError> {
        params.validate()?;
        check("duration_s", duration_s, duration_s > 0.0)?;
        let env = params.environment(origin)?;
        let sim = Simulator::new(
            params.mission(origin),
            env,
            SimConfig {
                imu_rate_hz: params.imu_rate_hz,
                substeps: params.substeps,
                seed,
                ..SimConfig::default()
            },
        )?;
        let suite = SensorSuite::for_simulator(sensors, seed, &sim)?;
        Ok(Self {
            sim,
            suite,
            end_s: duration_s,
        })
    }

    /// The measurements of the next step, or `None` once the run is over.
    pub fn step(&mut self) -> Option<Result<Measurements, SuiteError>> {
        let next_t = self.sim.truth().t_s + self.sim.dt_s();
        if self.sim.finished() || next_t > self.end_s + 0.5 * self.sim.dt_s() {
            return None;
        }
        let (truth, imu) = self.sim.step();
        Some(self.suite.step(&truth, &imu))
    }

    /// Registers an LBL interrogation ([`SensorSuite::interrogate`]).
    pub fn interrogate(&mut self, transponder_id: u32, stamp_ns: u64) -> Result<(), SuiteError> {
        self.suite.interrogate(transponder_id, stamp_ns)
    }

    /// The truth simulator.
    pub fn simulator(&self) -> &Simulator {
        &self.sim
    }

    /// The sensor suite.
    pub fn suite(&self) -> &SensorSuite {
        &self.suite
    }

    /// Simulated time of the last step, s.
    pub fn t_s(&self) -> f64 {
        self.sim.truth().t_s
    }

    /// The configured end, s.
    pub fn end_s(&self) -> f64 {
        self.end_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(params: &ScenarioParams, seed: u64, duration_s: f64) -> (u64, f64, Measurements) {
        let mut g = Generator::new(
            params,
            Origin::lisbon(),
            params.sensors_preset(),
            seed,
            duration_s,
        )
        .unwrap();
        let mut n = 0;
        let mut last = None;
        while let Some(m) = g.step() {
            last = Some(m.unwrap());
            n += 1;
        }
        (n, g.t_s(), last.unwrap())
    }

    #[test]
    fn a_run_ends_at_its_duration_or_at_the_end_of_the_mission() {
        let p = ScenarioParams::default();
        let (n, t, last) = count(&p, 1, 12.0);
        assert_eq!(n, 1200);
        assert!((t - 12.0).abs() < 1e-9);
        assert_eq!(last.stamp_ns, 12_000_000_000);
        let short = ScenarioParams {
            scenario: ScenarioKind::Still,
            attitude_duration_s: 3.0,
            ..p
        };
        let (n, _, _) = count(&short, 1, 100.0);
        assert_eq!(n, 300);
    }

    #[test]
    fn the_vehicle_rests_during_the_still_period() {
        let p = ScenarioParams::default();
        let mut g = Generator::new(&p, Origin::lisbon(), p.sensors_preset(), 3, 30.0).unwrap();
        let mut max_rate_still = 0.0f64;
        let mut moved_after = 0.0f64;
        while let Some(m) = g.step() {
            let m = m.unwrap();
            let t = m.stamp_ns as f64 * 1e-9;
            let rate = nalgebra::Vector3::from(m.truth.rate_nb_body_rad_s).norm();
            if t < p.still_s {
                max_rate_still = max_rate_still.max(rate);
                assert!(m.truth.distance_m < 1e-9, "moved at {t}");
            } else {
                moved_after = m.truth.distance_m;
            }
        }
        // Only the Earth-relative attitude is held; no rotation while still.
        assert!(max_rate_still < 1e-12, "{max_rate_still}");
        assert!(moved_after > 5.0, "{moved_after}");
    }

    #[test]
    fn presets_follow_the_scenario() {
        let lbl = ScenarioParams {
            scenario: ScenarioKind::Lbl,
            lbl_layout: LblLayout::Four,
            ..Default::default()
        };
        let c = lbl.sensors_preset();
        assert!(c.lbl.enabled && !c.dvl.enabled && c.lbl.transponders.len() == 4);
        let env = lbl.environment(Origin::lisbon()).unwrap();
        assert!(env.current.mean_ned_m_s.norm() > 0.1);
        assert!(!ScenarioParams::default().sensors_preset().lbl.enabled);
    }

    #[test]
    fn bad_parameters_are_refused_by_name() {
        for (p, name) in [
            (
                ScenarioParams {
                    still_s: -1.0,
                    ..Default::default()
                },
                "still_s",
            ),
            (
                ScenarioParams {
                    dr_manoeuvre: 4,
                    ..Default::default()
                },
                "dr_manoeuvre",
            ),
            (
                ScenarioParams {
                    survey: SurveyParams {
                        speed_m_s: f64::NAN,
                        ..Default::default()
                    },
                    ..Default::default()
                },
                "survey.speed_m_s",
            ),
        ] {
            match p.validate() {
                Err(ScenarioError::Invalid { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{name}: {other:?}"),
            }
        }
    }
}
