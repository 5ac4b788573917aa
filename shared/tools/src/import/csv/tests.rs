use std::path::{Path, PathBuf};

use nauta_messages::*;
use proptest::prelude::*;

use super::table::Table;
use super::*;

/// A fresh directory under the system's temporary one.
fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nauta-csv-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("tmp dir");
    d
}

const SITE: &str = "latitude_deg = 38.6\nlongitude_deg = -9.3\nmagnetic_declination_deg = -0.98\n";

fn write(dir: &Path, file: &str, text: &str) {
    std::fs::write(dir.join(file), text).expect("write");
}

fn err_of(dir: &Path) -> String {
    match read(dir) {
        Ok(_) => panic!("{} imported", dir.display()),
        Err(e) => format!("{e:#}"),
    }
}

fn parse_err(file: &str, text: &[u8], spec: &[table::Col]) -> String {
    match Table::parse(file, text, spec) {
        Ok(t) => panic!("parsed: {t:?}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_fields_name_the_file_line_and_column() {
    let spec = channels::DEPTH;
    let cases: [(&[u8], &str); 8] = [
        (
            b"t_s,depth_m\n0,1\n1,x\n",
            "d.csv:3: column 2 (depth_m): not a number: \"x\"",
        ),
        (
            b"t_s,depth_m\n0,nan\n",
            "d.csv:2: column 2 (depth_m): not finite: \"nan\"",
        ),
        (
            b"t_s,depth_m\n0,1e400\n",
            "d.csv:2: column 2 (depth_m): not finite: \"1e400\"",
        ),
        (
            b"t_s,depth_m\n-inf,1\n",
            "d.csv:2: column 1 (t_s): not finite: \"-inf\"",
        ),
        (
            b"t_s,depth_m\n0,1\n1\n",
            "d.csv:3: 1 fields, expected 2 (as the header)",
        ),
        (b"t_s,depth_m\n0,\n", "d.csv:2: column 2 (depth_m): empty"),
        (b"t_s,depth_m\n0,1\n\xff\xfe,1\n", "d.csv:3: not UTF-8 text"),
        (b"", "d.csv: empty file: a header row is required"),
    ];
    for (text, want) in cases {
        let got = parse_err("d.csv", text, spec);
        assert!(got.contains(want), "{got:?} lacks {want:?}");
    }
}

#[test]
fn header_errors_name_the_column() {
    let got = parse_err("d.csv", b"t_s,depth_ft\n", channels::DEPTH);
    assert!(
        got.contains("d.csv:1: column 2 (\"depth_ft\") is not a column of this file; its columns are t_s, depth_m"),
        "{got}"
    );
    let got = parse_err("a.csv", b"t_s,roll_rad,roll_deg\n", channels::AHRS);
    assert!(
        got.contains("a.csv:1: column 3 (roll_deg) repeats column 2 (roll_rad)"),
        "{got}"
    );
    let got = parse_err("l.csv", b"t_s,transponder_id\n0,-1\n", channels::LBL);
    assert!(
        got.contains("l.csv:2: column 2 (transponder_id): -1 is outside [0, 4294967295]"),
        "{got}"
    );
    let got = parse_err("l.csv", b"t_s,transponder_id\n0,1.5\n", channels::LBL);
    assert!(got.contains("not an integer: \"1.5\""), "{got}");
}

#[test]
fn blank_lines_comments_bom_and_crlf_are_read() {
    let t = Table::parse(
        "d.csv",
        b"\xEF\xBB\xBF# a comment\r\n\r\n depth_m , t_s \r\n2.5,0\r\n\r\n# more\n3.5, 1\n",
        channels::DEPTH,
    )
    .expect("parse");
    assert_eq!(t.len(), 2);
    assert_eq!(
        (t.get(1, "t"), t.get(1, "depth"), t.line(1)),
        (Some(1.0), Some(3.5), 7)
    );
}

#[test]
fn units_are_converted_to_the_messages() {
    let t = Table::parse(
        "a.csv",
        b"t_s,roll_deg,pitch_rad,heading_mag_deg\n0,90,0.5,-90\n",
        channels::AHRS,
    )
    .expect("parse");
    let m = channels::ahrs(&t, &channels::Clock { t0_s: 0.0 }).expect("ahrs");
    let SensorMessage::Ahrs(a) = m[0] else {
        panic!("{m:?}")
    };
    assert!((a.roll_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert_eq!(a.pitch_rad, 0.5);
    assert!((a.heading_mag_rad - 1.5 * std::f64::consts::PI).abs() < 1e-12);
    let t =
        Table::parse("p.csv", b"t_s,shaft_speed_rpm\n0,60\n", channels::PROPELLER).expect("parse");
    let m = channels::propeller(&t, &channels::Clock { t0_s: 0.0 }).expect("propeller");
    let SensorMessage::Propeller(p) = m[0] else {
        panic!("{m:?}")
    };
    assert!((p.shaft_speed_rad_s - 2.0 * std::f64::consts::PI).abs() < 1e-12);
}

#[test]
fn missing_columns_unsorted_rows_and_unknown_files_are_refused() {
    let d = tmp("refusals");
    write(&d, "site.toml", SITE);
    write(&d, "dvl.csv", "t_s,vel_x_m_s,vel_y_m_s\n0,1,0\n");
    let e = err_of(&d);
    assert!(e.contains("dvl.csv: missing column vel_z_m_s"), "{e}");
    write(
        &d,
        "dvl.csv",
        "t_s,vel_x_m_s,vel_y_m_s,vel_z_m_s\n0,1,0,0\n2,1,0,0\n1,1,0,0\n",
    );
    let e = err_of(&d);
    assert!(
        e.contains(
            "dvl.csv:4: column 1 (t_s): time 1 s is not after line 3's; rows must be sorted by time"
        ),
        "{e}"
    );
    write(&d, "dvl.csv", "t_s,vel_x_m_s,vel_y_m_s,vel_z_m_s\n");
    let e = err_of(&d);
    assert!(e.contains("dvl.csv: no data rows after the header"), "{e}");
    write(
        &d,
        "dvl.csv",
        "t_s,vel_x_m_s,vel_y_m_s,vel_z_m_s,bottom_lock\n0,1,0,0,2\n",
    );
    let e = err_of(&d);
    assert!(
        e.contains("dvl.csv:2: column 5 (bottom_lock): 2 is outside [0, 1]"),
        "{e}"
    );
    write(
        &d,
        "dvl.csv",
        "t_s,vel_x_m_s,vel_y_m_s,vel_z_m_s\n0,1,0,0\n",
    );
    write(
        &d,
        "imu.csv",
        "t_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2,mag_x_ut\n0,0,0,0,0,0,-9.8,20\n1,0,0,0,0,0,-9.8,20\n",
    );
    let e = err_of(&d);
    assert!(
        e.contains("imu.csv: columns go together: missing mag_y_ut, mag_z_ut"),
        "{e}"
    );
    std::fs::remove_file(d.join("imu.csv")).expect("rm");
    write(
        &d,
        "gps.csv",
        "t_s,lat_deg,lon_deg,horizontal_std_m\n0,91,0,1\n",
    );
    let e = err_of(&d);
    assert!(
        e.contains("gps.csv:2: column 2 (lat_deg): 91° is not a latitude"),
        "{e}"
    );
    std::fs::remove_file(d.join("gps.csv")).expect("rm");
    write(&d, "dlv.csv", "t_s\n");
    let e = err_of(&d);
    assert!(e.contains("dlv.csv: not a channel file"), "{e}");
    std::fs::remove_file(d.join("dlv.csv")).expect("rm");
    std::fs::remove_file(d.join("site.toml")).expect("rm");
    let e = err_of(&d);
    assert!(e.contains("site.toml") && e.contains("cannot read"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn site_errors_name_the_line_and_key() {
    let e = CsvSite::parse("s.toml", "latitude_deg = 38.6\nlongitude_deg = -9.3\n")
        .expect_err("no declination");
    assert!(e.to_string().contains("magnetic_declination_deg"), "{e}");
    let e = CsvSite::parse("s.toml", &format!("{SITE}speed_of_sound = 1500\n"))
        .expect_err("unknown key");
    let s = e.to_string();
    assert!(
        s.contains("s.toml") && s.contains("line 4") && s.contains("speed_of_sound"),
        "{s}"
    );
    let e = CsvSite::parse("s.toml", &format!("{SITE}sound_speed_m_s = nan\n")).expect_err("nan");
    assert!(
        e.to_string()
            .contains("s.toml:4: sound_speed_m_s = NaN is outside [1300, 1800]"),
        "{e}"
    );
    let e = CsvSite::parse(
        "s.toml",
        "latitude_deg = 98.6\nlongitude_deg = -9.3\nmagnetic_declination_deg = 0\n",
    )
    .expect_err("latitude");
    assert!(
        e.to_string()
            .contains("s.toml:1: latitude_deg = 98.6 is outside [-90, 90]"),
        "{e}"
    );
    let two = "\n[[transponders]]\nid = 1\nnorth_m = 0\neast_m = 0\ndepth_m = 30\n";
    let e = CsvSite::parse("s.toml", &format!("{SITE}{two}{two}")).expect_err("twice");
    assert!(
        e.to_string()
            .contains("s.toml:12: transponders[1].id = 1 is given twice"),
        "{e}"
    );
    let e =
        CsvSite::parse("s.toml", &format!("{SITE}{}", two.replace("30", "-3"))).expect_err("depth");
    assert!(
        e.to_string()
            .contains("s.toml:9: transponders[0].depth_m = -3 is outside [0, 11000]"),
        "{e}"
    );
    let ok =
        CsvSite::parse("s.toml", &format!("{SITE}sound_speed_m_s = 1500\n{two}")).expect("valid");
    assert_eq!(ok.transponders.len(), 1);
    assert_eq!(
        CsvSite::parse("again", &ok.to_toml()).expect("round trip"),
        ok
    );
}

#[test]
fn equal_times_are_allowed_in_lbl_csv_only() {
    let d = tmp("ties");
    write(
        &d,
        "site.toml",
        &format!(
            "{SITE}sound_speed_m_s = 1500\nturnaround_s = 0.0125\n\n[[transponders]]\nid = 7\nnorth_m = 100\neast_m = -50\ndepth_m = 40\n"
        ),
    );
    // Two replies heard at once (10 s): allowed.
    write(
        &d,
        "lbl.csv",
        "t_s,transponder_id,range_m\n10,7,750\n10,7,600\n",
    );
    let log = read(&d).expect("ties in lbl.csv");
    assert_eq!(log.messages(Channel::Lbl).len(), 2);
    // The earliest time is the first ping: 10 − (2 × 750 / 1500 + 0.0125) s.
    assert!(
        (log.time_origin_s - 8.9875).abs() < 1e-12,
        "{}",
        log.time_origin_s
    );
    write(&d, "depth.csv", "t_s,depth_m\n10,1\n10,2\n");
    let e = err_of(&d);
    assert!(
        e.contains("depth.csv:3: column 1 (t_s): time 10 s is not after line 2's"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The expected rows of every channel in the round trip below.
fn round_trip_dir(d: &Path) {
    write(
        d,
        "site.toml",
        &format!(
            "{SITE}sound_speed_m_s = 1500.0\nturnaround_s = 0.0125\n\n[[transponders]]\nid = 3\nnorth_m = 300\neast_m = 0\ndepth_m = 40\nturnaround_s = 0.02\n"
        ),
    );
    write(
        d,
        "imu.csv",
        "t_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2,mag_x_ut,mag_y_ut,mag_z_ut\n100.00,0.01,-0.02,0.03,0.1,0.2,-9.8,20,1,40\n100.01,0.01,-0.02,0.03,0.1,0.2,-9.8,20,1,40\n",
    );
    write(
        d,
        "dvl.csv",
        "t_s,vel_x_m_s,vel_y_m_s,vel_z_m_s,altitude_m,bottom_lock,beams_valid,figure_of_merit_m_s\n100.2,1.5,0.1,-0.05,12.5,1,7,0.01\n",
    );
    write(
        d,
        "ahrs.csv",
        "t_s,roll_rad,pitch_rad,heading_mag_rad\n100.1,0.01,-0.02,6.0\n",
    );
    write(d, "depth.csv", "t_s,depth_m\n100.1,20.5\n");
    write(
        d,
        "gps.csv",
        "t_s,lat_deg,lon_deg,height_m,horizontal_std_m,quality,satellites,vel_n_m_s,vel_e_m_s,vel_d_m_s,vel_std_m_s\n100.0,38.6,-9.3,51.2,2.5,2,9,1.0,0.5,0.0,0.1\n",
    );
    write(
        d,
        "modem.csv",
        "t_s,buoy_lat_deg,buoy_lon_deg,buoy_depth_m,range_m\n101.0,38.601,-9.301,1.5,600\n",
    );
    write(
        d,
        "lbl.csv",
        "t_s,transponder_id,round_trip_s\n102.0,3,0.5\n",
    );
    write(d, "propeller.csv", "t_s,shaft_speed_rad_s\n100.1,50\n");
    write(
        d,
        "truth.csv",
        "t_s,lat_deg,lon_deg,depth_m,vel_n_m_s,vel_e_m_s,vel_d_m_s,roll_rad,pitch_rad,yaw_rad\n99.5,38.6,-9.3,20,1.5,0,0,0,0,0.5\n100.5,38.60001,-9.3,20,1.5,0,0,0,0,0.5\n",
    );
}

#[test]
fn every_channel_round_trips_through_a_recording() {
    let d = tmp("roundtrip");
    round_trip_dir(&d);
    let log = read(&d).expect("import");
    assert_eq!(log.time_origin_s, 99.5);
    let out = d.join("out.mcap");
    let text = manifest(&log, &d, 5.0);
    let n = super::write(&log, &d, &out, &text, "written").expect("write");
    assert_eq!(n, 11);
    let mut got: Vec<(String, SensorMessage)> = Vec::new();
    let rec = nauta_log::read(&out, |ch, m| {
        let msg = SensorMessage::decode(&ch.topic, &ch.type_name, m.data)
            .expect("a sensor channel")
            .expect("decodes");
        assert_eq!(m.publish_time_ns, msg.header().stamp_ns);
        got.push((ch.topic.clone(), msg));
        Ok(())
    })
    .expect("read back");
    // The file's order: by stamp, the sensor's order within a stamp.
    let keys: Vec<(u64, usize)> = got
        .iter()
        .map(|(_, m)| (m.header().stamp_ns, m.order()))
        .collect();
    let mut sorted = keys.clone();
    sorted.sort();
    assert_eq!(keys, sorted);
    let one = |topic: &str| -> Vec<SensorMessage> {
        got.iter()
            .filter(|(t, _)| t == topic)
            .map(|(_, m)| *m)
            .collect()
    };
    // Stamps: t − 99.5 s + 1 s.
    let ns = |t: f64| ((t - 99.5 + 1.0) * 1e9_f64).round() as u64;
    let h = |t: f64, seq: u64| Header::new(ns(t), seq, Role::Sensor, 0);
    let imu = one(IMU_SERVICE);
    assert_eq!(imu.len(), 2);
    let SensorMessage::Imu(i) = imu[1] else {
        panic!()
    };
    assert_eq!(i.header, h(100.01, 1));
    assert_eq!(
        (i.gyro_rad_s, i.accel_m_s2, i.mag_ut),
        ([0.01, -0.02, 0.03], [0.1, 0.2, -9.8], [20.0, 1.0, 40.0])
    );
    assert!((i.interval_s - 0.01).abs() < 1e-9, "{}", i.interval_s);
    assert_eq!(
        one(DVL_SERVICE),
        [SensorMessage::Dvl(DvlSample {
            header: h(100.2, 0),
            velocity_body_m_s: [1.5, 0.1, -0.05],
            altitude_m: 12.5,
            beams_valid: 7,
            bottom_lock: 1,
            figure_of_merit_m_s: 0.01,
        })]
    );
    assert_eq!(
        one(AHRS_SERVICE),
        [SensorMessage::Ahrs(AhrsSample {
            header: h(100.1, 0),
            roll_rad: 0.01,
            pitch_rad: -0.02,
            heading_mag_rad: 6.0,
        })]
    );
    assert_eq!(
        one(DEPTH_SERVICE),
        [SensorMessage::Depth(DepthSample {
            header: h(100.1, 0),
            depth_m: 20.5
        })]
    );
    assert_eq!(
        one(GPS_SERVICE),
        [SensorMessage::Gps(GpsFix {
            header: h(100.0, 0),
            lat_rad: 38.6f64.to_radians(),
            lon_rad: (-9.3f64).to_radians(),
            height_m: 51.2,
            horizontal_std_m: 2.5,
            quality: 2,
            satellites: 9,
            vel_ned_m_s: [1.0, 0.5, 0.0],
            vel_std_m_s: 0.1,
            velocity_valid: 1,
            pad: 0,
        })]
    );
    // The buoy's 600 m at the site's 1500 m/s: 0.4 s one way.
    let SensorMessage::Modem(b) = one(MODEM_SERVICE)[0] else {
        panic!()
    };
    assert_eq!(b.header, h(101.0, 0));
    assert!((b.buoy_lat_rad - 38.601f64.to_radians()).abs() < 1e-15);
    assert!((b.buoy_lon_rad - (-9.301f64).to_radians()).abs() < 1e-15);
    assert_eq!((b.buoy_depth_m, b.sound_speed_m_s), (1.5, 1500.0));
    assert!((b.time_of_flight_s - 0.4).abs() < 1e-15);
    assert_eq!(
        one(LBL_REPLY_SERVICE),
        [SensorMessage::Lbl(LblReply {
            header: h(102.0, 0),
            transponder_id: 3,
            pad: 0,
            interrogation_stamp_ns: ns(101.5),
            reply_stamp_ns: ns(102.0),
            round_trip_s: 0.5,
        })]
    );
    assert_eq!(
        one(PROPELLER_SERVICE),
        [SensorMessage::Propeller(PropellerSample {
            header: h(100.1, 0),
            shaft_speed_rad_s: 50.0
        })]
    );
    let truth = one(TRUTH_SERVICE);
    let SensorMessage::Truth(t) = truth[1] else {
        panic!()
    };
    assert_eq!(t.header, h(100.5, 1));
    assert_eq!((t.depth_m, t.vel_ned_m_s), (20.0, [1.5, 0.0, 0.0]));
    // 1e-5° of latitude: 1.11 m.
    assert!((t.distance_m - 1.11).abs() < 0.01, "{}", t.distance_m);
    let q = [(0.25f64).cos(), 0.0, 0.0, (0.25f64).sin()];
    for (got, want) in t.quat_nb.iter().zip(q) {
        assert!((got - want).abs() < 1e-12, "{:?}", t.quat_nb);
    }
    // The metadata: origin, acoustics and the transponders for the tools.
    let info =
        nauta_log::run::RunInfo::read(rec.metadata(nauta_log::META_RUN), &Default::default(), None);
    let o = info.origin.expect("origin").value;
    assert!((o.lat_rad - 38.6f64.to_radians()).abs() < 1e-15);
    assert_eq!(info.sound_speed_m_s, Some(1500.0));
    assert_eq!(info.turnaround_s, Some(0.0125));
    assert_eq!(info.transponders.len(), 1);
    assert_eq!(info.transponders[0].turnaround_s, Some(0.02));
    let import = rec.metadata("nauta.import").expect("nauta.import");
    assert_eq!(import["time_origin_s"], "99.5");
    assert_eq!(import["rows.lbl.csv"], "1");
    // The manifest parses, and runs the attitude (magnetometer) and ekf (IMU).
    let m: toml::Table = toml::from_str(&text).expect("manifest TOML");
    assert_eq!(m["process"]["attitude"]["variant"].as_str(), Some("pf"));
    assert_eq!(m["process"]["ains"]["variant"].as_str(), Some("ekf"));
    assert!(text.contains("1 transponders"), "{text}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn lbl_and_modem_ranges_use_the_site() {
    let d = tmp("ranges");
    round_trip_dir(&d);
    write(&d, "lbl.csv", "t_s,transponder_id,range_m\n102.0,3,600\n");
    let log = read(&d).expect("import");
    let SensorMessage::Lbl(l) = log.messages(Channel::Lbl)[0] else {
        panic!()
    };
    // 2 × 600 m / 1500 m/s + transponder 3's own 0.02 s.
    assert!((l.round_trip_s - 0.82).abs() < 1e-12, "{}", l.round_trip_s);
    assert_eq!(l.reply_stamp_ns - l.interrogation_stamp_ns, 820_000_000);
    write(&d, "lbl.csv", "t_s,transponder_id,range_m\n102.0,4,600\n");
    let e = err_of(&d);
    assert!(
        e.contains(
            "lbl.csv:2: column 2 (transponder_id): transponder 4 is not in site.toml's transponders"
        ),
        "{e}"
    );
    write(
        &d,
        "lbl.csv",
        "t_s,transponder_id,range_m,round_trip_s\n102.0,3,600,0.8\n",
    );
    let e = err_of(&d);
    assert!(
        e.contains("lbl.csv: give round_trip_s or range_m, not both"),
        "{e}"
    );
    write(
        &d,
        "lbl.csv",
        "t_s,transponder_id,round_trip_s\n102.0,3,0.5\n",
    );
    write(
        &d,
        "site.toml",
        &format!("{SITE}\n[[transponders]]\nid = 3\nnorth_m = 300\neast_m = 0\ndepth_m = 40\n"),
    );
    let e = err_of(&d);
    assert!(
        e.contains(
            "modem.csv: a buoy message needs a sound speed: give sound_speed_m_s in site.toml"
        ),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_plan_follows_the_channels() {
    let d = tmp("plan");
    write(&d, "site.toml", SITE);
    write(
        &d,
        "dvl.csv",
        "t_s,vel_x_m_s,vel_y_m_s,vel_z_m_s\n0,1,0,0\n1,1,0,0\n",
    );
    write(
        &d,
        "ahrs.csv",
        "t_s,roll_rad,pitch_rad,heading_mag_rad\n0,0,0,0\n1,0,0,0\n",
    );
    let p = plan(&read(&d).expect("dvl+ahrs"));
    assert_eq!((p.attitude, p.ains), (false, Some("dr")));
    write(
        &d,
        "imu.csv",
        "t_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n0,0,0,0,0,0,-9.8\n1,0,0,0,0,0,-9.8\n",
    );
    let p = plan(&read(&d).expect("imu without magnetometer"));
    assert_eq!((p.attitude, p.ains), (false, Some("ekf")));
    std::fs::remove_file(d.join("ahrs.csv")).expect("rm");
    let p = plan(&read(&d).expect("imu and dvl"));
    assert_eq!((p.attitude, p.ains), (false, None));
    assert!(
        p.notes.iter().any(|n| n.contains("no ains")),
        "{:?}",
        p.notes
    );
    let _ = std::fs::remove_dir_all(&d);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Any bytes as any channel file: an error or a table, never a panic;
    /// and a table's conversion to messages never panics either.
    #[test]
    fn hostile_files_never_panic(
        bytes in prop::collection::vec(any::<u8>(), 0..400),
        k in 0usize..9,
    ) {
        let c = Channel::ALL[k];
        if let Ok(t) = Table::parse(c.file(), &bytes, c.spec()) {
            let clock = channels::Clock { t0_s: 0.0 };
            let site = CsvSite::parse("s", SITE).expect("site");
            let _ = match c {
                Channel::Truth => channels::truth(&t, &clock),
                Channel::Imu => channels::imu(&t, &clock),
                Channel::Ahrs => channels::ahrs(&t, &clock),
                Channel::Dvl => channels::dvl(&t, &clock),
                Channel::Depth => channels::depth(&t, &clock),
                Channel::Gps => channels::gps(&t, &clock),
                Channel::Propeller => channels::propeller(&t, &clock),
                Channel::Modem => channels::modem(&t, &clock, &site),
                Channel::Lbl => channels::lbl_rows(&t, &site)
                    .and_then(|rows| channels::lbl(&t, &rows, &clock)),
            };
        }
    }

    /// Plausible rows with hostile numbers (huge, tiny, negative, NaN, cut
    /// short): errors, never panics.
    #[test]
    fn hostile_numbers_never_panic(
        rows in prop::collection::vec(
            prop::collection::vec(
                prop_oneof![
                    any::<f64>().prop_map(|x| x.to_string()),
                    Just("1e308".to_owned()),
                    Just("-1e308".to_owned()),
                    Just("18446744073709551616".to_owned()),
                    Just(String::new()),
                    (0u32..5).prop_map(|x| x.to_string()),
                ],
                1..8,
            ),
            0..6,
        ),
        k in 0usize..9,
    ) {
        let c = Channel::ALL[k];
        let header: Vec<&str> = c.spec().iter().map(|col| col.names[0].0).collect();
        let mut text = header.join(",") + "\n";
        for r in &rows {
            text += &r.join(",");
            text += "\n";
        }
        if let Ok(t) = Table::parse(c.file(), text.as_bytes(), c.spec()) {
            let t0 = channels::times(&t).reduce(f64::min).unwrap_or(0.0);
            let clock = channels::Clock { t0_s: t0 };
            let site = CsvSite::parse("s", &format!("{SITE}sound_speed_m_s = 1500\nturnaround_s = 0\n[[transponders]]\nid = 1\nnorth_m = 0\neast_m = 0\ndepth_m = 1\n")).expect("site");
            let _ = match c {
                Channel::Truth => channels::truth(&t, &clock),
                Channel::Imu => channels::imu(&t, &clock),
                Channel::Ahrs => channels::ahrs(&t, &clock),
                Channel::Dvl => channels::dvl(&t, &clock),
                Channel::Depth => channels::depth(&t, &clock),
                Channel::Gps => channels::gps(&t, &clock),
                Channel::Propeller => channels::propeller(&t, &clock),
                Channel::Modem => channels::modem(&t, &clock, &site),
                Channel::Lbl => channels::lbl_rows(&t, &site)
                    .and_then(|rows| channels::lbl(&t, &rows, &clock)),
            };
        }
    }

    /// Any text as site.toml: an error or a site, never a panic.
    #[test]
    fn hostile_sites_never_panic(text in ".{0,200}") {
        let _ = CsvSite::parse("s.toml", &text);
        let _ = CsvSite::parse("s.toml", &format!("{SITE}{text}"));
    }
}
