//! Issue 12 (points 1, 2): what a hostile file or another local user can do
//! to nauta. A recording is data, never a program: replaying it starts only
//! nauta's own service binaries. Run files live in a per-user 0700 directory,
//! are created 0600 without following symlinks, and nothing another user owns
//! is trusted. Every test runs under a watchdog; runs use unique namespaces.

use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::os::unix::fs::{MetadataExt as _, PermissionsExt as _};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use nauta_log::{LogWriter, WriterOptions};
use nauta_runtime::Namespace;
use nauta_runtime::run_files::runs_dir_path;
use nauta_tests::*;

const BOUND: Duration = Duration::from_secs(240);

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir()
        .join("nauta-test-security")
        .join(format!("{name}-{}", Namespace::unique()));
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

/// Runs `nauta ARGS` with extra environment: (exit code, stdout, stderr).
fn nauta_env(args: &[&OsStr], env: &[(&str, &OsStr)]) -> (Option<i32>, String, String) {
    let mut cmd = Command::new(bin("nauta"));
    cmd.args(args)
        .current_dir(workspace_root())
        .env_remove("XDG_RUNTIME_DIR")
        .stdin(Stdio::null());
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = cmd.output().expect("run nauta");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn mode(p: &Path) -> u32 {
    std::fs::symlink_metadata(p)
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
        .mode()
        & 0o7777
}

/// A script that leaves `marker` behind when anything runs it.
fn evil_script(dir: &Path, name: &str, marker: &Path) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(
        &path,
        format!("#!/bin/sh\ntouch '{}'\nexit 1\n", marker.display()),
    )
    .expect("script");
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).expect("chmod");
    path
}

/// A recording holding only its run metadata, with `manifest` as the
/// recorded manifest.
fn crafted_recording(path: &Path, manifest: &str) {
    let mut w = LogWriter::create(path, WriterOptions::default()).expect("create");
    let mut meta = BTreeMap::new();
    meta.insert("manifest".to_owned(), manifest.to_owned());
    w.metadata(nauta_log::META_RUN, meta).expect("metadata");
    w.finish().expect("finish");
}

fn manifest_with_attitude_bin(bin: &str) -> String {
    format!(
        r#"[run]
clock = "sim"
duration_s = 5
seed = 3

[process.sensor]
bin = "nauta-sensor"
params = {{ scenario = "survey" }}

[process.attitude]
bin = "{bin}"
variant = "gyro"
"#
    )
}

/// Issue 12.1: a recording whose manifest names another program (a path,
/// or a name found on PATH) is refused before anything runs.
#[test]
fn a_replayed_recording_never_runs_the_program_its_manifest_names() {
    bin_dir();
    let wd = Watchdog::new("replay_runs_no_program", BOUND);
    let dir = scratch("replay");
    let on_path = dir.join("path");
    std::fs::create_dir_all(&on_path).expect("dir");
    let marker = dir.join("marker");
    let by_path = evil_script(&dir, "evil.sh", &marker);
    evil_script(&on_path, "nauta-evil", &marker);
    let path_env = format!(
        "{}:{}",
        on_path.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    for bin in [by_path.display().to_string(), "nauta-evil".to_owned()] {
        wd.check();
        let file = dir.join("crafted.mcap");
        crafted_recording(&file, &manifest_with_attitude_bin(&bin));
        let (code, out, err) = nauta_env(
            &["replay".as_ref(), file.as_os_str(), "--fast".as_ref()],
            &[("PATH", path_env.as_ref())],
        );
        assert!(
            code.is_some_and(|c| c != 0),
            "{bin}: the replay succeeded\n{out}{err}"
        );
        assert!(
            err.contains("refusing to run") && err.contains("--manifest"),
            "{bin}: no clear refusal\n{err}"
        );
        assert!(!marker.exists(), "{bin}: the recording ran a program");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 12.1: a user's manifest may name any binary, but not an empty one
/// or a directory.
#[test]
fn check_refuses_an_empty_bin_and_a_directory() {
    bin_dir();
    let dir = scratch("bins");
    for (bin, expect) in [("", "bin is empty"), ("/tmp", "is a directory")] {
        let m = dir.join("m.toml");
        std::fs::write(&m, manifest_with_attitude_bin(bin)).expect("manifest");
        let (code, out, err) = nauta_cli(&["check".as_ref(), m.as_os_str()]);
        assert_eq!(code, Some(1), "{bin:?} accepted\n{out}{err}");
        assert!(
            err.contains(expect) && err.contains("process.attitude.bin"),
            "{bin:?}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A refused run directory: name, how to make it, what the error says.
type Case<'a> = (&'a str, &'a dyn Fn(&Path), &'a str);

/// Issue 12.2: a run directory another user owns, with a mode other than
/// 0700, or a symlink in its place is refused by every command that uses it.
#[test]
fn a_run_directory_of_another_user_or_with_another_mode_is_refused() {
    bin_dir();
    let survey = survey_manifest();
    // SAFETY: geteuid(2) cannot fail.
    let uid = unsafe { libc::geteuid() };
    let cases: [Case; 3] = [
        (
            "other uid",
            &|d| {
                std::fs::create_dir(d).expect("dir");
                std::fs::set_permissions(d, std::fs::Permissions::from_mode(0o700)).expect("chmod");
                std::os::unix::fs::chown(d, Some(12345), Some(12345)).expect("chown");
            },
            "owned by uid 12345",
        ),
        (
            "mode 0777",
            &|d| {
                std::fs::create_dir(d).expect("dir");
                std::fs::set_permissions(d, std::fs::Permissions::from_mode(0o777)).expect("chmod");
            },
            "its mode is 0777",
        ),
        (
            "symlink",
            &|d| {
                let elsewhere = d.with_file_name("elsewhere");
                std::fs::create_dir(&elsewhere).expect("dir");
                std::fs::set_permissions(&elsewhere, std::fs::Permissions::from_mode(0o700))
                    .expect("chmod");
                std::os::unix::fs::symlink(&elsewhere, d).expect("symlink");
            },
            "symbolic link",
        ),
    ];
    for (name, make, expect) in cases {
        let tmp = scratch("owner");
        make(&tmp.join(format!("nauta-{uid}")));
        let env = [("TMPDIR", tmp.as_os_str())];
        for args in [
            vec!["check".as_ref(), survey.as_os_str()],
            vec!["status".as_ref()],
            vec!["stop".as_ref()],
        ] {
            let cmd = args[0].to_string_lossy().into_owned();
            let (code, out, err) = nauta_env(&args, &env);
            assert_eq!(code, Some(1), "{name}: nauta {cmd} accepted it\n{out}{err}");
            assert!(
                err.contains("refusing the run directory") && err.contains(expect),
                "{name}: nauta {cmd}: unclear error\n{err}"
            );
        }
        let _ = std::fs::remove_dir_all(&tmp);
    }
}

/// Issue 12.2: symlinks planted in a run's directory (as another user could
/// plant them in the shared `/tmp/nauta` of old) are never followed: the
/// files they point at are unchanged after a run in that namespace.
#[test]
fn a_symlink_planted_in_the_run_directory_is_not_followed() {
    bin_dir();
    let wd = Watchdog::new("planted_symlink", BOUND);
    let dir = scratch("symlink");
    let ns = Namespace::unique();
    let runs = runs_dir_path();
    let (code, _, err) = nauta_cli(&["check".as_ref(), survey_manifest().as_os_str()]);
    assert_eq!(code, Some(0), "{err}");
    let run_dir = runs.join(ns.as_str());
    std::fs::create_dir(&run_dir).expect("run dir");
    std::fs::set_permissions(&run_dir, std::fs::Permissions::from_mode(0o700)).expect("chmod");
    let mut victims = Vec::new();
    for file in ["manifest.toml", "status.json", "lock"] {
        let victim = dir.join(format!("victim-{file}"));
        std::fs::write(&victim, b"precious").expect("victim");
        std::os::unix::fs::symlink(&victim, run_dir.join(file)).expect("plant");
        victims.push(victim);
    }
    // Left by a run that ended long ago.
    let touched = Command::new("touch")
        .args(["-h", "-d", "1 hour ago"])
        .arg(&run_dir)
        .status()
        .expect("touch");
    assert!(touched.success());
    let out = launch(
        &wd,
        &[
            "--fast",
            "--duration",
            "5",
            "--namespace",
            ns.as_str(),
            "--set",
            "attitude.variant=gyro",
        ],
    );
    assert_eq!(out.code(), Some(0), "{out}");
    for v in &victims {
        assert_eq!(
            std::fs::read(v).expect("victim"),
            b"precious",
            "{} was written through a planted symlink",
            v.display()
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 12.2: the files of a running pipeline: the run directory 0700,
/// every file in it (manifest copy, status, lock, the snapshot a restarted
/// process gets) 0600, and every shared-memory segment of the run 0600
/// (iceoryx2 makes its management segment 0666).
#[test]
fn the_files_of_a_running_pipeline_are_private() {
    bin_dir();
    let wd = Watchdog::new("run_file_modes", BOUND);
    let ns = Namespace::unique();
    let run = start_launch(
        &wd,
        &[
            "--clock",
            "wall",
            "--rate",
            "5",
            "--duration",
            "40",
            "--namespace",
            ns.as_str(),
            "--set",
            "attitude.variant=gyro",
            "--set",
            "attitude.restart={ policy = \"on-failure\", max = 3 }",
        ],
    );
    // Running, and past a few snapshots.
    assert!(
        wait_until(&wd, Duration::from_secs(60), || {
            status_json(ns.as_str()).is_some_and(|s| {
                s["processes"].as_array().is_some_and(|p| {
                    p.iter().any(|p| {
                        p["name"] == "attitude"
                            && p["state"] == "running"
                            && p["uptime_s"].as_f64() > Some(3.0)
                    })
                })
            })
        }),
        "the attitude process never ran"
    );
    let (code, out, err) = nauta_cli(&["restart", "attitude", "--namespace", ns.as_str()]);
    assert_eq!(code, Some(0), "restart refused\n{out}{err}");
    let run_dir = runs_dir_path().join(ns.as_str());
    let snapshot = run_dir.join("snapshot-attitude-1.bin");
    assert!(
        wait_until(&wd, Duration::from_secs(30), || snapshot.exists()),
        "no snapshot handed to the restarted attitude process"
    );
    assert_eq!(mode(&runs_dir_path()), 0o700);
    assert_eq!(mode(&run_dir), 0o700);
    let mut names = Vec::new();
    for e in std::fs::read_dir(&run_dir).expect("run dir") {
        let e = e.expect("entry");
        let name = e.file_name().to_string_lossy().into_owned();
        if name.ends_with(".tmp") {
            continue; // a status being written
        }
        assert_eq!(mode(&e.path()), 0o600, "{name}");
        names.push(name);
    }
    for f in [
        "manifest.toml",
        "status.json",
        "lock",
        "snapshot-attitude-1.bin",
    ] {
        assert!(names.iter().any(|n| n == f), "{f} missing in {names:?}");
    }
    // Once the restarted instance runs, no segment is being created (one
    // being initialised is not yet readable, by design).
    assert!(
        wait_until(&wd, Duration::from_secs(30), || {
            status_json(ns.as_str()).is_some_and(|s| {
                s["processes"].as_array().is_some_and(|p| {
                    p.iter().any(|p| {
                        p["name"] == "attitude" && p["instance"] == 1 && p["state"] == "running"
                    })
                })
            })
        }),
        "the restarted attitude process never ran"
    );
    let shm = ns.shm_files();
    assert!(
        shm.iter().any(|f| f.ends_with(".global_mgmt")),
        "no management segment in {shm:?}"
    );
    for f in &shm {
        assert_eq!(mode(&Path::new("/dev/shm").join(f)), 0o600, "/dev/shm/{f}");
    }
    let out = run.wait(&wd);
    assert_eq!(out.code(), Some(0), "{out}");
    assert_eq!(out.summary().restarts("attitude"), 1, "{out}");
}

/// A restrictive umask (0177, as some hardened accounts set) took the
/// execute bit off a new run directory, which the launcher then refused as
/// not private ("its mode is 0600"): a run must start whatever the umask.
#[test]
fn a_restrictive_umask_does_not_make_the_launcher_refuse_its_own_run_directory() {
    bin_dir();
    let _wd = Watchdog::new("umask_0177", BOUND);
    let tmp = scratch("umask");
    let ns = Namespace::unique();
    let script = format!(
        "umask 177 && exec '{}' launch '{}' --duration 2 --fast --namespace {}",
        bin("nauta").display(),
        survey_manifest().display(),
        ns.as_str()
    );
    let out = Command::new("sh")
        .args(["-c", &script])
        .current_dir(workspace_root())
        .env_remove("XDG_RUNTIME_DIR")
        .env("TMPDIR", &tmp)
        .stdin(Stdio::null())
        .output()
        .expect("run sh");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(0),
        "the run failed under umask 0177\n{err}"
    );
    let _ = std::fs::remove_dir_all(&tmp);
}
