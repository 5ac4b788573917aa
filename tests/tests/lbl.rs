//! Issue 15: `nauta-lbl` in the pipeline of `launch/lbl.toml` (sensor,
//! attitude, lbl). The closed loop with the transponders runs in lock step
//! in `sim` clock, so the same seed gives the same bytes; four transponders
//! with `--set sensor.params.lbl_layout=Four` are four for every process; a
//! kill -9 and a hot swap keep every `lbl/nav` stamp exactly once; a layout
//! whose transponders coincide is refused before anything starts. Every
//! test runs in its own namespace under a watchdog.

use std::path::PathBuf;
use std::time::Duration;

use nauta_messages::{LblReply, codec};
use nauta_runtime::{Namespace, services};
use nauta_tests::*;

const BOUND: Duration = Duration::from_secs(400);
/// `lbl/nav`'s period, ns (10 Hz).
const NAV_PERIOD_NS: u64 = 100_000_000;

fn lbl_manifest() -> PathBuf {
    workspace_root().join("launch").join("lbl.toml")
}

/// The whole mission (two transponders) twice with seed 7: the same bytes,
/// `lbl/nav` at 10 Hz from the first GPS fix to the end, every interrogation
/// registered at its stamp, only multipath refused, and the accuracy of the
/// in-process tests (shared/estimation/tests/lbl).
#[test]
fn the_lbl_mission_is_deterministic_and_accurate() {
    bin_dir();
    let wd = Watchdog::new("lbl_mission", BOUND);
    let run = || {
        let ns = Namespace::unique();
        let out = launch_manifest(
            &wd,
            &lbl_manifest(),
            &["--fast", "--namespace", ns.as_str()],
        );
        assert_eq!(out.code(), Some(0), "{out}");
        out.assert_lbl_lock_step();
        out.summary()
    };
    let (a, b) = (run(), run());
    let d = a
        .digest_of("lbl/nav")
        .unwrap_or_else(|| panic!("no digest\n{a}"));
    assert_eq!(b.digest_of("lbl/nav"), Some(d), "same seed, other bytes");
    assert_eq!(
        a.digest_of("lbl/interrogate"),
        b.digest_of("lbl/interrogate")
    );
    let mission = a.mission_s().expect("mission");
    let nav = a.count("lbl/nav").expect("lbl/nav") as f64;
    assert!(
        (nav - 10.0 * mission).abs() < 15.0,
        "{nav} solutions in {mission} s\n{a}"
    );
    let pings = a.count("lbl/interrogate").expect("pings");
    let replies = a.count("sensor/lbl").expect("replies");
    assert!(
        pings > 2500 && replies + 2 >= pings,
        "{pings} pings, {replies} replies\n{a}"
    );
    // Refused: the multipath replies (5 %), nothing else.
    let rejected = a.rejected().expect("rejected");
    assert!(rejected > 0 && rejected * 100 < replies * 8, "{a}");
    assert_eq!(a.gaps(), Some(0), "{a}");
    let rms = a.error("lbl/nav", "horizontal_rms_m").expect("eval");
    let inside = a.error("lbl/nav", "inside_95_pct").expect("eval");
    assert!(rms < 0.5, "{rms} m\n{a}");
    assert!((90.0..=99.0).contains(&inside), "{inside} %\n{a}");
}

/// `--set sensor.params.lbl_layout=Four` gives four transponders to the
/// simulator and to the navigator alike: replies come from all four.
#[test]
fn four_transponders_are_four_everywhere() {
    bin_dir();
    let wd = Watchdog::new("lbl_four", BOUND);
    let ns = Namespace::unique();
    let dir = tempfile::tempdir().expect("tempdir");
    let record = dir.path().join("four.mcap");
    let out = launch_manifest(
        &wd,
        &lbl_manifest(),
        &[
            "--fast",
            "--duration",
            "300",
            "--namespace",
            ns.as_str(),
            "--set",
            "sensor.params.lbl_layout=Four",
            "--record",
            record.to_str().expect("utf-8"),
        ],
    );
    assert_eq!(out.code(), Some(0), "{out}");
    let mut ids = std::collections::BTreeSet::new();
    nauta_log::read(&record, |ch, m| {
        if ch.topic == "sensor/lbl" {
            let r: LblReply = codec::decode(m.data)?;
            ids.insert(r.transponder_id);
        }
        Ok(())
    })
    .expect("read the recording");
    assert_eq!(ids.into_iter().collect::<Vec<_>>(), [1, 2, 3, 4], "{out}");
    let s = out.summary();
    assert!(s.error("lbl/nav", "horizontal_rms_m") < Some(0.5), "{s}");
}

/// A layout whose transponders coincide is refused by `nauta check`, with
/// the key and the reason.
#[test]
fn coincident_transponders_are_refused_at_check() {
    bin_dir();
    let dir = tempfile::tempdir().expect("tempdir");
    let text = std::fs::read_to_string(lbl_manifest())
        .expect("lbl.toml")
        .replace("lbl_layout = \"Two\"", "")
        .replace(
            "sound_speed_m_s = 1507.5\n",
            "sound_speed_m_s = 1507.5\ntransponders = [\n  { id = 1, north_m = -50.0, east_m = -150.0, depth_m = 20.0 },\n  { id = 2, north_m = -50.0, east_m = -149.5, depth_m = 30.0 },\n]\n",
        );
    let m = dir.path().join("m.toml");
    std::fs::write(&m, text).expect("manifest");
    let (code, out, err) = nauta_cli(&["check".as_ref(), m.as_os_str()]);
    assert_eq!(code, Some(1), "accepted\n{out}{err}");
    assert!(
        err.contains("site.transponders") && err.contains("cannot tell a position apart"),
        "{err}"
    );
}

/// A kill -9 of the LBL navigator (restarted warm from its snapshot) and a
/// hot swap to a new instance keep every `lbl/nav` stamp exactly once, in
/// `wall` clock at twice real time.
#[test]
fn kill_9_and_swap_of_lbl_keep_every_stamp_exactly_once() {
    bin_dir();
    let wd = Watchdog::new("lbl_kill_swap", BOUND);
    let run = kill_9_then_swap(
        &wd,
        &lbl_manifest(),
        2.0,
        &[
            "--clock",
            "wall",
            "--rate",
            "2",
            "--duration",
            "60",
            "--set",
            "attitude.variant=gyro",
        ],
        "lbl",
        &services::lbl_solution(),
        "ekf",
    );
    let out = &run.out;
    assert_eq!(out.code(), Some(0), "the run failed\n{out}");
    let s = out.summary();
    assert_eq!((s.restarts("lbl"), s.swaps("lbl")), (1, 1), "{s}");
    run.assert_every_stamp_once("lbl/nav", NAV_PERIOD_NS);
    assert_eq!(s.gaps(), Some(0), "{s}");
    assert!(s.all_exited_0(), "{s}");
}
