//! `nauta bench chaos`: the survey in `wall` clock at a multiple of real time
//! (DESIGN §7) while a seeded script kills a random estimator with SIGKILL
//! every few seconds of wall time. It reports the kills, the restarts the
//! launcher recorded, the time from each kill to the restarted process's first
//! output, what the consumers lost, and the attitude error against the truth
//! beside a run of the same mission without kills (`--fast`, deterministic).
//!
//! The estimators run with `restart = on-failure` and warm-start from their
//! snapshots (docs/design-notes.md, "Supervision"). Both runs are read from
//! the launcher's JSON summary (`nauta launch --json`): the attitude error is
//! its `errors` (`nauta eval`'s computation), the losses its `gaps` and
//! `lost`. The bench itself follows the estimators' outputs
//! (`attitude/estimate`, `ains/nav`, `positioning/fix`) for what only a
//! consumer sees: stamps missing or repeated across the restarts (fixes come
//! one per buoy message and surface GPS fix, so theirs are counted against
//! the reference run's) and each instance's first output, the restart
//! latency of a killed attitude or ains. A positioning publishes a fix only
//! every 30 s of mission; its restart latency is to its first watermark on
//! `positioning/progress`, when it processes inputs again. Once the sensor
//! has ended its stream nothing more is killed: the run drains, and the
//! launcher restarts nothing then (a kill of an estimator that is finishing
//! failed one run of five on 2026-12-03).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context as _, bail};
use nauta_messages::*;
use nauta_runtime::ports::Inbox;
use nauta_runtime::{ClockMode, Context, Manifest, Namespace, Subscriber, services};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::json;

use nauta_launcher::pipeline;

/// Options of `nauta bench chaos`.
#[derive(Debug, Clone, clap::Args)]
pub struct ChaosArgs {
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// The manifest to run.
    #[arg(long, default_value = "launch/survey.toml")]
    pub manifest: PathBuf,
    /// Mission seconds (default: the whole mission).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Multiple of real time.
    #[arg(long, default_value_t = 10.0)]
    pub rate: f64,
    /// Seed of the kill script (and of the run).
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
    /// Shortest wall time between two kills, s.
    #[arg(long, default_value_t = 5.0)]
    pub min_interval: f64,
    /// Longest wall time between two kills, s.
    #[arg(long, default_value_t = 15.0)]
    pub max_interval: f64,
    /// The attitude variant to run.
    #[arg(long, default_value = "mekf")]
    pub variant: String,
    /// Write the run's log (the launcher's and every process's stderr, the
    /// run with kills only) to this file instead of discarding it.
    #[arg(long, value_name = "FILE")]
    pub log: Option<PathBuf>,
}

/// The estimators' output streams the bench follows, each with the process
/// that publishes it in the shipped manifests.
const FOLLOWED: [(&str, &str); 3] = [
    (ATTITUDE_ESTIMATE_SERVICE, "attitude"),
    (NAV_SOLUTION_SERVICE, "ains"),
    (POSITION_FIX_SERVICE, "positioning"),
];

/// Follows the estimators' outputs and the run events.
struct Follower {
    estimates: Subscriber<AttitudeEstimate>,
    nav: Subscriber<NavSolution>,
    fixes: Subscriber<PositionFix>,
    /// The positioning's watermarks: its first one is a restarted
    /// instance's first sign of work.
    positioning_progress: Subscriber<Progress>,
    /// The sensor's watermarks: after its end of stream the run drains, and
    /// the launcher restarts nothing more (a kill then fails the run).
    sensor_progress: Subscriber<Progress>,
    sensor_ended: bool,
    events: Subscriber<RunEvent>,
    _inboxes: [Inbox; 6],
    /// Every stamp of each followed stream, in arrival order.
    stamps: [Vec<u64>; 3],
    /// First arrival of each (process, instance).
    first_of_instance: BTreeMap<(&'static str, u32), Instant>,
    /// Run events: (kind, process, instance).
    events_seen: Vec<(u32, String, u32)>,
}

impl Follower {
    fn new(ctx: &Context) -> anyhow::Result<Self> {
        let (estimates, a) = ctx.subscriber(&services::attitude_estimate())?;
        let (nav, b) = ctx.subscriber(&services::nav_solution())?;
        let (fixes, c) = ctx.subscriber(&services::position_fix())?;
        let (positioning_progress, d) = ctx.subscriber(&services::progress(Role::Positioning))?;
        let (sensor_progress, f) = ctx.subscriber(&services::progress(Role::Sensor))?;
        let (events, e) = ctx.subscriber(&services::run_events())?;
        Ok(Self {
            estimates,
            nav,
            fixes,
            positioning_progress,
            sensor_progress,
            sensor_ended: false,
            events,
            _inboxes: [a, b, c, d, e, f],
            stamps: [Vec::new(), Vec::new(), Vec::new()],
            first_of_instance: BTreeMap::new(),
            events_seen: Vec::new(),
        })
    }

    fn poll(&mut self) -> anyhow::Result<()> {
        let now = Instant::now();
        let first = &mut self.first_of_instance;
        let [att, nav, fix] = &mut self.stamps;
        self.estimates.drain(|e| {
            first
                .entry((FOLLOWED[0].1, e.header.instance))
                .or_insert(now);
            att.push(e.header.stamp_ns);
        })?;
        self.nav.drain(|n| {
            first
                .entry((FOLLOWED[1].1, n.header.instance))
                .or_insert(now);
            nav.push(n.header.stamp_ns);
        })?;
        self.fixes.drain(|f| fix.push(f.header.stamp_ns))?;
        self.positioning_progress.drain(|p| {
            if !p.header.is_end_of_stream() {
                first
                    .entry((FOLLOWED[2].1, p.header.instance))
                    .or_insert(now);
            }
        })?;
        let ended = &mut self.sensor_ended;
        self.sensor_progress
            .drain(|p| *ended |= p.header.is_end_of_stream())?;
        let seen = &mut self.events_seen;
        self.events.drain(|e| {
            seen.push((e.kind, fixed_str(&e.process), e.instance));
        })?;
        Ok(())
    }
}

/// Stamps missing from a stream (after its first, at its smallest step) and
/// stamps received twice or going backwards.
fn missing_and_repeated(stamps: &[u64]) -> (u64, u64) {
    let repeated = stamps.windows(2).filter(|w| w[1] <= w[0]).count() as u64;
    let mut sorted = stamps.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    let Some(period) = sorted.windows(2).map(|w| w[1] - w[0]).min() else {
        return (0, repeated);
    };
    let missing = sorted.windows(2).map(|w| (w[1] - w[0]) / period - 1).sum();
    (missing, repeated)
}

/// Fixes missing against the reference run's count, plus stamps received
/// twice or going backwards.
fn fixes_lost(stamps: &[u64], reference: u64) -> u64 {
    let repeated = stamps.windows(2).filter(|w| w[1] <= w[0]).count() as u64;
    let mut unique = stamps.to_vec();
    unique.sort_unstable();
    unique.dedup();
    reference.saturating_sub(unique.len() as u64) + repeated
}

/// Messages of `stream` in a launcher's JSON summary (0 when absent).
fn stream_messages(summary: &serde_json::Value, stream: &str) -> u64 {
    summary["streams"][stream]["messages"].as_u64().unwrap_or(0)
}

/// RMS roll, pitch, yaw (degrees) of `attitude/estimate` in a JSON summary,
/// and the samples compared.
fn summary_rms(summary: &serde_json::Value) -> Option<([f64; 3], u64)> {
    let e = summary.get("errors")?.get(ATTITUDE_ESTIMATE_SERVICE)?;
    let num = |key: &str| e.get(key)?.as_f64();
    Some((
        [
            num("roll_rms_deg")?,
            num("pitch_rms_deg")?,
            num("yaw_rms_deg")?,
        ],
        e.get("samples")?.as_u64()?,
    ))
}

fn launch_args(a: &ChaosArgs, extra: &[&str]) -> Vec<String> {
    let mut v: Vec<String> = vec![
        "launch".into(),
        a.manifest.display().to_string(),
        "--json".into(),
    ];
    v.extend(extra.iter().map(|s| s.to_string()));
    v.extend([
        "--seed".into(),
        a.seed.to_string(),
        "--set".into(),
        format!("attitude.variant=\"{}\"", a.variant),
    ]);
    if let Some(d) = a.duration {
        v.extend(["--duration".into(), format!("{d:?}")]);
    }
    v
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i]
}

/// Runs the benchmark.
pub fn run(a: &ChaosArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        a.min_interval > 0.0 && a.max_interval >= a.min_interval,
        "--min-interval and --max-interval must satisfy 0 < min <= max"
    );
    let exe = std::env::current_exe()?;
    // The reference: the same mission without kills, deterministic.
    if !a.json {
        eprintln!("nauta bench chaos: reference run (--fast, no kills)");
    }
    let reference = Command::new(&exe)
        .args(launch_args(a, &["--fast"]))
        .stderr(Stdio::null())
        .output()
        .context("cannot run the reference")?;
    let ref_out = String::from_utf8_lossy(&reference.stdout).into_owned();
    anyhow::ensure!(
        reference.status.success(),
        "the reference run failed: {ref_out}"
    );
    let ref_summary = super::summary(&ref_out).context("the reference run")?;
    let ref_fixes = stream_messages(&ref_summary, POSITION_FIX_SERVICE);
    let (ref_rms, _) =
        summary_rms(&ref_summary).context("no attitude error in the reference summary")?;

    let ns = Namespace::unique();
    let mut settings = Context::settings(Role::Test);
    settings.process = "chaos".into();
    settings.clock = ClockMode::Wall { rate: a.rate };
    let ctx = Context::new(&ns, settings)?;
    let mut follower = Follower::new(&ctx)?;
    let rate = format!("{:?}", a.rate);
    let args = launch_args(
        a,
        &[
            "--clock",
            "wall",
            "--rate",
            &rate,
            "--namespace",
            ns.as_str(),
        ],
    );
    // Every estimator restarts as often as it is killed.
    let mut args = args;
    for name in Manifest::load(&a.manifest)?.processes.keys() {
        if name != Role::Sensor.name() && name != "logger" {
            args.extend([
                "--set".into(),
                format!(
                    "{name}.restart={{ policy = \"on-failure\", max = 1000, window_s = 60, backoff_ms = [0, 100] }}"
                ),
            ]);
        }
    }
    let stderr = match &a.log {
        Some(path) => Stdio::from(
            std::fs::File::create(path)
                .with_context(|| format!("cannot create the log {}", path.display()))?,
        ),
        None => Stdio::null(),
    };
    let mut child: Child = Command::new(&exe)
        .args(&args)
        .stdout(Stdio::piped())
        .stderr(stderr)
        .spawn()
        .context("cannot start the run")?;
    let mut rng = ChaCha8Rng::seed_from_u64(a.seed);
    let mut next_kill =
        Instant::now() + Duration::from_secs_f64(rng.random_range(a.min_interval..=a.max_interval));
    let mut kills: Vec<(Instant, String, u32)> = Vec::new();
    let started = Instant::now();
    let status = loop {
        follower.poll()?;
        if let Some(s) = child.try_wait()? {
            break s;
        }
        if Instant::now() >= next_kill && !follower.sensor_ended {
            next_kill = Instant::now()
                + Duration::from_secs_f64(rng.random_range(a.min_interval..=a.max_interval));
            // A random estimator that runs now (sources are not estimators).
            if let Ok(run) = pipeline::find(Some(ns.as_str())) {
                let candidates: Vec<&pipeline::ProcessStatus> = run
                    .processes
                    .iter()
                    .filter(|p| p.role != Role::Sensor.name() && p.pid > 0 && p.state == "running")
                    .collect();
                if !candidates.is_empty() {
                    let p = candidates[rng.random_range(0..candidates.len())];
                    // SAFETY: kill(2) on a process of the run this bench started.
                    unsafe {
                        libc::kill(p.pid as i32, libc::SIGKILL);
                    }
                    kills.push((Instant::now(), p.name.clone(), p.instance));
                    if !a.json {
                        eprintln!(
                            "nauta bench chaos: {:.0} s: killed {} (instance {}, pid {})",
                            started.elapsed().as_secs_f64(),
                            p.name,
                            p.instance,
                            p.pid
                        );
                    }
                }
            }
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    follower.poll()?;
    let mut out = String::new();
    if let Some(mut so) = child.stdout.take() {
        use std::io::Read;
        so.read_to_string(&mut out)?;
    }
    let summary = super::summary(&out).context("the run with kills")?;
    drop(follower.estimates);
    drop(follower.nav);
    drop(follower.fixes);
    drop(follower.positioning_progress);
    drop(follower.sensor_progress);
    let events = std::mem::take(&mut follower.events_seen);
    drop(follower.events);
    drop(follower._inboxes);
    ctx.finish();

    // Restart latency: kill to the first output of the next instance.
    let mut latencies: Vec<f64> = kills
        .iter()
        .filter_map(|(t, name, instance)| {
            let (_, process) = FOLLOWED.iter().find(|(_, p)| p == name)?;
            follower
                .first_of_instance
                .get(&(*process, instance + 1))
                .map(|first| first.duration_since(*t).as_secs_f64() * 1e3)
        })
        .collect();
    latencies.sort_by(f64::total_cmp);
    let restarts = events
        .iter()
        .filter(|(k, _, _)| *k == event_kind::RESTARTED)
        .count();
    let every_kill_restarted = kills.iter().all(|(_, name, instance)| {
        events
            .iter()
            .any(|(k, p, i)| *k == event_kind::RESTARTED && p == name && *i == instance + 1)
    });
    let completed = status.success() && summary["exit"] == "ok";
    if !completed {
        bail!("the run did not complete: {status}\n{summary:#}");
    }
    let (rms, compared) =
        summary_rms(&summary).context("no attitude error in the summary of the run")?;
    let change = rms
        .iter()
        .zip(ref_rms)
        .map(|(k, r)| 100.0 * (k - r).abs() / r.max(1e-9))
        .fold(0.0f64, f64::max);
    let count = |key: &str| summary[key].as_u64().unwrap_or(u64::MAX);
    let (gaps, in_processes) = (count("gaps"), count("lost"));
    let [(att_missing, att_repeated), (nav_missing, nav_repeated)] =
        [0, 1].map(|k| missing_and_repeated(&follower.stamps[k]));
    let lost_estimates = att_missing + att_repeated;
    let lost_nav = nav_missing + nav_repeated;
    let lost_fixes = fixes_lost(&follower.stamps[2], ref_fixes);
    let lost = lost_estimates
        .saturating_add(lost_nav)
        .saturating_add(lost_fixes)
        .saturating_add(gaps)
        .saturating_add(in_processes);
    let report = json!({
        "kills": kills.len(),
        "restarts": restarts,
        "every_kill_restarted": every_kill_restarted,
        "restart_p50_ms": percentile(&latencies, 0.5),
        "restart_max_ms": latencies.last().copied().unwrap_or(f64::NAN),
        "restart_latencies_measured": latencies.len(),
        "lost_messages": lost,
        "lost_per_consumer": {
            "attitude/estimate stream (missing or repeated stamps)": lost_estimates,
            "ains/nav stream (missing or repeated stamps)": lost_nav,
            "positioning/fix stream (missing against the reference, or repeated)": lost_fixes,
            "launcher taps (sequence gaps)": gaps,
            "inside processes (health dropped)": in_processes,
        },
        "metric_change_pct": change,
        "attitude_rms_deg": {"with_kills": rms, "reference": ref_rms},
        "compared_estimates": compared,
        "completed": completed,
        "rate": a.rate,
        "variant": a.variant,
        "wall_s": started.elapsed().as_secs_f64(),
    });
    if a.json {
        println!("{report}");
    } else {
        println!(
            "kills {} | restarts {} (every kill restarted: {every_kill_restarted}) | restart to first output p50 {:.0} ms, max {:.0} ms (target 1000 ms)",
            kills.len(),
            restarts,
            percentile(&latencies, 0.5),
            latencies.last().copied().unwrap_or(f64::NAN)
        );
        println!(
            "lost: {lost_estimates} estimate and {lost_nav} navigation stamps missing or repeated, {lost_fixes} fixes, {gaps} sequence gaps at the launcher, {in_processes} inside processes"
        );
        println!(
            "attitude rms roll/pitch/yaw {:.3}/{:.3}/{:.3}° with kills vs {:.3}/{:.3}/{:.3}° without: largest change {change:.2} % (target < 10 %)",
            rms[0], rms[1], rms[2], ref_rms[0], ref_rms[1], ref_rms[2]
        );
    }
    Ok(())
}
