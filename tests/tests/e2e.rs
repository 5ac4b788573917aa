//! End-to-end tests of the first slice (sensor → attitude, launched by `nauta
//! launch`): real processes exchanging messages over iceoryx2 shared memory.
//!
//! Every test runs in its own namespace, under a watchdog; none asserts on wall
//! time. Tests that need a killed process's leftovers to stay put close the
//! launch gate (see `nauta_tests::Gate`), because every `nauta launch` removes
//! the leftovers of dead processes of every run on the machine when it starts.

use std::os::unix::process::ExitStatusExt;
use std::time::Duration;

use nauta_messages::{Header, ImuSample, Role};
use nauta_runtime::{Namespace, services};
use nauta_tests::*;

/// Bound of a test that only runs launches.
const BOUND: Duration = Duration::from_secs(180);
/// Bound of a test that may wait for every other test's launches (closed gate).
const GATED_BOUND: Duration = Duration::from_secs(300);

/// Checks a completed sim run: exit 0, its namespace, `imu` IMU messages, no
/// gap, one estimate per IMU sample after the alignment, every process exited 0.
fn assert_complete_run(out: &Finished, ns: &Namespace, imu: u64) -> Summary {
    assert_eq!(out.code(), Some(0), "nauta launch failed\n{out}");
    let s = out.summary();
    assert_eq!(
        s.namespace(),
        Some(ns.as_str()),
        "summary of another run?\n{out}"
    );
    assert_eq!(s.count("sensor/imu"), Some(imu), "IMU count\n{out}");
    assert_eq!(s.gaps(), Some(0), "sequence gaps\n{out}");
    let align = alignment_samples(&survey_manifest());
    assert!((1..=imu).contains(&align), "alignment_samples {align}");
    assert_eq!(
        s.count("attitude/estimate"),
        Some(imu - (align - 1)),
        "attitude estimates: one per IMU sample from the end of the alignment ({align} samples); \
         IMU gaps reported by nauta-attitude itself: {:?}\n{out}",
        attitude_input_gaps(&out.stderr)
    );
    assert!(s.all_exited_0(), "a process failed\n{out}");
    assert!(s.digest().is_some(), "no attitude digest\n{out}");
    s
}

/// The IMU gaps nauta-attitude logs when it ends (`attitude: done ... gaps=N`),
/// for diagnostics: the summary's `gaps` counts only the launcher's own taps.
fn attitude_input_gaps(stderr: &str) -> Option<u64> {
    stderr
        .lines()
        .filter(|l| l.contains("attitude") && l.contains(" done "))
        .find_map(|l| {
            l.split_whitespace()
                .find_map(|w| w.strip_prefix("gaps=")?.parse().ok())
        })
}

fn digest(s: &Summary) -> String {
    s.digest().unwrap_or_default()
}

/// Criterion 1: Two processes exchange 100,000 IMU messages in sim mode with no sequence gap.
/// Starts `nauta-attitude` directly (the binary contract, no launcher) in `ns`
/// and waits until it reports ready.
fn spawn_attitude_until_ready(
    wd: &Watchdog,
    ns: &Namespace,
    manifest: &std::path::Path,
    watch: &mut EventWatch,
) -> Running {
    let mut attitude = Running::spawn(
        wd,
        &bin("nauta-attitude"),
        &[
            "--manifest",
            &manifest.display().to_string(),
            "--process",
            "attitude",
            "--namespace",
            ns.as_str(),
            "--instance",
            "0",
        ],
        None,
    );
    if !watch.wait_ready(wd, "attitude", &mut attitude) {
        panic!(
            "nauta-attitude exited before it was ready\n{}",
            attitude.wait(wd)
        );
    }
    attitude
}

#[test]
fn sim_run_moves_100k_imu_messages_without_gap() {
    bin_dir();
    let wd = Watchdog::new("sim_run_moves_100k_imu_messages_without_gap", BOUND);
    let ns = Namespace::unique();
    let out = launch(
        &wd,
        &["--fast", "--duration", "1000", "--namespace", ns.as_str()],
    );
    assert_complete_run(&out, &ns, 100_000);
}

/// Criterion 2: Two runs in different namespaces side by side do not see each other.
#[test]
fn side_by_side_runs_are_isolated() {
    bin_dir();
    let wd = Watchdog::new("side_by_side_runs_are_isolated", BOUND);
    let (seed_a, seed_b) = ("21", "22");
    let (ns_a, ns_b) = (Namespace::unique(), Namespace::unique());
    let args = |ns: &Namespace, seed: &'static str| -> Vec<String> {
        [
            "--fast",
            "--duration",
            "120",
            "--seed",
            seed,
            "--namespace",
            ns.as_str(),
        ]
        .map(String::from)
        .to_vec()
    };
    let a_args = args(&ns_a, seed_a);
    let b_args = args(&ns_b, seed_b);
    let a = start_launch(&wd, &a_args.iter().map(String::as_str).collect::<Vec<_>>());
    let b = start_launch(&wd, &b_args.iter().map(String::as_str).collect::<Vec<_>>());
    let a = a.wait(&wd);
    let b = b.wait(&wd);
    let sa = assert_complete_run(&a, &ns_a, 12_000);
    let sb = assert_complete_run(&b, &ns_b, 12_000);
    assert_ne!(
        digest(&sa),
        digest(&sb),
        "different seeds gave the same attitude digest\n{a}\n{b}"
    );

    // Each equals a run alone with the same seed.
    for (seed, side_by_side) in [(seed_a, &sa), (seed_b, &sb)] {
        let ns = Namespace::unique();
        let solo_args = args(&ns, seed);
        let solo = launch(
            &wd,
            &solo_args.iter().map(String::as_str).collect::<Vec<_>>(),
        );
        let s = assert_complete_run(&solo, &ns, 12_000);
        assert_eq!(
            digest(&s),
            digest(side_by_side),
            "seed {seed}: the run side by side differs from the run alone\nside by side: {side_by_side}\n{solo}"
        );
    }
}

/// Criterion 3: A run stopped with SIGTERM leaves no file of its run in /dev/shm.
#[test]
fn sigterm_leaves_no_shared_memory() {
    stop_by_signal_leaves_no_shared_memory(libc::SIGTERM, "SIGTERM");
}

/// Issue 4: the same after SIGINT (Ctrl-C in the launcher's shell).
#[test]
fn sigint_leaves_no_shared_memory() {
    stop_by_signal_leaves_no_shared_memory(libc::SIGINT, "SIGINT");
}

fn stop_by_signal_leaves_no_shared_memory(signal: i32, name: &str) {
    bin_dir();
    let wd = Watchdog::new(&format!("{name}_leaves_no_shared_memory"), BOUND);
    let ns = Namespace::unique();
    // Joins the run only to see its processes report ready; leaves before the stop.
    let mut watch = EventWatch::new(&ns, Duration::from_millis(500));
    let mut run = start_launch(
        &wd,
        &[
            "--clock",
            "wall",
            "--duration",
            "3600",
            "--namespace",
            ns.as_str(),
        ],
    );
    // The launcher starts the attitude, then the sensor, each after the previous is ready.
    for p in ["attitude", "sensor"] {
        if !watch.wait_ready(&wd, p, &mut run) {
            panic!(
                "the launcher exited before {p} was ready\n{}",
                run.wait(&wd)
            );
        }
    }
    watch.finish();
    assert!(
        !ns.shm_files().is_empty(),
        "a running run has no file with prefix {} in /dev/shm",
        ns.prefix()
    );
    // Let the launcher go from starting processes to running them (a signal while
    // starting is an error, not a stop).
    std::thread::sleep(Duration::from_millis(1000));
    assert!(
        run.is_running(),
        "the launcher exited on its own\n{}",
        run.wait(&wd)
    );

    run.signal(signal);
    let out = run.wait(&wd);
    assert_eq!(
        out.code(),
        Some(130),
        "nauta launch stopped by {name} should exit 130\n{out}"
    );
    let s = out.summary();
    assert_eq!(s.stopped(), Some("signal"), "{s}");
    assert_eq!(s.json["exit_code"], 130, "{s}");

    // Processes may finish removing their files just after they exit.
    let gone = wait_until(&wd, Duration::from_secs(10), || ns.shm_files().is_empty());
    let config = ns.config().expect("config");
    assert!(
        gone,
        "files of run {ns} left in /dev/shm after {name}: {:?}\n(all files of the run: {:?})\n{out}",
        ns.shm_files(),
        ns.all_files(&config)
    );
}

/// Criterion 4: The leftovers of a process killed with -9 are removed by the next start.
#[test]
fn next_launch_removes_leftovers_of_kill_9() {
    bin_dir();
    let wd = Watchdog::new("next_launch_removes_leftovers_of_kill_9", GATED_BOUND);
    let ns = Namespace::unique();
    let config = ns.config().expect("config");
    let manifest = survey_manifest();
    let mut watch = EventWatch::new(&ns, Duration::from_millis(500));
    // The attitude reports ready once its inputs have publishers: stand in for the sensor.
    let inputs = (
        watch
            .ctx
            .publisher(&services::imu())
            .expect("IMU publisher"),
        watch
            .ctx
            .publisher(&services::progress(Role::Sensor))
            .expect("progress publisher"),
    );
    let attitude = spawn_attitude_until_ready(&wd, &ns, &manifest, &mut watch);
    drop(inputs);
    watch.finish();
    assert!(
        !ns.shm_files().is_empty(),
        "nauta-attitude is ready but has no file with prefix {} in /dev/shm",
        ns.prefix()
    );

    // No launch of this test process may clean up until this test's own launch.
    let _closed = Gate::close();
    attitude.signal(libc::SIGKILL);
    let killed = attitude.wait(&wd);
    assert_eq!(killed.status.signal(), Some(libc::SIGKILL), "{killed}");
    let left = ns.all_files(&config);
    assert!(
        !ns.shm_files().is_empty(),
        "kill -9 left no file in /dev/shm, nothing to test (all files: {left:?})"
    );

    let other = Namespace::unique();
    let out = start_launch_with(
        &wd,
        &["--fast", "--duration", "1", "--namespace", other.as_str()],
        None,
    )
    .wait(&wd);
    assert_eq!(out.code(), Some(0), "nauta launch failed\n{out}");
    let remaining = ns.all_files(&config);
    assert!(
        remaining.is_empty(),
        "files of the killed process's run {ns} remain after the next launch: {remaining:?}\n\
         (left by kill -9: {left:?})\n{out}"
    );
}

/// Criterion 5: A back-pressured publisher whose subscriber was killed with -9 is free
/// again within its deadline.
#[test]
fn publisher_is_freed_from_a_subscriber_killed_with_9() {
    bin_dir();
    let wd = Watchdog::new(
        "publisher_is_freed_from_a_subscriber_killed_with_9",
        GATED_BOUND,
    );
    let ns = Namespace::unique();
    let manifest = survey_manifest();
    let deadline = Duration::from_millis(500);
    let mut watch = EventWatch::new(&ns, deadline);
    let mut imu = watch
        .ctx
        .publisher(&services::imu())
        .unwrap_or_else(|e| panic!("IMU publisher: {e:#}"));
    // The attitude's other input, so that it connects and reports ready.
    let _progress = watch
        .ctx
        .publisher(&services::progress(Role::Sensor))
        .unwrap_or_else(|e| panic!("progress publisher: {e:#}"));
    let attitude = spawn_attitude_until_ready(&wd, &ns, &manifest, &mut watch);
    let subscribed = wait_until(&wd, Duration::from_secs(30), || imu.subscriber_count() >= 1);
    assert!(
        subscribed,
        "nauta-attitude is ready but does not subscribe to sensor/imu"
    );

    // No launch of this test process may remove the dead subscriber meanwhile.
    let _closed = Gate::close();
    attitude.signal(libc::SIGKILL);
    let killed = attitude.wait(&wd);
    assert_eq!(killed.status.signal(), Some(libc::SIGKILL), "{killed}");

    // The dead subscriber's queue fills, the publisher blocks until its deadline,
    // gives that delivery up, removes the dead node and is free again. A hang
    // here is caught by this watchdog (it aborts the test process).
    let publishing = Watchdog::new("publishing to a dead subscriber", Duration::from_secs(60));
    // Twice what the dead subscriber's queue holds (the queue grew from 512
    // to 2048 once; a fixed count then fitted in it and nothing was given up).
    let n = 2 * services::imu().buffer as u64;
    for k in 0..n {
        let msg = ImuSample {
            header: Header::new((k + 1) * 10_000_000, 0, Role::Test, 0),
            gyro_rad_s: [1e-4, -2e-4, 5e-5],
            accel_m_s2: [0.0, 0.0, -9.81],
            mag_ut: [22.0, 0.5, 38.0],
            interval_s: 0.01,
        };
        imu.publish(msg)
            .unwrap_or_else(|e| panic!("publish #{k}: {e:#}"));
        if (k + 1) % 32 == 0 {
            imu.flush();
        }
    }
    imu.flush();
    publishing.check();
    drop(publishing);
    assert_eq!(imu.published(), n);
    assert!(
        imu.given_up() >= 1,
        "no delivery was given up: the dead subscriber's queue cannot have taken {n} samples"
    );
    assert_eq!(
        imu.subscriber_count(),
        0,
        "the dead subscriber is still attached after the publisher gave up ({} given up)",
        imu.given_up()
    );
    assert!(watch.ctx.any_delivery_given_up());
    drop((imu, _progress));
    watch.finish();
    let config = ns.config().expect("config");
    assert!(
        ns.all_files(&config).is_empty(),
        "the run's files outlive its last process: {:?}",
        ns.all_files(&config)
    );
}

/// Criterion 6: Two sim runs with the same seed give bit-identical attitude outputs; another
/// seed differs.
#[test]
fn sim_runs_are_deterministic() {
    bin_dir();
    let wd = Watchdog::new("sim_runs_are_deterministic", BOUND);
    let run = |seed: &str| {
        let ns = Namespace::unique();
        let out = launch(
            &wd,
            &[
                "--fast",
                "--duration",
                "300",
                "--seed",
                seed,
                "--namespace",
                ns.as_str(),
            ],
        );
        let s = assert_complete_run(&out, &ns, 30_000);
        // The launcher evaluates the estimates against the truth by stamp,
        // whatever order the two publishers' messages arrived in: equal error
        // figures mean the same pairing, whatever the scheduling.
        let error = s.json["errors"]["attitude/estimate"].to_string();
        ((digest(&s), error), out)
    };
    let (first, out1) = run("11");
    assert!(
        first.1.contains("roll_rms_deg"),
        "no attitude error in the summary\n{out1}"
    );
    let (second, out2) = run("11");
    assert_eq!(
        first, second,
        "two runs with seed 11 differ\n{out1}\n{out2}"
    );
    let (third, out3) = run("12");
    assert_ne!(
        first.0, third.0,
        "seeds 11 and 12 gave the same attitude digest\n{out1}\n{out3}"
    );
}

/// The summary reader itself: one JSON object, nothing else.
#[test]
fn summary_parsing() {
    let json = r#"{"namespace": "r1-2-3", "mission_s": 60.0, "messages": 12600, "gaps": 0,
        "lost": 0, "rejected": 0,
        "streams": {"attitude/estimate": {"messages": 5801, "rate_hz": 100.0},
                    "sensor/imu": {"messages": 6000, "rate_hz": 100.0},
                    "sim/truth": {"messages": 6000, "rate_hz": 100.0}},
        "sensor_span": {"topic": "sim/truth", "simulated_s": 59.99, "wall_s": 0.12},
        "errors": {"attitude/estimate": {"samples": 5801, "roll_rms_deg": 0.14}},
        "digests": {"attitude/estimate": "6dd6335c7369c535"},
        "restarts": {"attitude": 1}, "swaps": {}, "stopped": "end", "exit": "ok",
        "failures": [], "exit_code": 0}"#;
    let s = Summary::parse(&format!("{json}\n")).expect("summary");
    assert_eq!(s.namespace(), Some("r1-2-3"));
    assert_eq!(s.count("sensor/imu"), Some(6000));
    assert_eq!(s.count("attitude/estimate"), Some(5801));
    assert_eq!(s.count("sensor/dvl"), None);
    assert_eq!(s.gaps(), Some(0));
    assert_eq!(s.sensor_span(), Some(("sim/truth".to_owned(), 59.99, 0.12)));
    assert_eq!(s.mission_s(), Some(60.0));
    assert_eq!(s.digest().as_deref(), Some("6dd6335c7369c535"));
    assert_eq!(s.error("attitude/estimate", "roll_rms_deg"), Some(0.14));
    assert_eq!((s.restarts("attitude"), s.swaps("attitude")), (1, 0));
    assert!(s.all_exited_0());
    assert!(Summary::parse("nauta: error: x").is_err());
    assert!(Summary::parse(&format!("{json}\n{json}")).is_err());
    assert!(Summary::parse("[1]").is_err());
}

/// Without `--json`, `nauta launch` prints one line with the figures of the
/// JSON summary (the attitude digest of the earlier line is the JSON's
/// `attitude/estimate` digest); with it, stdout is one JSON object only.
#[test]
fn the_summary_line_and_the_json_summary_agree() {
    bin_dir();
    let wd = Watchdog::new("the_summary_line_and_the_json_summary_agree", BOUND);
    let args = ["--fast", "--duration", "30", "--seed", "5"];
    let ns = Namespace::unique();
    let json = launch(&wd, &[&args[..], &["--namespace", ns.as_str()]].concat());
    let s = assert_complete_run(&json, &ns, 3000);
    let mut plain: Vec<String> = vec!["launch".into(), survey_manifest().display().to_string()];
    plain.extend(args.iter().map(|a| a.to_string()));
    let line = Running::spawn(&wd, &bin("nauta"), &plain, Some(Gate::share())).wait(&wd);
    assert_eq!(line.code(), Some(0), "{line}");
    let text = line.stdout.trim();
    assert!(
        text.starts_with("nauta: run ") && !text.contains('\n'),
        "not one summary line\n{line}"
    );
    let digest = s.digest().expect("digest");
    assert!(
        text.contains(&format!("| attitude digest {digest} |")),
        "the line's digest is not the JSON's {digest}\n{line}"
    );
    assert!(
        text.contains(&format!(
            "| sensor/imu {} msgs",
            s.count("sensor/imu").unwrap_or(0)
        )),
        "{line}"
    );
    assert!(text.ends_with("| all processes exited 0"), "{line}");
    // Log lines on a pipe (here, the test's) carry no colour codes.
    for out in [&json, &line] {
        assert!(
            out.stderr.contains(" INFO ") && !out.stderr.contains('\u{1b}'),
            "escape codes (or no log) on stderr, a pipe\n{out}"
        );
    }
}

/// The diagnostic parser of nauta-attitude's final log line.
#[test]
fn attitude_gaps_parsing() {
    let log =
        "2026-11-22T15:00:25.692639Z  INFO attitude: done inputs=11383 gaps=617 by_signal=false\n";
    assert_eq!(attitude_input_gaps(log), Some(617));
    assert_eq!(attitude_input_gaps("nothing"), None);
}

/// A pseudo-terminal: (master, path of the slave).
fn open_pty() -> (std::fs::File, std::path::PathBuf) {
    use std::os::fd::FromRawFd;
    // SAFETY: posix_openpt returns a new descriptor we own (or -1).
    let fd = unsafe { libc::posix_openpt(libc::O_RDWR | libc::O_NOCTTY) };
    assert!(fd >= 0, "posix_openpt: {}", std::io::Error::last_os_error());
    // SAFETY: `fd` is a valid pty master; `name` is large enough for ptsname_r.
    let mut name = [0 as libc::c_char; 128];
    let ok = unsafe {
        libc::grantpt(fd) == 0
            && libc::unlockpt(fd) == 0
            && libc::ptsname_r(fd, name.as_mut_ptr(), name.len()) == 0
    };
    assert!(ok, "pty setup: {}", std::io::Error::last_os_error());
    // SAFETY: ptsname_r wrote a NUL-terminated path into `name`.
    let path = unsafe { std::ffi::CStr::from_ptr(name.as_ptr()) }
        .to_string_lossy()
        .into_owned();
    // SAFETY: `fd` is ours and owned by the File from here on.
    (unsafe { std::fs::File::from_raw_fd(fd) }, path.into())
}

/// Log lines carry colour codes when stderr is a terminal, and none when
/// `NO_COLOR` is set there too (<https://no-color.org>); on a pipe they never
/// do (`the_summary_line_and_the_json_summary_agree`).
#[test]
fn log_colour_on_a_terminal_unless_no_color() {
    use std::io::Read;
    bin_dir();
    let wd = Watchdog::new("log_colour_on_a_terminal", BOUND);
    let run = |no_color: Option<&str>| -> String {
        let (mut master, slave_path) = open_pty();
        let slave = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&slave_path)
            .unwrap_or_else(|e| panic!("open {}: {e}", slave_path.display()));
        let ns = Namespace::unique();
        let mut cmd = std::process::Command::new(bin("nauta"));
        cmd.current_dir(workspace_root())
            .args(["launch", &survey_manifest().display().to_string(), "--json"])
            .args(["--fast", "--duration", "2", "--namespace", ns.as_str()])
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .stderr(slave)
            .env_remove("NO_COLOR");
        if let Some(v) = no_color {
            cmd.env("NO_COLOR", v);
        }
        let _gate = Gate::share();
        let mut child = cmd.spawn().expect("start nauta launch");
        wd.watch(child.id());
        // The slave closes in this process with `cmd`; the master reads until
        // the last process holding it (the launcher and its children) exits.
        drop(cmd);
        let reader = std::thread::spawn(move || {
            let mut buf = Vec::new();
            let _ = master.read_to_end(&mut buf); // EIO once every writer is gone
            String::from_utf8_lossy(&buf).into_owned()
        });
        let status = child.wait().expect("wait");
        wd.unwatch(child.id());
        let text = reader.join().expect("reader");
        assert!(status.success(), "{status}\n{text}");
        assert!(text.contains("INFO"), "no log on the terminal\n{text}");
        text
    };
    assert!(run(None).contains('\u{1b}'), "no colour on a terminal");
    assert!(
        run(Some("")).contains('\u{1b}'),
        "an empty NO_COLOR disabled colour"
    );
    let plain = run(Some("1"));
    assert!(
        !plain.contains('\u{1b}'),
        "colour despite NO_COLOR=1\n{plain}"
    );
}
