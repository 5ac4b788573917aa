//! `nauta bench lbl [--json] [--quick]`: the LBL role's estimator (paper
//! 003's EKF, `nauta-lbl`'s `ekf`) in process on the simulator's `lbl`
//! scenario, in closed loop with its transponders as the sensor runs them
//! in `sim` clock (`nauta_sim::lbl_inputs::LblLoop`), with the shipped
//! `launch/lbl.toml`'s parameters and site; `lbl/nav` goes through
//! `nauta_tools::eval` as a recording's bytes would (issue 15 point 7).
//!
//! Over seeds 100-199 (`--quick`: 100-102), each a whole mission:
//!
//! - per layout (2 and 4 transponders, `sensor.params.lbl_layout`): eval's
//!   horizontal RMS and truth inside the 95 % ellipse of `lbl/nav`, the p50
//!   of the 1σ ellipse's semi-major axis over every solution of every seed,
//!   the multipath replies the gate refused and the direct ones it refused,
//!   the current's RMS error from 5 minutes after the first range accepted;
//! - `sensor.params.sensors.lbl.blackout_s = [600, 1200]` (ten minutes
//!   without a reply): the interrogations after the blackout up to the first
//!   range accepted and up to the horizontal error back within 2× its p50 of
//!   the five minutes before, in cycles (one interrogation of each
//!   transponder), the worst seed;
//! - four transponders, one interrogation every 2 s (`interval_s = 2`), the
//!   same `Q`: the mean trace of `P_xy` from 60 s on with `selection =
//!   "fom"` over the same with `"round-robin"` (paper 003 §V-D).
//!
//! The smoothed figures are `nauta smooth`'s (issue 15 point 4): each
//! mission's inputs (as the closed loop fed them) go through the filter
//! again ([`nauta_estimation::lbl::forward_pass`]) and the command's own
//! backward pass ([`nauta_tools::smooth::track::smoothed_track`], the
//! bridged smoother), and eval scores the track on `smoother/lbl/nav` as it
//! scores `lbl/nav`: per layout `smoothed` holds the same figures as
//! `filter` and `rms_over_filter` (smoothed RMS over the filter's).
//! `smooth_2h_s` is `nauta bench smooth`'s (the passes over a 2-hour
//! mission, [`crate::smooth::smooth_2h`]).
//!
//! The IMU and the truth run at 20 Hz instead of the manifest's 100 Hz: the
//! LBL role takes no IMU, its sensors (AHRS, depth, propeller, 10 Hz) draw
//! the same numbers at any IMU rate (each has its own random stream), and
//! the truth is needed at the 10 Hz of `lbl/nav`.

use std::path::Path;
use std::time::Instant;

use anyhow::Context as _;
use serde_json::{Value, json};

use nauta_estimation::lbl::{Lbl, LblInput, LblOutput, LblParams, LblSite, LblStats, forward_pass};
use nauta_messages::{GPS_SERVICE, LblSolution, SensorMessage, TRUTH_SERVICE, TruthState};
use nauta_runtime::Manifest;
use nauta_runtime::manifest::apply_override;
use nauta_sim::lbl_inputs::LblLoop;
use nauta_sim::mission::Origin;
use nauta_sim::params::SensorParams;
use nauta_sim::scenario::Generator;
use nauta_sim::suite::LblLayout;
use nauta_tools::eval::{self, Data};
use nauta_tools::smooth::track::{TOPIC as SMOOTHED, smoothed_track};

use crate::nav::{par_map, take};

/// Arguments of `nauta bench lbl`.
#[derive(Debug, clap::Args)]
pub struct LblArgs {
    /// Print one JSON object (keys in the README and BENCHMARKS.md, "LBL").
    #[arg(long)]
    pub json: bool,
    /// Seeds 100-102 instead of 100-199.
    #[arg(long)]
    pub quick: bool,
}

/// The seeds (100-199 are the benchmarks').
fn seeds(quick: bool) -> Vec<u64> {
    (100..if quick { 103 } else { 200 }).collect()
}

/// The shipped manifest: the bench runs what a vehicle runs.
const MANIFEST: &str = include_str!("../../../launch/lbl.toml");

/// The ten minutes without a reply of issue 15's check, s.
pub const BLACKOUT_S: [f64; 2] = [600.0, 1200.0];

/// The current is scored from this long after the first range accepted, s.
const CURRENT_AFTER_S: f64 = 300.0;

/// The trace of `P_xy` is averaged from this stamp on, s (after the first
/// ranges have brought the start's uncertainty down).
const TRACE_FROM_S: f64 = 60.0;

/// What `launch/lbl.toml` with `overrides` (`--set` syntax) gives the
/// estimator and the simulator.
#[derive(Debug, Clone)]
pub struct Setup {
    /// `process.lbl`'s `ekf` parameters.
    pub params: LblParams,
    /// `[site]` as `nauta-lbl` reads it.
    pub site: LblSite,
    /// The sensor's parameters, its transponders the site's (as
    /// `nauta-sensor` takes them).
    pub sensor: SensorParams,
    /// `run.duration_s`.
    pub duration_s: f64,
}

impl Setup {
    /// The shipped manifest with `overrides` applied.
    pub fn new(overrides: &[String]) -> anyhow::Result<Self> {
        let path = Path::new("launch/lbl.toml");
        let mut table: toml::Table = toml::from_str(MANIFEST).context("launch/lbl.toml")?;
        for o in overrides {
            apply_override(&mut table, o).with_context(|| format!("--set {o}"))?;
        }
        let m = Manifest::parse(path, &toml::to_string(&table)?)?;
        let params: LblParams = m.params("lbl", Some("ekf"))?;
        let site = m.site.as_ref().context("launch/lbl.toml has no [site]")?;
        let place = "launch/lbl.toml: process.sensor.params";
        let mut sensor = SensorParams::from_table(m.params("sensor", None)?, place)?;
        sensor.sensors.lbl.transponders = site.transponders.clone();
        sensor.scenario.imu_rate_hz = 20.0;
        Ok(Self {
            params,
            site: site.lbl_site()?,
            sensor,
            duration_s: m.run.duration_s,
        })
    }

    /// The shipped manifest on `layout`, with `more` overrides.
    pub fn on(layout: LblLayout, more: &[&str]) -> anyhow::Result<Self> {
        let mut o = vec![format!("sensor.params.lbl_layout={}", layout.name())];
        o.extend(more.iter().map(|s| s.to_string()));
        Self::new(&o)
    }
}

/// One solution with what the truth says at its stamp.
#[derive(Debug, Clone, Copy)]
struct Solution {
    stamp_ns: u64,
    /// The 1σ ellipse's semi-major axis, m.
    major_m: f64,
    /// trace(P_xy), m².
    trace_m2: f64,
    /// The estimated current's error, north and east, m/s.
    current_error_m_s: [f64; 2],
    /// True depth, m.
    depth_m: f64,
}

/// What one mission gave.
#[derive(Debug, Clone)]
pub struct Run {
    /// eval's metrics of `lbl/nav`.
    pub metrics: eval::Metrics,
    /// eval's metrics of the smoothed track (`smoother/lbl/nav`).
    pub smoothed: eval::Metrics,
    /// The 1σ semi-major axis of every smoothed solution, m.
    pub smoothed_majors: Vec<f64>,
    /// eval's horizontal error of each solution: (stamp, m).
    pub errors: Vec<(u64, f64)>,
    solutions: Vec<Solution>,
    /// Every reply: (stamp, a multipath reply, refused by the gate).
    pub replies: Vec<(u64, bool, bool)>,
    /// Every interrogation's stamp.
    pub pings: Vec<u64>,
    /// The estimator's counters at the end.
    pub stats: LblStats,
    /// Transponders of the layout.
    pub transponders: usize,
    /// Mission seconds.
    pub mission_s: f64,
}

/// Runs `setup` at `seed`: the estimator and the simulator in lock step.
pub fn run(setup: &Setup, seed: u64) -> anyhow::Result<Run> {
    let s = &setup.site;
    let origin = Origin::from_degrees(s.origin_lat_rad.to_degrees(), s.origin_lon_rad.to_degrees());
    let mut g = Generator::new(
        &setup.sensor.scenario,
        origin,
        setup.sensor.sensors.clone(),
        seed,
        setup.duration_s,
    )
    .context("the scenario")?;
    let mut est = Lbl::new(&setup.params, setup.site.clone())?;
    let mut lp = LblLoop::new(setup.sensor.lbl_sync_hz);
    // The filter's inputs as the loop feeds them, for the smoother's
    // forward pass (a recording's logged inputs).
    let mut fed: Vec<(LblInput, Option<nauta_sim::suite::LblReplyReading>)> = Vec::new();
    // The origin a recording's `nauta.run` metadata carries: the site's.
    let mut data = Data::default();
    data.run.origin = Some(nauta_log::run::Found {
        value: nauta_log::run::GeoOrigin {
            lat_rad: s.origin_lat_rad,
            lon_rad: s.origin_lon_rad,
        },
        source: "launch/lbl.toml [site]".to_owned(),
    });
    let (mut solutions, mut replies, mut pings) = (Vec::new(), Vec::new(), Vec::new());
    let mut wire = Vec::new();
    let mut last = 0;
    while let Some((m, step)) = lp.step(&mut g, &mut est) {
        nauta_sim::lbl_inputs::inputs(&m, &mut fed);
        wire.clear();
        nauta_sim::wire::to_wire(&m, &mut wire);
        for w in &wire {
            match w {
                SensorMessage::Truth(t) => take::<TruthState>(&mut data, TRUTH_SERVICE, t)?,
                SensorMessage::Gps(f) => take(&mut data, GPS_SERVICE, f)?,
                _ => {}
            }
        }
        for o in &step.outputs {
            match o {
                LblOutput::Nav(n) => {
                    take(&mut data, "lbl/nav", &LblSolution::from(n))?;
                    let p = nalgebra::Matrix2::new(n.p[0][0], n.p[0][1], n.p[1][0], n.p[1][1]);
                    let c = m.truth.current_ned_m_s;
                    solutions.push(Solution {
                        stamp_ns: n.stamp_ns,
                        major_m: eval::compute::ellipse_axes(&p).0,
                        trace_m2: p.trace(),
                        current_error_m_s: [n.current_m_s[0] - c[0], n.current_m_s[1] - c[1]],
                        depth_m: m.truth.depth_m,
                    });
                }
                LblOutput::Ping(p) => pings.push(p.stamp_ns),
            }
        }
        for (reply, result) in &step.replies {
            let gated = result.as_ref().is_err_and(|e| e.kind == "gated");
            replies.push((reply.stamp_ns, reply.multipath, gated));
        }
        last = m.stamp_ns;
    }
    // `nauta smooth`: the filter forward again over the same inputs, then
    // the command's backward pass.
    let pass = forward_pass(
        Lbl::new(&setup.params, setup.site.clone())?,
        fed.iter().map(|(i, _)| i),
    );
    drop(fed);
    let track = smoothed_track(&pass).map_err(|e| anyhow::anyhow!("smoothing: {e}"))?;
    drop(pass);
    let mut smoothed_majors = Vec::with_capacity(track.solutions.len());
    for s in &track.solutions {
        take(&mut data, SMOOTHED, s)?;
        let p = nalgebra::Matrix2::new(s.p[0][0], s.p[0][1], s.p[1][0], s.p[1][1]);
        smoothed_majors.push(eval::compute::ellipse_axes(&p).0);
    }
    eval::live::sort(&mut data);
    let evaluation = eval::evaluate(Path::new("(in process)"), &data)?;
    let stream = |topic: &str| {
        evaluation
            .streams
            .get(topic)
            .cloned()
            .with_context(|| format!("{topic} not evaluated: {:?}", evaluation.skipped))
    };
    let metrics = stream("lbl/nav")?;
    let smoothed = stream(SMOOTHED)?;
    let errors = evaluation
        .series
        .get("lbl/nav")
        .map(|v| {
            v.iter()
                .filter_map(|e| Some((e.stamp_ns, e.ne_m?[0].hypot(e.ne_m?[1]))))
                .collect()
        })
        .unwrap_or_default();
    Ok(Run {
        metrics,
        smoothed,
        smoothed_majors,
        errors,
        solutions,
        replies,
        pings,
        stats: est.stats(),
        transponders: setup.site.layout.transponders().len(),
        mission_s: last as f64 * 1e-9,
    })
}

impl Run {
    /// RMS error of the current, m/s, submerged, from `CURRENT_AFTER_S`
    /// after the first range accepted; with the number of solutions.
    fn current_error(&self) -> (f64, usize) {
        let Some(first) = self.replies.iter().find(|r| !r.2).map(|r| r.0) else {
            return (f64::NAN, 0);
        };
        let from = first + (CURRENT_AFTER_S * 1e9) as u64;
        let (mut sq, mut n) = (0.0, 0);
        for s in self
            .solutions
            .iter()
            .filter(|s| s.stamp_ns >= from && s.depth_m > 1.0)
        {
            sq += s.current_error_m_s[0].powi(2) + s.current_error_m_s[1].powi(2);
            n += 1;
        }
        (sq, n)
    }

    /// Mean trace(P_xy) from `TRACE_FROM_S`, m².
    fn mean_trace(&self) -> f64 {
        let from = (TRACE_FROM_S * 1e9) as u64;
        let v: Vec<f64> = self
            .solutions
            .iter()
            .filter(|s| s.stamp_ns >= from)
            .map(|s| s.trace_m2)
            .collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    }

    /// After the blackout `[start, end]`: (interrogations up to the first
    /// range accepted, interrogations up to the horizontal error back
    /// within 2× its p50 of the five minutes before, that p50 in m);
    /// `None` when either never happens.
    pub fn blackout(&self, blackout_s: [f64; 2]) -> Option<(usize, usize, f64)> {
        let [start, end] = blackout_s.map(|t| (t * 1e9) as u64);
        let before = start.saturating_sub(300_000_000_000);
        let mut pre: Vec<f64> = self
            .errors
            .iter()
            .filter(|e| e.0 >= before && e.0 < start)
            .map(|e| e.1)
            .collect();
        pre.sort_by(f64::total_cmp);
        let p50 = *pre.get(pre.len() / 2)?;
        let accepted = self.replies.iter().find(|r| r.0 >= end && !r.2)?.0;
        let back = self
            .errors
            .iter()
            .find(|e| e.0 >= end && e.1 <= 2.0 * p50)?
            .0;
        let count = |until: u64| {
            self.pings
                .iter()
                .filter(|&&p| p >= end && p < until)
                .count()
        };
        Some((count(accepted), count(back), p50))
    }
}

/// What one job measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Job {
    /// The mission on a layout.
    Mission(LblLayout, u64),
    /// The mission with the blackout.
    Blackout(LblLayout, u64),
    /// Four transponders, one interrogation every 2 s, with `fom` (true)
    /// or `round-robin`.
    Selection(bool, u64),
}

/// The figures one job keeps (the runs themselves are large).
#[derive(Debug, Clone)]
struct Outcome {
    job: Job,
    rms_m: f64,
    inside_pct: f64,
    majors: Vec<f64>,
    /// The same of the smoothed track.
    smoothed_rms_m: f64,
    smoothed_inside_pct: f64,
    smoothed_majors: Vec<f64>,
    /// (multipath, of them gated, direct, of them gated).
    replies: [usize; 4],
    /// Σ squared current error, solutions.
    current: (f64, usize),
    mean_trace_m2: f64,
    blackout: Option<(usize, usize, f64)>,
    transponders: usize,
    timeouts: u64,
    crossings: u64,
    mission_s: f64,
}

fn run_job(job: Job) -> anyhow::Result<Outcome> {
    let blackout = format!(
        "sensor.params.sensors.lbl.blackout_s=[{:.1}, {:.1}]",
        BLACKOUT_S[0], BLACKOUT_S[1]
    );
    let (setup, seed) = match job {
        Job::Mission(layout, seed) => (Setup::on(layout, &[])?, seed),
        Job::Blackout(layout, seed) => (Setup::on(layout, &[&blackout])?, seed),
        Job::Selection(fom, seed) => {
            let sel = if fom { "fom" } else { "round-robin" };
            let sel = format!("lbl.params.selection={sel}");
            (
                Setup::on(LblLayout::Four, &["lbl.params.interval_s=2.0", &sel])?,
                seed,
            )
        }
    };
    let r = run(&setup, seed).with_context(|| format!("{job:?}"))?;
    let mut rep = [0; 4];
    for &(_, multipath, gated) in &r.replies {
        let i = if multipath { 0 } else { 2 };
        rep[i] += 1;
        rep[i + 1] += usize::from(gated);
    }
    Ok(Outcome {
        job,
        rms_m: r.metrics.horizontal_rms_m.unwrap_or(f64::NAN),
        inside_pct: r.metrics.inside_95_pct.unwrap_or(f64::NAN),
        majors: r.solutions.iter().map(|s| s.major_m).collect(),
        smoothed_rms_m: r.smoothed.horizontal_rms_m.unwrap_or(f64::NAN),
        smoothed_inside_pct: r.smoothed.inside_95_pct.unwrap_or(f64::NAN),
        smoothed_majors: r.smoothed_majors.clone(),
        replies: rep,
        current: r.current_error(),
        mean_trace_m2: r.mean_trace(),
        blackout: matches!(job, Job::Blackout(..))
            .then(|| r.blackout(BLACKOUT_S))
            .flatten(),
        transponders: r.transponders,
        timeouts: r.stats.timeouts,
        crossings: r.stats.baseline_crossings,
        mission_s: r.mission_s,
    })
}

fn pct(part: usize, whole: usize) -> f64 {
    100.0 * part as f64 / whole.max(1) as f64
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn max(v: impl Iterator<Item = f64>) -> f64 {
    v.fold(f64::NAN, f64::max)
}

fn min(v: impl Iterator<Item = f64>) -> f64 {
    v.fold(f64::NAN, f64::min)
}

/// Cycles of `n` interrogations (one of each transponder) holding `k`.
fn cycles(k: usize, n: usize) -> usize {
    k.div_ceil(n.max(1))
}

/// The track figures of `missions`: the p50 of the semi-major axes of
/// every solution, the RMS over seeds, the mean, worst and best inside
/// 95 %, of what `of` picks (RMS, inside 95 %, semi-major axes).
fn track_figures(missions: &[&Outcome], of: impl Fn(&Outcome) -> (f64, f64, &[f64])) -> Value {
    let n = missions.len();
    let rms = (missions.iter().map(|o| of(o).0.powi(2)).sum::<f64>() / n as f64).sqrt();
    let inside = missions.iter().map(|o| of(o).1).sum::<f64>() / n as f64;
    let majors = missions
        .iter()
        .flat_map(|o| of(o).2.iter().copied())
        .collect();
    json!({
        "ellipse_major_p50_m": median(majors),
        "horizontal_rms_m": rms,
        "inside_95_pct": inside,
        "horizontal_rms_worst_m": max(missions.iter().map(|o| of(o).0)),
        "inside_95_min_pct": min(missions.iter().map(|o| of(o).1)),
        "inside_95_max_pct": max(missions.iter().map(|o| of(o).1)),
    })
}

/// The figures of one layout's missions and blackouts.
fn layout_figures(missions: &[&Outcome], blackouts: &[&Outcome]) -> Value {
    let n = missions.len();
    let filter = track_figures(missions, |o| (o.rms_m, o.inside_pct, &o.majors));
    let mut smoothed = track_figures(missions, |o| {
        (o.smoothed_rms_m, o.smoothed_inside_pct, &o.smoothed_majors)
    });
    let ratio = |v: &Value| v["horizontal_rms_m"].as_f64().unwrap_or(f64::NAN);
    smoothed["rms_over_filter"] = (ratio(&smoothed) / ratio(&filter)).into();
    smoothed["rms_over_filter_worst_seed"] =
        max(missions.iter().map(|o| o.smoothed_rms_m / o.rms_m)).into();
    let mut rep = [0; 4];
    for o in missions {
        for (a, b) in rep.iter_mut().zip(o.replies) {
            *a += b;
        }
    }
    let (sq, k) = missions
        .iter()
        .fold((0.0, 0), |a, o| (a.0 + o.current.0, a.1 + o.current.1));
    let b: Vec<_> = blackouts.iter().filter_map(|o| o.blackout).collect();
    let tx = missions.first().map_or(1, |o| o.transponders);
    json!({
        "filter": filter,
        // `nauta smooth`'s track (issue 15 point 4).
        "smoothed": smoothed,
        "multipath_rejected_pct": pct(rep[1], rep[0]),
        "valid_rejected_pct": pct(rep[3], rep[2]),
        "multipath_replies": rep[0],
        "valid_replies": rep[2],
        "current_rms_error_m_s": (sq / k.max(1) as f64).sqrt(),
        "timeouts": missions.iter().map(|o| o.timeouts).sum::<u64>(),
        "baseline_crossings": missions.iter().map(|o| o.crossings).sum::<u64>(),
        "mission_s": missions.first().map_or(f64::NAN, |o| o.mission_s),
        "seeds": n,
        "blackout": {
            "reaccept_interrogations_max": b.iter().map(|x| x.0).max(),
            "recover_interrogations_max": b.iter().map(|x| x.1).max(),
            "reaccept_cycles_max": b.iter().map(|x| cycles(x.0, tx)).max(),
            "recover_cycles_max": b.iter().map(|x| cycles(x.1, tx)).max(),
            "recover_cycles_p50": median(b.iter().map(|x| cycles(x.1, tx) as f64).collect()),
            "pre_blackout_error_p50_m": median(b.iter().map(|x| x.2).collect()),
            "seeds": b.len(),
            "seeds_without_recovery": blackouts.len() - b.len(),
        },
    })
}

/// Runs the benchmark: the JSON object of the module docs.
pub fn measure(quick: bool, progress: bool) -> anyhow::Result<Value> {
    let t0 = Instant::now();
    let layouts = [LblLayout::Two, LblLayout::Four];
    let mut jobs = Vec::new();
    for &seed in &seeds(quick) {
        for layout in layouts {
            jobs.push(Job::Mission(layout, seed));
            jobs.push(Job::Blackout(layout, seed));
        }
        jobs.push(Job::Selection(true, seed));
        jobs.push(Job::Selection(false, seed));
    }
    let outcomes = par_map(&jobs, |&job| {
        let o = run_job(job)?;
        if progress {
            eprintln!(
                "  {job:?}: RMS {:.2} m, inside 95 % {:.1} %, mean trace {:.3} m², blackout {:?}",
                o.rms_m, o.inside_pct, o.mean_trace_m2, o.blackout
            );
        }
        Ok(o)
    })?;
    let mut per_layout = serde_json::Map::new();
    let (mut sq, mut k) = (0.0, 0);
    let (mut reaccept, mut recover) = (Vec::new(), Vec::new());
    for layout in layouts {
        let m: Vec<_> = outcomes
            .iter()
            .filter(|o| matches!(o.job, Job::Mission(l, _) if l == layout))
            .collect();
        let b: Vec<_> = outcomes
            .iter()
            .filter(|o| matches!(o.job, Job::Blackout(l, _) if l == layout))
            .collect();
        for o in &m {
            sq += o.current.0;
            k += o.current.1;
        }
        for o in &b {
            let (a, r) = o.blackout.map_or((None, None), |x| {
                (
                    Some(cycles(x.0, o.transponders)),
                    Some(cycles(x.1, o.transponders)),
                )
            });
            reaccept.push(a);
            recover.push(r);
        }
        per_layout.insert(
            layout.transponders().len().to_string(),
            layout_figures(&m, &b),
        );
    }
    let trace = |fom: bool| -> Vec<f64> {
        outcomes
            .iter()
            .filter(|o| matches!(o.job, Job::Selection(f, _) if f == fom))
            .map(|o| o.mean_trace_m2)
            .collect()
    };
    let (fom, rr) = (trace(true), trace(false));
    // After the missions: timed alone, as `nauta bench smooth` does.
    let smooth_2h_s = crate::smooth::smooth_2h()?.smooth_2h_s;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let ratios: Vec<f64> = fom.iter().zip(&rr).map(|(a, b)| a / b).collect();
    // The worst seed; a seed that never re-accepts or recovers is `null`.
    let worst = |v: &[Option<usize>]| -> Value {
        if v.iter().any(Option::is_none) {
            Value::Null
        } else {
            v.iter().flatten().max().copied().into()
        }
    };
    Ok(json!({
        "transponders": per_layout,
        "fom_over_round_robin_trace": mean(&fom) / mean(&rr),
        "fom_mean_trace_m2": mean(&fom),
        "round_robin_mean_trace_m2": mean(&rr),
        "fom_over_round_robin_worst_seed": max(ratios.iter().copied()),
        "fom_over_round_robin_p50_seed": median(ratios.clone()),
        "current_rms_error_m_s": (sq / k.max(1) as f64).sqrt(),
        "blackout_reaccept_cycles": worst(&reaccept),
        "blackout_recover_cycles": worst(&recover),
        "blackout_s": BLACKOUT_S,
        // `nauta smooth`'s passes over the 2-hour mission (issue 15 point 4).
        "smooth_2h_s": smooth_2h_s,
        "seeds": seeds(quick),
        "wall_s": t0.elapsed().as_secs_f64(),
    }))
}

/// `nauta bench lbl`.
pub fn run_bench(args: &LblArgs) -> anyhow::Result<()> {
    let r = measure(args.quick, !args.json)?;
    if args.json {
        println!("{r}");
    } else {
        print_table(&r);
    }
    Ok(())
}

fn print_table(r: &Value) {
    let f = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
    println!("LBL (paper 003's EKF) in process on the simulator, nauta eval's figures");
    if let Some(v) = r["transponders"].as_object() {
        for (n, l) in v {
            let fl = &l["filter"];
            let b = &l["blackout"];
            println!(
                "{n} transponders, {} seeds: ellipse semi-major p50 {:.2} m, horizontal RMS {:.3} m (worst seed {:.3}), \
                 inside 95 % {:.1} % ({:.1}-{:.1}); multipath refused {:.1} % of {}, valid refused {:.2} % of {}; \
                 current RMS {:.3} m/s; blackout: re-accepted within {} cycles, recovered within {} (p50 {})",
                l["seeds"],
                f(&fl["ellipse_major_p50_m"]),
                f(&fl["horizontal_rms_m"]),
                f(&fl["horizontal_rms_worst_m"]),
                f(&fl["inside_95_pct"]),
                f(&fl["inside_95_min_pct"]),
                f(&fl["inside_95_max_pct"]),
                f(&l["multipath_rejected_pct"]),
                l["multipath_replies"],
                f(&l["valid_rejected_pct"]),
                l["valid_replies"],
                f(&l["current_rms_error_m_s"]),
                b["reaccept_cycles_max"],
                b["recover_cycles_max"],
                b["recover_cycles_p50"],
            );
        }
    }
    println!(
        "figure of merit over round robin (4 transponders, a ping every 2 s): mean trace(P_xy) {:.4} / {:.4} m² = {:.3} (per seed: p50 {:.3}, worst {:.3}; issue 15: <= 0.8)",
        f(&r["fom_mean_trace_m2"]),
        f(&r["round_robin_mean_trace_m2"]),
        f(&r["fom_over_round_robin_trace"]),
        f(&r["fom_over_round_robin_p50_seed"]),
        f(&r["fom_over_round_robin_worst_seed"]),
    );
    println!(
        "current RMS error {:.3} m/s (issue 15: <= 0.06); blackout re-accept {} cycles (<= 3), recover {} cycles (<= 10)",
        f(&r["current_rms_error_m_s"]),
        r["blackout_reaccept_cycles"],
        r["blackout_recover_cycles"],
    );
    println!("{:.0} s", f(&r["wall_s"]));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The manifest's overrides reach the estimator and the simulator: four
    /// transponders for both, the blackout for the sensor, the selection
    /// for the filter.
    #[test]
    fn overrides_reach_both_sides() {
        let s = Setup::on(
            LblLayout::Four,
            &[
                "sensor.params.sensors.lbl.blackout_s=[600.0, 1200.0]",
                "lbl.params.selection=round-robin",
            ],
        )
        .expect("setup");
        assert_eq!(s.site.layout.transponders().len(), 4);
        assert_eq!(s.sensor.sensors.lbl.transponders.len(), 4);
        assert_eq!(s.sensor.sensors.lbl.blackout_s, Some([600.0, 1200.0]));
        assert_eq!(
            s.params.selection,
            nauta_estimation::lbl::Selection::RoundRobin
        );
        assert!(Setup::on(LblLayout::Two, &["lbl.params.nonsense=1"]).is_err());
    }

    /// A short run: eval scores `lbl/nav` at 10 Hz, every reply is seen, a
    /// blackout that the run does not reach gives no figure; the smoothed
    /// track has a solution at every one of the filter's, a smaller p50
    /// semi-major axis and a smaller RMS.
    #[test]
    fn a_short_run_is_scored_by_eval() {
        let mut s = Setup::on(LblLayout::Two, &[]).expect("setup");
        s.duration_s = 120.0;
        let r = run(&s, 100).expect("run");
        assert!((r.solutions.len() as f64 - 10.0 * r.mission_s).abs() < 20.0);
        assert_eq!(r.metrics.samples as usize, r.solutions.len());
        assert!(r.metrics.horizontal_rms_m.expect("rms") < 1.0);
        assert!(!r.replies.is_empty() && !r.pings.is_empty());
        assert!(r.blackout(BLACKOUT_S).is_none());
        assert_eq!(r.smoothed.samples, r.metrics.samples);
        assert_eq!(r.smoothed_majors.len(), r.solutions.len());
        let p50 = median(r.solutions.iter().map(|s| s.major_m).collect());
        assert!(median(r.smoothed_majors.clone()) < p50);
        let (f, s) = (r.metrics.horizontal_rms_m, r.smoothed.horizontal_rms_m);
        assert!(s.expect("smoothed rms") < f.expect("rms"), "{s:?} vs {f:?}");
    }
}
