//! `nauta import akit`: a trajectory in the A-KIT data set's format (written
//! here: the data set has no licence, nothing of it is committed) becomes a
//! recording that `nauta replay` runs the aided INS on, and `nauta eval`
//! scores against the imported reference.

use std::ffi::OsStr;
use std::path::Path;
use std::time::Duration;

use nauta_tests::*;

const BOUND: Duration = Duration::from_secs(240);

/// A 200 s leg in A-KIT's format: the reference at 1.0025 s steps (as the
/// data set's), heading 30° with a gentle turn, 1.5 m/s forward, 20 m deep;
/// the DVL measures the body velocity exactly.
fn write_trajectory(dir: &Path, bad_row: bool) {
    std::fs::create_dir_all(dir).expect("dir");
    let mut gt = String::from(
        "Time [s],Longitude [rad],Latitude [rad],Altitude [m],V North [m/s],V East [m/s],V Down [m/s],Roll [rad],Pitch [rad],Yaw [rad]\n",
    );
    let mut dvl = String::from("Time [s],DVL X [m/s],DVL Y [m/s],DVL Z [m/s]\n");
    let (lat0, lon0) = (32.8f64.to_radians(), 34.95f64.to_radians());
    let (rn, re) = (6_371_000.0, 6_371_000.0 * lat0.cos());
    let (mut n, mut e) = (0.0, 0.0);
    let dt = 1.0025062656641603;
    for k in 0..200 {
        let t = k as f64 * dt;
        let yaw = (30.0 + 0.1 * t).to_radians();
        let (vn, ve) = (1.5 * yaw.cos(), 1.5 * yaw.sin());
        gt += &format!(
            "{t},{},{},-20.0,{vn},{ve},0.0,0.0,0.0,{}\n",
            lon0 + e / re,
            lat0 + n / rn,
            if yaw > std::f64::consts::PI {
                yaw - 2.0 * std::f64::consts::PI
            } else {
                yaw
            }
        );
        dvl += &format!("{t},1.5,0.0,0.0\n");
        if bad_row && k == 10 {
            dvl += "10.5,1.5,zero,0.0\n";
        }
        // The next position: the mean of this and the next step's velocity.
        let yaw2 = (30.0 + 0.1 * (t + dt)).to_radians();
        n += 0.75 * (yaw.cos() + yaw2.cos()) * dt;
        e += 0.75 * (yaw.sin() + yaw2.sin()) * dt;
    }
    std::fs::write(dir.join("GT_trajectory9.csv"), gt).expect("gt");
    std::fs::write(dir.join("DVL_trajectory9.csv"), dvl).expect("dvl");
}

#[test]
fn an_akit_trajectory_imports_replays_through_the_ains_and_evaluates() {
    bin_dir();
    let _wd = Watchdog::new("import_akit", BOUND);
    let tmp = std::env::temp_dir().join(format!("nauta-akit-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let dir = tmp.join("Trajectory9");
    write_trajectory(&dir, false);
    let out = tmp.join("t9.mcap");
    let (code, _, err) = nauta_cli(&[
        "import".as_ref(),
        "akit".as_ref(),
        dir.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let run = tmp.join("run.mcap");
    let (code, _, err) = nauta_cli(&[
        "replay".as_ref(),
        out.as_os_str(),
        "--fast".as_ref(),
        "--record".as_ref(),
        run.as_os_str(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let (code, json, err) = nauta_cli(&["eval".as_ref(), run.as_os_str(), "--json".as_ref()]);
    assert_eq!(code, Some(0), "{err}");
    let eval: serde_json::Value = serde_json::from_str(&json).expect("eval JSON");
    let nav = &eval["streams"]["ains/nav"];
    // One solution per 1 Hz sample, along the 300 m leg; the dead reckoning
    // of an exact DVL and attitude stays within a fraction of a percent
    // (what is left: the zero-order hold of a 1 Hz velocity in a turn of
    // 0.1°/s, 0.33 % here).
    assert_eq!(nav["samples"].as_u64(), Some(200), "{nav}");
    let d = nav["distance_m"].as_f64().expect("distance");
    assert!((290.0..310.0).contains(&d), "{nav}");
    let pct = nav["final_error_pct"].as_f64().expect("final_error_pct");
    assert!(pct < 0.5, "{nav}");

    // A bad row: a clear error naming the file, the line and the column.
    let bad = tmp.join("Bad").join("Trajectory9");
    write_trajectory(&bad, true);
    let (code, _, err) = nauta_cli(&[
        "import".as_ref(),
        "akit".as_ref(),
        bad.as_os_str(),
        "-o".as_ref(),
        OsStr::new(&tmp.join("bad.mcap")),
    ]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("DVL_trajectory9.csv:13: column 3 (DVL Y [m/s]) is not a number"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&tmp);
}
