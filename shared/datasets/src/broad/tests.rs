use std::io::Write as _;

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use nauta_estimation::HeadingInclinationError;
use nauta_estimation::attitude::{from_euler, quat_from_rotation_vector};
use proptest::prelude::*;

use super::*;

const ROWS: &str = "t_s,gyr_x_rad_s,gyr_y_rad_s,gyr_z_rad_s,acc_x_m_s2,acc_y_m_s2,acc_z_m_s2,mag_x_uT,mag_y_uT,mag_z_uT,ref_qw,ref_qx,ref_qy,ref_qz,moving
0,-0.001,0.002,0.005,-0.23,-0.36,9.91,0.22,15.8,-38.3,0.999732737,-0.019642706,0.0121226302,-0.00128893308,0
0.0035,0,0,0.006,-0.24,-0.33,9.89,0.22,15.8,-38.3,NaN,NaN,NaN,NaN,1
";

fn parse(text: &str) -> Result<BroadTrial, BroadReadError> {
    parse_trial(Path::new("test.csv"), "test", text.as_bytes())
}

#[test]
fn parses_rows_and_occlusions() {
    let t = parse(ROWS).expect("valid");
    assert_eq!(t.name, "test");
    assert_eq!(t.samples.len(), 2);
    let s = &t.samples[0];
    assert_eq!(s.t_s, 0.0);
    assert_eq!(s.gyro_rad_s, Vector3::new(-0.001, 0.002, 0.005));
    assert_eq!(s.accel_m_s2, Vector3::new(-0.23, -0.36, 9.91));
    assert_eq!(s.mag_ut, Vector3::new(0.22, 15.8, -38.3));
    let q = s.reference_enu.expect("visible");
    assert!((q.w - 0.999_732_737).abs() < 1e-6);
    assert!(!s.moving);
    assert_eq!(t.samples[1].reference_enu, None);
    assert!(t.samples[1].moving);
}

#[test]
fn refuses_malformed_files() {
    assert!(matches!(
        parse("t,a,b\n1,2,3\n"),
        Err(BroadReadError::Header { .. })
    ));
    let header = ROWS.lines().next().expect("header");
    assert!(matches!(
        parse(&format!("{header}\n")),
        Err(BroadReadError::Empty { .. })
    ));
    for (row, want) in [
        ("0,1,2,3,4,5,6,7,8,9,1,0,0,0", "columns"),
        ("0,1,2,3,4,5,6,7,8,9,1,0,0,0,1,5", "more than"),
        ("0,1,2,3,4,5,6,7,8,x,1,0,0,0,1", "mag_z_uT"),
        ("0,1,2,NaN,4,5,6,7,8,9,1,0,0,0,1", "not finite"),
        ("0,1,2,3,4,5,6,7,8,9,1,0,NaN,0,1", "partly NaN"),
        ("0,1,2,3,4,5,6,7,8,9,2,0,0,0,1", "norm"),
        ("0,1,2,3,4,5,6,7,8,9,1,0,0,0,2", "moving"),
    ] {
        match parse(&format!("{header}\n{row}\n")) {
            Err(BroadReadError::Row { line, message, .. }) => {
                assert_eq!(line, 2);
                assert!(message.contains(want), "{row}: {message}");
            }
            other => panic!("{row}: {other:?}"),
        }
    }
}

#[test]
fn names_and_listing() {
    assert_eq!(
        trial_name(Path::new("/x/01_undisturbed_slow_rotation_A.csv.gz")),
        "01_undisturbed_slow_rotation_A"
    );
    assert_eq!(trial_name(Path::new("a.b.csv")), "a");
    assert!(is_trial_file(Path::new("x.csv")));
    assert!(is_trial_file(Path::new("x.csv.gz")));
    assert!(!is_trial_file(Path::new("x.json")));
    assert!(!is_trial_file(Path::new("README.md")));
}

/// Writes `ROWS` plain and gzip-compressed into a fresh directory, lists and
/// reads both back.
#[test]
fn reads_plain_and_gzip_files() {
    let dir = std::env::temp_dir().join(format!("nauta-datasets-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(dir.join("b_plain.csv"), ROWS).expect("write");
    let gz = File::create(dir.join("a_packed.csv.gz")).expect("create");
    let mut enc = flate2::write::GzEncoder::new(gz, flate2::Compression::default());
    enc.write_all(ROWS.as_bytes()).expect("write");
    enc.finish().expect("finish");
    std::fs::write(dir.join("notes.txt"), "not a trial").expect("write");
    let files = list_trials(&dir).expect("list");
    let names: Vec<String> = files.iter().map(|p| trial_name(p)).collect();
    assert_eq!(names, ["a_packed", "b_plain"]);
    let a = read_trial(&files[0]).expect("gzip");
    let b = read_trial(&files[1]).expect("plain");
    assert_eq!(a.samples, b.samples);
    assert_eq!(a.name, "a_packed");
    // A corrupt gzip stream is an I/O error, not a panic.
    std::fs::write(dir.join("c_bad.csv.gz"), b"\x1f\x8b\x08garbage").expect("write");
    assert!(matches!(
        read_trial(&dir.join("c_bad.csv.gz")),
        Err(BroadReadError::Io { .. })
    ));
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// (B1) in matrix form: `C_enu_b = M C_ned_b` with `M` the axis swap.
#[test]
fn enu_conversion_is_the_axis_swap() {
    let m = Matrix3::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0);
    assert!(
        (q_enu_ned().to_rotation_matrix().into_inner() - m)
            .abs()
            .max()
            < 1e-15
    );
    let q = from_euler(0.3, -0.2, 2.0);
    let lhs = enu_from_ned(&q).to_rotation_matrix().into_inner();
    let rhs = m * q.to_rotation_matrix().into_inner();
    assert!((lhs - rhs).abs().max() < 1e-15);
    assert!(ned_from_enu(&enu_from_ned(&q)).angle_to(&q) < 1e-15);
}

/// Golden cases: a level body heading north (x forward, z down) has its x
/// axis on ENU's y (north) and its z axis on ENU's −z; its specific force at
/// rest (−g along body z, nauta's convention) is +g up in ENU, as BROAD's
/// accelerometer reads. Heading east: x on ENU's x.
#[test]
fn enu_conversion_golden_axes() {
    let level_north = enu_from_ned(&UnitQuaternion::identity());
    assert!((level_north * Vector3::x() - Vector3::y()).norm() < 1e-15);
    assert!((level_north * Vector3::z() + Vector3::z()).norm() < 1e-15);
    let f = level_north * Vector3::new(0.0, 0.0, -9.81);
    assert!((f - Vector3::new(0.0, 0.0, 9.81)).norm() < 1e-14);
    let east = enu_from_ned(&from_euler(0.0, 0.0, std::f64::consts::FRAC_PI_2));
    assert!((east * Vector3::x() - Vector3::x()).norm() < 1e-15);
}

proptest! {
    /// The BROAD heading and inclination errors are the same computed in NED
    /// or, after (B1), in ENU (the heading error changes sign with the
    /// vertical's direction; BROAD reports its absolute value).
    #[test]
    fn broad_metric_is_frame_independent(
        r in -3.0f64..3.0, p in -1.5f64..1.5, y in -3.0f64..3.0,
        a in -0.5f64..0.5, b in -0.5f64..0.5, c in -0.5f64..0.5,
    ) {
        let truth = from_euler(r, p, y);
        let est = quat_from_rotation_vector(&Vector3::new(a, b, c)) * truth;
        let ned = HeadingInclinationError::between(&est, &truth);
        let enu = HeadingInclinationError::between(&enu_from_ned(&est), &enu_from_ned(&truth));
        prop_assert!((ned.heading_rad.abs() - enu.heading_rad.abs()).abs() < 1e-12);
        prop_assert!((ned.inclination_rad - enu.inclination_rad).abs() < 1e-12);
    }
}
