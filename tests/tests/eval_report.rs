//! Issue 5: `nauta eval` and `nauta report` on recordings whose errors are
//! known exactly: the simulator's survey truth, and synthetic estimate
//! streams built from it with chosen errors (the position estimators do not
//! exist yet). Every expected figure follows from those choices; none is
//! read back from the program.

use nauta_estimation::frames::{Frd, Ned, Rotation};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;

use nauta_estimation::attitude::{from_euler, to_euler};
use nauta_estimation::earth::{meridian_radius, transverse_radius};
use nauta_log::{LogWriter, WriterOptions};
use nauta_messages::*;
use nauta_sim::mission::Origin;
use nauta_sim::scenario::{Generator, ScenarioParams};
use nauta_tests::*;
use serde_json::Value;

const BOUND: Duration = Duration::from_secs(300);

/// Mission seconds of the survey the recordings are built from: the 10 s
/// still at the surface, the dive and the first leg.
const MISSION_S: f64 = 90.0;

/// Relative tolerance of the exact expectations. The errors are built in
/// metres and converted to latitude/longitude offsets of ~5e-7 rad on
/// latitudes of ~0.67 rad; the subtraction in eval loses ~1e-10 of them.
const REL: f64 = 1e-6;
/// Absolute tolerance where the expected value is zero (roll and pitch errors
/// of a yaw-only offset: Euler recomposition round-off, ~1e-13 deg).
const ZERO: f64 = 1e-9;

struct Mission {
    truth: Vec<TruthState>,
    gps: Vec<GpsFix>,
}

/// The survey's first `MISSION_S` seconds, once per test binary.
fn mission() -> &'static Mission {
    static M: OnceLock<Mission> = OnceLock::new();
    M.get_or_init(|| {
        let params = ScenarioParams::default();
        let mut g = Generator::new(
            &params,
            Origin::lisbon(),
            params.sensors_preset(),
            5,
            MISSION_S,
        )
        .expect("generator");
        let (mut truth, mut gps) = (Vec::new(), Vec::new());
        while let Some(m) = g.step() {
            let m = m.expect("step");
            let t = m.truth;
            truth.push(TruthState {
                header: Header::new(t.stamp_ns, truth.len() as u64, Role::Sensor, 0),
                lat_rad: t.lat_rad,
                lon_rad: t.lon_rad,
                depth_m: t.depth_m,
                vel_ned_m_s: t.vel_ned_m_s,
                quat_nb: t.quat_nb,
                rate_nb_body_rad_s: t.rate_nb_body_rad_s,
                current_ned_m_s: t.current_ned_m_s,
                distance_m: t.distance_m,
            });
            if let Some(f) = m.gps {
                gps.push(GpsFix {
                    header: Header::new(f.stamp_ns, gps.len() as u64, Role::Sensor, 0),
                    lat_rad: f.lat_rad,
                    lon_rad: f.lon_rad,
                    height_m: f.height_m,
                    horizontal_std_m: f.horizontal_std_m,
                    quality: f.quality,
                    satellites: f.satellites,
                    vel_ned_m_s: f.vel_ned_m_s,
                    vel_std_m_s: f.vel_std_m_s,
                    velocity_valid: 1,
                    pad: 0,
                });
            }
        }
        assert!(truth.len() as f64 >= MISSION_S * 99.0, "{}", truth.len());
        let travelled = truth.last().map(|t| t.distance_m).unwrap_or_default();
        assert!(travelled > 50.0, "the survey moved {travelled} m");
        Mission { truth, gps }
    })
}

/// (lat, lon) `dn` m north and `de` m east of (lat, lon) at height `h`: the
/// inverse of paper 002 eq. 2 with the meridian and transverse radii.
fn offset(lat: f64, lon: f64, h: f64, dn: f64, de: f64) -> (f64, f64) {
    (
        lat + dn / (meridian_radius(lat) + h),
        lon + de / ((transverse_radius(lat) + h) * lat.cos()),
    )
}

fn quat(q: nalgebra::UnitQuaternion<f64>) -> [f64; 4] {
    Rotation::<Frd, Ned>::from_nalgebra(q).to_wxyz()
}

fn truth_quat(t: &TruthState) -> nalgebra::UnitQuaternion<f64> {
    let q = t.quat_nb;
    nalgebra::UnitQuaternion::new_normalize(Rotation::<Frd, Ned>::quaternion_from_wxyz(q))
}

/// The truth rotated by Euler-angle errors (rad).
fn perturbed(t: &TruthState, droll: f64, dpitch: f64, dyaw: f64) -> [f64; 4] {
    let (r, p, y) = to_euler(&truth_quat(t));
    quat(from_euler(r + droll, p + dpitch, y + dyaw))
}

// ---------------------------------------------------------------------------
// The synthetic streams and their known errors
// ---------------------------------------------------------------------------

const NAV_DN: f64 = 3.0;
/// East error of `ains/nav`, alternating in sign (RMS 4, mean 0).
const NAV_DE: f64 = 4.0;
const NAV_DD: f64 = -1.0;
const NAV_DV: [f64; 3] = [0.1, -0.2, 0.05];
const NAV_DYAW_DEG: f64 = 1.0;

/// `ains/nav` at truth sample `i`: the truth with the errors above; its
/// position std is 5 m on every 4th sample (error inside the 95% ellipse:
/// 3²/5² + 4²/5² = 1 ≤ 5.991) and 1 m otherwise (25 > 5.991: outside).
fn nav(i: usize, t: &TruthState, alternate: bool) -> NavSolution {
    let de = if alternate && i % 2 == 1 {
        -NAV_DE
    } else {
        NAV_DE
    };
    let (lat, lon) = offset(t.lat_rad, t.lon_rad, -t.depth_m, NAV_DN, de);
    let std = if i.is_multiple_of(4) { 5.0 } else { 1.0 };
    NavSolution {
        header: Header::new(t.header.stamp_ns, i as u64, Role::Ains, 0),
        lat_rad: lat,
        lon_rad: lon,
        depth_m: t.depth_m + NAV_DD,
        vel_ned_m_s: [0, 1, 2].map(|k| t.vel_ned_m_s[k] + NAV_DV[k]),
        quat_nb: perturbed(t, 0.0, 0.0, NAV_DYAW_DEG.to_radians()),
        pos_std_ned_m: [std, std, 1.0],
        vel_std_ned_m_s: [0.1; 3],
        ..Default::default()
    }
}

const ATT_DROLL_DEG: f64 = 0.5;
const ATT_DPITCH_DEG: f64 = -0.3;
const ATT_DYAW_DEG: f64 = 2.0;

/// `attitude/estimate` at truth sample `i`: roll error ±0.5° (alternating),
/// pitch −0.3°, yaw +2°; std 1 rad on even samples (the ~2° error is well
/// inside the 95% region) and 1e-4 rad on odd ones (far outside).
fn attitude(i: usize, t: &TruthState) -> AttitudeEstimate {
    let droll = if i.is_multiple_of(2) {
        ATT_DROLL_DEG
    } else {
        -ATT_DROLL_DEG
    };
    AttitudeEstimate {
        header: Header::new(t.header.stamp_ns, i as u64, Role::Attitude, 0),
        quat_nb: perturbed(
            t,
            droll.to_radians(),
            ATT_DPITCH_DEG.to_radians(),
            ATT_DYAW_DEG.to_radians(),
        ),
        std_rad: if i.is_multiple_of(2) {
            [1.0; 3]
        } else {
            [1e-4; 3]
        },
        ..Default::default()
    }
}

const FIX_DN: f64 = -2.0;
const FIX_DE: f64 = 1.0;

/// `positioning/fix` midway between truth samples `a` and `a + 1` (5 ms off
/// the truth's grid, so eval interpolates the truth): the midpoint plus
/// (−2, +1) m. Even fixes: std (2, 1) m, correlation 0.5, Mahalanobis
/// distance² 4 (inside); odd: std (1, 0.5) m, correlation 0.5, 16 (outside).
fn fix(k: usize, a: &TruthState, b: &TruthState) -> PositionFix {
    let lat = 0.5 * (a.lat_rad + b.lat_rad);
    let lon = 0.5 * (a.lon_rad + b.lon_rad);
    let h = -0.5 * (a.depth_m + b.depth_m);
    let (lat, lon) = offset(lat, lon, h, FIX_DN, FIX_DE);
    let (sn, se) = if k.is_multiple_of(2) {
        (2.0, 1.0)
    } else {
        (1.0, 0.5)
    };
    PositionFix {
        header: Header::new(
            (a.header.stamp_ns + b.header.stamp_ns) / 2,
            k as u64,
            Role::Positioning,
            0,
        ),
        lat_rad: lat,
        lon_rad: lon,
        std_north_m: sn,
        std_east_m: se,
        corr_ne: 0.5,
        effective_particles: 100.0,
        fix_source: 1,
        pad: 0,
    }
}

const LBL_DX: f64 = 1.5;
const LBL_DY: f64 = -2.0;

/// `lbl/nav` at truth sample `i`: local north/east of the run's origin plus
/// (1.5, −2) m, `P_xy = diag(4, 1)` (1.5²/4 + 2²/1 = 4.56: inside).
fn lbl(i: usize, t: &TruthState) -> LblSolution {
    let (n, e) = Origin::lisbon().to_local(t.lat_rad, t.lon_rad);
    let mut p = [[0.0; 4]; 4];
    p[0][0] = 4.0;
    p[1][1] = 1.0;
    p[2][2] = 0.01;
    p[3][3] = 0.01;
    LblSolution {
        header: Header::new(t.header.stamp_ns, i as u64, Role::Lbl, 0),
        x_m: n + LBL_DX,
        y_m: e + LBL_DY,
        p,
        ellipse_major_m: 2.0,
        ellipse_minor_m: 1.0,
        last_innovation_m: 0.05 * ((i / 20) % 7) as f64 - 0.15,
        transponder_id: 1 + ((i / 20) % 2) as u32,
        accepted: u32::from(!(i / 20).is_multiple_of(9)),
        ..Default::default()
    }
}

// ---------------------------------------------------------------------------
// Recordings
// ---------------------------------------------------------------------------

fn run_metadata() -> BTreeMap<String, String> {
    let mut m = BTreeMap::new();
    // As nauta-logger writes them: the site as the origin, the sensor's section.
    m.insert("origin_lat_deg".into(), "38.6".into());
    m.insert("origin_lon_deg".into(), "-9.3".into());
    m.insert(
        "sensor_config.sensor".into(),
        "[params]\nscenario = \"lbl\"\n".into(),
    );
    m
}

/// What goes into a recording.
#[derive(Clone, Copy)]
struct Contents {
    truth: bool,
    gps_from_sensor: bool,
    gps_every_second: bool,
    nav: bool,
    nav_alternate: bool,
    attitude: bool,
    fix: bool,
    lbl: bool,
    corrupt: bool,
}

const NOTHING: Contents = Contents {
    truth: false,
    gps_from_sensor: false,
    gps_every_second: false,
    nav: false,
    nav_alternate: false,
    attitude: false,
    fix: false,
    lbl: false,
    corrupt: false,
};

/// Writes a recording; messages in stamp order, as the logger receives them.
fn write(path: &Path, c: Contents) {
    let m = mission();
    let mut w = LogWriter::create(path, WriterOptions::default()).expect("create");
    w.metadata(nauta_log::META_RUN, run_metadata())
        .expect("metadata");
    let log_time = |stamp: u64| 1_700_000_000_000_000_000 + stamp;
    let mut gps = m.gps.iter().peekable();
    let mut fix_k = 0;
    for (i, t) in m.truth.iter().enumerate() {
        let s = t.header.stamp_ns;
        if c.truth {
            w.write_message(TRUTH_SERVICE, log_time(s), t)
                .expect("truth");
        }
        while let Some(g) = gps.next_if(|g| g.header.stamp_ns <= s) {
            if c.gps_from_sensor {
                w.write_message(GPS_SERVICE, log_time(s), g).expect("gps");
            }
        }
        if c.gps_every_second && i.is_multiple_of(100) {
            let g = GpsFix {
                header: Header::new(s, (i / 100) as u64, Role::Sensor, 0),
                lat_rad: t.lat_rad,
                lon_rad: t.lon_rad,
                height_m: -t.depth_m,
                horizontal_std_m: 2.5,
                quality: 1,
                satellites: 9,
                ..Default::default()
            };
            w.write_message(GPS_SERVICE, log_time(s), &g).expect("gps");
        }
        if c.nav {
            w.write_message(
                NAV_SOLUTION_SERVICE,
                log_time(s),
                &nav(i, t, c.nav_alternate),
            )
            .expect("nav");
        }
        if c.attitude {
            w.write_message(ATTITUDE_ESTIMATE_SERVICE, log_time(s), &attitude(i, t))
                .expect("attitude");
        }
        if c.lbl && i.is_multiple_of(10) {
            w.write_message(LBL_SOLUTION_SERVICE, log_time(s), &lbl(i, t))
                .expect("lbl");
        }
        if c.fix
            && i % 100 == 50
            && let Some(next) = m.truth.get(i + 1)
        {
            w.write_message(POSITION_FIX_SERVICE, log_time(s), &fix(fix_k, t, next))
                .expect("fix");
            fix_k += 1;
        }
        if c.corrupt && i == 1000 {
            // A NaN latitude, and a message cut after its header: both are
            // counted as rejected, neither stops eval.
            let mut bad = nav(i, t, c.nav_alternate);
            bad.lat_rad = f64::NAN;
            w.write_message(NAV_SOLUTION_SERVICE, log_time(s), &bad)
                .expect("nan");
            let ch = w
                .channel(NAV_SOLUTION_SERVICE, &TypeInfo::of::<NavSolution>())
                .expect("channel");
            let bytes = codec::encode(&bad).expect("encode");
            w.write(ch, log_time(s), &bytes[..40]).expect("cut");
        }
        if c.lbl && i.is_multiple_of(3000) {
            let (lat, lon) = Origin::lisbon().to_geodetic(100.0 + i as f64 * 0.01, 50.0);
            let b = BuoyRange {
                header: Header::new(s, (i / 3000) as u64, Role::Sensor, 0),
                buoy_lat_rad: lat,
                buoy_lon_rad: lon,
                buoy_depth_m: 1.0,
                time_of_flight_s: 0.1,
                sound_speed_m_s: 1500.0,
            };
            w.write_message(MODEM_SERVICE, log_time(s), &b)
                .expect("buoy");
        }
    }
    w.finish().expect("finish");
}

fn nauta(wd: &Watchdog, args: &[&std::ffi::OsStr]) -> Finished {
    Running::spawn(wd, &bin("nauta"), args, None).wait(wd)
}

fn eval_json(wd: &Watchdog, file: &Path) -> (Value, Finished) {
    let out = nauta(wd, &["eval".as_ref(), file.as_os_str(), "--json".as_ref()]);
    assert_eq!(out.code(), Some(0), "{out}");
    let v: Value = serde_json::from_str(&out.stdout)
        .unwrap_or_else(|e| panic!("eval --json is not JSON: {e}\n{out}"));
    (v, out)
}

fn get(stream: &Value, key: &str) -> f64 {
    stream
        .get(key)
        .and_then(Value::as_f64)
        .unwrap_or_else(|| panic!("no number {key} in {stream:#}"))
}

fn close(stream: &Value, key: &str, want: f64) {
    let got = get(stream, key);
    let ok = if want == 0.0 {
        got.abs() <= ZERO
    } else {
        ((got - want) / want).abs() <= REL
    };
    assert!(ok, "{key}: got {got}, want {want}\n{stream:#}");
}

fn absent(stream: &Value, keys: &[&str]) {
    for k in keys {
        assert!(
            stream.get(*k).is_none(),
            "{k} should not apply:\n{stream:#}"
        );
    }
}

fn tmp(name: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::Builder::new()
        .prefix(&format!("nauta-{name}-"))
        .tempdir()
        .expect("tempdir");
    let file = dir.path().join(format!("{name}.mcap"));
    (dir, file)
}

const FULL: Contents = Contents {
    truth: true,
    gps_from_sensor: true,
    nav: true,
    nav_alternate: true,
    attitude: true,
    fix: true,
    lbl: true,
    corrupt: true,
    ..NOTHING
};

#[test]
fn eval_against_the_truth_gives_the_known_errors() {
    let wd = Watchdog::new("eval_against_the_truth_gives_the_known_errors", BOUND);
    let (_dir, file) = tmp("truth");
    write(&file, FULL);
    let (v, out) = eval_json(&wd, &file);
    let m = mission();
    let n = m.truth.len();
    assert_eq!(v["reference"], "truth", "{v:#}");
    assert_eq!(v["file"], file.display().to_string());
    let streams = v["streams"].as_object().expect("streams");
    let topics: Vec<&str> = streams.keys().map(String::as_str).collect();
    assert_eq!(
        topics,
        [
            "ains/nav",
            "attitude/estimate",
            "lbl/nav",
            "positioning/fix"
        ],
        "{v:#}"
    );
    let first = &m.truth[0];
    let last = &m.truth[n - 1];

    // ains/nav: every truth sample, constant and alternating errors.
    let nav = &v["streams"]["ains/nav"];
    assert_eq!(get(nav, "samples") as usize, n);
    assert_eq!(get(nav, "rejected"), 2.0, "{nav:#}");
    assert_eq!(get(nav, "unmatched"), 0.0);
    close(nav, "north_rms_m", NAV_DN);
    close(nav, "east_rms_m", NAV_DE);
    close(nav, "down_rms_m", NAV_DD.abs());
    close(nav, "horizontal_rms_m", NAV_DN.hypot(NAV_DE));
    close(nav, "horizontal_max_m", NAV_DN.hypot(NAV_DE));
    close(nav, "vel_north_rms_m_s", NAV_DV[0].abs());
    close(nav, "vel_east_rms_m_s", NAV_DV[1].abs());
    close(nav, "vel_down_rms_m_s", NAV_DV[2].abs());
    close(nav, "roll_rms_deg", 0.0);
    close(nav, "pitch_rms_deg", 0.0);
    close(nav, "yaw_rms_deg", NAV_DYAW_DEG);
    let distance = last.distance_m - first.distance_m;
    close(nav, "distance_m", distance);
    close(nav, "final_error_m", NAV_DN.hypot(NAV_DE));
    close(
        nav,
        "final_error_pct",
        100.0 * NAV_DN.hypot(NAV_DE) / distance,
    );
    close(
        nav,
        "drift_m_per_km",
        1000.0 * NAV_DN.hypot(NAV_DE) / distance,
    );
    let inside = (0..n).filter(|i| i.is_multiple_of(4)).count();
    close(nav, "inside_95_pct", 100.0 * inside as f64 / n as f64);
    assert_eq!(get(nav, "covariance_samples") as usize, n);

    // attitude/estimate: attitude keys only.
    let att = &v["streams"]["attitude/estimate"];
    assert_eq!(get(att, "samples") as usize, n);
    close(att, "roll_rms_deg", ATT_DROLL_DEG);
    close(att, "pitch_rms_deg", ATT_DPITCH_DEG.abs());
    close(att, "yaw_rms_deg", ATT_DYAW_DEG);
    let inside = (0..n).filter(|i| i.is_multiple_of(2)).count();
    close(att, "inside_95_pct", 100.0 * inside as f64 / n as f64);
    absent(
        att,
        &[
            "north_rms_m",
            "down_rms_m",
            "horizontal_rms_m",
            "vel_north_rms_m_s",
            "final_error_m",
            "final_error_pct",
            "drift_m_per_km",
            "distance_m",
        ],
    );

    // positioning/fix: 5 ms off the truth grid, horizontal only.
    let fixes: Vec<(usize, &TruthState, &TruthState)> = (0..n - 1)
        .filter(|i| i % 100 == 50)
        .enumerate()
        .map(|(k, i)| (k, &m.truth[i], &m.truth[i + 1]))
        .collect();
    let pf = &v["streams"]["positioning/fix"];
    assert_eq!(get(pf, "samples") as usize, fixes.len());
    close(pf, "north_rms_m", FIX_DN.abs());
    close(pf, "east_rms_m", FIX_DE);
    close(pf, "horizontal_rms_m", FIX_DN.hypot(FIX_DE));
    close(pf, "final_error_m", FIX_DN.hypot(FIX_DE));
    let mid = |(_, a, b): &(usize, &TruthState, &TruthState)| 0.5 * (a.distance_m + b.distance_m);
    let (f0, f1) = (fixes.first().expect("fix"), fixes.last().expect("fix"));
    close(pf, "distance_m", mid(f1) - mid(f0));
    let inside = fixes.iter().filter(|(k, _, _)| k.is_multiple_of(2)).count();
    close(
        pf,
        "inside_95_pct",
        100.0 * inside as f64 / fixes.len() as f64,
    );
    absent(pf, &["down_rms_m", "vel_north_rms_m_s", "roll_rms_deg"]);

    // lbl/nav: local frame at the metadata's origin, P_xy.
    let l = &v["streams"]["lbl/nav"];
    assert_eq!(get(l, "samples") as usize, n.div_ceil(10));
    close(l, "north_rms_m", LBL_DX);
    close(l, "east_rms_m", LBL_DY.abs());
    close(l, "inside_95_pct", 100.0);
    absent(l, &["down_rms_m", "vel_north_rms_m_s", "yaw_rms_deg"]);

    assert!(
        out.stderr.contains("ains/nav: 2 messages"),
        "the rejected messages are reported:\n{out}"
    );

    // The table says the same.
    let table = nauta(&wd, &["eval".as_ref(), file.as_os_str()]);
    assert_eq!(table.code(), Some(0), "{table}");
    for needle in [
        "against the truth",
        "north RMS (m)",
        "ains/nav",
        "3.000",
        "4.000",
    ] {
        assert!(table.stdout.contains(needle), "{needle} missing:\n{table}");
    }
}

#[test]
fn eval_against_gps_when_the_file_has_no_truth() {
    let wd = Watchdog::new("eval_against_gps_when_the_file_has_no_truth", BOUND);
    let (_dir, file) = tmp("gps");
    write(
        &file,
        Contents {
            gps_every_second: true,
            nav: true,
            attitude: true,
            ..NOTHING
        },
    );
    let (v, out) = eval_json(&wd, &file);
    assert_eq!(v["reference"], "gps", "{v:#}");
    let m = mission();
    let fixes: Vec<&TruthState> = m.truth.iter().step_by(100).collect();
    let nav = &v["streams"]["ains/nav"];
    assert_eq!(get(nav, "samples") as usize, fixes.len(), "{nav:#}");
    close(nav, "north_rms_m", NAV_DN);
    close(nav, "east_rms_m", NAV_DE);
    close(nav, "horizontal_rms_m", NAV_DN.hypot(NAV_DE));
    close(nav, "final_error_m", NAV_DN.hypot(NAV_DE));
    // Fix error 5 m against the estimate's (1 or 5 m)² plus the fix's 2.5 m²:
    // 25 / (1 + 6.25) = 3.4 and 25 / (25 + 6.25) = 0.8, both inside.
    close(nav, "inside_95_pct", 100.0);
    // The estimated track's length: the truth's shifted by a constant offset,
    // summed over 10 ms chords where the truth integrates its substeps; the
    // two agree to ~1e-6 of the distance, well inside 1e-4.
    let (a, b) = (fixes[0], fixes[fixes.len() - 1]);
    let want = b.distance_m - a.distance_m;
    let got = get(nav, "distance_m");
    assert!(
        ((got - want) / want).abs() < 1e-4,
        "distance {got} vs {want}"
    );
    close(nav, "final_error_pct", 100.0 * NAV_DN.hypot(NAV_DE) / got);
    absent(
        nav,
        &[
            "down_rms_m",
            "vel_north_rms_m_s",
            "vel_east_rms_m_s",
            "vel_down_rms_m_s",
            "roll_rms_deg",
            "pitch_rms_deg",
            "yaw_rms_deg",
        ],
    );
    // GPS gives no attitude reference: the attitude stream is reported skipped.
    assert!(v["streams"].get("attitude/estimate").is_none(), "{v:#}");
    assert!(
        v["skipped"]["attitude/estimate"].is_string(),
        "{v:#}\n{}",
        out.stderr
    );
    assert!(
        out.stderr.contains("attitude/estimate not evaluated"),
        "{out}"
    );
}

#[test]
fn eval_refuses_a_file_without_estimates_or_reference() {
    let wd = Watchdog::new("eval_refuses_a_file_without_estimates_or_reference", BOUND);
    let (_dir, file) = tmp("none");
    write(
        &file,
        Contents {
            truth: true,
            gps_from_sensor: true,
            ..NOTHING
        },
    );
    let out = nauta(&wd, &["eval".as_ref(), file.as_os_str(), "--json".as_ref()]);
    assert_eq!(out.code(), Some(1), "{out}");
    assert!(out.stderr.contains("no estimate stream"), "{out}");
    assert!(out.stdout.is_empty(), "{out}");

    write(
        &file,
        Contents {
            nav: true,
            ..NOTHING
        },
    );
    let out = nauta(&wd, &["eval".as_ref(), file.as_os_str()]);
    assert_eq!(out.code(), Some(1), "{out}");
    assert!(out.stderr.contains("no reference"), "{out}");

    let not_mcap = file.with_extension("txt");
    std::fs::write(&not_mcap, "hello").expect("write");
    let out = nauta(&wd, &["eval".as_ref(), not_mcap.as_os_str()]);
    assert_eq!(out.code(), Some(1), "{out}");
    assert!(out.stderr.contains("not an MCAP file"), "{out}");
}

#[test]
fn report_writes_the_plots_and_an_index() {
    let wd = Watchdog::new("report_writes_the_plots_and_an_index", BOUND);
    let (dir, file) = tmp("report");
    write(&file, FULL);
    let out_dir = dir.path().join("report");
    let out = nauta(
        &wd,
        &[
            "report".as_ref(),
            file.as_os_str(),
            "-o".as_ref(),
            out_dir.as_os_str(),
        ],
    );
    assert_eq!(out.code(), Some(0), "{out}");
    let index = std::fs::read_to_string(out_dir.join("index.html")).expect("index.html");
    for png in [
        "trajectory.png",
        "position_error.png",
        "ellipse_axes.png",
        "range_residuals.png",
        "attitude_error.png",
    ] {
        let bytes =
            std::fs::read(out_dir.join(png)).unwrap_or_else(|e| panic!("{png}: {e}\n{out}"));
        assert!(
            bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
            "{png} is not a PNG"
        );
        assert!(
            bytes.len() > 5_000,
            "{png} is nearly empty ({} bytes)",
            bytes.len()
        );
        assert!(
            index.contains(&format!("src=\"{png}\"")),
            "index.html does not show {png}"
        );
    }
    // The eval table, with eval's own figures.
    for needle in [
        "<table>",
        "ains/nav",
        "lbl/nav",
        "north RMS (m)",
        "3.000",
        "4.000",
    ] {
        assert!(index.contains(needle), "{needle} missing from index.html");
    }

    // Against GPS: no attitude plot, the rest still drawn.
    let (_gdir, gfile) = tmp("report-gps");
    write(
        &gfile,
        Contents {
            gps_every_second: true,
            nav: true,
            ..NOTHING
        },
    );
    let gout = gfile.with_extension("d");
    let out = nauta(
        &wd,
        &[
            "report".as_ref(),
            gfile.as_os_str(),
            "-o".as_ref(),
            gout.as_os_str(),
        ],
    );
    assert_eq!(out.code(), Some(0), "{out}");
    assert!(gout.join("trajectory.png").is_file());
    assert!(gout.join("position_error.png").is_file());
    assert!(!gout.join("attitude_error.png").exists());
    assert!(!gout.join("range_residuals.png").exists());
}
