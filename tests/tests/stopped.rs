//! Issue 12 (point 3): a stopped process is not a dead one. SIGSTOP and
//! SIGCONT interrupt an estimator's wait (EINTR), which must not end it; and
//! an estimator that exits 0 before its inputs ended is a failure for the
//! launcher (restarted under its policy, reported, exit code 1). Every test
//! runs under a watchdog in its own namespace.

use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

use nauta_runtime::Namespace;
use nauta_tests::*;

const BOUND: Duration = Duration::from_secs(240);

#[test]
fn sigstop_and_sigcont_of_an_estimator_do_not_end_it() {
    bin_dir();
    let wd = Watchdog::new("sigstop_sigcont", BOUND);
    let ns = Namespace::unique();
    let duration_s = 20;
    let mut run = start_launch(
        &wd,
        &[
            "--clock",
            "wall",
            "--rate",
            "4",
            "--duration",
            &duration_s.to_string(),
            "--namespace",
            ns.as_str(),
            "--set",
            "attitude.variant=gyro",
        ],
    );
    let pid = wait_running_pid(&wd, ns.as_str(), "attitude");
    let pid = pid as i32;
    for _ in 0..5 {
        // SAFETY: kill(2) on the attitude process of this test's own run.
        unsafe {
            libc::kill(pid, libc::SIGSTOP);
        }
        std::thread::sleep(Duration::from_millis(100));
        // SAFETY: as above.
        unsafe {
            libc::kill(pid, libc::SIGCONT);
        }
        std::thread::sleep(Duration::from_millis(200));
        assert!(
            run.is_running(),
            "the run ended while the test stopped attitude"
        );
    }
    // SAFETY: kill(2) with signal 0 only checks that the process exists.
    assert_eq!(
        unsafe { libc::kill(pid, 0) },
        0,
        "nauta-attitude ended after SIGSTOP/SIGCONT"
    );
    let out = run.wait(&wd);
    assert_eq!(out.code(), Some(0), "{out}");
    let s = out.summary();
    assert!(s.all_exited_0(), "{s}");
    assert_eq!(s.restarts("attitude"), 0, "attitude was restarted: {s}");
    let imu = duration_s * 100;
    assert_eq!(s.count("sensor/imu"), Some(imu), "{s}");
    let align = alignment_samples(&survey_manifest());
    assert_eq!(
        s.count("attitude/estimate"),
        Some(imu - (align - 1)),
        "one estimate per IMU sample after the alignment ({align} samples): {s}"
    );
}

/// A consumer of `sensor/imu` in role `ains`: `nauta-fake` with
/// `NAUTA_FAKE_RUN=exit-early` exits 0 after its first sample, seconds
/// before the sensor ends a `wall` run at 10x.
const EARLY: &str = r#"{"role":"ains","inputs":[{"service":"sensor/imu","type":"nauta.ImuSample.v1"}],"outputs":[],"variants":["fake"]}"#;

fn early_manifest(restart: &str) -> PathBuf {
    let dir = std::env::temp_dir()
        .join("nauta-test-stopped")
        .join(Namespace::unique().as_str());
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("early.toml");
    // The small manifest in `wall` clock at 10x for 30 s, with the fake in
    // place of the attitude process.
    let text = SMALL_MANIFEST
        .replace("clock = \"sim\"", "clock = \"wall\"\nrate = 10.0")
        .replace("duration_s = 5", "duration_s = 30")
        .replace(
            "[process.attitude]\nbin = \"nauta-attitude\"\nvariant = \"gyro\"\n",
            &format!("[process.fake]\nbin = \"nauta-fake\"\n{restart}\n"),
        );
    assert!(
        text.contains("nauta-fake") && text.contains("rate = 10.0"),
        "{text}"
    );
    std::fs::write(&path, text).expect("manifest");
    path
}

fn launch_early(wd: &Watchdog, restart: &str) -> Finished {
    let manifest = early_manifest(restart);
    let ns = Namespace::unique();
    let mut cmd = Command::new(bin("nauta"));
    cmd.args([
        "launch",
        &manifest.display().to_string(),
        "--namespace",
        ns.as_str(),
        "--json",
    ])
    .env("NAUTA_FAKE_DESCRIBE", EARLY)
    .env("NAUTA_FAKE_RUN", "exit-early");
    let _gate = Gate::share();
    let out = cmd.output().expect("run nauta launch");
    wd.check();
    let _ = std::fs::remove_dir_all(manifest.parent().expect("dir"));
    Finished {
        command: format!("nauta launch {} (exit-early fake)", manifest.display()),
        status: out.status,
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

#[test]
fn an_estimator_that_exits_0_before_its_inputs_ended_fails_the_run() {
    bin_dir();
    let wd = Watchdog::new("early_exit_0", BOUND);
    let out = launch_early(&wd, "");
    assert_eq!(out.code(), Some(1), "{out}");
    let s = out.summary();
    assert!(
        s.failure()
            .is_some_and(|f| f.contains("fake exited 0 before its inputs ended")),
        "{s}"
    );
}

#[test]
fn an_estimator_that_exits_0_early_is_restarted_under_its_policy() {
    bin_dir();
    let wd = Watchdog::new("early_exit_0_restarted", BOUND);
    let out = launch_early(
        &wd,
        r#"restart = { policy = "on-failure", max = 2, window_s = 60, backoff_ms = [20, 100] }"#,
    );
    assert_eq!(out.code(), Some(1), "{out}");
    let s = out.summary();
    assert_eq!(s.restarts("fake"), 2, "{s}");
    assert!(
        s.failure().is_some_and(
            |f| f.contains("fake exited 0 before its inputs ended and was restarted 2 times")
        ),
        "{s}"
    );
}
