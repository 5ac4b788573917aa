//! Issue 12 (points 5, 7): faults that stopped a run, and inputs that passed
//! `check` and then hung, cross-fed or overwrote. Each is refused with a
//! clear error at check time, or survived. Every test runs under a watchdog;
//! runs use unique namespaces.

use std::ffi::OsStr;
use std::path::PathBuf;
use std::time::Duration;

use nauta_runtime::Namespace;
use nauta_runtime::run_files::runs_dir_path;
use nauta_tests::*;

const BOUND: Duration = Duration::from_secs(240);

const GOOD: &str = SMALL_MANIFEST;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir()
        .join("nauta-test-refusals")
        .join(format!("{name}-{}", Namespace::unique()));
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

/// `nauta check` of `text`: (exit code, stderr).
fn check_text(text: &str) -> (Option<i32>, String) {
    let dir = scratch("check");
    let m = dir.join("m.toml");
    std::fs::write(&m, text).expect("manifest");
    let (code, out, err) = nauta_cli(&["check".as_ref(), m.as_os_str()]);
    let _ = std::fs::remove_dir_all(&dir);
    (code, format!("{out}{err}"))
}

fn assert_refused(what: &str, text: &str, expect: &[&str]) {
    let (code, out) = check_text(text);
    assert_eq!(code, Some(1), "{what}: accepted\n{out}");
    for e in expect {
        assert!(out.contains(e), "{what}: the error lacks {e:?}\n{out}");
    }
}

fn os(s: &str) -> &OsStr {
    s.as_ref()
}

fn wall_run(wd: &Watchdog, ns: &Namespace, duration_s: u32, extra: &[&str]) -> Running {
    let d = duration_s.to_string();
    let mut args = vec![
        "--clock",
        "wall",
        "--rate",
        "5",
        "--duration",
        &d,
        "--namespace",
        ns.as_str(),
        "--set",
        "attitude.variant=gyro",
    ];
    args.extend_from_slice(extra);
    start_launch(wd, &args)
}

/// Issue 12.5: a second launch in a namespace that a running pipeline has
/// is refused (both used to run and feed each other); the first run is
/// undisturbed. Issue 12.7: `nauta swap` of a process that does not exist
/// exits 1 with the launcher's reason.
#[test]
fn a_second_launch_in_a_namespace_in_use_is_refused() {
    bin_dir();
    let wd = Watchdog::new("namespace_in_use", BOUND);
    let ns = Namespace::unique();
    let first = wall_run(&wd, &ns, 20, &[]);
    wait_running_pid(&wd, ns.as_str(), "attitude");
    let second = launch(
        &wd,
        &["--fast", "--duration", "5", "--namespace", ns.as_str()],
    );
    assert_eq!(second.code(), Some(1), "{second}");
    assert!(
        second.stderr.contains(&format!("namespace {ns} is in use")),
        "{second}"
    );
    assert!(
        !second.stderr.contains("nauta: run "),
        "it started\n{second}"
    );
    for (args, expect) in [
        (vec!["swap", "nosuch", "gyro"], "no process nosuch"),
        (vec!["swap", "attitude", "nosuch"], "no variant nosuch"),
        (vec!["restart", "nosuch"], "no process nosuch"),
        (
            vec!["swap", "attitude-with-a-name-far-over-32-bytes", "gyro"],
            "at most 32 bytes",
        ),
    ] {
        let mut all: Vec<&OsStr> = args.iter().map(|a| os(a)).collect();
        all.extend([os("--namespace"), os(ns.as_str())]);
        let (code, out, err) = nauta_cli(&all);
        assert_eq!(code, Some(1), "nauta {args:?} exited {code:?}\n{out}{err}");
        assert!(err.contains(expect), "nauta {args:?}: {err}");
    }
    let out = first.wait(&wd);
    assert_eq!(out.code(), Some(0), "{out}");
    let s = out.summary();
    assert_eq!(s.count("sensor/imu"), Some(2000), "cross-fed? {s}");
    assert_eq!(s.gaps(), Some(0), "{s}");
}

/// Issue 12.5: a snapshot that cannot be written where it was meant to go
/// (a temp cleaner removed the run directory) does not stop the run: the
/// launcher recreates what it needs, logs it, and restarts the process.
#[test]
fn a_removed_run_directory_does_not_stop_the_run() {
    bin_dir();
    let wd = Watchdog::new("run_dir_removed", BOUND);
    let ns = Namespace::unique();
    let run = wall_run(
        &wd,
        &ns,
        40,
        &[
            "--set",
            "attitude.restart={ policy = \"on-failure\", max = 3 }",
        ],
    );
    let pid = wait_running_pid(&wd, ns.as_str(), "attitude");
    // Past a few snapshots.
    std::thread::sleep(Duration::from_secs(2));
    std::fs::remove_dir_all(runs_dir_path().join(ns.as_str())).expect("remove the run dir");
    // SAFETY: kill(2) on the attitude process of this test's own run.
    unsafe {
        libc::kill(pid as i32, libc::SIGKILL);
    }
    let out = run.wait(&wd);
    assert_eq!(out.code(), Some(0), "{out}");
    let s = out.summary();
    assert_eq!(s.restarts("attitude"), 1, "{s}");
    assert_eq!(s.count("sensor/imu"), Some(4000), "{s}");
    assert!(
        out.stderr
            .contains("the run directory was removed; recreated it"),
        "{out}"
    );
}

/// Issue 12.5: two processes of one role would publish into each other's
/// services: refused at check time.
#[test]
fn two_processes_of_one_role_are_refused_at_check() {
    bin_dir();
    assert_refused(
        "two attitude processes",
        &format!("{GOOD}\n[process.attitude2]\nbin = \"nauta-attitude\"\nvariant = \"gyro\"\n"),
        &[
            "process.attitude2.bin",
            "attitude and attitude2 both have role attitude",
        ],
    );
}

/// Issue 12.7: values that passed `check` and then made the launch wait 30
/// s, let a manifest override the launcher's own flags, or "succeeded"
/// without running anything.
#[test]
fn names_over_32_bytes_launcher_flags_in_args_and_empty_manifests_are_refused() {
    bin_dir();
    let long = "a".repeat(33);
    assert_refused(
        "33-byte process name",
        &GOOD.replace("[process.attitude]", &format!("[process.{long}]")),
        &[&format!("process.{long}"), "1-32 bytes"],
    );
    for arg in [
        "--namespace",
        "--resume-after=5",
        "--instance",
        "--snapshot",
    ] {
        assert_refused(
            arg,
            &GOOD.replace(
                "variant = \"gyro\"",
                &format!("variant = \"gyro\"\nargs = [\"{arg}\", \"7\"]"),
            ),
            &[
                "process.attitude.args",
                arg.split('=').next().unwrap_or(arg),
                "set by the launcher",
            ],
        );
    }
    let run_only = GOOD.split("[site]").next().unwrap_or(GOOD);
    assert_refused("empty manifest", run_only, &["no process"]);
}

/// Issue 12.7: `--record` into a directory that does not exist is refused
/// (it used to be created silently), by `launch`, `check` and `record`.
#[test]
fn recording_into_a_missing_directory_is_refused() {
    bin_dir();
    let dir = scratch("record");
    let missing = dir.join("nonexistent").join("x.mcap");
    let survey = survey_manifest();
    for args in [
        vec![
            os("check"),
            survey.as_os_str(),
            os("--record"),
            missing.as_os_str(),
        ],
        vec![
            os("launch"),
            survey.as_os_str(),
            os("--fast"),
            os("--duration"),
            os("2"),
            os("--record"),
            missing.as_os_str(),
        ],
        vec![os("record"), os("-o"), missing.as_os_str()],
    ] {
        let (code, out, err) = nauta_cli(&args);
        assert_eq!(code, Some(1), "{args:?} accepted\n{out}{err}");
        assert!(err.contains("does not exist"), "{args:?}: {err}");
        assert!(!dir.join("nonexistent").exists(), "{args:?} created it");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 12.7: `nauta replay F --record F` would overwrite its own input:
/// refused, by path (also through `..` or a symlink) and by file (a hard link).
#[test]
fn a_replay_never_records_over_its_own_input() {
    bin_dir();
    let dir = scratch("replay-self");
    let file = dir.join("in.mcap");
    std::fs::write(&file, b"not read: refused before").expect("input");
    let hard = dir.join("hard.mcap");
    std::fs::hard_link(&file, &hard).expect("hard link");
    let soft = dir.join("soft.mcap");
    std::os::unix::fs::symlink(&file, &soft).expect("symlink");
    let dotted = dir.join("sub").join("..").join("in.mcap");
    std::fs::create_dir(dir.join("sub")).expect("sub");
    for out in [&file, &hard, &soft, &dotted] {
        let (code, o, err) = nauta_cli(&[
            os("replay"),
            file.as_os_str(),
            os("--fast"),
            os("--record"),
            out.as_os_str(),
        ]);
        assert_eq!(code, Some(1), "{}: accepted\n{o}{err}", out.display());
        assert!(
            err.contains("is the recording being replayed"),
            "{}: {err}",
            out.display()
        );
        assert_eq!(
            std::fs::read(&file).expect("input"),
            b"not read: refused before"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 12.6: values that passed `check` and then panicked the launcher or
/// the sensor, slept forever, or read forever are refused with the key and
/// the value; the command line's special values get a clear error instead
/// of "unexpected argument" or a string.
#[test]
fn values_that_panicked_or_hung_are_refused_at_check() {
    bin_dir();
    let survey = survey_manifest();
    for (args, expect) in [
        (vec!["--rate", "1e-300"], vec!["run.rate", "1e-300"]),
        (vec!["--rate", "-1"], vec!["run.rate", "-1"]),
        (vec!["--rate", "nan"], vec!["run.rate", "NaN"]),
        (vec!["--duration", "-5"], vec!["run.duration_s", "-5"]),
        (vec!["--duration", "inf"], vec!["run.duration_s", "inf"]),
        (
            vec![
                "--set",
                "attitude.restart={ policy = \"always\", window_s = 1e300 }",
            ],
            vec!["process.attitude.restart.window_s", "1e300"],
        ),
        (
            vec!["--seed", "18446744073709551615"],
            vec!["--seed", "9223372036854775807"],
        ),
    ] {
        let mut all = vec![os("check"), survey.as_os_str()];
        all.extend(args.iter().map(|a| os(a)));
        let (code, out, err) = nauta_cli(&all);
        assert!(
            code.is_some_and(|c| c == 1 || c == 2),
            "{args:?}: exit {code:?}\n{out}{err}"
        );
        for e in expect {
            assert!(err.contains(e), "{args:?}: the error lacks {e:?}\n{err}");
        }
    }
    let (code, _, err) = nauta_cli(&[os("check"), os("/dev/zero")]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("a manifest is a regular file"), "{err}");
}
