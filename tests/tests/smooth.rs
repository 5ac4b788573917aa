//! `nauta smooth` end to end (issue 15): a recording of `launch/lbl.toml`
//! smoothed from its recorded manifest, then `nauta eval` and `nauta
//! report` on the output; and what it refuses (a recording without LBL
//! inputs, one without a manifest, the input as the output), leaving no
//! output behind.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use nauta_log::{LogWriter, WriterOptions};
use nauta_messages::{DepthSample, Header, Role};
use nauta_runtime::Namespace;
use nauta_tests::*;
use serde_json::Value;

const BOUND: Duration = Duration::from_secs(300);

/// Mission seconds recorded: the surface start, the dive and most of the
/// first side of the box (the smoother's figures over whole missions are
/// `nauta bench lbl`'s).
const MISSION_S: &str = "600";

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nauta-smooth-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn json_of(out: &str) -> Value {
    serde_json::from_str(out).unwrap_or_else(|e| panic!("not one JSON object ({e}): {out}"))
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_recording_of_the_lbl_manifest_is_smoothed_and_evaluated() {
    let wd = Watchdog::new("smooth_lbl_recording", BOUND);
    let dir = temp_dir("run");
    let record = dir.join("lbl.mcap");
    let ns = Namespace::unique();
    let out = launch_manifest(
        &wd,
        &workspace_root().join("launch/lbl.toml"),
        &[
            "--fast",
            "--duration",
            MISSION_S,
            "--namespace",
            ns.as_str(),
            "--record",
            record.to_str().expect("utf-8 path"),
        ],
    );
    assert_eq!(out.code(), Some(0), "{out}");
    let navs = out.summary().count("lbl/nav").expect("lbl/nav count");
    assert!(navs > 5000, "{navs} lbl/nav\n{out}");

    let smoothed = dir.join("smoothed.mcap");
    let (code, stdout, err) = nauta_cli(&[
        "smooth".as_ref(),
        record.as_os_str(),
        "-o".as_ref(),
        smoothed.as_os_str(),
        "--json".as_ref(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let s = json_of(&stdout);
    // The forward pass steps at 10 Hz like the service, and publishes what
    // it published: one smoothed solution per recorded lbl/nav.
    assert_eq!(s["smoothed"].as_u64(), Some(navs), "{s}");
    assert_eq!(s["state_dim"], 4, "{s}");
    // ... and refuses what the live filter refused (the run's only
    // refusals: the attitude refuses none of the simulator's IMU samples).
    let refused: u64 = s["refused"]
        .as_object()
        .expect("refused")
        .values()
        .filter_map(Value::as_u64)
        .sum();
    assert_eq!(Some(refused), out.summary().rejected(), "{s}\n{out}");
    for part in ["read_s", "forward_s", "backward_s", "write_s"] {
        assert!(s[part].as_f64().is_some_and(|t| t >= 0.0), "{part}: {s}");
    }
    // Only the two recordings: no part file left.
    assert_eq!(files_in(&dir), ["lbl.mcap", "smoothed.mcap"]);

    let (code, stdout, err) =
        nauta_cli(&["eval".as_ref(), smoothed.as_os_str(), "--json".as_ref()]);
    assert_eq!(code, Some(0), "{err}");
    let eval = json_of(&stdout);
    let metric = |topic: &str, key: &str| {
        eval["streams"][topic][key]
            .as_f64()
            .unwrap_or_else(|| panic!("streams[{topic:?}][{key:?}] missing: {eval}"))
    };
    let (filter, smooth) = (
        metric("lbl/nav", "horizontal_rms_m"),
        metric("smoother/lbl/nav", "horizontal_rms_m"),
    );
    eprintln!(
        "horizontal RMS: filter {filter:.3} m, smoothed {smooth:.3} m; inside the 95 % ellipse: filter {:.1} %, smoothed {:.1} %",
        metric("lbl/nav", "inside_95_pct"),
        metric("smoother/lbl/nav", "inside_95_pct")
    );
    assert!(
        smooth <= 0.7 * filter,
        "smoothed {smooth} m, filter {filter} m"
    );
    assert!(metric("smoother/lbl/nav", "inside_95_pct") >= 90.0);
    // The copy holds every message of the recording.
    let (code, stdout, err) = nauta_cli(&["eval".as_ref(), record.as_os_str(), "--json".as_ref()]);
    assert_eq!(code, Some(0), "{err}");
    let original = json_of(&stdout);
    assert_eq!(
        original["streams"]["lbl/nav"], eval["streams"]["lbl/nav"],
        "the copy changed lbl/nav"
    );

    // The report draws paper 004's ellipse axes, real time against smoothed.
    let report = dir.join("report");
    let (code, _, err) = nauta_cli(&[
        "report".as_ref(),
        smoothed.as_os_str(),
        "-o".as_ref(),
        report.as_os_str(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let html = std::fs::read_to_string(report.join("index.html")).expect("index.html");
    assert!(report.join("ellipse_axes.png").is_file(), "{html}");
    assert!(html.contains("paper 004 Fig. 8"), "{html}");
    assert!(html.contains("smoother/lbl/nav"), "{html}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A recording of `depth` samples only, with `manifest` recorded (if any).
fn write_recording(path: &Path, manifest: Option<&str>) {
    let mut w = LogWriter::create(path, WriterOptions::default()).expect("create");
    if let Some(text) = manifest {
        w.metadata(
            nauta_log::META_RUN,
            BTreeMap::from([("manifest".to_owned(), text.to_owned())]),
        )
        .expect("metadata");
    }
    for i in 0..10u64 {
        let m = DepthSample {
            header: Header::new(i * 100_000_000, i, Role::Sensor, 0),
            depth_m: 5.0,
        };
        w.write_message(nauta_messages::DEPTH_SERVICE, i, &m)
            .expect("write");
    }
    w.finish().expect("finish");
}

#[test]
fn what_cannot_be_smoothed_is_refused_with_a_clear_error() {
    let dir = temp_dir("bad");
    let manifest =
        std::fs::read_to_string(workspace_root().join("launch/lbl.toml")).expect("lbl.toml");
    let no_manifest = dir.join("no-manifest.mcap");
    write_recording(&no_manifest, None);
    let depth_only = dir.join("depth-only.mcap");
    write_recording(&depth_only, Some(&manifest));
    let survey = dir.join("survey.mcap");
    write_recording(
        &survey,
        Some(&std::fs::read_to_string(survey_manifest()).expect("survey.toml")),
    );
    let out = dir.join("out.mcap");
    let cases: [(&Path, &Path, &[&str], &str); 5] = [
        (&no_manifest, &out, &[], "--manifest"),
        (&survey, &out, &[], "runs no nauta-lbl process"),
        // The depth alone never starts the filter (no GPS fix).
        (&depth_only, &out, &[], "never started"),
        (&depth_only, &depth_only, &[], "is the input"),
        (
            &depth_only,
            &out,
            &["--set", "lbl.params.range_sigma_m=-1"],
            "range_sigma_m",
        ),
    ];
    for (input, output, extra, expected) in cases {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "smooth".as_ref(),
            input.as_os_str(),
            "-o".as_ref(),
            output.as_os_str(),
        ];
        args.extend(extra.iter().map(|a| std::ffi::OsStr::new(*a)));
        let (code, stdout, err) = nauta_cli(&args);
        assert_eq!(code, Some(1), "{input:?} {extra:?}: {stdout}{err}");
        assert!(err.contains(expected), "{input:?} {extra:?}: {err}");
    }
    // Nothing written: no output, no part file.
    assert_eq!(
        files_in(&dir),
        ["depth-only.mcap", "no-manifest.mcap", "survey.mcap"]
    );
    let _ = std::fs::remove_dir_all(&dir);
}
