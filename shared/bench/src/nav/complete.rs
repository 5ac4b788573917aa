//! Paper 000's complete navigation system in process (issue 14, point 4):
//! the simulator's sensors, the attitude PF, the aided INS and the
//! positioning, wired as `launch/survey.toml` wires the processes.
//!
//! At each stamp, as the estimator shell orders ties: the aided INS takes
//! the sensor's inputs and the attitude estimate and publishes `ains/nav`;
//! the positioning takes that solution (an aiding input), then the depth,
//! GPS and modem readings, and publishes `positioning/fix`; the aided INS
//! takes those fixes last (its optional aiding input). Every message goes
//! through its wire type and the checked conversion, as between processes,
//! and `nauta eval`'s own code scores both streams.

use std::time::{Duration, Instant};

use anyhow::Context as _;
use serde_json::{Map, Value, json};

use nauta_estimation::ains::{AinsCore, AinsInput};
use nauta_estimation::attitude_core::AttitudeCore;
use nauta_estimation::positioning::{Positioning, PositioningInput, PositioningStats};
use nauta_estimation::readings::{Fix, Nav};
use nauta_estimation::{Estimator, Stamped as _};
use nauta_messages::checked::{BuoyRangeReading, Depth, Gps};
use nauta_messages::{GPS_SERVICE, NavSolution, PositionFix, SensorMessage, TRUTH_SERVICE};
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioParams};
use nauta_sim::suite::SuiteConfig;
use nauta_tools::eval::{self, Data, Metrics};

use super::{StepInputs, take};

/// A measured range this much longer than the truth is one of the
/// simulator's multipath outliers (+20 to +200 m; the direct path's errors
/// are metres), m.
const OUTLIER_EXCESS_M: f64 = 15.0;

/// What one run of the complete system gave.
#[derive(Debug)]
pub struct CompleteRun {
    /// `nauta eval`'s figures of `ains/nav`.
    pub nav: Metrics,
    /// Its figures of `positioning/fix`, when the positioning ran and
    /// published.
    pub fix: Option<Metrics>,
    /// Mission seconds simulated.
    pub mission_s: f64,
    /// Time spent in the positioning's `on_input`.
    pub positioning: Duration,
    /// The positioning's counters.
    pub stats: PositioningStats,
    /// Buoy messages received, those that were multipath outliers, and
    /// the outliers the positioning refused.
    pub messages: u64,
    pub outliers: u64,
    pub outliers_refused: u64,
    /// Per solution: mission time, s, and its north and east error against
    /// the truth of its step, m.
    pub nav_errors: Vec<[f64; 3]>,
    /// Per buoy fix: mission time, s, north and east error against the
    /// truth of the step it came in (at most one step, 10 ms, after its
    /// stamp), m, and its north, east σ, m, and correlation.
    pub fix_errors: Vec<[f64; 6]>,
}

/// North and east of `(lat, lon)` from the truth, m.
fn error_m(truth: &nauta_sim::suite::TruthReading, lat_rad: f64, lon_rad: f64) -> [f64; 2] {
    let (n, e) =
        nauta_estimation::local::flat::to_local(truth.lat_rad, truth.lon_rad, lat_rad, lon_rad);
    [n, e]
}

/// The positioning's side of the cycle: its inputs in, its fixes to the
/// aided INS, and the counts.
#[derive(Debug, Default)]
struct Cycle {
    fixes: Vec<Fix>,
    spent: Duration,
    messages: u64,
    outliers: u64,
    outliers_refused: u64,
    errors: Vec<[f64; 6]>,
}

impl Cycle {
    fn feed(
        &mut self,
        pos: &mut Positioning,
        ains: &mut AinsCore,
        inputs: &[PositioningInput],
        step: &nauta_sim::suite::Measurements,
        data: &mut Data,
    ) -> anyhow::Result<()> {
        for input in inputs {
            self.fixes.clear();
            let t0 = Instant::now();
            let refused = pos.on_input(input, &mut self.fixes).is_err();
            self.spent += t0.elapsed();
            if let (PositioningInput::Modem(b), Some(truth)) = (input, &step.modem) {
                self.messages += 1;
                let outlier =
                    b.time_of_flight_s * b.sound_speed_m_s > truth.true_range_m + OUTLIER_EXCESS_M;
                self.outliers += u64::from(outlier);
                self.outliers_refused += u64::from(outlier && refused);
            }
            for f in &self.fixes {
                if f.source == nauta_estimation::positioning::source::BUOY {
                    let [en, ee] = error_m(&step.truth, f.lat_rad, f.lon_rad);
                    let t = f.stamp_ns as f64 * 1e-9;
                    self.errors
                        .push([t, en, ee, f.std_north_m, f.std_east_m, f.corr_ne]);
                }
                let wire = PositionFix::from(f);
                take(data, "positioning/fix", &wire)?;
                if let Ok(f) = Fix::try_from(&wire) {
                    let mut more = Vec::new();
                    // A gated fix is counted by the aided INS.
                    let _ = ains.on_input(&AinsInput::Fix(f), &mut more);
                    for n in &more {
                        take(data, "ains/nav", &NavSolution::from(n))?;
                    }
                }
            }
        }
        Ok(())
    }
}

/// The positioning's sensor inputs among a step's messages `wire`: those
/// stamped before the step's `stamp_ns` (a buoy message, stamped at its
/// reception between two steps), and the others (depth, GPS).
pub fn positioning_inputs(
    wire: &[SensorMessage],
    stamp_ns: u64,
) -> (Vec<PositioningInput>, Vec<PositioningInput>) {
    let (mut early, mut late) = (Vec::new(), Vec::new());
    for m in wire {
        let input = match m {
            SensorMessage::Depth(w) => Depth::try_from(w).ok().map(PositioningInput::Depth),
            SensorMessage::Gps(w) => Gps::try_from(w).ok().map(PositioningInput::Gps),
            SensorMessage::Modem(w) => BuoyRangeReading::try_from(w)
                .ok()
                .map(PositioningInput::Modem),
            _ => None,
        };
        if let Some(i) = input {
            if i.stamp_ns() < stamp_ns {
                early.push(i);
            } else {
                late.push(i);
            }
        }
    }
    (early, late)
}

/// Runs the complete system over `scenario` with `sensors` and `seed`;
/// without `positioning`, the aided INS alone (no fixes).
pub fn run_complete(
    scenario: &ScenarioParams,
    sensors: SuiteConfig,
    seed: u64,
    ains: &mut AinsCore,
    mut positioning: Option<&mut Positioning>,
    attitude: &mut AttitudeCore,
) -> anyhow::Result<CompleteRun> {
    let mut g =
        Generator::new(scenario, Origin::lisbon(), sensors, seed, 1e6).context("the scenario")?;
    let mut data = Data::default();
    let mut step_inputs = StepInputs::default();
    let (mut wire, mut nav) = (Vec::new(), Vec::<Nav>::new());
    let mut cycle = Cycle::default();
    let mut nav_errors = Vec::new();
    let mut last_stamp = 0;
    while let Some(step) = g.step() {
        let step = step.context("a simulator step")?;
        wire.clear();
        nauta_sim::wire::to_wire(&step, &mut wire);
        step_inputs.collect(&wire, Some(&mut *attitude), |m| match m {
            SensorMessage::Truth(t) => take(&mut data, TRUTH_SERVICE, t),
            SensorMessage::Gps(f) => take(&mut data, GPS_SERVICE, f),
            _ => Ok(()),
        })?;
        // The positioning's sensor inputs: a buoy message is stamped at its
        // reception, between the simulator's steps, so it comes before this
        // step's solution; the depth and GPS come with it, after it.
        let (early, mut late) = if positioning.is_some() {
            positioning_inputs(&wire, step.stamp_ns)
        } else {
            (Vec::new(), Vec::new())
        };
        if let Some(pos) = positioning.as_deref_mut() {
            cycle.feed(pos, ains, &early, &step, &mut data)?;
        }
        nav.clear();
        for input in step_inputs.inputs() {
            // A refusal (a spike, a gated fix) is counted by the service;
            // here it only means the input was not used.
            let _ = ains.on_input(input, &mut nav);
        }
        for n in &nav {
            take(&mut data, "ains/nav", &NavSolution::from(n))?;
            let [en, ee] = error_m(&step.truth, n.lat_rad, n.lon_rad);
            nav_errors.push([n.stamp_ns as f64 * 1e-9, en, ee]);
        }
        if let Some(pos) = positioning.as_deref_mut() {
            let mut inputs: Vec<PositioningInput> = nav
                .iter()
                .filter_map(|n| Nav::try_from(&NavSolution::from(n)).ok())
                .map(PositioningInput::Nav)
                .collect();
            inputs.append(&mut late);
            cycle.feed(pos, ains, &inputs, &step, &mut data)?;
        }
        last_stamp = step.stamp_ns;
    }
    eval::live::sort(&mut data);
    let mut evaluation = eval::evaluate(std::path::Path::new("(in process)"), &data)?;
    let nav = evaluation
        .streams
        .remove("ains/nav")
        .context("the aided INS published no solution")?;
    Ok(CompleteRun {
        nav,
        fix: evaluation.streams.remove("positioning/fix"),
        mission_s: last_stamp as f64 * 1e-9,
        positioning: cycle.spent,
        stats: positioning.map(|p| p.stats()).unwrap_or_default(),
        messages: cycle.messages,
        outliers: cycle.outliers,
        outliers_refused: cycle.outliers_refused,
        nav_errors,
        fix_errors: cycle.errors,
    })
}

/// The positioning variant `variant` with the manifest's parameters.
pub fn positioning_core(
    manifest: &nauta_runtime::Manifest,
    variant: &str,
) -> anyhow::Result<Positioning> {
    match variant {
        "ekf" => Positioning::ekf(&manifest.params("positioning", Some("ekf"))?),
        _ => Positioning::pf(&manifest.params("positioning", Some("pf"))?),
    }
}

/// A robustness case of issue 14: the survey's sensors changed.
type Case = (&'static str, fn(&mut SuiteConfig));

/// Issue 14's robustness cases, each alone and all together.
const CASES: [Case; 6] = [
    ("nominal", |_| {}),
    ("loss_30pct", |s| s.modem.noise.loss_probability = 0.3),
    ("sound_speed_plus_1pct", |s| {
        s.modem.noise.sound_speed_error = 0.01
    }),
    ("buoy_gps_5m", |s| s.modem.buoy_gps_sigma_m = 5.0),
    ("multipath_2pct", |s| {
        s.modem.noise.multipath_probability = 0.02
    }),
    ("all", |s| {
        s.modem.noise.loss_probability = 0.3;
        s.modem.noise.sound_speed_error = 0.01;
        s.modem.buoy_gps_sigma_m = 5.0;
        s.modem.noise.multipath_probability = 0.02;
    }),
];

/// Horizontal RMS of `errors` (`[t, north, east, ..]`) in `[from, to)` s.
fn horizontal_rms<const N: usize>(errors: &[[f64; N]], from: f64, to: f64) -> Option<f64> {
    let (mut sq, mut n) = (0.0, 0.0);
    for e in errors.iter().filter(|e| e[0] >= from && e[0] < to) {
        sq += e[1] * e[1] + e[2] * e[2];
        n += 1.0;
    }
    (n > 0.0).then(|| (sq / n).sqrt())
}

/// The figures of one run: eval's keys of both streams, the thirds of the
/// dive, the outliers, the positioning's speed.
fn figures(r: &CompleteRun) -> anyhow::Result<Value> {
    // The dive: from the first buoy fix to the last (the surface before
    // and after is GPS).
    let (from, to) = match (r.fix_errors.first(), r.fix_errors.last()) {
        (Some(a), Some(b)) => (a[0], b[0] + 1e-9),
        _ => (0.0, 0.0),
    };
    let third = (to - from) / 3.0;
    Ok(json!({
        "nav": serde_json::to_value(&r.nav)?,
        "fix": serde_json::to_value(&r.fix)?,
        "first_third_horizontal_rms_m": horizontal_rms(&r.nav_errors, from, from + third),
        "last_third_horizontal_rms_m": horizontal_rms(&r.nav_errors, to - third, to),
        "buoy_fix_horizontal_rms_m": horizontal_rms(&r.fix_errors, from, to),
        "messages": r.messages,
        "outliers": r.outliers,
        "outliers_refused": r.outliers_refused,
        "positioning_realtime_factor": r.mission_s / r.positioning.as_secs_f64().max(1e-12),
    }))
}

/// The mean and worst over seeds of the keys issue 14 judges.
fn summary(per_seed: &[(u64, Value)]) -> Value {
    const KEYS: [(&str, &str); 9] = [
        ("nav", "north_rms_m"),
        ("nav", "east_rms_m"),
        ("nav", "down_rms_m"),
        ("nav", "horizontal_rms_m"),
        ("nav", "vel_north_rms_m_s"),
        ("nav", "vel_east_rms_m_s"),
        ("nav", "vel_down_rms_m_s"),
        ("nav", "inside_95_pct"),
        ("fix", "inside_95_pct"),
    ];
    let mut out = Map::new();
    for (stream, key) in KEYS {
        let v: Vec<(u64, f64)> = per_seed
            .iter()
            .filter_map(|(s, f)| Some((*s, f[stream][key].as_f64()?)))
            .collect();
        let mean = v.iter().map(|x| x.1).sum::<f64>() / v.len().max(1) as f64;
        // The worst: the largest error, the coverage farthest from 95 %.
        let worst = v.iter().copied().max_by(|a, b| {
            let bad = |x: f64| {
                if key == "inside_95_pct" {
                    (x - 95.0).abs()
                } else {
                    x
                }
            };
            bad(a.1).total_cmp(&bad(b.1))
        });
        out.insert(
            format!("{stream}.{key}"),
            json!({ "mean": mean, "worst": worst.map(|w| w.1), "worst_seed": worst.map(|w| w.0) }),
        );
    }
    for key in [
        "buoy_fix_horizontal_rms_m",
        "first_third_horizontal_rms_m",
        "last_third_horizontal_rms_m",
        "positioning_realtime_factor",
    ] {
        let v: Vec<f64> = per_seed
            .iter()
            .filter_map(|(_, f)| f[key].as_f64())
            .collect();
        out.insert(
            key.to_owned(),
            json!(v.iter().sum::<f64>() / v.len().max(1) as f64),
        );
    }
    let (o, r) = per_seed.iter().fold((0, 0), |(o, r), (_, f)| {
        (
            o + f["outliers"].as_u64().unwrap_or(0),
            r + f["outliers_refused"].as_u64().unwrap_or(0),
        )
    });
    out.insert("outliers".into(), json!(o));
    out.insert("outliers_refused".into(), json!(r));
    out.insert("seeds".into(), json!(per_seed.len()));
    Value::Object(out)
}

/// Issue 14, point 4: the complete system (sensor, attitude `pf`, ains
/// `pf`, positioning `pf` and `ekf`) on the survey over `seeds`, each
/// robustness case with the shipped variant, and the DVL-aided INS alone
/// on the same seeds for reference.
pub fn complete_section(seeds: &[u64], progress: bool) -> anyhow::Result<Value> {
    let survey = ScenarioParams::default();
    let manifest = super::survey_manifest()?;
    let shipped = manifest
        .processes
        .get("positioning")
        .context("launch/survey.toml runs no positioning")?
        .variant
        .clone()
        .unwrap_or_else(|| "pf".to_owned());
    let mut jobs: Vec<(String, &'static str, u64)> = Vec::new();
    for &seed in seeds {
        for v in ["pf", "ekf", "none"] {
            jobs.push((v.to_owned(), "nominal", seed));
        }
        for (case, _) in &CASES[1..] {
            jobs.push((shipped.clone(), case, seed));
        }
    }
    let results = super::par_map(&jobs, |(variant, case, seed)| {
        let tweak = CASES
            .iter()
            .find(|c| c.0 == *case)
            .map(|c| c.1)
            .context("a case")?;
        let mut sensors = survey.sensors_preset();
        tweak(&mut sensors);
        let site = super::site(&survey, sensors.clone(), *seed)?;
        let aided = variant != "none";
        let mut ains = super::variant_cores(site, aided)?.swap_remove(0);
        let mut attitude = super::survey_attitude()?;
        let mut pos = if aided {
            Some(positioning_core(&manifest, variant)?)
        } else {
            None
        };
        let r = run_complete(
            &survey,
            sensors,
            *seed,
            &mut ains,
            pos.as_mut(),
            &mut attitude,
        )?;
        let f = figures(&r)?;
        if progress {
            eprintln!(
                "  complete {variant} {case} seed {seed}: ains/nav horizontal RMS {:.2} m, in 95 % {:.0} %; buoy fixes {:.2} m; outliers {} refused {}",
                f["nav"]["horizontal_rms_m"].as_f64().unwrap_or(f64::NAN),
                f["nav"]["inside_95_pct"].as_f64().unwrap_or(f64::NAN),
                f["buoy_fix_horizontal_rms_m"].as_f64().unwrap_or(f64::NAN),
                r.outliers,
                r.outliers_refused
            );
        }
        Ok(f)
    })?;
    let mut out = Map::new();
    for (variant, case) in [("pf", "nominal"), ("ekf", "nominal"), ("none", "nominal")]
        .into_iter()
        .chain(CASES[1..].iter().map(|c| (shipped.as_str(), c.0)))
    {
        let per_seed: Vec<(u64, Value)> = jobs
            .iter()
            .zip(&results)
            .filter(|((v, c, _), _)| v == variant && *c == case)
            .map(|((_, _, s), f)| (*s, f.clone()))
            .collect();
        let name = if case == "nominal" {
            variant.to_owned()
        } else {
            format!("{variant}.{case}")
        };
        out.insert(name, summary(&per_seed));
    }
    out.insert("shipped_variant".into(), json!(shipped));
    Ok(Value::Object(out))
}
