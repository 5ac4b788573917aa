use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nauta_messages::*;

use super::*;
use crate::{LogWriter, WriterOptions};

const LAT0: f64 = 38.6;
const LON0: f64 = -9.3;

fn origin() -> GeoOrigin {
    GeoOrigin::from_degrees(LAT0, LON0).expect("origin")
}

/// 60 s of a vehicle going north-east at 1 m/s: truth and nav at 100 Hz
/// (nav 3 m north of the truth), GPS at 1 Hz for the first 10 s, LBL at 10 Hz,
/// attitude at 100 Hz, a depth channel, and with `meta` the origin.
fn write_run(dir: &Path, meta: bool) -> PathBuf {
    let path = dir.join("run.mcap");
    let mut w = LogWriter::create(&path, WriterOptions::default()).expect("create");
    if meta {
        let mut m = BTreeMap::new();
        m.insert("origin_lat_deg".to_owned(), LAT0.to_string());
        m.insert("origin_lon_deg".to_owned(), LON0.to_string());
        m.insert(
            "sensor_config.sensor".to_owned(),
            "[params.sensors.lbl]\ntransponders = [{ id = 1, north_m = -50.0, east_m = -150.0, depth_m = 20.0 }]\n"
                .to_owned(),
        );
        w.metadata(crate::META_RUN, m).expect("meta");
    }
    let o = origin();
    for i in 0..6000u64 {
        let t = i as f64 * 0.01;
        let stamp = i * 10_000_000;
        let (n, e) = (
            t * std::f64::consts::FRAC_1_SQRT_2,
            t * std::f64::consts::FRAC_1_SQRT_2,
        );
        let (lat, lon) = o.to_geodetic(n, e);
        let q = [0.9238795325112867, 0.0, 0.0, 0.3826834323650898]; // yaw 45°
        let truth = TruthState {
            header: Header::new(stamp, i, Role::Sensor, 0),
            lat_rad: lat,
            lon_rad: lon,
            depth_m: t * 0.1,
            vel_ned_m_s: [0.7, 0.7, 0.1],
            quat_nb: q,
            ..Default::default()
        };
        w.write_message("sim/truth", 1_000 + i, &truth)
            .expect("write");
        let (nlat, nlon) = o.to_geodetic(n + 3.0, e);
        let nav = NavSolution {
            header: Header::new(stamp, i, Role::Ains, 0),
            lat_rad: nlat,
            lon_rad: nlon,
            depth_m: t * 0.1,
            quat_nb: q,
            pos_std_ned_m: [1.0, 2.0, 0.5],
            ..Default::default()
        };
        w.write_message("ains/nav", 1_000 + i, &nav).expect("write");
        let att = AttitudeEstimate {
            header: Header::new(stamp, i, Role::Attitude, 0),
            quat_nb: q,
            std_rad: [0.01, 0.01, 0.02],
            ..Default::default()
        };
        w.write_message("attitude/estimate", 1_000 + i, &att)
            .expect("write");
        if i.is_multiple_of(100) && i < 1000 {
            let gps = GpsFix {
                header: Header::new(stamp, i / 100, Role::Sensor, 0),
                lat_rad: lat,
                lon_rad: lon,
                horizontal_std_m: 2.5,
                quality: 1,
                ..Default::default()
            };
            w.write_message("sensor/gps", 1_000 + i, &gps)
                .expect("write");
        }
        if i.is_multiple_of(10) {
            let mut lbl = LblSolution {
                header: Header::new(stamp, i / 10, Role::Lbl, 0),
                x_m: n,
                y_m: e,
                ..Default::default()
            };
            lbl.p[0][0] = 4.0;
            lbl.p[1][1] = 9.0;
            w.write_message("lbl/nav", 1_000 + i, &lbl).expect("write");
            let d = DepthSample {
                header: Header::new(stamp, i / 10, Role::Sensor, 0),
                depth_m: t * 0.1,
            };
            w.write_message("sensor/depth", 1_000 + i, &d)
                .expect("write");
        }
        if i.is_multiple_of(3000) {
            let (blat, blon) = o.to_geodetic(300.0, 125.0);
            let b = BuoyRange {
                header: Header::new(stamp, i / 3000, Role::Sensor, 0),
                buoy_lat_rad: blat,
                buoy_lon_rad: blon,
                buoy_depth_m: 1.0,
                time_of_flight_s: 0.2,
                sound_speed_m_s: 1500.0,
            };
            w.write_message("sensor/modem", 1_000 + i, &b)
                .expect("write");
        }
    }
    w.finish().expect("finish");
    path
}

fn run(input: &Path, out: &Path, format: Format) -> Result<ExportSummary, ExportError> {
    export(input, out, &ExportOptions::new(format), |_, _| {})
}

fn track<'a>(s: &'a ExportSummary, topic: &str) -> &'a TrackSummary {
    s.tracks
        .iter()
        .find(|t| t.topic == topic)
        .unwrap_or_else(|| panic!("no {topic} in {:?}", s.tracks))
}

#[test]
fn kml_has_one_line_per_track_decimated_to_one_hertz() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write_run(dir.path(), true);
    let out = dir.path().join("run.kml");
    let s = run(&input, &out, Format::Kml).expect("export");
    let text = std::fs::read_to_string(&out).expect("read");
    assert_eq!(text.matches("<LineString>").count(), 4, "{:?}", s.tracks);
    // 0, 1, ..., 59 s and the last sample at 59.99 s.
    assert_eq!(track(&s, "sim/truth").written, 61);
    assert_eq!(track(&s, "lbl/nav").written, 61);
    assert_eq!(track(&s, "sensor/gps").written, 10);
    assert_eq!(s.landmarks, 3, "2 buoy broadcasts and 1 transponder");
    assert!(text.contains("<name>transponder 1</name>"));
    assert!(text.contains("clampToGround"));
    assert!(s.notes.is_empty(), "{:?}", s.notes);
    // The first point is the origin, longitude first.
    assert!(
        text.contains("-9.30000000,38.60000000,0.000"),
        "{text:.2000}"
    );
    // No partial file is left beside the output.
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(left.len(), 2, "{left:?}");
}

#[test]
fn lbl_without_origin_is_left_out_of_maps_with_a_note_and_kept_in_csv() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write_run(dir.path(), false);
    let s = run(&input, &dir.path().join("a.geojson"), Format::GeoJson).expect("export");
    assert_eq!(track(&s, "lbl/nav").written, 0);
    assert!(
        s.notes
            .iter()
            .any(|n| n.starts_with("lbl/nav") && n.contains("--origin")),
        "{:?}",
        s.notes
    );
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("a.geojson")).expect("read"))
            .expect("json");
    let lines = doc["features"]
        .as_array()
        .expect("features")
        .iter()
        .filter(|f| f["geometry"]["type"] == "LineString")
        .count();
    assert_eq!(lines, 3);

    let s = run(&input, &dir.path().join("a.csv"), Format::Csv).expect("csv");
    assert_eq!(track(&s, "lbl/nav").written, 600);
    let mut opts = ExportOptions::new(Format::Kml);
    opts.origin = Some(origin());
    let s = export(&input, &dir.path().join("a.kml"), &opts, |_, _| {}).expect("kml");
    assert_eq!(track(&s, "lbl/nav").written, 61);
}

#[test]
fn csv_has_a_row_per_message_and_the_documented_header() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write_run(dir.path(), true);
    let out = dir.path().join("run.csv");
    let s = run(&input, &out, Format::Csv).expect("export");
    let text = std::fs::read_to_string(&out).expect("read");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(csv::COLUMNS.join(",").as_str()));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.iter().all(|r| r.len() == csv::COLUMNS.len()));
    let count = |topic: &str| rows.iter().filter(|r| r[2] == topic).count();
    assert_eq!(count("sim/truth"), 6000);
    assert_eq!(count("ains/nav"), 6000);
    assert_eq!(count("attitude/estimate"), 6000);
    assert_eq!(count("lbl/nav"), 600);
    assert_eq!(count("sensor/gps"), 10);
    assert_eq!(count("sensor/depth"), 0);
    assert_eq!(s.written, 18_610);
    // The nav row at 10 s: 3 m north of the truth, yaw 45°, std 1 / 2 / 0.5.
    let col = |name: &str| {
        csv::COLUMNS
            .iter()
            .position(|c| *c == name)
            .expect("column")
    };
    let nav = rows
        .iter()
        .find(|r| r[2] == "ains/nav" && r[1] == "10000000000")
        .expect("nav row");
    let t = 10.0 * std::f64::consts::FRAC_1_SQRT_2;
    let north: f64 = nav[col("north_m")].parse().expect("north");
    assert!((north - (t + 3.0)).abs() < 1e-6, "{north}");
    let yaw: f64 = nav[col("yaw_deg")].parse().expect("yaw");
    assert!((yaw - 45.0).abs() < 1e-9, "{yaw}");
    assert_eq!(nav[col("std_east_m")], "2");
    assert_eq!(nav[col("time_s")], "10");
    let lbl = rows.iter().find(|r| r[2] == "lbl/nav").expect("lbl row");
    assert_eq!(lbl[col("std_east_m")], "3");
    assert_eq!(lbl[col("lat_deg")], "38.6");
}

#[test]
fn gpx_splits_at_gaps_and_adds_times_with_a_utc_start() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write_run(dir.path(), true);
    let out = dir.path().join("run.gpx");
    let mut opts = ExportOptions::new(Format::Gpx);
    opts.utc_start = Some(UtcTime::parse("2026-06-21T09:30:00Z").expect("utc"));
    let s = export(&input, &out, &opts, |_, _| {}).expect("export");
    let text = std::fs::read_to_string(&out).expect("read");
    assert_eq!(text.matches("<trk>").count(), 4);
    assert_eq!(text.matches("<wpt ").count(), s.landmarks as usize);
    assert!(text.contains("<time>2026-06-21T09:30:59.990Z</time>"));
    assert!(text.contains("<ele>-0.100</ele>"));
    let without = run(&input, &out, Format::Gpx).expect("export");
    assert_eq!(without.written, s.written);
    assert!(
        !std::fs::read_to_string(&out)
            .expect("read")
            .contains("<time>")
    );
}

#[test]
fn foxglove_copies_every_message_as_json_and_adds_location_fixes() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write_run(dir.path(), true);
    let out = dir.path().join("run.foxglove.mcap");
    let s = run(&input, &out, Format::Foxglove).expect("export");
    assert_eq!(s.messages_read, 6000 * 3 + 10 + 600 * 2 + 2);
    let map: u64 = s.tracks.iter().map(|t| t.written).sum();
    assert_eq!(s.written, s.messages_read + map);
    assert_eq!(map, 61 * 3 + 10);
    let bytes = std::fs::read(&out).expect("read");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("has a summary");
    let mut counts: BTreeMap<String, u64> = BTreeMap::new();
    let stats = summary.stats.as_ref().expect("stats");
    for (id, n) in &stats.channel_message_counts {
        let ch = &summary.channels[id];
        assert_eq!(ch.message_encoding, "json");
        let schema = ch.schema.as_ref().expect("schema");
        assert_eq!(schema.encoding, "jsonschema");
        counts.insert(ch.topic.clone(), *n);
    }
    assert_eq!(counts["sim/truth"], 6000);
    assert_eq!(counts["/map/sim/truth"], 61);
    assert_eq!(counts["sensor/modem"], 2);
    assert_eq!(summary.metadata_indexes.len(), 1);
    let mut first = None;
    for m in mcap::MessageStream::new(&bytes).expect("stream") {
        let m = m.expect("message");
        if m.channel.topic == "/map/ains/nav" {
            first = Some(serde_json::from_slice::<serde_json::Value>(&m.data).expect("json"));
            break;
        }
    }
    let fix = first.expect("a location fix");
    assert_eq!(fix["frame_id"], "ains/nav");
    assert_eq!(fix["position_covariance"][0], 4.0);
    assert_eq!(fix["position_covariance_type"], 2);
    assert!((fix["heading"].as_f64().expect("heading") - 45f64.to_radians()).abs() < 1e-9);
}

#[test]
fn bad_messages_are_skipped_and_counted() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("bad.mcap");
    let mut w = LogWriter::create(&path, WriterOptions::default()).expect("create");
    let o = origin();
    for i in 0..10u64 {
        let (lat, lon) = o.to_geodetic(i as f64, 0.0);
        let m = TruthState {
            header: Header::new(i * 1_000_000_000, i, Role::Sensor, 0),
            lat_rad: if i == 3 { f64::NAN } else { lat },
            lon_rad: lon,
            quat_nb: [1.0, 0.0, 0.0, 0.0],
            ..Default::default()
        };
        w.write_message("sim/truth", i, &m).expect("write");
    }
    let ch = w
        .channel("sim/truth", &TypeInfo::of::<TruthState>())
        .expect("channel");
    w.write(ch, 99, &[0u8; 40]).expect("short payload");
    w.finish().expect("finish");
    for format in Format::ALL {
        let out = dir.path().join(format!("bad.{format}"));
        let s = run(&path, &out, format).expect("export");
        assert_eq!(s.decode_failures.get("sim/truth"), Some(&1), "{format}");
        assert!(
            s.notes.iter().any(|n| n.contains("did not decode")),
            "{format}"
        );
        let t = track(&s, "sim/truth");
        assert_eq!(t.invalid, 1, "{format}");
        match format {
            Format::Csv => assert_eq!(t.written, 10),
            Format::Foxglove => {
                assert_eq!(t.written, 9);
                assert_eq!(s.non_finite_left_out, 1);
            }
            _ => assert_eq!(t.written, 9, "{format}"),
        }
    }
}

#[test]
fn clear_errors() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("imu.mcap");
    let mut w = LogWriter::create(&path, WriterOptions::default()).expect("create");
    w.write_message("sensor/imu", 1, &ImuSample::default())
        .expect("write");
    w.finish().expect("finish");
    let out = dir.path().join("x.kml");
    let e = run(&path, &out, Format::Kml).expect_err("no track");
    assert!(matches!(e, ExportError::NoPositionStream { .. }), "{e}");
    assert!(
        e.to_string().contains("sensor/imu (nauta.ImuSample.v1)"),
        "{e}"
    );
    assert!(!out.exists());
    assert!(std::fs::read_dir(dir.path()).expect("dir").count() == 1);
    let e = run(&path, &dir.path().join("x.csv"), Format::Csv).expect_err("no rows");
    assert!(matches!(e, ExportError::NothingToExport { .. }), "{e}");
    // Foxglove takes any channel.
    let s = run(&path, &dir.path().join("x.mcap"), Format::Foxglove).expect("foxglove");
    assert_eq!(s.written, 1);

    let e = run(&path, &dir.path().join("no/such/dir/x.kml"), Format::Kml).expect_err("dir");
    assert!(
        matches!(e, ExportError::Write { .. }) && e.to_string().contains("no/such/dir/x.kml"),
        "{e}"
    );
    let e = run(&path, &path, Format::Foxglove).expect_err("overwrite");
    assert!(matches!(e, ExportError::OutputIsInput(_)), "{e}");
    let e = run(&dir.path().join("nope.mcap"), &out, Format::Kml).expect_err("missing");
    assert!(e.to_string().contains("no such file"), "{e}");
    std::fs::write(dir.path().join("text.mcap"), "hello").expect("write");
    let e = run(&dir.path().join("text.mcap"), &out, Format::Kml).expect_err("not mcap");
    assert!(e.to_string().contains("not an MCAP file"), "{e}");
    let mut opts = ExportOptions::new(Format::Kml);
    opts.track_hz = f64::NAN;
    let e = export(&path, &out, &opts, |_, _| {}).expect_err("nan rate");
    assert!(matches!(e, ExportError::InvalidOption(_)), "{e}");
    assert!(matches!(
        Format::parse("shp"),
        Err(ExportError::UnknownFormat(_))
    ));
    assert_eq!(
        Format::from_extension(Path::new("a/b.GeoJSON")),
        Some(Format::GeoJson)
    );
}

#[test]
fn a_foxglove_export_of_a_file_with_no_channel_fails_and_writes_nothing() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("empty.mcap");
    LogWriter::create(&path, WriterOptions::default())
        .expect("create")
        .finish()
        .expect("finish");
    let out = dir.path().join("x.mcap");
    let e = run(&path, &out, Format::Foxglove).expect_err("nothing to export");
    assert!(matches!(e, ExportError::NothingToExport { .. }), "{e}");
    assert!(e.to_string().contains("no channel"), "{e}");
    assert!(!out.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).expect("dir").count(),
        1,
        "a part file left"
    );
}

#[test]
fn a_cut_recording_exports_what_it_holds_with_a_note() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write_run(dir.path(), true);
    let bytes = std::fs::read(&input).expect("read");
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).expect("write");
    let s = run(&cut, &dir.path().join("cut.kml"), Format::Kml).expect("export");
    assert!(s.truncated);
    assert!(
        s.notes.iter().any(|n| n.contains("cut short")),
        "{:?}",
        s.notes
    );
}

#[test]
fn every_sample_is_kept_with_a_zero_rate() {
    let dir = tempfile::tempdir().expect("tmp");
    let input = write_run(dir.path(), true);
    let mut opts = ExportOptions::new(Format::GeoJson);
    opts.track_hz = 0.0;
    let s = export(&input, &dir.path().join("a.geojson"), &opts, |_, _| {}).expect("export");
    assert_eq!(track(&s, "sim/truth").written, 6000);
    opts.track_hz = 10.0;
    let s = export(&input, &dir.path().join("a.geojson"), &opts, |_, _| {}).expect("export");
    assert_eq!(track(&s, "sim/truth").written, 601);
}
