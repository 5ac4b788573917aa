//! The IMU's axes and clock: a trajectory in the data set's format (written
//! here; nothing of the data set is committed) whose IMU file follows the
//! Snapir logs' convention (Y left, the file's own clock) imports as FRD
//! body rates and specific force on the reference's clock.

use std::path::Path;

use nauta_estimation::frames::Vector;

use super::*;

const G: f64 = 9.8;
const SPACING_S: f64 = 400.0 / 399.0;
/// The IMU clock's offset the files are written with (about held-out
/// trajectory 5's); the import fits it.
const OFFSET_S: f64 = -0.47;

/// The attitude at reference time `t`: a weave in yaw, pitch and roll.
fn euler(t: f64) -> [f64; 3] {
    [
        0.03 * (0.21 * t).sin(),
        0.06 * (0.13 * t).sin(),
        1.0 + 0.4 * (0.05 * t).sin(),
    ]
}

fn rotation(t: f64) -> Rotation<Frd, Ned> {
    let [r, p, y] = euler(t);
    Rotation::from_euler(r, p, y)
}

/// The body rate (FRD) at `t`, from the attitude's increment.
fn body_rate(t: f64) -> [f64; 3] {
    let h = 1e-4;
    let [w, x, y, z] = (rotation(t - h).inverse() * rotation(t + h)).to_wxyz();
    let s = 2.0 * w.signum() / (2.0 * h);
    [s * x, s * y, s * z]
}

/// Specific force (FRD) at `t` of a vehicle without linear acceleration.
fn specific_force(t: f64) -> [f64; 3] {
    (rotation(t).inverse() * Vector::<Ned>::from_array([0.0, 0.0, -G])).to_array()
}

/// Writes a 120-sample trajectory; the IMU's axes are FRD's with `signs`
/// applied to gyro and accelerometer alike, on the file clock that
/// [`IMU_CLOCK_SCALE`] and [`OFFSET_S`] undo.
fn write(dir: &Path, signs: [f64; 3]) {
    std::fs::create_dir_all(dir).expect("dir");
    let mut gt = GT_HEADER.join(",") + "\n";
    let (lat0, lon0) = (0.5733, 0.609);
    for k in 0..120 {
        let t = k as f64 * SPACING_S;
        let [r, p, y] = euler(t);
        gt += &format!(
            "{t},{lon0},{},-20.0,1.5,0.0,0.0,{r},{p},{y}\n",
            lat0 + 2e-7 * t
        );
    }
    let mut dvl = DVL_HEADER.join(",") + "\n";
    for k in 0..120 {
        dvl += &format!("{},1.5,0.0,0.0\n", k as f64 * SPACING_S);
    }
    let mut imu = IMU_HEADER.join(",") + "\n";
    let end = (119.0 * SPACING_S - OFFSET_S) / IMU_CLOCK_SCALE;
    let mut k = 0;
    loop {
        let t_file = k as f64 * 0.01;
        if t_file > end {
            break;
        }
        let t = IMU_CLOCK_SCALE * t_file + OFFSET_S;
        let (w, f) = (body_rate(t), specific_force(t));
        imu += &format!(
            "{t_file},{},{},{},{},{},{}\n",
            signs[0] * f[0],
            signs[1] * f[1],
            signs[2] * f[2],
            signs[0] * w[0],
            signs[1] * w[1],
            signs[2] * w[2]
        );
        k += 1;
    }
    std::fs::write(dir.join("GT_trajectory3.csv"), gt).expect("gt");
    std::fs::write(dir.join("DVL_trajectory3.csv"), dvl).expect("dvl");
    std::fs::write(dir.join("IMU_trajectory3.csv"), imu).expect("imu");
}

fn tmp(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("nauta-akit-imu-{name}-{}", std::process::id()))
}

/// Each imported sample is FRD on the reference's clock: its gyro is the
/// reference's body rate and its accelerometer the specific force there.
fn assert_frd(t: &Trajectory) {
    let imu = t.imu.as_ref().expect("imu");
    let check = t.imu_check.expect("check");
    assert!((check.clock_offset_s - OFFSET_S).abs() < 0.005, "{check:?}");
    assert!(
        (imu[0].0 - check.clock_offset_s).abs() < 1e-9,
        "{:?}",
        imu[0]
    );
    for (t_s, f, w) in imu.iter().step_by(997) {
        // At the stamp the import gives, off by at most the fit's error
        // (5 ms: some µrad/s and mm/s² here).
        let (w_ref, f_ref) = (body_rate(*t_s), specific_force(*t_s));
        for i in 0..3 {
            assert!(
                (w[i] - w_ref[i]).abs() < 2e-5,
                "{t_s}: {w:?} against {w_ref:?}"
            );
            assert!(
                (f[i] - f_ref[i]).abs() < 2e-3,
                "{t_s}: {f:?} against {f_ref:?}"
            );
        }
    }
    assert!(
        check.rate_correlation.iter().all(|c| *c > 0.99),
        "{check:?}"
    );
}

#[test]
fn the_data_sets_y_left_imu_imports_as_frd_on_the_references_clock() {
    let dir = tmp("left").join("Trajectory3");
    write(&dir, [1.0, -1.0, 1.0]);
    let t = read(&dir, true).expect("read");
    let check = t.imu_check.expect("check");
    assert!(check.y_negated, "{check:?}");
    assert!(check.gyro_y_pitch_correlation < -0.99, "{check:?}");
    assert_frd(&t);
    // With the IMU, the DVL is stamped on the reference's clock too.
    let first_dvl = messages(&t)
        .into_iter()
        .find_map(|(s, _, m)| matches!(m, SensorMessage::Dvl(_)).then_some(s));
    assert_eq!(first_dvl, Some(stamp_ns(DVL_LAG_S)));
    let _ = std::fs::remove_dir_all(dir.parent().expect("parent"));
}

#[test]
fn an_imu_already_in_frd_is_left_as_it_is() {
    let dir = tmp("frd").join("Trajectory3");
    write(&dir, [1.0, 1.0, 1.0]);
    let t = read(&dir, true).expect("read");
    assert!(!t.imu_check.expect("check").y_negated);
    assert_frd(&t);
    let _ = std::fs::remove_dir_all(dir.parent().expect("parent"));
}

#[test]
fn an_imu_in_another_frame_is_refused() {
    // Upside down (X and Z negated): Y's sign cannot make it FRD.
    let dir = tmp("other").join("Trajectory3");
    write(&dir, [-1.0, 1.0, -1.0]);
    let err = read(&dir, true).expect_err("refused").to_string();
    assert!(
        err.contains("does not follow the reference's body rates"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(dir.parent().expect("parent"));
}
