//! Issue 6: `nauta calibrate magnetometer`. The shipped manifests carry the
//! calibration the command computes for them, and a recorded calibration
//! manoeuvre (`--from`) gives back the hard and soft iron it was made with.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use nauta_messages::{Header, IMU_SERVICE, ImuSample, Role};
use nauta_tests::*;

fn nauta(args: &[&std::ffi::OsStr]) -> (Option<i32>, String, String) {
    nauta_cli(args)
}

/// The `magnetometer = {...}` line of the command's output, parsed.
fn parse(stdout: &str) -> (Vector3<f64>, Matrix3<f64>) {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("magnetometer = "))
        .unwrap_or_else(|| panic!("no magnetometer line in\n{stdout}"));
    let t: toml::Table = toml::from_str(line).expect("TOML");
    let m = t["magnetometer"].as_table().expect("table");
    let num = |v: &toml::Value| v.as_float().expect("number");
    let h: Vec<f64> = m["hard_iron_ut"]
        .as_array()
        .expect("array")
        .iter()
        .map(num)
        .collect();
    let w: Vec<f64> = m["soft_iron_inv"]
        .as_array()
        .expect("rows")
        .iter()
        .flat_map(|r| {
            r.as_array()
                .expect("row")
                .iter()
                .map(num)
                .collect::<Vec<_>>()
        })
        .collect();
    (Vector3::from_row_slice(&h), Matrix3::from_row_slice(&w))
}

#[test]
fn the_shipped_manifests_carry_their_computed_calibration() {
    for m in ["survey", "lbl", "dr"] {
        let path = workspace_root().join("launch").join(format!("{m}.toml"));
        let (code, out, err) = nauta(&[
            "calibrate".as_ref(),
            "magnetometer".as_ref(),
            path.as_os_str(),
        ]);
        assert_eq!(code, Some(0), "{err}");
        assert!(err.contains("norm spread"), "{err}");
        let (h, w) = parse(&out);
        let manifest = nauta_runtime::Manifest::load(&path).expect("manifest");
        let params: toml::Table = manifest.params("attitude", None).expect("params");
        let line = format!("magnetometer = {}", params["magnetometer"]);
        let (mh, mw) = parse(&line);
        assert!(
            (h - mh).amax() < 1e-3,
            "{m}: hard iron {h} vs manifest {mh}"
        );
        assert!(
            (w - mw).amax() < 1e-5,
            "{m}: soft iron {w} vs manifest {mw}"
        );
    }
}

#[test]
fn a_recorded_manoeuvre_gives_back_its_hard_and_soft_iron() {
    let dir = std::env::temp_dir().join(format!("nauta-calibrate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let file = dir.join("manoeuvre.mcap");
    let field = Vector3::new(22.0, -0.5, 37.0); // µT, NED
    let soft = Matrix3::new(1.03, 0.02, 0.0, 0.02, 0.96, 0.01, 0.0, 0.01, 1.02);
    let hard = Vector3::new(3.0, -2.0, 1.0);
    let mut w =
        nauta_log::LogWriter::create(&file, nauta_log::WriterOptions::default()).expect("create");
    let mut n = 0u64;
    for i in 0..10 {
        for j in 0..10 {
            for k in 0..20 {
                let q = UnitQuaternion::from_euler_angles(
                    (i as f64 * 36.0 - 180.0).to_radians(),
                    (j as f64 * 17.0 - 80.0).to_radians(),
                    (k as f64 * 18.0).to_radians(),
                );
                let m = soft * q.inverse_transform_vector(&field) + hard;
                let s = ImuSample {
                    header: Header::new(n * 10_000_000, n, Role::Sensor, 0),
                    mag_ut: m.into(),
                    interval_s: 0.01,
                    ..Default::default()
                };
                w.write_message(IMU_SERVICE, n, &s).expect("write");
                n += 1;
            }
        }
    }
    w.finish().expect("finish");
    let (code, out, err) = nauta(&[
        "calibrate".as_ref(),
        "magnetometer".as_ref(),
        "--from".as_ref(),
        file.as_os_str(),
        "--field-ut".as_ref(),
        format!("{}", field.norm()).as_ref(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let (h, wi) = parse(&out);
    assert!((h - hard).amax() < 1e-3, "hard iron {h}, made with {hard}");
    // W S is a rotation when W is the symmetric inverse of S's stretch; here S
    // is symmetric, so W S = I.
    assert!(
        (wi * soft - Matrix3::identity()).amax() < 1e-4,
        "W S = {}",
        wi * soft
    );
    let _ = std::fs::remove_dir_all(&dir);
}
