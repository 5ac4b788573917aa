//! `nauta bench chaos`: the survey in `wall` clock at a multiple of real time
//! (DESIGN §7) while a seeded script kills a random estimator with SIGKILL
//! every few seconds of wall time. It reports the kills, the restarts the
//! launcher recorded, the time from each kill to the restarted process's first
//! output, what the consumers lost, and the attitude error against the truth
//! beside a run of the same mission without kills (`--fast`, deterministic).
//!
//! The estimators run with `restart = on-failure` and warm-start from their
//! snapshots (docs/design-notes.md, "Supervision"). Until `nauta eval` exists
//! (logger issue) the bench computes the error itself: it follows
//! `attitude/estimate` and `sim/truth` and pairs them by stamp.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context as _, bail};
use nalgebra::{Quaternion, UnitQuaternion};
use nauta_estimation::AttitudeError;
use nauta_messages::*;
use nauta_runtime::ports::Inbox;
use nauta_runtime::{ClockMode, Context, Namespace, Subscriber, services};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::json;

use crate::pipeline;

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
}

/// Error sums against the truth.
#[derive(Debug, Default, Clone, Copy)]
struct Rms {
    n: u64,
    sum_sq: [f64; 3],
}

impl Rms {
    fn push(&mut self, e: &AttitudeError) {
        self.n += 1;
        for (s, v) in self
            .sum_sq
            .iter_mut()
            .zip([e.roll_rad, e.pitch_rad, e.yaw_rad])
        {
            *s += v * v;
        }
    }

    fn deg(&self) -> [f64; 3] {
        self.sum_sq
            .map(|s| (s / self.n.max(1) as f64).sqrt().to_degrees())
    }
}

fn quat(q: [f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
}

/// Follows the attitude stream and the truth of the run.
struct Follower {
    estimates: Subscriber<AttitudeEstimate>,
    truth: Subscriber<TruthState>,
    events: Subscriber<RunEvent>,
    _inboxes: [Inbox; 3],
    truths: BTreeMap<u64, UnitQuaternion<f64>>,
    pending: Vec<AttitudeEstimate>,
    rms: Rms,
    last_stamp: Option<u64>,
    /// Stamps missing from the estimate stream (after its first).
    missing: u64,
    /// Stamps received twice or going backwards.
    repeated: u64,
    /// First arrival of each instance.
    first_of_instance: BTreeMap<u32, Instant>,
    /// Run events: (kind, process, instance).
    events_seen: Vec<(u32, String, u32)>,
    period_ns: u64,
}

impl Follower {
    fn new(ctx: &Context) -> anyhow::Result<Self> {
        let (estimates, a) = ctx.subscriber(&services::attitude_estimate())?;
        let (truth, b) = ctx.subscriber(&services::truth())?;
        let (events, c) = ctx.subscriber(&services::run_events())?;
        Ok(Self {
            estimates,
            truth,
            events,
            _inboxes: [a, b, c],
            truths: BTreeMap::new(),
            pending: Vec::new(),
            rms: Rms::default(),
            last_stamp: None,
            missing: 0,
            repeated: 0,
            first_of_instance: BTreeMap::new(),
            events_seen: Vec::new(),
            period_ns: 10_000_000,
        })
    }

    fn poll(&mut self) -> anyhow::Result<()> {
        let now = Instant::now();
        let truths = &mut self.truths;
        self.truth.drain(|t| {
            truths.insert(t.header.stamp_ns, quat(t.quat_nb));
        })?;
        let pending = &mut self.pending;
        let first = &mut self.first_of_instance;
        self.estimates.drain(|e| {
            first.entry(e.header.instance).or_insert(now);
            pending.push(e);
        })?;
        let seen = &mut self.events_seen;
        self.events.drain(|e| {
            seen.push((e.kind, fixed_str(&e.process), e.instance));
        })?;
        let mut keep = Vec::new();
        for e in std::mem::take(&mut self.pending) {
            let s = e.header.stamp_ns;
            match self.last_stamp {
                Some(last) if s <= last => self.repeated += 1,
                Some(last) => self.missing += (s - last) / self.period_ns - 1,
                None => {}
            }
            self.last_stamp = Some(self.last_stamp.map_or(s, |l| l.max(s)));
            match self.truths.get(&s) {
                Some(t) => self.rms.push(&AttitudeError::between(&quat(e.quat_nb), t)),
                None if self.truths.last_key_value().is_some_and(|(k, _)| *k >= s) => {}
                None => keep.push(e),
            }
        }
        self.pending = keep;
        while self.truths.len() > 3000 {
            self.truths.pop_first();
        }
        Ok(())
    }
}

/// RMS roll, pitch, yaw (degrees) from a `nauta launch` summary line.
fn summary_rms(line: &str) -> Option<[f64; 3]> {
    let part = line
        .split(" | ")
        .find(|p| p.starts_with("attitude error rms"))?;
    let num = |key: &str| -> Option<f64> {
        let rest = part.split(key).nth(1)?.trim_start();
        rest.split('°').next()?.trim().parse().ok()
    };
    Some([num("roll")?, num("pitch")?, num("yaw")?])
}

fn launch_args(a: &ChaosArgs, extra: &[&str]) -> Vec<String> {
    let mut v: Vec<String> = vec!["launch".into(), a.manifest.display().to_string()];
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
    let ref_line = String::from_utf8_lossy(&reference.stdout).into_owned();
    anyhow::ensure!(
        reference.status.success(),
        "the reference run failed: {ref_line}"
    );
    let ref_rms = summary_rms(&ref_line).context("no attitude error in the reference summary")?;

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
            "--set",
            "attitude.restart={ policy = \"on-failure\", max = 1000, window_s = 60, backoff_ms = [0, 100] }",
        ],
    );
    let mut child: Child = Command::new(&exe)
        .args(&args)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
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
        if Instant::now() >= next_kill {
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
    let line = out
        .lines()
        .rev()
        .find(|l| l.starts_with("nauta: run "))
        .unwrap_or_default()
        .to_owned();
    drop(follower.estimates);
    drop(follower.truth);
    let events = std::mem::take(&mut follower.events_seen);
    drop(follower.events);
    drop(follower._inboxes);
    ctx.finish();

    // Restart latency: kill to the first estimate of the next instance.
    let mut latencies: Vec<f64> = kills
        .iter()
        .filter_map(|(t, _, instance)| {
            follower
                .first_of_instance
                .get(&(instance + 1))
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
    let rms = follower.rms.deg();
    let change = rms
        .iter()
        .zip(ref_rms)
        .map(|(k, r)| 100.0 * (k - r).abs() / r.max(1e-9))
        .fold(0.0f64, f64::max);
    let gaps: u64 = line
        .split(" | ")
        .find_map(|p| p.strip_prefix("gaps ")?.trim().parse().ok())
        .unwrap_or(u64::MAX);
    let in_processes: u64 = line
        .split(" | ")
        .find_map(|p| {
            p.strip_prefix("lost in processes ")?
                .split(',')
                .next()?
                .trim()
                .parse()
                .ok()
        })
        .unwrap_or(u64::MAX);
    let lost_estimates = follower.missing + follower.repeated;
    let lost = lost_estimates
        .saturating_add(gaps)
        .saturating_add(in_processes);
    let completed = status.success() && line.contains("all processes exited 0");
    if !completed {
        bail!("the run did not complete: {status}\n{line}");
    }
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
            "launcher taps (sequence gaps)": gaps,
            "inside processes (health dropped)": in_processes,
        },
        "metric_change_pct": change,
        "attitude_rms_deg": {"with_kills": rms, "reference": ref_rms},
        "compared_estimates": follower.rms.n,
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
            "lost: {lost_estimates} estimate stamps missing or repeated, {gaps} sequence gaps at the launcher, {in_processes} inside processes"
        );
        println!(
            "attitude rms roll/pitch/yaw {:.3}/{:.3}/{:.3}° with kills vs {:.3}/{:.3}/{:.3}° without: largest change {change:.2} % (target < 10 %)",
            rms[0], rms[1], rms[2], ref_rms[0], ref_rms[1], ref_rms[2]
        );
        println!("{line}");
    }
    Ok(())
}
