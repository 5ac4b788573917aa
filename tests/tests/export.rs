//! Issue 5: `nauta export`. A recording written with `nauta_log::LogWriter`
//! (60 s of the survey from nauta-sim's `Generator`: truth, IMU, depth, GPS at
//! the surface, the buoy; a synthetic `ains/nav` 5 m north-east of the truth,
//! `attitude/estimate`, `positioning/fix`, `lbl/nav` from the truth's local
//! position, health and events; the `nauta.run` metadata the logger writes)
//! is exported by the real binary in every format, and each output is checked
//! by independent readers in Python (`tests/py/check_exports.py`): the KML
//! against the OGC KML 2.2 XML Schema, the GeoJSON against a GeoJSON JSON
//! Schema and RFC 7946's rules, the GPX with gpxpy and GPX 1.1's element
//! order, the CSV with Python's csv module, the Foxglove file with the PyPI
//! `mcap` reader and `jsonschema`.

use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;

use nauta_log::{LogWriter, WriterOptions};
use nauta_messages::*;
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioParams};
use nauta_sim::suite::LblLayout;
use nauta_tests::*;
use serde_json::{Value, json};

const BOUND: Duration = Duration::from_secs(300);

/// Simulated seconds in the test recording.
const DURATION_S: f64 = 60.0;

/// The `ains/nav` message (by count) with a non-finite depth.
const REJECTED_NAV: u64 = 4321;

/// Offset of the synthetic `ains/nav` from the truth, north and east, m.
const NAV_OFFSET_M: (f64, f64) = (5.0, 2.0);

/// The documented CSV header (`nauta_log::export::csv`), written out here so
/// that a change to it fails this test.
const CSV_HEADER: &str = "time_s,stamp_ns,topic,lat_deg,lon_deg,depth_m,north_m,east_m,\
    vel_north_m_s,vel_east_m_s,vel_down_m_s,roll_deg,pitch_deg,yaw_deg,std_north_m,std_east_m,\
    std_down_m,corr_north_east,std_vel_north_m_s,std_vel_east_m_s,std_vel_down_m_s,\
    std_att_north_deg,std_att_east_deg,std_att_down_deg,type";

/// A directory for this test process's files, under the target directory.
fn scratch(name: &str) -> PathBuf {
    let dir = bin_dir()
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(std::env::temp_dir)
        .join("nauta-test-exports")
        .join(format!("{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn nauta(wd: &Watchdog, args: &[&OsStr]) -> (Option<i32>, String, String) {
    wd.check();
    let out = std::process::Command::new(bin("nauta"))
        .args(args)
        .stdin(std::process::Stdio::null())
        .output()
        .expect("run nauta");
    wd.check();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `nauta export FILE --format FORMAT -o OUT [extra]`, which must exit 0.
fn export(wd: &Watchdog, file: &Path, format: &str, out: &Path, extra: &[&str]) -> String {
    let mut args: Vec<&OsStr> = vec![
        "export".as_ref(),
        file.as_os_str(),
        "--format".as_ref(),
        format.as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ];
    args.extend(extra.iter().map(|a| OsStr::new(*a)));
    let (code, stdout, stderr) = nauta(wd, &args);
    assert_eq!(
        code,
        Some(0),
        "nauta export --format {format} failed\nstdout:\n{stdout}\nstderr:\n{stderr}"
    );
    stderr
}

/// The test recording and what the checks expect of its exports.
struct Fixture {
    recording: PathBuf,
    expect: PathBuf,
}

/// Writes the recording once per test process.
fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let dir = scratch("fixture");
        let recording = dir.join("survey.mcap");
        let expect = write_recording(&recording);
        let expect_path = dir.join("expect.json");
        std::fs::write(
            &expect_path,
            serde_json::to_vec_pretty(&expect).expect("json"),
        )
        .expect("write expectations");
        Fixture {
            recording,
            expect: expect_path,
        }
    })
}

/// The `nauta.run` metadata as the logger writes it.
fn run_metadata() -> BTreeMap<String, String> {
    let manifest = std::fs::read_to_string(survey_manifest()).expect("survey manifest");
    let mut m = BTreeMap::new();
    m.insert("origin_lat_deg".to_owned(), "38.6".to_owned());
    m.insert("origin_lon_deg".to_owned(), "-9.3".to_owned());
    m.insert("manifest".to_owned(), manifest);
    m.insert("seed".to_owned(), "7".to_owned());
    // The survey's sensors with the LBL transponders switched on: the default
    // layout, which `nauta export` finds through the simulator's presets.
    m.insert(
        "sensor_config.sensor".to_owned(),
        "[params]\nscenario = \"survey\"\nstill_s = 10.0\n\n[params.sensors.lbl]\nenabled = true\n"
            .to_owned(),
    );
    m
}

/// Writes the recording; returns the expectations for `check_exports.py`.
fn write_recording(path: &Path) -> Value {
    let params = ScenarioParams::default();
    let origin = Origin::lisbon();
    let mut generator = Generator::new(&params, origin, params.sensors_preset(), 7, DURATION_S)
        .expect("survey generator");
    let mut w = LogWriter::create(path, WriterOptions::default()).expect("create recording");
    w.metadata(nauta_log::META_RUN, run_metadata())
        .expect("metadata");
    let mut counts: BTreeMap<&str, u64> = BTreeMap::new();
    let mut first_truth = None;
    // Log times as a wall-clock logger would stamp them.
    let epoch_ns: u64 = 1_782_034_200_000_000_000;
    let mut put = |w: &mut LogWriter, topic: &'static str, bytes: Vec<u8>, stamp: u64| {
        *counts.entry(topic).or_insert(0) += 1;
        let ch = match topic {
            "sim/truth" => w.channel(topic, &TypeInfo::of::<TruthState>()),
            "sensor/imu" => w.channel(topic, &TypeInfo::of::<ImuSample>()),
            "sensor/depth" => w.channel(topic, &TypeInfo::of::<DepthSample>()),
            "sensor/gps" => w.channel(topic, &TypeInfo::of::<GpsFix>()),
            "sensor/modem" => w.channel(topic, &TypeInfo::of::<BuoyRange>()),
            "ains/nav" => w.channel(topic, &TypeInfo::of::<NavSolution>()),
            "attitude/estimate" => w.channel(topic, &TypeInfo::of::<AttitudeEstimate>()),
            "positioning/fix" => w.channel(topic, &TypeInfo::of::<PositionFix>()),
            "lbl/nav" => w.channel(topic, &TypeInfo::of::<LblSolution>()),
            "attitude/health" => w.channel(topic, &TypeInfo::of::<Health>()),
            "run/events" => w.channel(topic, &TypeInfo::of::<RunEvent>()),
            other => panic!("unexpected topic {other}"),
        }
        .expect("channel");
        w.write(ch, epoch_ns + stamp + 50_000, &bytes)
            .expect("write");
    };
    fn enc<M: Message>(m: &M) -> Vec<u8> {
        codec::encode(m).expect("encode")
    }
    let mut n = 0u64;
    let mut last_fix = 0u64;
    let mut rejected_stamp = None;
    while let Some(m) = generator.step() {
        let m = m.expect("step");
        let t = &m.truth;
        let s = t.stamp_ns;
        let h = |role: Role, seq: u64| Header::new(s, seq, role, 0);
        first_truth.get_or_insert((t.lat_rad, t.lon_rad));
        // The sensor channels the exports read, as the sensor publishes them.
        let mut sensors = Vec::new();
        nauta_sim::wire::to_wire(&m, &mut sensors);
        for mut msg in sensors {
            let topic = msg.service();
            if matches!(
                topic,
                "sim/truth" | "sensor/imu" | "sensor/depth" | "sensor/gps" | "sensor/modem"
            ) {
                msg.header_mut().seq = n;
                let stamp = msg.header().stamp_ns;
                put(&mut w, topic, msg.encode().expect("encode"), stamp);
            }
        }
        let (north, east) = origin.to_local(t.lat_rad, t.lon_rad);
        if n == REJECTED_NAV {
            rejected_stamp = Some(s);
        }
        // Synthetic estimates: the truth with a known error.
        let (nlat, nlon) = origin.to_geodetic(north + NAV_OFFSET_M.0, east + NAV_OFFSET_M.1);
        put(
            &mut w,
            "ains/nav",
            enc(&NavSolution {
                header: h(Role::Ains, n),
                lat_rad: nlat,
                lon_rad: nlon,
                // One non-finite depth: the message fails its check (DESIGN
                // §4), so it is a CSV row of its stamp with no values and no
                // map point; the Foxglove copy of the channel (every field as
                // recorded) leaves the depth out of that JSON message.
                depth_m: if n == REJECTED_NAV {
                    f64::NAN
                } else {
                    t.depth_m
                },
                vel_ned_m_s: t.vel_ned_m_s,
                quat_nb: t.quat_nb,
                pos_std_ned_m: [1.5, 1.5, 0.2],
                vel_std_ned_m_s: [0.05, 0.05, 0.02],
                predicted_drift_m: 0.01 * t.distance_m,
                aiding_mode: 1,
                advisory: 0,
            }),
            s,
        );
        put(
            &mut w,
            "attitude/estimate",
            enc(&AttitudeEstimate {
                header: h(Role::Attitude, n),
                quat_nb: t.quat_nb,
                std_rad: [0.002, 0.002, 0.01],
                gyro_bias_rad_s: [1e-5, -1e-5, 2e-5],
                calibration: 1,
                pad: 0,
            }),
            s,
        );
        if s >= last_fix + 5_000_000_000 || n == 0 {
            last_fix = s;
            let (flat, flon) = origin.to_geodetic(north - 3.0, east + 1.0);
            put(
                &mut w,
                "positioning/fix",
                enc(&PositionFix {
                    header: h(Role::Positioning, s / 5_000_000_000),
                    lat_rad: flat,
                    lon_rad: flon,
                    std_north_m: 4.0,
                    std_east_m: 3.0,
                    corr_ne: 0.2,
                    effective_particles: 420.0,
                    fix_source: 1,
                    pad: 0,
                }),
                s,
            );
        }
        if n.is_multiple_of(10) {
            let mut p = [[0.0; 4]; 4];
            p[0][0] = 4.0;
            p[1][1] = 6.25;
            p[0][1] = 1.0;
            p[1][0] = 1.0;
            p[2][2] = 0.01;
            p[3][3] = 0.01;
            put(
                &mut w,
                "lbl/nav",
                enc(&LblSolution {
                    header: h(Role::Lbl, n / 10),
                    x_m: north,
                    y_m: east,
                    current_x_m_s: 0.1,
                    current_y_m_s: -0.05,
                    p,
                    ellipse_major_m: 2.6,
                    ellipse_minor_m: 1.9,
                    ellipse_orientation_rad: 1.2,
                    last_innovation_m: 0.3,
                    transponder_id: (n / 10 % 2 + 1) as u32,
                    accepted: 1,
                }),
                s,
            );
        }
        if n.is_multiple_of(100) {
            put(
                &mut w,
                "attitude/health",
                enc(&Health {
                    header: h(Role::Attitude, n / 100),
                    inputs: n,
                    outputs: n,
                    variant: to_fixed_str("gyro"),
                    ..Default::default()
                }),
                s,
            );
        }
        if n == 0 {
            put(
                &mut w,
                "run/events",
                enc(&RunEvent {
                    header: h(Role::Launcher, 0),
                    kind: event_kind::STARTED,
                    role: Role::Attitude as u32,
                    pid: 4242,
                    process: to_fixed_str("attitude"),
                    variant: to_fixed_str("gyro"),
                    ..Default::default()
                }),
                s,
            );
        }
        n += 1;
    }
    // A damaged message: skipped and counted by every format, never a panic.
    put(&mut w, "ains/nav", vec![7u8; 35], n * 10_000_000);
    w.finish().expect("finish");

    let (lat, lon) = first_truth.expect("truth");
    let transponders: Vec<Value> = LblLayout::Two
        .transponders()
        .iter()
        .map(|t| {
            let (lat, lon) = origin.to_geodetic(t.north_m, t.east_m);
            json!({"id": t.id, "lat_deg": lat.to_degrees(), "lon_deg": lon.to_degrees()})
        })
        .collect();
    let csv_topics = [
        "sim/truth",
        "ains/nav",
        "attitude/estimate",
        "positioning/fix",
        "lbl/nav",
        "sensor/gps",
    ];
    assert!(
        counts["sensor/gps"] > 1,
        "no GPS fixes at the surface: {counts:?}"
    );
    assert!(counts["sensor/modem"] >= 1, "no buoy message: {counts:?}");
    json!({
        "source": path,
        "source_counts": counts,
        "skipped": {"ains/nav": 1},
        "tracks": ["sim/truth", "ains/nav", "positioning/fix", "lbl/nav", "sensor/gps"],
        "csv_header": CSV_HEADER,
        "csv_counts": csv_topics
            .iter()
            .map(|t| (t.to_string(), json!(counts[t] - u64::from(*t == "ains/nav"))))
            .collect::<serde_json::Map<_, _>>(),
        "known_point": {"topic": "sim/truth", "lat_deg": lat.to_degrees(), "lon_deg": lon.to_degrees()},
        "nav_offset_m": [NAV_OFFSET_M.0, NAV_OFFSET_M.1],
        "rejected_rows": [{"topic": "ains/nav", "stamp_ns": rejected_stamp.expect("rejected nav").to_string()}],
        "buoy_points": counts["sensor/modem"],
        "transponders": transponders,
    })
}

fn check(format: &str, out: &Path) -> String {
    let f = fixture();
    run_python(
        "check_exports.py",
        &[OsStr::new(format), out.as_os_str(), f.expect.as_os_str()],
    )
}

fn export_and_check(name: &str, format: &str, ext: &str, extra: &[&str]) -> String {
    let wd = Watchdog::new(name, BOUND);
    let f = fixture();
    let dir = scratch(name);
    let out = dir.join(format!("survey.{ext}"));
    let stderr = export(&wd, &f.recording, format, &out, extra);
    assert!(
        stderr.contains("ains/nav: 1 message(s) did not decode and were skipped"),
        "the damaged message is not reported:\n{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    let report = check(format, &out);
    assert!(report.contains(&format!("ok {format}")), "{report}");
    report
}

#[test]
fn kml_validates_and_holds_one_line_string_per_track() {
    export_and_check("kml", "kml", "kml", &[]);
}

#[test]
fn kml_with_absolute_altitude_validates() {
    export_and_check("kml-absolute", "kml", "kml", &["--altitude", "absolute"]);
}

#[test]
fn geojson_validates_against_rfc_7946_longitude_first() {
    export_and_check("geojson", "geojson", "geojson", &[]);
}

#[test]
fn gpx_parses_with_one_trk_per_track_and_times_from_the_utc_start() {
    let report = export_and_check(
        "gpx",
        "gpx",
        "gpx",
        &["--utc-start", "2026-06-21T09:30:00Z"],
    );
    assert!(report.contains("times yes"), "{report}");
    let report = export_and_check("gpx-no-time", "gpx", "gpx", &[]);
    assert!(report.contains("times no"), "{report}");
}

#[test]
fn csv_has_the_documented_header_and_a_row_per_message() {
    export_and_check("csv", "csv", "csv", &[]);
}

#[test]
fn foxglove_messages_are_json_that_matches_their_json_schema() {
    export_and_check("foxglove", "foxglove", "mcap", &[]);
}

#[test]
fn every_sample_is_kept_on_request() {
    let report = export_and_check("geojson-all", "geojson", "geojson", &["--track-hz", "0"]);
    let f = fixture();
    let expect: Value =
        serde_json::from_slice(&std::fs::read(&f.expect).expect("read")).expect("json");
    let truth = expect["source_counts"]["sim/truth"]
        .as_u64()
        .expect("count");
    assert!(
        report.contains(&format!("sim/truth {truth} points")),
        "{report}"
    );
}

#[test]
fn errors_are_clear_and_exit_non_zero() {
    let wd = Watchdog::new("errors", BOUND);
    let f = fixture();
    let dir = scratch("errors");

    // Unknown format: clap lists the formats.
    let (code, _, err) = nauta(
        &wd,
        &[
            "export".as_ref(),
            f.recording.as_os_str(),
            "--format".as_ref(),
            "shp".as_ref(),
            "-o".as_ref(),
            dir.join("x.shp").as_os_str(),
        ],
    );
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("kml") && err.contains("foxglove"), "{err}");

    // No format and an extension that says none.
    let (code, _, err) = nauta(
        &wd,
        &[
            "export".as_ref(),
            f.recording.as_os_str(),
            "-o".as_ref(),
            dir.join("x.txt").as_os_str(),
        ],
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("--format"), "{err}");

    // The format from the extension.
    let (code, out, err) = nauta(
        &wd,
        &[
            "export".as_ref(),
            f.recording.as_os_str(),
            "-o".as_ref(),
            dir.join("x.gpx").as_os_str(),
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(out.contains("(gpx)"), "{out}");

    // An unwritable output.
    let bad = dir.join("no-such-dir").join("x.kml");
    let (code, _, err) = nauta(
        &wd,
        &[
            "export".as_ref(),
            f.recording.as_os_str(),
            "--format".as_ref(),
            "kml".as_ref(),
            "-o".as_ref(),
            bad.as_os_str(),
        ],
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("cannot write") && err.contains("no-such-dir"),
        "{err}"
    );

    // A recording without a position stream, for a map format.
    let imu_only = dir.join("imu.mcap");
    let mut w = LogWriter::create(&imu_only, WriterOptions::default()).expect("create");
    for i in 0..10 {
        w.write_message(
            "sensor/imu",
            i,
            &ImuSample {
                header: Header::new(i * 10_000_000, i, Role::Sensor, 0),
                ..Default::default()
            },
        )
        .expect("write");
    }
    w.finish().expect("finish");
    let kml = dir.join("imu.kml");
    let (code, _, err) = nauta(
        &wd,
        &[
            "export".as_ref(),
            imu_only.as_os_str(),
            "--format".as_ref(),
            "kml".as_ref(),
            "-o".as_ref(),
            kml.as_os_str(),
        ],
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("no position stream") && err.contains("sensor/imu"),
        "{err}"
    );
    assert!(!kml.exists(), "a failed export left {}", kml.display());

    // Not a recording.
    let text = dir.join("notes.mcap");
    std::fs::write(&text, "not a recording").expect("write");
    let (code, _, err) = nauta(
        &wd,
        &[
            "export".as_ref(),
            text.as_os_str(),
            "-o".as_ref(),
            dir.join("n.kml").as_os_str(),
        ],
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("not an MCAP file"), "{err}");

    // A bad --origin or --utc-start.
    for (opt, value) in [("--origin", "91,0"), ("--utc-start", "yesterday")] {
        let (code, _, err) = nauta(
            &wd,
            &[
                "export".as_ref(),
                f.recording.as_os_str(),
                "-o".as_ref(),
                dir.join("o.kml").as_os_str(),
                opt.as_ref(),
                value.as_ref(),
            ],
        );
        assert_eq!(code, Some(1), "{opt} {value}: {err}");
        assert!(err.contains(opt), "{err}");
    }
}

#[test]
fn lbl_without_an_origin_is_left_out_with_a_note() {
    let wd = Watchdog::new("no-origin", BOUND);
    let dir = scratch("no-origin");
    let input = dir.join("lbl.mcap");
    let origin = Origin::lisbon();
    let mut w = LogWriter::create(&input, WriterOptions::default()).expect("create");
    for i in 0..100u64 {
        let (north, east) = (i as f64, 0.5 * i as f64);
        let (lat, lon) = origin.to_geodetic(north, east);
        w.write_message(
            "sim/truth",
            i,
            &TruthState {
                header: Header::new(i * 100_000_000, i, Role::Sensor, 0),
                lat_rad: lat,
                lon_rad: lon,
                quat_nb: [1.0, 0.0, 0.0, 0.0],
                ..Default::default()
            },
        )
        .expect("write");
        w.write_message(
            "lbl/nav",
            i,
            &LblSolution {
                header: Header::new(i * 100_000_000, i, Role::Lbl, 0),
                x_m: north,
                y_m: east,
                ..Default::default()
            },
        )
        .expect("write");
    }
    w.finish().expect("finish");
    let out = dir.join("lbl.kml");
    let stderr = export(&wd, &input, "kml", &out, &[]);
    assert!(
        stderr.contains("lbl/nav") && stderr.contains("--origin"),
        "{stderr}"
    );
    let kml = std::fs::read_to_string(&out).expect("read");
    assert_eq!(kml.matches("<LineString>").count(), 1, "{kml:.3000}");
    // With --origin it is placed: its last point is the truth's.
    let stderr = export(&wd, &input, "geojson", &out, &["--origin", "38.6,-9.3"]);
    assert!(!stderr.contains("--origin"), "{stderr}");
    let doc: Value = serde_json::from_slice(&std::fs::read(&out).expect("read")).expect("json");
    let line = |topic: &str| {
        doc["features"]
            .as_array()
            .and_then(|f| f.iter().find(|f| f["properties"]["topic"] == topic))
            .map(|f| f["geometry"]["coordinates"].clone())
            .unwrap_or_else(|| panic!("no {topic} in {doc}"))
    };
    let (lbl, truth) = (line("lbl/nav"), line("sim/truth"));
    let last = |v: &Value| {
        let a = v.as_array().expect("coordinates");
        let p = a.last().expect("point");
        (p[0].as_f64().expect("lon"), p[1].as_f64().expect("lat"))
    };
    let (a, b) = (last(&lbl), last(&truth));
    assert!(
        (a.0 - b.0).abs() < 1e-7 && (a.1 - b.1).abs() < 1e-7,
        "{a:?} {b:?}"
    );
}

/// Issue 11: eval and export place `lbl/nav` (local metres) on the globe
/// through the one run-metadata reader and the one projection. The fixture's
/// `lbl/nav` is the truth's own local position, so the export must put each
/// point on the truth's latitude and longitude (to 1e-9°, 0.1 mm) and eval
/// must find no horizontal error (below 1 mm).
#[test]
fn eval_and_export_place_an_lbl_point_at_the_same_latitude_and_longitude() {
    let wd = Watchdog::new("lbl_placement", BOUND);
    let f = fixture();
    let dir = scratch("lbl_placement");
    let out = dir.join("survey.csv");
    export(&wd, &f.recording, "csv", &out, &[]);
    let text = std::fs::read_to_string(&out).expect("csv");
    let mut truth: BTreeMap<String, (f64, f64)> = BTreeMap::new();
    let mut lbl: Vec<(String, f64, f64)> = Vec::new();
    for line in text.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        let (stamp, topic) = (cols[1].to_owned(), cols[2]);
        let lat: f64 = cols[3].parse().unwrap_or(f64::NAN);
        let lon: f64 = cols[4].parse().unwrap_or(f64::NAN);
        match topic {
            "sim/truth" => {
                truth.insert(stamp, (lat, lon));
            }
            "lbl/nav" => lbl.push((stamp, lat, lon)),
            _ => {}
        }
    }
    assert!(lbl.len() > 100, "{} lbl/nav rows", lbl.len());
    for (stamp, lat, lon) in &lbl {
        let (tlat, tlon) = truth[stamp];
        assert!(
            (lat - tlat).abs() < 1e-9 && (lon - tlon).abs() < 1e-9,
            "lbl/nav at {stamp}: export {lat},{lon}, truth {tlat},{tlon}"
        );
    }
    let (code, stdout, stderr) = nauta(
        &wd,
        &[
            OsStr::new("eval"),
            f.recording.as_os_str(),
            OsStr::new("--json"),
        ],
    );
    assert_eq!(code, Some(0), "{stderr}");
    let eval: Value = serde_json::from_str(&stdout).expect("eval json");
    let rms = eval["streams"]["lbl/nav"]["horizontal_rms_m"]
        .as_f64()
        .unwrap_or_else(|| panic!("no lbl/nav error: {stdout}"));
    assert!(rms < 1e-3, "eval places lbl/nav {rms} m from the truth");
}
