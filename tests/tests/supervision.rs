//! Issue 4: supervision. An estimator killed with -9 is restarted and
//! publishes again while the rest of the pipeline keeps running; the launcher
//! killed with -9 takes every process with it, and the next launch removes what
//! it left in shared memory. Every test runs in its own namespace under a
//! watchdog; latencies are printed (benchmark figures), not asserted.

use std::time::{Duration, Instant};

use nauta_messages::{AttitudeEstimate, RunEvent, event_kind, fixed_str};
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

#[test]
fn kill_9_of_an_estimator_restarts_it_and_the_rest_keeps_running() {
    bin_dir();
    let wd = Watchdog::new("estimator_restart", BOUND);
    let ns = Namespace::unique();
    let watch = EventWatch::with_clock(
        &ns,
        Duration::from_millis(500),
        ClockMode::Wall { rate: 1.0 },
    );
    let (mut events, events_inbox) = watch
        .ctx
        .subscriber(&services::run_events())
        .expect("run/events");
    let (mut estimates, estimates_inbox): (Subscriber<AttitudeEstimate>, _) = watch
        .ctx
        .subscriber(&services::attitude_estimate())
        .expect("attitude/estimate");
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
            "attitude.restart={ policy = \"on-failure\", max = 3, window_s = 60, backoff_ms = [20, 500] }",
        ],
    );
    let mut seen = Vec::new();
    // Running: estimates from instance 0 (after its alignment).
    let mut last0 = None;
    while last0.is_none_or(|s: u64| s < 8_000_000_000) {
        wd.check();
        assert!(
            launch.is_running(),
            "the run ended early\n{}",
            launch.wait(&wd)
        );
        ready_pids(&mut events, &mut seen);
        estimates
            .drain(|e| {
                if e.header.instance == 0 {
                    last0 = Some(e.header.stamp_ns);
                }
            })
            .expect("estimates");
        std::thread::sleep(Duration::from_millis(10));
    }
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
    // Restarted and publishing again: an estimate from instance 1.
    let mut first1 = None;
    while first1.is_none() {
        wd.check();
        assert!(
            launch.is_running(),
            "the run ended before the restart\n{}",
            launch.wait(&wd)
        );
        estimates
            .drain(|e| {
                if e.header.instance == 1 && first1.is_none() {
                    first1 = Some(e.header.stamp_ns);
                }
            })
            .expect("estimates");
        std::thread::sleep(Duration::from_millis(2));
    }
    eprintln!(
        "restart to first output: {:.0} ms after kill -9 (benchmark target: 1 s)",
        killed.elapsed().as_secs_f64() * 1e3
    );
    ready_pids(&mut events, &mut seen);
    assert!(
        seen.iter()
            .any(|(n, p, i)| n == "attitude" && *i == 1 && *p != pid),
        "no READY from the restarted attitude: {seen:?}"
    );
    drop((estimates, events, estimates_inbox, events_inbox));
    let out = launch.wait(&wd);
    watch.finish();
    assert_eq!(out.code(), Some(0), "the run failed\n{out}");
    let s = out.summary();
    assert!(s.line.contains("restarts attitude 1"), "{}", s.line);
    // Nothing else stopped: every sensor sample was delivered, without a gap,
    // and no process reports a loss.
    assert_eq!(s.count("sensor/imu"), Some(2500), "{}", s.line);
    assert_eq!(s.gaps(), Some(0), "{}", s.line);
    assert!(s.line.contains("lost in processes 0"), "{}", s.line);
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
    assert!(s.line.contains("stopped by request"), "{}", s.line);
    assert!(s.line.contains("restarts attitude 1"), "{}", s.line);
    assert!(
        ns.all_files(&config).is_empty(),
        "the stopped run left files"
    );
    let (code, _, _) = nauta(&["status", "--namespace", ns.as_str()]);
    assert_eq!(code, Some(1), "status still finds the stopped run");
}
