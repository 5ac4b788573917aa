//! Issue 5: recordings. A whole `--fast` survey recorded by the logger holds
//! exactly what the publishers say they published, without a sequence gap; an
//! independent MCAP reader (PyPI `mcap`) sees the same channels and counts; a
//! replay of the recording through the pipeline reproduces the recorded
//! estimates bit for bit; a logger killed with -9 leaves a file whose every
//! flushed chunk is read back, and the reader reports the cut.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;

use nauta_estimation::frames::{Frd, Ned, Rotation};
use nauta_tests::*;

const BOUND: Duration = Duration::from_secs(300);

/// A directory for this test process's files, removed at exit by nobody: it
/// lives under the target directory and is recreated per process.
fn scratch(name: &str) -> PathBuf {
    let dir = bin_dir()
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(std::env::temp_dir)
        .join("nauta-test-recordings")
        .join(format!("{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn nauta(args: &[&std::ffi::OsStr]) -> (Option<i32>, String, String) {
    nauta_cli(args)
}

fn log_info(file: &Path) -> serde_json::Value {
    let (code, out, err) = nauta(&[
        "log".as_ref(),
        "info".as_ref(),
        file.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(
        code,
        Some(0),
        "nauta log info {} failed:\n{err}",
        file.display()
    );
    serde_json::from_str(&out).unwrap_or_else(|e| panic!("log info JSON: {e}\n{out}"))
}

fn channel<'a>(info: &'a serde_json::Value, topic: &str) -> &'a serde_json::Value {
    info["channels"]
        .as_array()
        .and_then(|c| c.iter().find(|c| c["topic"] == topic))
        .unwrap_or_else(|| panic!("no channel {topic} in {info}"))
}

/// The per-service counts a process logged in its `done` line:
/// `counts=[("sim/truth", 260335), ...]`.
fn sensor_counts(stderr: &str) -> BTreeMap<String, u64> {
    let line = stderr
        .lines()
        .find(|l| l.contains("sensor") && l.contains(" done ") && l.contains("counts="))
        .unwrap_or_else(|| panic!("no sensor `done` line in\n{stderr}"))
        .to_owned();
    let list = line
        .split_once("counts=[")
        .and_then(|(_, rest)| rest.split_once(']'))
        .map(|(list, _)| list)
        .expect("counts list");
    list.split("), (")
        .map(|item| {
            let item = item.trim_matches(|c| c == '(' || c == ')');
            let (name, n) = item.split_once(", ").expect("name, count");
            (name.trim_matches('"').to_owned(), n.parse().expect("count"))
        })
        .collect()
}

/// `outputs=N` of a process's `done` line.
fn done_field(stderr: &str, process: &str, field: &str) -> u64 {
    let line = stderr
        .lines()
        .find(|l| l.contains(&format!("{process}:")) && l.contains(" done "))
        .unwrap_or_else(|| panic!("no {process} `done` line in\n{stderr}"));
    line.split_whitespace()
        .find_map(|w| w.strip_prefix(&format!("{field}=")))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no {field}= in {line}"))
}

/// One recorded run of the whole survey, `--fast`, shared by the tests below:
/// (file, the launcher's output).
fn survey_recording() -> &'static (PathBuf, Finished) {
    static REC: OnceLock<(PathBuf, Finished)> = OnceLock::new();
    REC.get_or_init(|| {
        let wd = Watchdog::new("survey_recording", BOUND);
        let file = scratch("survey").join("survey.mcap");
        let f = launch(
            &wd,
            &["--fast", "--record", file.to_str().expect("utf-8 path")],
        );
        assert_eq!(f.code(), Some(0), "{f}");
        (file, f)
    })
}

/// Done when: a 45-minute `--fast` survey recording has zero sequence gaps on
/// every channel and exactly as many messages per channel as were published.
#[test]
fn a_fast_survey_recording_holds_every_published_message_without_gaps() {
    let (file, run) = survey_recording();
    let info = log_info(file);
    assert_eq!(info["truncated"], false, "{info}");
    let mission_s = info["duration_s"].as_f64().expect("duration");
    assert!(mission_s > 2500.0, "the survey is ~2603 s, got {mission_s}");
    for c in info["channels"].as_array().expect("channels") {
        assert_eq!(c["gaps"], 0, "gaps on {}", c["topic"]);
        assert_eq!(c["out_of_order"], 0, "out of order on {}", c["topic"]);
    }
    // The sensor's own per-service counts.
    let published = sensor_counts(&run.stderr);
    assert!(published.len() >= 9, "{published:?}");
    for (topic, n) in &published {
        if *n == 0 {
            continue; // a service without traffic (sensor/lbl in the survey)
        }
        assert_eq!(
            channel(&info, topic)["count"].as_u64(),
            Some(*n),
            "{topic}: recorded vs published"
        );
    }
    // The attitude's own count of its estimates.
    let estimates = done_field(&run.stderr, "attitude", "outputs");
    assert!(estimates > 250_000, "{estimates}");
    assert_eq!(
        channel(&info, "attitude/estimate")["count"].as_u64(),
        Some(estimates)
    );
    // The metadata says how the run was made.
    let run_meta = &info["metadata"]["nauta.run"];
    for key in [
        "manifest",
        "seed",
        "git_revision",
        "command_line",
        "sensor_config.sensor",
    ] {
        assert!(
            run_meta.get(key).is_some(),
            "nauta.run lacks {key}: {run_meta}"
        );
    }
    assert_eq!(run_meta["seed"], "7");
    // Lifecycle events are recorded.
    let events = info["events"].as_array().expect("events");
    for (kind, process) in [
        ("started", "attitude"),
        ("started", "sensor"),
        ("exited", "attitude"),
    ] {
        assert!(
            events
                .iter()
                .any(|e| e["kind"] == kind && e["process"] == process),
            "no {kind} event of {process}: {events:?}"
        );
    }
}

/// Done when: an independent reader (the PyPI package `mcap`) opens the file
/// and lists the same channels and counts.
#[test]
fn an_independent_mcap_reader_sees_the_same_channels_and_counts() {
    let (file, _) = survey_recording();
    let info = log_info(file);
    let py: serde_json::Value =
        serde_json::from_str(&run_python("mcap_counts.py", &[file.as_os_str()]))
            .expect("python JSON");
    assert_eq!(py["profile"], "nauta");
    let ours: BTreeMap<String, u64> = info["channels"]
        .as_array()
        .expect("channels")
        .iter()
        .map(|c| {
            (
                c["topic"].as_str().expect("topic").to_owned(),
                c["count"].as_u64().expect("count"),
            )
        })
        .collect();
    let theirs: BTreeMap<String, u64> = py["channels"]
        .as_object()
        .expect("channels")
        .iter()
        .map(|(t, c)| (t.clone(), c["count"].as_u64().expect("count")))
        .collect();
    assert_eq!(ours, theirs);
    let imu = &py["channels"]["sensor/imu"];
    assert_eq!(imu["schema"], "nauta.ImuSample.v1");
    assert_eq!(imu["schema_encoding"], nauta_log::SCHEMA_ENCODING);
    assert_eq!(imu["message_encoding"], nauta_log::MESSAGE_ENCODING);
}

/// The payloads of `topic` in `file`, in file order.
fn payloads(file: &Path, topic: &str) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    nauta_log::read(file, |ch, m| {
        if ch.topic == topic {
            out.push(m.data.to_vec());
        }
        Ok(())
    })
    .unwrap_or_else(|e| panic!("read {}: {e:#}", file.display()));
    out
}

/// Done when: replaying a recording into the pipeline in `sim` mode
/// reproduces the recorded estimator outputs bit for bit.
#[test]
fn a_replay_reproduces_the_recorded_estimates_bit_for_bit() {
    let (file, _) = survey_recording();
    let wd = Watchdog::new("replay", BOUND);
    let out = scratch("replay").join("replayed.mcap");
    let _gate = Gate::share();
    let r = Running::spawn(
        &wd,
        &bin("nauta"),
        &[
            "replay".as_ref(),
            file.as_os_str(),
            "--fast".as_ref(),
            "--record".as_ref(),
            out.as_os_str(),
        ],
        None,
    )
    .wait(&wd);
    assert_eq!(r.code(), Some(0), "{r}");
    for topic in ["sensor/imu", "sim/truth", "sensor/dvl", "sensor/gps"] {
        let (a, b) = (payloads(file, topic), payloads(&out, topic));
        assert_eq!(a.len(), b.len(), "{topic}: count");
        assert!(a == b, "{topic}: the replay published other bytes");
    }
    let (a, b) = (
        payloads(file, "attitude/estimate"),
        payloads(&out, "attitude/estimate"),
    );
    assert!(a.len() > 250_000, "{}", a.len());
    assert_eq!(a.len(), b.len(), "estimate count");
    let first_diff = a.iter().zip(&b).position(|(x, y)| x != y);
    assert_eq!(first_diff, None, "the replayed estimates differ");
}

/// Every message of `file` as (topic, payload), in file order, and whether
/// the reader found the file cut short.
fn all_messages(file: &Path) -> (Vec<(String, Vec<u8>)>, bool) {
    let mut out = Vec::new();
    let rec = nauta_log::read(file, |ch, m| {
        out.push((ch.topic.clone(), m.data.to_vec()));
        Ok(())
    })
    .unwrap_or_else(|e| panic!("read {}: {e:#}", file.display()));
    (out, rec.recovery.truncated)
}

/// `nauta status --json` of the run in `ns`, once it answers.
fn status(ns: &str) -> Option<serde_json::Value> {
    let (code, out, _) = nauta(&[
        "status".as_ref(),
        "--json".as_ref(),
        "--namespace".as_ref(),
        ns.as_ref(),
    ]);
    (code == Some(0)).then(|| serde_json::from_str(&out).ok())?
}

fn logger_status(ns: &str) -> Option<serde_json::Value> {
    status(ns)?["processes"]
        .as_array()?
        .iter()
        .find(|p| p["name"] == "logger")
        .cloned()
}

/// The survey in `wall` clock at 10x in namespace `ns`, with `extra` options.
fn start_wall_run(wd: &Watchdog, ns: &str, extra: &[&str]) -> Running {
    let mut args = vec![
        "--clock",
        "wall",
        "--rate",
        "10",
        "--duration",
        "600",
        "--namespace",
        ns,
    ];
    args.extend_from_slice(extra);
    start_launch(wd, &args)
}

/// Done when: the logger killed with `kill -9` mid-run: the file opens,
/// every chunk flushed before the kill is read back, and the reader reports
/// the truncation instead of failing. The launcher restarts the logger into
/// `NAME.1.mcap`, which ends complete.
#[test]
fn a_logger_killed_with_9_leaves_every_flushed_chunk_readable() {
    let wd = Watchdog::new("logger_kill_9", BOUND);
    let dir = scratch("kill9");
    let file = dir.join("run.mcap");
    let ns = nauta_runtime::Namespace::unique();
    let run = start_wall_run(
        &wd,
        ns.as_str(),
        &["--record", file.to_str().expect("utf-8 path")],
    );
    // Running, and at least three flushes (one per second) on disk.
    let mut pid = 0;
    assert!(
        wait_until(&wd, Duration::from_secs(60), || {
            if let Some(l) = logger_status(ns.as_str())
                && l["state"] == "running"
            {
                pid = l["pid"].as_u64().unwrap_or(0) as u32;
            }
            pid > 0
        }),
        "the logger never ran\n{}",
        run.wait(&wd)
    );
    std::thread::sleep(Duration::from_millis(3500));
    // What is on disk now was flushed before the kill.
    let before = dir.join("before-kill.mcap");
    std::fs::copy(&file, &before).expect("copy");
    // SAFETY: kill(2) on the logger's pid, read from the run's status.
    assert_eq!(unsafe { libc::kill(pid as i32, libc::SIGKILL) }, 0);
    assert!(
        wait_until(&wd, Duration::from_secs(30), || {
            logger_status(ns.as_str())
                .is_some_and(|l| l["restarts"] == 1 && l["state"] == "running")
        }),
        "the logger was not restarted\n{}",
        run.wait(&wd)
    );
    std::thread::sleep(Duration::from_millis(1500));
    let (code, _, err) = nauta(&[
        "stop".as_ref(),
        "--namespace".as_ref(),
        ns.as_str().as_ref(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let f = run.wait(&wd);
    assert!(
        !f.stdout.is_empty() && f.code().is_some(),
        "the launcher did not end normally\n{f}"
    );

    // The killed instance's file: cut short, readable, reported.
    let (flushed, cut_before) = all_messages(&before);
    let (kept, cut) = all_messages(&file);
    assert!(cut_before && cut, "the reader did not report the cut");
    assert!(
        flushed.len() > 1000,
        "only {} messages flushed in 3.5 s",
        flushed.len()
    );
    assert!(kept.len() >= flushed.len());
    assert!(
        kept[..flushed.len()] == flushed[..],
        "a message flushed before the kill was not read back"
    );
    let info = log_info(&file);
    assert_eq!(info["truncated"], true, "{info}");
    assert!(info["recovery"]["read_bytes"].as_u64() <= info["recovery"]["file_bytes"].as_u64());
    assert!(
        info["messages"].as_u64() == Some(kept.len() as u64),
        "{info}"
    );
    // The restarted logger's file is complete.
    let second = dir.join("run.1.mcap");
    let (more, cut_second) = all_messages(&second);
    assert!(!cut_second, "the restarted logger's file is not complete");
    assert!(!more.is_empty());
    let info2 = log_info(&second);
    assert_eq!(info2["truncated"], false);
    assert_eq!(info2["metadata"]["nauta.run"]["instance"], "1");
    // It starts with who runs, as the first file did.
    let events = info2["events"].as_array().expect("events");
    for process in ["sensor", "attitude", "logger"] {
        assert!(
            events
                .iter()
                .any(|e| e["kind"] == "started" && e["process"] == process),
            "no started event of {process} in the restarted logger's file: {events:?}"
        );
    }
}

/// `nauta record -o FILE` attaches a logger to a running pipeline; it ends
/// with the run and leaves a complete file whose gap counts agree with the
/// logger's own.
#[test]
fn nauta_record_attaches_to_a_running_pipeline() {
    let wd = Watchdog::new("record_attach", BOUND);
    let dir = scratch("attach");
    let file = dir.join("attached.mcap");
    let ns = nauta_runtime::Namespace::unique();
    let run = start_wall_run(&wd, ns.as_str(), &[]);
    assert!(
        wait_until(&wd, Duration::from_secs(60), || {
            status(ns.as_str()).is_some_and(|s| {
                s["processes"]
                    .as_array()
                    .is_some_and(|p| p.iter().all(|p| p["state"] == "running"))
            })
        }),
        "the pipeline never ran\n{}",
        run.wait(&wd)
    );
    let record = Running::spawn(
        &wd,
        &bin("nauta"),
        &[
            "record".as_ref(),
            "-o".as_ref(),
            file.as_os_str(),
            "--namespace".as_ref(),
            ns.as_str().as_ref(),
        ],
        None,
    );
    std::thread::sleep(Duration::from_secs(3));
    let (code, _, err) = nauta(&[
        "stop".as_ref(),
        "--namespace".as_ref(),
        ns.as_str().as_ref(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let launched = run.wait(&wd);
    assert_eq!(launched.code(), Some(0), "{launched}");
    let recorded = record.wait(&wd);
    assert_eq!(recorded.code(), Some(0), "{recorded}");
    let info = log_info(&file);
    assert_eq!(info["truncated"], false, "{info}");
    for topic in ["sensor/imu", "sim/truth", "attitude/estimate"] {
        let c = channel(&info, topic);
        assert!(c["count"].as_u64() > Some(100), "{topic}: {c}");
    }
    // The gaps the file shows are the gaps the logger counted as it received.
    let stats = &info["metadata"]["nauta.logger.stats"];
    for c in info["channels"].as_array().expect("channels") {
        let topic = c["topic"].as_str().expect("topic");
        let own = stats[topic].as_str().unwrap_or_default();
        assert!(
            own.contains(&format!("received={} gaps={} ", c["count"], c["gaps"])),
            "{topic}: file {c} against the logger's {own:?}"
        );
    }
    assert!(
        info["metadata"]["nauta.run"]["command_line"]
            .as_str()
            .is_some_and(|c| c.contains("record")),
        "{info}"
    );
}

/// A BROAD-format trial (the columns of `nauta_datasets::broad::HEADER`)
/// written from the simulator: paper 000's yaw motion, 120 s at 100 Hz,
/// with a clean magnetometer, the optical reference being the truth in ENU.
/// Returns the site (degrees) and the field's declination (degrees).
fn simulated_broad_trial(path: &Path) -> (f64, f64, f64) {
    use nauta_sim::scenario::{Generator, ScenarioKind, ScenarioParams};
    let params = ScenarioParams {
        scenario: ScenarioKind::Yaw,
        attitude_duration_s: 120.0,
        ..Default::default()
    };
    let mut sensors = params.sensors_preset();
    sensors.imu.mag.hard_iron = [0.0; 3];
    sensors.imu.mag.soft_iron = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let origin = nauta_sim::mission::Origin::lisbon();
    let mut g = Generator::new(&params, origin, sensors, 7, 120.0).expect("scenario");
    let declination = g
        .simulator()
        .environment()
        .magnetic
        .declination_rad
        .to_degrees();
    let mut csv = nauta_datasets::broad::HEADER.join(",") + "\n";
    let mut t0 = None;
    while let Some(m) = g.step() {
        let m = m.expect("step");
        let Some(r) = m.imu else { continue };
        let t = r.stamp_ns as f64 * 1e-9 - *t0.get_or_insert(r.stamp_ns as f64 * 1e-9);
        let q_nb = Rotation::<Frd, Ned>::from_wxyz(m.truth.quat_nb).expect("unit truth");
        let q = nauta_datasets::broad::enu_from_ned(q_nb.as_nalgebra());
        let v = |a: [f64; 3]| format!("{},{},{}", a[0], a[1], a[2]);
        csv += &format!(
            "{t},{},{},{},{},{},{},{},1\n",
            v(r.gyro_rad_s),
            v(r.accel_m_s2),
            v(r.mag_ut),
            q.w,
            q.i,
            q.j,
            q.k
        );
    }
    std::fs::write(path, csv).expect("write trial");
    (
        origin.lat_rad.to_degrees(),
        origin.lon_rad.to_degrees(),
        declination,
    )
}

/// Issue 6: `nauta import broad` turns a trial in BROAD's format (Laidig et
/// al. 2021; ../shared/data/broad holds eight real ones, replayed the same
/// way in BENCHMARKS.md) into a recording that replays through the running
/// pipeline, where the attitude process's `pf` follows the reference within
/// the per-trial bound (4.5°). The trial here is written from the
/// simulator (paper 000's yaw motion), so that the test needs no outside data.
#[test]
fn an_imported_broad_trial_replays_through_the_attitude_process() {
    let dir = scratch("broad");
    let trial = dir.join("yaw_motion.csv");
    let (lat, lon, declination) = simulated_broad_trial(&trial);
    let imported = dir.join("imported.mcap");
    let site = format!("{lat},{lon}");
    let dec = format!("{declination}");
    let (code, _, err) = nauta(&[
        "import".as_ref(),
        "broad".as_ref(),
        trial.as_os_str(),
        "-o".as_ref(),
        imported.as_os_str(),
        "--site".as_ref(),
        site.as_ref(),
        "--declination".as_ref(),
        dec.as_ref(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let info = log_info(&imported);
    let imu = channel(&info, "sensor/imu")["count"]
        .as_u64()
        .expect("count");
    assert!(imu > 11_000, "{imu}");
    assert_eq!(channel(&info, "sim/truth")["count"].as_u64(), Some(imu));
    assert!(
        (channel(&info, "sensor/imu")["rate_hz"]
            .as_f64()
            .expect("rate")
            - 100.0)
            .abs()
            < 0.01
    );
    assert_eq!(
        info["metadata"]["nauta.run"]["origin_lat_deg"],
        format!("{lat}")
    );

    let wd = Watchdog::new("broad_replay", BOUND);
    let run_file = dir.join("run.mcap");
    let _gate = Gate::share();
    let f = Running::spawn(
        &wd,
        &bin("nauta"),
        &[
            "replay".as_ref(),
            imported.as_os_str(),
            "--fast".as_ref(),
            "--record".as_ref(),
            run_file.as_os_str(),
        ],
        None,
    )
    .wait(&wd);
    assert_eq!(f.code(), Some(0), "{f}");
    let run = log_info(&run_file);
    assert_eq!(channel(&run, "sensor/imu")["count"].as_u64(), Some(imu));
    let estimates = channel(&run, "attitude/estimate")["count"]
        .as_u64()
        .expect("count");
    assert!(
        estimates + 400 >= imu,
        "{estimates} estimates of {imu} samples"
    );
    // The replay's summary line (`nauta replay` has no `--json`).
    let line = &f.stdout;
    let total: f64 = line
        .split_once("total ")
        .and_then(|(_, rest)| rest.split_once('°'))
        .and_then(|(v, _)| v.parse().ok())
        .unwrap_or_else(|| panic!("no attitude error in\n{line}"));
    println!("simulated BROAD-format trial through the pipeline (pf): total RMS {total:.3}°");
    assert!(total < 4.5, "{line}");
}
