//! Issue 4: supervision. An estimator killed with -9 is restarted and
//! publishes again while the rest of the pipeline keeps running; the launcher
//! killed with -9 takes every process with it, and the next launch removes what
//! it left in shared memory. Every test runs in its own namespace under a
//! watchdog; latencies are printed (benchmark figures), not asserted.

use nauta_estimation::frames::{Frd, Ned, Rotation};
use std::time::{Duration, Instant};

use std::collections::BTreeMap;

use nalgebra::{UnitQuaternion, Vector3};
use nauta_messages::{AttitudeEstimate, RunEvent, TruthState, event_kind, fixed_str};
use nauta_runtime::ports::Inbox;
use nauta_runtime::{ClockMode, Namespace, Subscriber, services};
use nauta_tests::*;

const BOUND: Duration = Duration::from_secs(240);
const GATED_BOUND: Duration = Duration::from_secs(300);

fn gone(pid: u32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Err(_) => true,
        // A zombie waiting for its new parent to reap it runs nothing.
        Ok(stat) => stat
            .rsplit_once(") ")
            .is_some_and(|(_, rest)| rest.starts_with('Z')),
    }
}

/// Pids of the processes that announced READY, by name.
fn ready_pids(events: &mut Subscriber<RunEvent>, seen: &mut Vec<(String, u32, u32)>) {
    events
        .drain(|e| {
            if e.kind == event_kind::READY {
                seen.push((fixed_str(&e.process), e.pid, e.instance));
            }
        })
        .unwrap_or_else(|e| panic!("run/events: {e:#}"));
}

/// An estimate and the truth at its stamp.
#[derive(Debug, Clone, Copy)]
struct Sample {
    stamp_ns: u64,
    instance: u32,
    /// Attitude error against the truth, as a rotation vector in NED (the
    /// frame of the estimate's `std_rad`), rad.
    error_ned: Vector3<f64>,
    std_ned: Vector3<f64>,
}

/// Follows `attitude/estimate` and `sim/truth` of a wall-clock run.
struct Follower {
    estimates: Subscriber<AttitudeEstimate>,
    truth: Subscriber<TruthState>,
    _inboxes: (Inbox, Inbox),
    truths: BTreeMap<u64, UnitQuaternion<f64>>,
    pending: Vec<AttitudeEstimate>,
    samples: Vec<Sample>,
}

fn quat(q: [f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(Rotation::<Frd, Ned>::quaternion_from_wxyz(q))
}

impl Follower {
    fn new(watch: &EventWatch) -> Self {
        let (estimates, a) = watch
            .ctx
            .subscriber(&services::attitude_estimate())
            .expect("attitude/estimate");
        let (truth, b) = watch.ctx.subscriber(&services::truth()).expect("sim/truth");
        Self {
            estimates,
            truth,
            _inboxes: (a, b),
            truths: BTreeMap::new(),
            pending: Vec::new(),
            samples: Vec::new(),
        }
    }

    /// Takes what arrived; pairs estimates with the truth of their stamp.
    fn poll(&mut self) {
        let truths = &mut self.truths;
        self.truth
            .drain(|t| {
                truths.insert(t.header.stamp_ns, quat(t.quat_nb));
            })
            .expect("truth");
        let pending = &mut self.pending;
        self.estimates
            .drain(|e| pending.push(e))
            .expect("estimates");
        let mut keep = Vec::new();
        for e in self.pending.drain(..) {
            match self.truths.get(&e.header.stamp_ns) {
                Some(t) => {
                    let d = quat(e.quat_nb) * t.inverse();
                    self.samples.push(Sample {
                        stamp_ns: e.header.stamp_ns,
                        instance: e.header.instance,
                        error_ned: d.scaled_axis(),
                        std_ned: Vector3::from(e.std_rad),
                    });
                }
                None => keep.push(e),
            }
        }
        self.pending = keep;
        // Keep a few seconds of truth.
        while self.truths.len() > 2000 {
            self.truths.pop_first();
        }
    }

    fn last_of(&self, instance: u32) -> Option<Sample> {
        self.samples
            .iter()
            .rev()
            .find(|s| s.instance == instance)
            .copied()
    }

    fn first_of(&self, instance: u32) -> Option<Sample> {
        self.samples
            .iter()
            .find(|s| s.instance == instance)
            .copied()
    }
}

/// Checks that instance `new` took over from `old` seamlessly: every stamp
/// exactly once (the first new stamp is the last old one plus one IMU
/// interval), and the estimate continues within 3σ: its error against the
/// truth changed by at most 3σ on each axis (a cold start would re-converge).
fn assert_seamless(f: &Follower, old: u32, new: u32) {
    let before = f.last_of(old).expect("estimates before the switch");
    let after = f.first_of(new).expect("estimates after the switch");
    assert_eq!(
        after.stamp_ns,
        before.stamp_ns + 10_000_000,
        "instance {new} starts at {} after instance {old} ended at {}: stamps lost or repeated",
        after.stamp_ns,
        before.stamp_ns
    );
    let mut stamps: Vec<u64> = f.samples.iter().map(|s| s.stamp_ns).collect();
    let n = stamps.len();
    stamps.dedup();
    assert_eq!(stamps.len(), n, "a stamp was published twice");
    assert!(
        stamps.windows(2).all(|w| w[1] > w[0]),
        "stamps go backwards"
    );
    for axis in 0..3 {
        let jump = (after.error_ned[axis] - before.error_ned[axis]).abs();
        let sigma = after.std_ned[axis];
        assert!(
            sigma > 0.0,
            "instance {new} publishes no uncertainty: {after:?}"
        );
        assert!(
            jump <= 3.0 * sigma,
            "axis {axis}: the error jumped by {:.4}° at the switch, more than 3σ = {:.4}°\nbefore {before:?}\nafter {after:?}",
            jump.to_degrees(),
            3.0 * sigma.to_degrees()
        );
    }
    // Roll and pitch (north and east axes) are consistent with the truth.
    for axis in 0..2 {
        assert!(
            after.error_ned[axis].abs() <= 3.0 * after.std_ned[axis],
            "axis {axis}: first estimate after the switch off the truth by more than 3σ: {after:?}"
        );
    }
}

fn wall_watch(ns: &Namespace) -> EventWatch {
    EventWatch::with_clock(
        ns,
        Duration::from_millis(500),
        ClockMode::Wall { rate: 1.0 },
    )
}

/// Waits until the follower has estimates of `instance` stamped after `t_ns`.
fn follow_until(wd: &Watchdog, launch: &mut Running, f: &mut Follower, instance: u32, t_ns: u64) {
    while !f
        .samples
        .iter()
        .any(|s| s.instance == instance && s.stamp_ns >= t_ns)
    {
        wd.check();
        assert!(
            launch.is_running(),
            "the run ended before instance {instance} published past {t_ns} ns"
        );
        f.poll();
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn kill_9_of_an_estimator_restarts_it_warm_and_the_rest_keeps_running() {
    bin_dir();
    let wd = Watchdog::new("estimator_restart", BOUND);
    let ns = Namespace::unique();
    let watch = wall_watch(&ns);
    let (mut events, events_inbox) = watch
        .ctx
        .subscriber(&services::run_events())
        .expect("run/events");
    let mut follower = Follower::new(&watch);
    let mut launch = start_launch(
        &wd,
        &[
            "--clock",
            "wall",
            "--duration",
            "25",
            "--namespace",
            ns.as_str(),
            "--set",
            "attitude.variant=mekf",
            "--set",
            "attitude.restart={ policy = \"on-failure\", max = 3, window_s = 60, backoff_ms = [20, 500] }",
        ],
    );
    // Running, aligned, and past a few snapshots.
    follow_until(&wd, &mut launch, &mut follower, 0, 9_000_000_000);
    let mut seen = Vec::new();
    ready_pids(&mut events, &mut seen);
    let pid = seen
        .iter()
        .find(|(n, _, i)| n == "attitude" && *i == 0)
        .map(|(_, p, _)| *p)
        .expect("attitude announced ready");
    // SAFETY: kill(2) on the attitude process of this test's own run.
    unsafe {
        libc::kill(pid as i32, libc::SIGKILL);
    }
    let killed = Instant::now();
    follow_until(&wd, &mut launch, &mut follower, 1, 0);
    eprintln!(
        "restart to first output: {:.0} ms after kill -9 (benchmark target: 1 s)",
        killed.elapsed().as_secs_f64() * 1e3
    );
    // A few more seconds of the new instance, then the checks.
    let resumed = follower.first_of(1).expect("instance 1").stamp_ns;
    follow_until(&wd, &mut launch, &mut follower, 1, resumed + 2_000_000_000);
    assert_seamless(&follower, 0, 1);
    ready_pids(&mut events, &mut seen);
    assert!(
        seen.iter()
            .any(|(n, p, i)| n == "attitude" && *i == 1 && *p != pid),
        "no READY from the restarted attitude: {seen:?}"
    );
    drop((follower, events, events_inbox));
    let out = launch.wait(&wd);
    watch.finish();
    assert_eq!(out.code(), Some(0), "the run failed\n{out}");
    let s = out.summary();
    assert_eq!(s.restarts("attitude"), 1, "{s}");
    assert_eq!(s.swaps("attitude"), 0, "{s}");
    // Nothing else stopped: every sensor sample was delivered, without a gap,
    // and no process reports a loss.
    assert_eq!(s.count("sensor/imu"), Some(2500), "{s}");
    assert_eq!(s.gaps(), Some(0), "{s}");
    assert_eq!(s.lost(), Some(0), "{s}");
    assert!(s.all_exited_0(), "{s}");
}

/// Issue 4: `nauta swap attitude mekf` and back during a wall run: every
/// stamp reaches the consumer exactly once across each switch, and the
/// estimate continues within 3σ.
#[test]
fn swap_to_another_variant_and_back_is_seamless() {
    bin_dir();
    let wd = Watchdog::new("swap", BOUND);
    let ns = Namespace::unique();
    let watch = wall_watch(&ns);
    let mut follower = Follower::new(&watch);
    // Recorded too: the swaps are lifecycle events of the recording (DESIGN §5).
    let record = std::env::temp_dir().join(format!("nauta-swap-{}.mcap", ns.as_str()));
    let mut launch = start_launch(
        &wd,
        &[
            "--clock",
            "wall",
            "--duration",
            "40",
            "--namespace",
            ns.as_str(),
            "--set",
            "attitude.variant=mekf",
            "--record",
            record.to_str().expect("utf-8 path"),
        ],
    );
    // Swap during the cruise (from t = 20 s; the vehicle starts moving at
    // 10 s). mekf -> gyro carries the attitude and bias (gyro publishes no
    // uncertainty); gyro -> mekf restores them, with the mekf's configured
    // initial covariance since gyro has none. Measured: swapping back at the
    // start of the motion (t = 10 s), the re-converging mekf's pitch error was
    // 1.72° against a 3σ of 1.70°; in the cruise it stays well inside.
    follow_until(&wd, &mut launch, &mut follower, 0, 20_000_000_000);
    for (variant, instance) in [("gyro", 1u32), ("mekf", 2)] {
        swap_when_accepted(&wd, &ns, variant);
        let resumed_from = follower.samples.last().map_or(0, |s| s.stamp_ns);
        follow_until(
            &wd,
            &mut launch,
            &mut follower,
            instance,
            resumed_from + 2_000_000_000,
        );
    }
    let before = follower.last_of(0).expect("mekf before");
    let gyro_first = follower.first_of(1).expect("gyro");
    assert_eq!(
        gyro_first.stamp_ns,
        before.stamp_ns + 10_000_000,
        "stamps lost or repeated at the swap to gyro"
    );
    // gyro carries the attitude without an uncertainty: compare its first
    // error with mekf's last against mekf's 3σ.
    for axis in 0..3 {
        let jump = (gyro_first.error_ned[axis] - before.error_ned[axis]).abs();
        assert!(
            jump <= 3.0 * before.std_ned[axis],
            "axis {axis}: jump {jump} at the swap to gyro; before {before:?} after {gyro_first:?}"
        );
    }
    assert_seamless(&follower, 1, 2);
    drop(follower);
    let out = launch.wait(&wd);
    watch.finish();
    assert_eq!(out.code(), Some(0), "{out}");
    let s = out.summary();
    assert_eq!(s.gaps(), Some(0), "{s}");
    assert_eq!((s.swaps("attitude"), s.restarts("attitude")), (2, 0), "{s}");
    let (code, info, err) = nauta_cli(&[
        "log".as_ref(),
        "info".as_ref(),
        record.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let info: serde_json::Value = serde_json::from_str(&info).expect("log info JSON");
    let swapped: Vec<&serde_json::Value> = info["events"]
        .as_array()
        .expect("events")
        .iter()
        .filter(|e| e["kind"] == "swapped" && e["process"] == "attitude")
        .collect();
    assert_eq!(swapped.len(), 2, "{}", info["events"]);
    let estimates = info["channels"]
        .as_array()
        .and_then(|c| c.iter().find(|c| c["topic"] == "attitude/estimate"))
        .expect("attitude/estimate recorded");
    assert_eq!(estimates["instances"], 3, "{estimates}");
    assert_eq!(estimates["gaps"], 0, "{estimates}");
    let _ = std::fs::remove_file(&record);
}

#[test]
fn kill_9_of_the_launcher_leaves_no_process_and_the_next_launch_cleans_up() {
    bin_dir();
    let wd = Watchdog::new("launcher_kill_9", GATED_BOUND);
    let ns = Namespace::unique();
    let config = ns.config().expect("config");
    let watch = EventWatch::new(&ns, Duration::from_millis(500));
    let (mut events, events_inbox) = watch
        .ctx
        .subscriber(&services::run_events())
        .expect("run/events");
    // Leftovers must stay until this test's own next launch.
    let closed = Gate::close();
    let mut launch = start_launch_with(
        &wd,
        &[
            "--clock",
            "wall",
            "--duration",
            "60",
            "--namespace",
            ns.as_str(),
        ],
        None,
    );
    let mut seen = Vec::new();
    while !(seen.iter().any(|(n, _, _)| n == "sensor")
        && seen.iter().any(|(n, _, _)| n == "attitude"))
    {
        wd.check();
        assert!(
            launch.is_running(),
            "the run ended early\n{}",
            launch.wait(&wd)
        );
        ready_pids(&mut events, &mut seen);
        std::thread::sleep(Duration::from_millis(5));
    }
    // Leave the run first (a port keeps the node alive until dropped).
    drop((events, events_inbox));
    watch.finish();
    launch.signal(libc::SIGKILL);
    let killed = Instant::now();
    let out = launch.wait(&wd);
    assert!(out.code().is_none(), "the launcher was not killed\n{out}");
    let pids: Vec<u32> = seen.iter().map(|(_, p, _)| *p).collect();
    while !pids.iter().all(|p| gone(*p)) {
        wd.check();
        std::thread::sleep(Duration::from_millis(5));
    }
    eprintln!(
        "every process of the run gone {:.0} ms after kill -9 of the launcher (benchmark target: 1 s)",
        killed.elapsed().as_secs_f64() * 1e3
    );
    let left = ns.all_files(&config);
    let next = Namespace::unique();
    let out = start_launch_with(
        &wd,
        &["--fast", "--duration", "1", "--namespace", next.as_str()],
        None,
    )
    .wait(&wd);
    drop(closed);
    assert_eq!(out.code(), Some(0), "the next launch failed\n{out}");
    let remaining = ns.all_files(&config);
    assert!(
        remaining.is_empty(),
        "files of the killed launcher's run remain after the next launch: {remaining:?} (left: {left:?})\n{out}"
    );
}

fn nauta(args: &[&str]) -> (Option<i32>, String, String) {
    let out = std::process::Command::new(bin("nauta"))
        .args(args)
        .stdin(std::process::Stdio::null())
        .output()
        .expect("run nauta");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `nauta swap attitude VARIANT`, asked again while it is refused (a
/// previous swap or a restart still starting, no snapshot yet).
fn swap_when_accepted(wd: &Watchdog, ns: &Namespace, variant: &str) {
    let mut tries = 0;
    loop {
        let (code, _, err) = nauta(&["swap", "attitude", variant, "--namespace", ns.as_str()]);
        if code == Some(0) {
            return;
        }
        tries += 1;
        assert!(tries < 200, "swap to {variant} refused: {err}");
        wd.check();
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// `pgrep -P PARENT -x NAME`: the pids of PARENT's children called NAME.
fn pgrep_children(parent: u32, name: &str) -> Vec<u32> {
    let out = std::process::Command::new("pgrep")
        .args(["-P", &parent.to_string(), "-x", name])
        .stdin(std::process::Stdio::null())
        .output()
        .expect("run pgrep");
    String::from_utf8_lossy(&out.stdout)
        .split_whitespace()
        .filter_map(|p| p.parse().ok())
        .filter(|p| !gone(*p))
        .collect()
}

/// The process `name` of `nauta status --json` in `ns`, once the status exists.
fn status_of(ns: &Namespace, name: &str) -> Option<serde_json::Value> {
    let (code, out, _) = nauta(&["status", "--json", "--namespace", ns.as_str()]);
    let status: serde_json::Value = serde_json::from_str(&out)
        .ok()
        .filter(|_| code == Some(0))?;
    status["processes"]
        .as_array()?
        .iter()
        .find(|p| p["name"] == name)
        .cloned()
}

/// The pid of the attitude process once `nauta status` says it runs (killed
/// before, it would fail the run's start instead of being restarted); `None`
/// if the run ended first.
fn running_attitude_pid(wd: &Watchdog, ns: &Namespace, launch: &mut Running) -> Option<u32> {
    let mut attitude = None;
    let up = wait_until(wd, Duration::from_secs(60), || {
        attitude = status_of(ns, "attitude").filter(|a| a["state"] == "running");
        attitude.is_some() || !launch.is_running()
    });
    let pid = attitude.and_then(|a| a["pid"].as_u64())? as u32;
    (up && launch.is_running()).then_some(pid)
}

/// The `nauta status` table's row of `process` as (column, value) pairs.
fn status_row(table: &str, process: &str) -> BTreeMap<String, String> {
    let mut lines = table.lines().skip_while(|l| !l.starts_with("process "));
    // One header is two words ("uptime s").
    let header = lines
        .next()
        .unwrap_or_else(|| panic!("no header in\n{table}"))
        .replace("uptime s", "uptime_s");
    let row = lines
        .find(|l| l.split_whitespace().next() == Some(process))
        .unwrap_or_else(|| panic!("no row {process} in\n{table}"));
    header
        .split_whitespace()
        .map(str::to_owned)
        .zip(row.split_whitespace().map(str::to_owned))
        .collect()
}

/// Issue 11: the shipped survey restarts a crashed estimator, and `nauta
/// status` counts restarts and swaps apart. `pgrep -P <launcher> -x
/// nauta-attitude` finds the estimator of a `--clock wall` run; after `kill
/// -9` a new one runs (the latency is printed, a benchmark figure; the bound
/// here is only the watchdog's); then one swap. The status table and its JSON
/// say 1 restart and 1 swap, and so does the run summary.
#[test]
fn the_shipped_survey_restarts_a_killed_estimator_and_status_counts_restarts_and_swaps_apart() {
    bin_dir();
    let wd = Watchdog::new("shipped_restart", BOUND);
    let ns = Namespace::unique();
    let mut launch = start_launch(
        &wd,
        &[
            "--clock",
            "wall",
            "--duration",
            "600",
            "--namespace",
            ns.as_str(),
        ],
    );
    let launcher = launch.pid();
    let running = |ns: &Namespace| status_of(ns, "attitude").filter(|a| a["state"] == "running");
    let Some(pid) = running_attitude_pid(&wd, &ns, &mut launch) else {
        panic!(
            "the attitude never ran
{}",
            launch.wait(&wd)
        );
    };
    assert_eq!(
        pgrep_children(launcher, "nauta-attitude"),
        vec![pid],
        "pgrep -P {launcher} -x nauta-attitude"
    );
    // SAFETY: kill(2) on the attitude process of this test's own run.
    unsafe {
        libc::kill(pid as i32, libc::SIGKILL);
    }
    let killed = Instant::now();
    let mut new = Vec::new();
    let restarted = wait_until(&wd, Duration::from_secs(60), || {
        new = pgrep_children(launcher, "nauta-attitude");
        new.iter().any(|p| *p != pid) || !launch.is_running()
    });
    assert!(
        restarted && launch.is_running(),
        "no new nauta-attitude after kill -9 of {pid}\n{}",
        launch.wait(&wd)
    );
    eprintln!(
        "a new nauta-attitude runs {:.0} ms after kill -9 (interface: within 1.5 s)",
        killed.elapsed().as_secs_f64() * 1e3
    );
    let restarted_once = wait_until(&wd, Duration::from_secs(60), || {
        running(&ns).is_some_and(|a| a["restarts"] == 1 && a["instance"] == 1)
    });
    assert!(restarted_once, "status: {:?}", status_of(&ns, "attitude"));

    swap_when_accepted(&wd, &ns, "gyro");
    let swapped = wait_until(&wd, Duration::from_secs(60), || {
        running(&ns).is_some_and(|a| a["swaps"] == 1 && a["variant"] == "gyro")
    });
    let a = status_of(&ns, "attitude").expect("attitude in the status");
    assert!(swapped, "status: {a}");
    assert_eq!((&a["restarts"], &a["swaps"]), (&1.into(), &1.into()), "{a}");
    let (code, table, err) = nauta(&["status", "--namespace", ns.as_str()]);
    assert_eq!(code, Some(0), "{err}");
    let row = status_row(&table, "attitude");
    assert_eq!(
        row.get("restarts").map(String::as_str),
        Some("1"),
        "{table}"
    );
    assert_eq!(row.get("swaps").map(String::as_str), Some("1"), "{table}");
    assert_eq!(
        row.get("variant").map(String::as_str),
        Some("gyro"),
        "{table}"
    );

    let (code, _, err) = nauta(&["stop", "--namespace", ns.as_str()]);
    assert_eq!(code, Some(0), "stop refused: {err}");
    let out = launch.wait(&wd);
    assert_eq!(out.code(), Some(0), "{out}");
    let s = out.summary();
    assert_eq!((s.restarts("attitude"), s.swaps("attitude")), (1, 1), "{s}");
    assert_eq!(s.stopped(), Some("request"), "{s}");
    assert!(s.all_exited_0(), "{s}");
}

/// Issue 11: a run whose estimator dies without a restart policy ends as
/// failed, and its JSON summary names the process and why.
#[test]
fn a_crash_without_restart_fails_the_run_and_the_summary_names_it() {
    bin_dir();
    let wd = Watchdog::new("crash_without_restart", BOUND);
    let ns = Namespace::unique();
    let mut launch = start_launch(
        &wd,
        &[
            "--clock",
            "wall",
            "--duration",
            "600",
            "--namespace",
            ns.as_str(),
            "--set",
            "attitude.restart={ policy = \"never\" }",
        ],
    );
    let Some(pid) = running_attitude_pid(&wd, &ns, &mut launch) else {
        panic!(
            "the attitude never ran
{}",
            launch.wait(&wd)
        );
    };
    // SAFETY: kill(2) on the attitude process of this test's own run.
    unsafe {
        libc::kill(pid as i32, libc::SIGKILL);
    }
    let out = launch.wait(&wd);
    assert_eq!(out.code(), Some(1), "{out}");
    let s = out.summary();
    assert_eq!(s.json["exit"], "failed", "{s}");
    assert_eq!(s.json["exit_code"], 1, "{s}");
    assert_eq!(s.stopped(), Some("end"), "{s}");
    assert_eq!(s.failure(), Some("attitude exited -9"), "{s}");
    assert_eq!(s.restarts("attitude"), 0, "{s}");
}

/// Issue 4: a running pipeline is controlled from another shell: `status`
/// lists its processes, `restart` restarts one, `swap` refuses an unknown
/// variant, `stop` ends the run in order and leaves nothing behind.
#[test]
fn status_restart_swap_and_stop_from_another_shell() {
    bin_dir();
    let wd = Watchdog::new("pipeline_control", BOUND);
    let ns = Namespace::unique();
    let config = ns.config().expect("config");
    let mut launch = start_launch(
        &wd,
        &[
            "--clock",
            "wall",
            "--duration",
            "120",
            "--namespace",
            ns.as_str(),
        ],
    );
    // `status` finds the run once it is registered and both processes run.
    let mut status = serde_json::Value::Null;
    while !status["processes"]
        .as_array()
        .is_some_and(|p| p.len() == 2 && p.iter().all(|p| p["state"] == "running"))
    {
        wd.check();
        assert!(
            launch.is_running(),
            "the run ended early\n{}",
            launch.wait(&wd)
        );
        std::thread::sleep(Duration::from_millis(100));
        let (code, out, _) = nauta(&["status", "--json", "--namespace", ns.as_str()]);
        if code == Some(0) {
            status = serde_json::from_str(&out).expect("status JSON");
        }
    }
    let procs = status["processes"].as_array().expect("processes");
    for key in [
        "name",
        "pid",
        "variant",
        "state",
        "restarts",
        "uptime_s",
        "inputs_per_s",
        "outputs_per_s",
        "rejected",
        "dropped",
    ] {
        assert!(procs[0].get(key).is_some(), "status lacks {key}: {status}");
    }
    let attitude = procs
        .iter()
        .find(|p| p["name"] == "attitude")
        .expect("attitude");
    let old_pid = attitude["pid"].as_u64().expect("pid");
    assert!(old_pid > 0 && !gone(old_pid as u32));
    // The readable form works too.
    let (code, out, err) = nauta(&["status", "--namespace", ns.as_str()]);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.contains("attitude") && out.contains("sensor"), "{out}");

    let (code, _, err) = nauta(&["restart", "attitude", "--namespace", ns.as_str()]);
    assert_eq!(code, Some(0), "restart refused: {err}");
    loop {
        wd.check();
        std::thread::sleep(Duration::from_millis(100));
        let (_, out, _) = nauta(&["status", "--json", "--namespace", ns.as_str()]);
        let Ok(s) = serde_json::from_str::<serde_json::Value>(&out) else {
            continue;
        };
        let a = s["processes"]
            .as_array()
            .and_then(|p| p.iter().find(|p| p["name"] == "attitude").cloned())
            .expect("attitude");
        if a["restarts"] == 1 && a["state"] == "running" {
            assert_ne!(a["pid"].as_u64(), Some(old_pid), "{s}");
            assert_eq!(a["instance"], 1, "{s}");
            break;
        }
    }
    let (code, _, err) = nauta(&[
        "swap",
        "attitude",
        "no-such-variant",
        "--namespace",
        ns.as_str(),
    ]);
    assert_eq!(code, Some(1), "an unknown variant was accepted");
    assert!(err.contains("no-such-variant"), "{err}");
    let (code, _, err) = nauta(&["restart", "sensor", "--namespace", ns.as_str()]);
    assert_eq!(code, Some(1), "a source was restarted");
    assert!(err.contains("source"), "{err}");

    let (code, _, err) = nauta(&["stop", "--namespace", ns.as_str()]);
    assert_eq!(code, Some(0), "stop refused: {err}");
    let out = launch.wait(&wd);
    assert_eq!(out.code(), Some(0), "{out}");
    let s = out.summary();
    assert_eq!(s.stopped(), Some("request"), "{s}");
    assert!(s.all_exited_0(), "{s}");
    assert_eq!(s.restarts("attitude"), 1, "{s}");
    assert!(
        ns.all_files(&config).is_empty(),
        "the stopped run left files"
    );
    let (code, _, _) = nauta(&["status", "--namespace", ns.as_str()]);
    assert_eq!(code, Some(1), "status still finds the stopped run");
}

/// Issue 4, the short version of `nauta bench chaos` that CI runs: a few kills
/// of the estimator during a 30 s wall-clock run at 10x; every kill is
/// restarted, nothing is lost, and the attitude error stays within 10 % of
/// the run without kills. (The full survey with 20+ kills is the benchmark.)
#[test]
fn chaos_short_version() {
    bin_dir();
    let wd = Watchdog::new("chaos_short", BOUND);
    // The benchmark launches a run: it shares the launch gate like every
    // launch, so a test that closed the gate (and then launches, cleaning up
    // every dead node on the machine) cannot remove a killed estimator's
    // shared memory before this run's launcher has drained it.
    let _gate = Gate::share();
    let (code, out, err) = {
        let child = std::process::Command::new(bin("nauta"))
            .current_dir(workspace_root())
            .args([
                "bench",
                "chaos",
                "--json",
                "--duration",
                "300",
                "--rate",
                "10",
                "--min-interval",
                "4",
                "--max-interval",
                "8",
            ])
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("nauta bench chaos");
        wd.watch(child.id());
        let o = child.wait_with_output().expect("wait");
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    assert_eq!(code, Some(0), "{out}\n{err}");
    let r: serde_json::Value = serde_json::from_str(out.trim()).expect("one JSON object");
    let kills = r["kills"].as_u64().expect("kills");
    assert!(kills >= 3, "{r}");
    assert_eq!(r["restarts"].as_u64(), Some(kills), "{r}");
    assert_eq!(r["every_kill_restarted"], true, "{r}");
    assert_eq!(r["restart_latencies_measured"].as_u64(), Some(kills), "{r}");
    assert_eq!(r["lost_messages"].as_u64(), Some(0), "{r}");
    assert!(
        r["metric_change_pct"].as_f64().is_some_and(|c| c < 10.0),
        "{r}"
    );
    for key in ["restart_p50_ms", "restart_max_ms"] {
        assert!(r[key].as_f64().is_some_and(f64::is_finite), "{key}: {r}");
    }
}
