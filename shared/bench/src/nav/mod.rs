//! `nauta bench nav [--json] [--quick]`: the aided INS's variants in process,
//! on the simulator, scored by `nauta eval`'s own code (issue 13, point 7).
//!
//! Each run feeds one estimator the simulator's sensor messages as the
//! service gets them: the wire messages of each step (`nauta_sim::wire`),
//! checked by the same conversions, in the service's tie order (IMU, DVL,
//! depth, GPS, AHRS); its `ains/nav` outputs, the truth and the GPS fixes go
//! through `nauta_tools::eval::Data::take` as a recording's bytes would, and
//! `eval::evaluate` gives the figures (`nauta eval`'s keys, dives included).
//!
//! - `dr`: paper 002's manoeuvres 1-3 over seeds 100-119 (`--quick`: 5):
//!   the first dive's realised error in % of the distance, its RMS over
//!   seeds, and the predictor's value at the same moment (paper 002:
//!   predicted 2.6 / 0.5 / 2.3 %, realised 3.2 / 1.6 / 2.8 %).
//! - `spikes`: manoeuvre 2, the same seeds with and without the simulator's
//!   DVL spikes (their own random stream), with and without the spike
//!   filter: the RMS over seeds of the end-position shift.
//! - `survey`: paper 000's survey with each variant, `aided` and `unaided`
//!   (without position aiding; `dr` has none, so both are the same run).
//! - `pf` and `ekf` on the same manoeuvres and seeds at the shipped 100 Hz
//!   IMU, the attitude PF feeding them.
//! - `realtime_factor`: mission seconds per second of the estimator's own
//!   time on the survey (the simulator's time not counted).
//! - `akit` (with `--akit DIR`): A-KIT's trajectories (module [`akit`]).
//! - `complete` (alone with `--complete`): the complete system with the
//!   positioning over seeds 100-109 and issue 14's robustness cases
//!   (module [`complete`]).
//!
//! Every variant takes the shipped survey manifest's parameters. The runs
//! over seeds share the machine's cores (each is its own seeded run, so the
//! figures do not depend on it); the survey's speed figures come from a run
//! alone.
//!
//! The `dr` scenarios run the IMU and the truth at 20 Hz (the `dr`'s own
//! sensors, AHRS 10 Hz, DVL 5 Hz, GPS 1 Hz, draw the same numbers at any IMU
//! rate: each sensor has its own random stream), as the accuracy test
//! `shared/estimation/tests/ains_dr` does; the survey runs at its 100 Hz.

use std::time::{Duration, Instant};

use anyhow::Context as _;
use serde_json::{Map, Value, json};

use nauta_estimation::Estimator;
use nauta_estimation::ains::dr::{DeadReckoning, DrParams, Site};
use nauta_estimation::ains::ekf::EkfParams;
use nauta_estimation::ains::pf::AinsPfParams;
use nauta_estimation::ains::{AinsCore, AinsInput, AinsParams};
use nauta_estimation::attitude_core::{AttitudeCore, VariantParams};
use nauta_estimation::readings::Nav;
use nauta_messages::checked::{Ahrs, Attitude, Depth, Dvl, Gps, Imu};
use nauta_messages::{
    AttitudeEstimate, GPS_SERVICE, Message, NavSolution, SensorMessage, TRUTH_SERVICE, TruthState,
    codec,
};
use nauta_runtime::Manifest;
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
use nauta_sim::suite::SuiteConfig;
use nauta_tools::eval::{self, Data, Metrics};

mod akit;
pub mod complete;

/// Arguments of `nauta bench nav`.
#[derive(Debug, clap::Args)]
pub struct NavArgs {
    /// Print one JSON object (keys in BENCHMARKS.md, "Aided INS").
    #[arg(long)]
    pub json: bool,
    /// Five seeds per manoeuvre instead of twenty.
    #[arg(long)]
    pub quick: bool,
    /// A-KIT's `Data/` directory (its `TrajectoryN/` subdirectories; github
    /// `ansfl/A-KIT`, read from a local copy): `dr` and naive 1 Hz dead
    /// reckoning on each trajectory.
    #[arg(long, value_name = "DIR")]
    pub akit: Option<std::path::PathBuf>,
    /// Only the complete system (issue 14: sensor, attitude, ains,
    /// positioning) over seeds 100-109 (`--quick`: 100-102), its
    /// robustness cases and the positioning's speed.
    #[arg(long)]
    pub complete: bool,
    /// The complete system's seeds instead of 100-109: a range `A-B`
    /// (inclusive) or a list `A,B,C` (tuning uses the development seeds
    /// 7-9; the benchmark's are 100-199).
    #[arg(long, value_name = "SEEDS", value_parser = parse_seeds)]
    pub seeds: Option<Seeds>,
}

/// The seeds `--seeds` names (a newtype: clap would take a `Vec` for
/// several occurrences of the option).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Seeds(pub Vec<u64>);

/// `A-B` (inclusive) or `A,B,...`: at least one seed, at most 1000.
fn parse_seeds(s: &str) -> Result<Seeds, String> {
    let number = |x: &str| {
        x.trim()
            .parse::<u64>()
            .map_err(|e| format!("{x:?} is not a seed: {e}"))
    };
    let seeds: Vec<u64> = match s.split_once('-') {
        Some((a, b)) => {
            let (a, b) = (number(a)?, number(b)?);
            if b < a {
                return Err(format!("{s:?}: the range ends before it starts"));
            }
            (a..=b).collect()
        }
        None => s.split(',').map(number).collect::<Result<_, _>>()?,
    };
    if seeds.is_empty() || seeds.len() > 1000 {
        return Err(format!("{s:?}: between 1 and 1000 seeds"));
    }
    Ok(Seeds(seeds))
}

/// The seeds of the complete system's runs (100-199 are the benchmark's).
fn complete_seeds(args: &NavArgs) -> Vec<u64> {
    args.seeds
        .clone()
        .map(|s| s.0)
        .unwrap_or_else(|| (100..if args.quick { 103 } else { 110 }).collect())
}

/// The seeds of the benchmarks over seeds (100-199 are the benchmark's).
fn seeds(quick: bool) -> Vec<u64> {
    (100..if quick { 105 } else { 120 }).collect()
}

/// One in-process run: what eval makes of it, its outputs, and time.
#[derive(Debug)]
pub struct Run {
    /// The evaluation of `ains/nav` against the truth.
    pub metrics: Metrics,
    /// Every solution, in order.
    pub nav: Vec<Nav>,
    /// Mission seconds simulated.
    pub mission_s: f64,
    /// Time spent in the estimator's `on_input`.
    pub estimator: Duration,
    /// IMU samples the attitude estimator took and the time it spent, when
    /// it ran.
    pub attitude: Option<(u64, Duration)>,
}

/// The service's order of inputs at one stamp (services/ains: IMU, DVL,
/// depth, GPS, AHRS), and each wire message as the input it becomes.
fn input_of(m: &SensorMessage) -> Option<(u8, AinsInput)> {
    Some(match m {
        SensorMessage::Imu(w) => (0, AinsInput::Imu(Imu::try_from(w).ok()?)),
        SensorMessage::Dvl(w) => (1, AinsInput::Dvl(Dvl::try_from(w).ok()?)),
        SensorMessage::Depth(w) => (2, AinsInput::Depth(Depth::try_from(w).ok()?)),
        SensorMessage::Gps(w) => (3, AinsInput::Gps(Gps::try_from(w).ok()?)),
        SensorMessage::Ahrs(w) => (4, AinsInput::Ahrs(Ahrs::try_from(w).ok()?)),
        _ => return None,
    })
}

pub(crate) fn take<M: Message>(data: &mut Data, topic: &str, m: &M) -> anyhow::Result<()> {
    data.take(topic, M::TYPE_NAME, &codec::encode(m)?);
    Ok(())
}

/// One stamp's inputs of the aided INS in the service's order: the
/// sensor's, then the attitude estimate of the attitude estimator that runs
/// on the stamp's IMU sample (when one runs), as the service declares it.
#[derive(Debug, Default)]
pub struct StepInputs {
    inputs: Vec<(u8, AinsInput)>,
    reports: Vec<<AttitudeCore as Estimator>::Output>,
    /// IMU samples the attitude estimator took, and the time it spent.
    pub attitude_samples: u64,
    pub attitude_spent: Duration,
}

impl StepInputs {
    /// The inputs of `wire` (one stamp's messages); `each` sees every
    /// message first (the truth and GPS for eval).
    pub fn collect(
        &mut self,
        wire: &[SensorMessage],
        mut attitude: Option<&mut AttitudeCore>,
        mut each: impl FnMut(&SensorMessage) -> anyhow::Result<()>,
    ) -> anyhow::Result<()> {
        self.inputs.clear();
        for m in wire {
            each(m)?;
            self.inputs.extend(input_of(m));
            if let (SensorMessage::Imu(w), Some(core)) = (m, attitude.as_deref_mut())
                && let Ok(imu) = Imu::try_from(w)
            {
                self.reports.clear();
                let t0 = Instant::now();
                let _ = core.on_input(&imu, &mut self.reports);
                self.attitude_spent += t0.elapsed();
                self.attitude_samples += 1;
                for r in &self.reports {
                    if let Ok(a) = Attitude::try_from(&AttitudeEstimate::from(r)) {
                        self.inputs.push((5, AinsInput::Attitude(a)));
                    }
                }
            }
        }
        self.inputs.sort_by_key(|(order, _)| *order);
        Ok(())
    }

    /// The inputs collected, in order.
    pub fn inputs(&self) -> impl Iterator<Item = &AinsInput> {
        self.inputs.iter().map(|(_, i)| i)
    }
}

/// Runs each of `estimators` over `scenario` with `sensors` and `seed`, on
/// the same sensor data; with `attitude`, that estimator runs on the IMU too
/// and its estimates are the `attitude/estimate` input (after the sensor's
/// inputs of the same stamp, as the service declares it).
pub fn run_all<E>(
    scenario: &ScenarioParams,
    sensors: SuiteConfig,
    seed: u64,
    estimators: &mut [E],
    mut attitude: Option<&mut AttitudeCore>,
) -> anyhow::Result<Vec<Run>>
where
    E: Estimator<Input = AinsInput, Output = Nav>,
{
    let mut g =
        Generator::new(scenario, Origin::lisbon(), sensors, seed, 1e6).context("the scenario")?;
    let n = estimators.len();
    let mut data: Vec<Data> = (0..n).map(|_| Data::default()).collect();
    let mut nav: Vec<Vec<Nav>> = vec![Vec::new(); n];
    let mut spent = vec![Duration::ZERO; n];
    let (mut wire, mut step_inputs, mut out) = (Vec::new(), StepInputs::default(), Vec::new());
    let mut last_stamp = 0;
    while let Some(step) = g.step() {
        let step = step.context("a simulator step")?;
        wire.clear();
        nauta_sim::wire::to_wire(&step, &mut wire);
        step_inputs.collect(&wire, attitude.as_deref_mut(), |m| {
            for d in data.iter_mut() {
                match m {
                    SensorMessage::Truth(t) => take::<TruthState>(d, TRUTH_SERVICE, t)?,
                    SensorMessage::Gps(f) => take(d, GPS_SERVICE, f)?,
                    _ => {}
                }
            }
            Ok(())
        })?;
        for (k, estimator) in estimators.iter_mut().enumerate() {
            for input in step_inputs.inputs() {
                out.clear();
                let t0 = Instant::now();
                // A refusal (a spike, a gated fix) is counted by the service;
                // here it only means the input was not used.
                let _ = estimator.on_input(input, &mut out);
                spent[k] += t0.elapsed();
                for o in &out {
                    take(&mut data[k], "ains/nav", &NavSolution::from(o))?;
                }
                nav[k].extend_from_slice(&out);
            }
        }
        last_stamp = step.stamp_ns;
    }
    let mut runs = Vec::with_capacity(n);
    for ((mut d, nav), spent) in data.into_iter().zip(nav).zip(spent) {
        eval::live::sort(&mut d);
        let evaluation = eval::evaluate(std::path::Path::new("(in process)"), &d)?;
        let metrics = evaluation
            .streams
            .get("ains/nav")
            .cloned()
            .context("the estimator published no solution")?;
        runs.push(Run {
            metrics,
            nav,
            mission_s: last_stamp as f64 * 1e-9,
            estimator: spent,
            attitude: attitude
                .is_some()
                .then_some((step_inputs.attitude_samples, step_inputs.attitude_spent)),
        });
    }
    Ok(runs)
}

/// [`run_all`] with one estimator.
pub fn run<E>(
    scenario: &ScenarioParams,
    sensors: SuiteConfig,
    seed: u64,
    estimator: E,
    attitude: Option<&mut AttitudeCore>,
) -> anyhow::Result<Run>
where
    E: Estimator<Input = AinsInput, Output = Nav>,
{
    run_all(scenario, sensors, seed, &mut [estimator], attitude)?
        .pop()
        .context("no run")
}

/// The shipped survey manifest: the bench runs what a vehicle runs (the
/// attitude's parameters and magnetometer calibration, the aided INS's).
const SURVEY_MANIFEST: &str = include_str!("../../../../launch/survey.toml");

/// The survey manifest, parsed.
pub fn survey_manifest() -> anyhow::Result<Manifest> {
    Manifest::parse(std::path::Path::new("launch/survey.toml"), SURVEY_MANIFEST)
}

/// The survey's attitude `pf`, as `nauta-attitude` builds it from the manifest.
pub fn survey_attitude() -> anyhow::Result<AttitudeCore> {
    let m = survey_manifest()?;
    let params = VariantParams::Pf(m.params("attitude", Some("pf"))?);
    let site = m.site.clone().context("launch/survey.toml has no [site]")?;
    AttitudeCore::new(
        &params,
        site.latitude_deg.to_radians(),
        site.magnetic_declination_deg.to_radians(),
    )
}

/// The simulator's site (origin and the declination its magnetometer and
/// AHRS have there).
pub fn site(scenario: &ScenarioParams, sensors: SuiteConfig, seed: u64) -> anyhow::Result<Site> {
    let g = Generator::new(scenario, Origin::lisbon(), sensors, seed, 1e6)?;
    let o = g.simulator().mission().origin();
    Ok(Site {
        lat_rad: o.lat_rad,
        lon_rad: o.lon_rad,
        declination_rad: g.suite().declination_rad(),
    })
}

fn dr_scenario(manoeuvre: u8) -> ScenarioParams {
    ScenarioParams {
        scenario: ScenarioKind::Dr,
        dr_manoeuvre: manoeuvre,
        imu_rate_hz: 20.0,
        ..Default::default()
    }
}

/// `dr` on `scenario` with `params`.
fn run_dr(
    scenario: &ScenarioParams,
    sensors: SuiteConfig,
    seed: u64,
    params: &DrParams,
) -> anyhow::Result<Run> {
    let dr = DeadReckoning::new(params, site(scenario, sensors.clone(), seed)?)?;
    run(scenario, sensors, seed, dr, None)
}

/// `f` of every job, in the jobs' order, on as many threads as the machine
/// has cores: each job is its own seeded run, so the figures do not depend
/// on the thread count (only the wall time does).
pub(crate) fn par_map<J: Sync, R: Send>(
    jobs: &[J],
    f: impl Fn(&J) -> anyhow::Result<R> + Sync,
) -> anyhow::Result<Vec<R>> {
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .clamp(1, jobs.len().max(1));
    let next = AtomicUsize::new(0);
    let results: Vec<Mutex<Option<anyhow::Result<R>>>> =
        jobs.iter().map(|_| Mutex::new(None)).collect();
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(job) = jobs.get(i) else { break };
                    let r = f(job);
                    if let Ok(mut slot) = results[i].lock() {
                        *slot = Some(r);
                    }
                }
            });
        }
    });
    results
        .into_iter()
        .map(|m| {
            m.into_inner()
                .map_err(|_| anyhow::anyhow!("a benchmark thread panicked"))?
                .context("a job did not run")?
        })
        .collect()
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// The first dive's realised error and the predictor's value then, both in
/// % of the distance submerged.
fn first_dive_pct(m: &Metrics) -> Option<(f64, f64)> {
    let d = m.dives.as_ref()?.first()?;
    Some((d.error_pct?, 100.0 * d.predicted_error_m? / d.distance_m))
}

/// Paper 002's manoeuvres: realised RMS over seeds and mean prediction, %.
fn dr_manoeuvres(quick: bool, progress: bool) -> anyhow::Result<Map<String, Value>> {
    let mut out = Map::new();
    for m in 1..=3u8 {
        let scenario = dr_scenario(m);
        let per_seed = par_map(&seeds(quick), |&seed| {
            let r = run_dr(
                &scenario,
                scenario.sensors_preset(),
                seed,
                &survey_dr_params()?,
            )?;
            let (e, p) = first_dive_pct(&r.metrics)
                .with_context(|| format!("manoeuvre {m}, seed {seed}: no dive"))?;
            if progress {
                eprintln!("  dr manoeuvre {m} seed {seed}: realised {e:.2} %, predicted {p:.2} %");
            }
            Ok((e, p))
        })?;
        let realised: Vec<f64> = per_seed.iter().map(|x| x.0).collect();
        let predicted_pct = per_seed.iter().map(|x| x.1).sum::<f64>() / per_seed.len() as f64;
        out.insert(
            m.to_string(),
            json!({ "dr": {
                "realised_rms_pct": rms(&realised),
                "predicted_pct": predicted_pct,
                "seeds": realised.len(),
            }}),
        );
    }
    Ok(out)
}

/// The `dr` parameters of the shipped survey manifest.
fn survey_dr_params() -> anyhow::Result<DrParams> {
    survey_manifest()?.params("ains", Some("dr"))
}

/// The `pf`, `ekf` and `dr` variants at `site` with the shipped survey
/// manifest's parameters (what a vehicle runs) and `position_aiding`.
pub fn variant_cores(site: Site, position_aiding: bool) -> anyhow::Result<Vec<AinsCore>> {
    let m = survey_manifest()?;
    let pf = AinsPfParams {
        position_aiding,
        ..m.params("ains", Some("pf"))?
    };
    let ekf = EkfParams {
        position_aiding,
        ..m.params("ains", Some("ekf"))?
    };
    Ok(vec![
        AinsCore::new(&AinsParams::Pf(pf), site)?,
        AinsCore::new(&AinsParams::Ekf(ekf), site)?,
        AinsCore::new(&AinsParams::Dr(m.params("ains", Some("dr"))?), site)?,
    ])
}

/// `pf` and `ekf` on paper 002's manoeuvres at the shipped 100 Hz IMU, with
/// the attitude PF feeding them, over the same seeds as `dr`: the RMS over
/// seeds of the first dive's error, %, beside `dr`'s entry.
fn filters_on_manoeuvres(
    out: &mut Map<String, Value>,
    quick: bool,
    progress: bool,
) -> anyhow::Result<()> {
    for m in 1..=3u8 {
        let scenario = ScenarioParams {
            imu_rate_hz: 100.0,
            ..dr_scenario(m)
        };
        let per_seed = par_map(&seeds(quick), |&seed| {
            let mut attitude = survey_attitude()?;
            let mut cores = variant_cores(site(&scenario, scenario.sensors_preset(), seed)?, true)?;
            cores.truncate(2);
            let runs = run_all(
                &scenario,
                scenario.sensors_preset(),
                seed,
                &mut cores,
                Some(&mut attitude),
            )?;
            let mut errors = Vec::new();
            for (k, r) in runs.iter().enumerate() {
                let e = r
                    .metrics
                    .dives
                    .as_ref()
                    .and_then(|d| d.first())
                    .and_then(|d| d.error_pct)
                    .with_context(|| format!("manoeuvre {m}, seed {seed}: no dive"))?;
                if progress {
                    eprintln!(
                        "  {} manoeuvre {m} seed {seed}: realised {e:.3} %",
                        cores[k].variant()
                    );
                }
                errors.push(e);
            }
            Ok(errors)
        })?;
        let entry = out
            .entry(m.to_string())
            .or_insert_with(|| json!({}))
            .as_object_mut()
            .context("an object")?;
        for (k, v) in ["pf", "ekf"].iter().enumerate() {
            let realised: Vec<f64> = per_seed.iter().map(|e| e[k]).collect();
            entry.insert(
                v.to_string(),
                json!({ "realised_rms_pct": rms(&realised), "seeds": realised.len() }),
            );
        }
    }
    Ok(())
}

/// The horizontal distance between two solutions, m (exact plane at the first).
fn shift_m(a: &Nav, b: &Nav) -> f64 {
    let (n, e) =
        nauta_estimation::local::flat::to_local(a.lat_rad, a.lon_rad, b.lat_rad, b.lon_rad);
    n.hypot(e)
}

/// The last solution before the end of the first dive.
fn dive_end(r: &Run) -> Option<Nav> {
    let end = r.metrics.dives.as_ref()?.first()?.end_stamp_ns;
    r.nav.iter().rev().find(|n| n.stamp_ns < end).copied()
}

/// Paper 002 Fig. 5: the spikes' end shift with and without the filter.
fn spikes(quick: bool, progress: bool) -> anyhow::Result<Value> {
    let scenario = dr_scenario(2);
    let spiky = scenario.sensors_preset();
    let mut clean = spiky.clone();
    clean.dvl.noise.spike_probability = 0.0;
    let filtered = survey_dr_params()?;
    let unfiltered = DrParams {
        spike_filter: false,
        ..filtered
    };
    let shifts = par_map(&seeds(quick), |&seed| {
        let end = |sensors: &SuiteConfig, params: &DrParams| -> anyhow::Result<Nav> {
            dive_end(&run_dr(&scenario, sensors.clone(), seed, params)?).context("no dive end")
        };
        let reference_f = end(&clean, &filtered)?;
        let reference_u = end(&clean, &unfiltered)?;
        let f = shift_m(&end(&spiky, &filtered)?, &reference_f);
        let u = shift_m(&end(&spiky, &unfiltered)?, &reference_u);
        if progress {
            eprintln!("  spikes seed {seed}: shift {f:.3} m filtered, {u:.3} m unfiltered");
        }
        Ok((f, u))
    })?;
    let with: Vec<f64> = shifts.iter().map(|x| x.0).collect();
    let without: Vec<f64> = shifts.iter().map(|x| x.1).collect();
    let (f, u) = (rms(&with), rms(&without));
    Ok(json!({ "dr": {
        "filtered_shift_m": f,
        "unfiltered_shift_m": u,
        "ratio": f / u,
        "seeds": with.len(),
    }}))
}

/// The eval keys of a run, as `nauta eval --json` prints them.
fn eval_keys(m: &Metrics) -> anyhow::Result<Value> {
    Ok(serde_json::to_value(m)?)
}

/// Runs the benchmark and prints its figures.
pub fn run_bench(args: &NavArgs) -> anyhow::Result<()> {
    let progress = !args.json;
    let t0 = Instant::now();
    let survey = ScenarioParams::default();
    anyhow::ensure!(
        survey.scenario == ScenarioKind::Survey,
        "the default scenario is not the survey"
    );
    if args.complete {
        let complete = complete::complete_section(&complete_seeds(args), progress)?;
        let result = json!({ "complete": complete, "wall_s": t0.elapsed().as_secs_f64() });
        if args.json {
            println!("{result}");
        } else {
            print_complete(&result["complete"]);
        }
        return Ok(());
    }
    // A-KIT first: it takes seconds, and a wrong directory fails at once.
    let akit = match &args.akit {
        Some(dir) => Value::Object(akit::akit_trajectories(dir, progress)?),
        None => Value::Null,
    };
    // Every variant on the same survey data, the shipped attitude PF
    // feeding `attitude/estimate`; its speed at its shipped particle count
    // is the attitude figure. These runs have no positioning (the complete
    // system is `complete`, below), so `aided` and `unaided` are the same
    // run here.
    let mut attitude = survey_attitude()?;
    let site7 = site(&survey, survey.sensors_preset(), 7)?;
    let mut cores = variant_cores(site7, false)?;
    let runs = run_all(
        &survey,
        survey.sensors_preset(),
        7,
        &mut cores,
        Some(&mut attitude),
    )?;
    let (att_n, att_t) = runs[0].attitude.context("the attitude ran")?;
    let attitude_rate = att_n as f64 / att_t.as_secs_f64().max(1e-12);
    if progress {
        eprintln!("survey, seed 7: attitude pf {attitude_rate:.0} samples/s");
    }
    let (mut survey_eval, mut realtime) = (Map::new(), Map::new());
    for (core, r) in cores.iter().zip(&runs) {
        let x = r.mission_s / r.estimator.as_secs_f64().max(1e-12);
        if progress {
            eprintln!(
                "survey, seed 7: {} {:.0} s of mission, {x:.0}x real time in process",
                core.variant(),
                r.mission_s
            );
        }
        survey_eval.insert(core.variant().to_owned(), eval_keys(&r.metrics)?);
        realtime.insert(core.variant().to_owned(), json!(x));
    }
    let mut dr = dr_manoeuvres(args.quick, progress)?;
    filters_on_manoeuvres(&mut dr, args.quick, progress)?;
    let spikes = spikes(args.quick, progress)?;
    let complete = complete::complete_section(&complete_seeds(args), progress)?;
    let result = json!({
        "complete": complete,
        "survey": {
            "aided": survey_eval,
            "unaided": survey_eval,
        },
        "dr": dr,
        "spikes": spikes,
        "akit": akit,
        "realtime_factor": realtime,
        "attitude_pf_samples_per_s": attitude_rate,
        "wall_s": t0.elapsed().as_secs_f64(),
    });
    if args.json {
        println!("{result}");
    } else {
        print_table(&result);
    }
    Ok(())
}

fn print_complete(c: &Value) {
    let Some(v) = c.as_object() else { return };
    let f = |x: &Value| x.as_f64().unwrap_or(f64::NAN);
    for (name, m) in v {
        if !m.is_object() {
            continue;
        }
        let k = |key: &str| &m[key];
        println!(
            "complete {name:<32} ains/nav N/E/D RMS {:.2} / {:.2} / {:.3} m (worst {:.2} / {:.2}), velocity {:.4} / {:.4} / {:.4} m/s, truth in 95 % {:.0} %; fix in 95 % {:.0} %; buoy fixes {:.2} m; thirds {:.2} -> {:.2} m; outliers {} of {} refused; positioning {:.0}x real time; {} seeds",
            f(&k("nav.north_rms_m")["mean"]),
            f(&k("nav.east_rms_m")["mean"]),
            f(&k("nav.down_rms_m")["mean"]),
            f(&k("nav.north_rms_m")["worst"]),
            f(&k("nav.east_rms_m")["worst"]),
            f(&k("nav.vel_north_rms_m_s")["mean"]),
            f(&k("nav.vel_east_rms_m_s")["mean"]),
            f(&k("nav.vel_down_rms_m_s")["mean"]),
            f(&k("nav.inside_95_pct")["mean"]),
            f(&k("fix.inside_95_pct")["mean"]),
            f(k("buoy_fix_horizontal_rms_m")),
            f(k("first_third_horizontal_rms_m")),
            f(k("last_third_horizontal_rms_m")),
            k("outliers_refused"),
            k("outliers"),
            f(k("positioning_realtime_factor")),
            k("seeds"),
        );
    }
    println!(
        "(issue 14 targets: N and E <= 1.0 m, D <= 0.03 m, velocity <= 0.010 m/s, last third <= 1.5x the first; robustness <= 2 m horizontal, >= 95 % of the outliers refused; fixes 90-98 % inside; positioning >= 1000x; paper 000: 1.54 / 2.38 / 0.03 m)"
    );
}

fn print_table(r: &Value) {
    println!("aided INS, in process on the simulator (nauta eval's figures)");
    if let Some(v) = r["survey"]["aided"].as_object() {
        for (variant, m) in v {
            println!(
                "survey {variant:<4} horizontal RMS {:.2} m, truth in the 95 % region {:.1} %, velocity RMS N/E/D {:.4} / {:.4} / {:.4} m/s, dive drift {:.2} m/km, slope N/E/D {} m/km",
                m["horizontal_rms_m"].as_f64().unwrap_or(f64::NAN),
                m["inside_95_pct"].as_f64().unwrap_or(f64::NAN),
                m["vel_north_rms_m_s"].as_f64().unwrap_or(f64::NAN),
                m["vel_east_rms_m_s"].as_f64().unwrap_or(f64::NAN),
                m["vel_down_rms_m_s"].as_f64().unwrap_or(f64::NAN),
                m["dive_drift_m_per_km"].as_f64().unwrap_or(f64::NAN),
                m["drift_slope_m_per_km"]
                    .as_array()
                    .map(|a| a
                        .iter()
                        .map(|x| format!("{:.2}", x.as_f64().unwrap_or(f64::NAN)))
                        .collect::<Vec<_>>()
                        .join(" / "))
                    .unwrap_or_default(),
            );
        }
    }
    if let Some(v) = r["dr"].as_object() {
        for (m, per) in v {
            let d = &per["dr"];
            println!(
                "manoeuvre {m}: dr realised RMS {:.2} %, predicted {:.2} % over {} seeds; pf {:.2} %, ekf {:.2} % over {} (paper 002: realised 3.2 / 1.6 / 2.8 %, predicted 2.6 / 0.5 / 2.3 %)",
                d["realised_rms_pct"].as_f64().unwrap_or(f64::NAN),
                d["predicted_pct"].as_f64().unwrap_or(f64::NAN),
                d["seeds"],
                per["pf"]["realised_rms_pct"].as_f64().unwrap_or(f64::NAN),
                per["ekf"]["realised_rms_pct"].as_f64().unwrap_or(f64::NAN),
                per["pf"]["seeds"],
            );
        }
    }
    let s = &r["spikes"]["dr"];
    println!(
        "spikes, manoeuvre 2: end shift RMS {:.3} m filtered, {:.3} m unfiltered, ratio {:.3} (target <= 0.10)",
        s["filtered_shift_m"].as_f64().unwrap_or(f64::NAN),
        s["unfiltered_shift_m"].as_f64().unwrap_or(f64::NAN),
        s["ratio"].as_f64().unwrap_or(f64::NAN),
    );
    if let Some(v) = r["akit"].as_object() {
        let (mut dr, mut naive) = (Vec::new(), Vec::new());
        for (n, t) in v {
            let (d, v) = (
                t["dr"]["final_error_pct"].as_f64().unwrap_or(f64::NAN),
                t["naive_dr_pct"].as_f64().unwrap_or(f64::NAN),
            );
            println!("A-KIT trajectory {n}: dr {d:.3} %, naive 1 Hz DR {v:.3} % of the distance");
            if let Some(e) = t["ekf_imu"]["final_error_pct"].as_f64() {
                println!("A-KIT trajectory {n}: ekf with the IMU {e:.3} %");
            }
            dr.push(d);
            naive.push(v);
        }
        let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len().max(1) as f64;
        println!(
            "A-KIT mean: dr {:.3} %, naive {:.3} % (target: dr below naive, aiming at 0.45 %)",
            mean(&dr),
            mean(&naive)
        );
    }
    print_complete(&r["complete"]);
    if let Some(v) = r["realtime_factor"].as_object() {
        for (variant, x) in v {
            println!(
                "speed {variant}: {:.0}x real time in process",
                x.as_f64().unwrap_or(f64::NAN)
            );
        }
    }
    println!(
        "attitude pf: {:.0} samples/s in process (target >= 100,000)",
        r["attitude_pf_samples_per_s"].as_f64().unwrap_or(f64::NAN)
    );
    println!("{:.0} s", r["wall_s"].as_f64().unwrap_or(f64::NAN));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--seeds` takes a range or a list and refuses the rest by name.
    #[test]
    fn seeds_parse_as_a_range_or_a_list() {
        assert_eq!(parse_seeds("7-9"), Ok(Seeds(vec![7, 8, 9])));
        assert_eq!(parse_seeds("100,105"), Ok(Seeds(vec![100, 105])));
        assert_eq!(parse_seeds("4"), Ok(Seeds(vec![4])));
        for bad in ["9-7", "a-3", "1,,2", "", "0-1000"] {
            assert!(parse_seeds(bad).is_err(), "{bad:?}");
        }
    }

    /// The in-process run is the service's: one solution per AHRS and DVL
    /// sample of `dr` (the inputs that trigger it), and eval finds the
    /// manoeuvre's one dive with the predictor's value at its end.
    #[test]
    fn a_dr_manoeuvre_runs_in_process_and_eval_finds_its_dive() {
        let scenario = dr_scenario(1);
        let r = run_dr(
            &scenario,
            scenario.sensors_preset(),
            100,
            &DrParams::default(),
        )
        .expect("run");
        let dives = r.metrics.dives.as_ref().expect("dives");
        assert_eq!(dives.len(), 1, "{dives:?}");
        let (realised, predicted) = first_dive_pct(&r.metrics).expect("a dive with a prediction");
        assert!(realised > 0.0 && predicted > 0.0, "{realised} {predicted}");
        assert_eq!(r.metrics.samples as usize, r.nav.len());
        assert!(r.mission_s > 600.0, "{}", r.mission_s);
        assert!(dive_end(&r).is_some());
    }
}
