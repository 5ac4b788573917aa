//! Eval and export place a local (`lbl/nav`) position at the same latitude and
//! longitude: both go through the one local-origin projection
//! (`nauta_estimation::local`) at the recording's origin. A recording whose
//! `lbl/nav` points are the truth's own positions in the local frame must
//! evaluate to no error, and export them at the truth's latitude and
//! longitude.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Duration;

use nauta_log::{LogWriter, WriterOptions};
use nauta_messages::*;
use nauta_sim::mission::Origin;
use nauta_tests::{Running, Watchdog, bin};
use serde_json::Value;

const BOUND: Duration = Duration::from_secs(120);
const ORIGIN: (f64, f64) = (38.6, -9.3);

/// Truth on a loop 6 km across, the `lbl/nav` at the same points.
fn write(path: &Path) {
    let mut w = LogWriter::create(path, WriterOptions::default()).expect("create");
    let mut meta = BTreeMap::new();
    meta.insert("origin_lat_deg".to_string(), ORIGIN.0.to_string());
    meta.insert("origin_lon_deg".to_string(), ORIGIN.1.to_string());
    w.metadata(nauta_log::META_RUN, meta).expect("metadata");
    let origin = Origin::from_degrees(ORIGIN.0, ORIGIN.1);
    for k in 0..600u64 {
        let a = k as f64 * std::f64::consts::TAU / 600.0;
        let (n, e) = (3_000.0 * a.sin(), 3_000.0 * (1.0 - a.cos()) - 1_500.0);
        let (lat, lon) = origin.to_geodetic(n, e);
        let stamp = k * 1_000_000_000;
        let truth = TruthState {
            header: Header::new(stamp, k, Role::Sensor, 0),
            lat_rad: lat,
            lon_rad: lon,
            depth_m: 10.0,
            quat_nb: [1.0, 0.0, 0.0, 0.0],
            distance_m: k as f64,
            ..Default::default()
        };
        let (ln, le) = origin.to_local(lat, lon);
        let mut lbl = LblSolution {
            header: Header::new(stamp, k, Role::Lbl, 0),
            x_m: ln,
            y_m: le,
            accepted: 1,
            ..Default::default()
        };
        lbl.p[0][0] = 1.0;
        lbl.p[1][1] = 1.0;
        let log_time = 1_700_000_000_000_000_000 + stamp;
        w.write_message(TRUTH_SERVICE, log_time, &truth)
            .expect("truth");
        w.write_message(LBL_SOLUTION_SERVICE, log_time, &lbl)
            .expect("lbl");
    }
    w.finish().expect("finish");
}

fn nauta(wd: &Watchdog, args: &[&std::ffi::OsStr]) -> String {
    let out = Running::spawn(wd, &bin("nauta"), args, None).wait(wd);
    assert_eq!(out.code(), Some(0), "{out}");
    out.stdout.clone()
}

#[test]
fn eval_and_export_place_an_lbl_point_at_the_same_latitude_and_longitude() {
    let wd = Watchdog::new("placement", BOUND);
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("placement.mcap");
    write(&file);

    let eval: Value = serde_json::from_str(&nauta(
        &wd,
        &["eval".as_ref(), file.as_os_str(), "--json".as_ref()],
    ))
    .expect("eval --json");
    let lbl = &eval["streams"]["lbl/nav"];
    let max = lbl["horizontal_max_m"].as_f64().expect("horizontal_max_m");
    assert!(
        max < 1e-3,
        "eval places lbl/nav {max} m off the truth\n{eval:#}"
    );
    assert_eq!(lbl["samples"].as_u64(), Some(600), "{eval:#}");

    let csv = dir.path().join("placement.csv");
    nauta(
        &wd,
        &[
            "export".as_ref(),
            file.as_os_str(),
            "-o".as_ref(),
            csv.as_os_str(),
        ],
    );
    let text = std::fs::read_to_string(&csv).expect("csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (stamp, topic, lat, lon) = (
        col("stamp_ns"),
        col("topic"),
        col("lat_deg"),
        col("lon_deg"),
    );
    let mut by_stamp: BTreeMap<(u64, String), (f64, f64)> = BTreeMap::new();
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let s: u64 = f[stamp].parse().expect("stamp");
        by_stamp.insert(
            (s, f[topic].to_string()),
            (f[lat].parse().expect("lat"), f[lon].parse().expect("lon")),
        );
    }
    let mut compared = 0;
    for ((s, t), (la, lo)) in &by_stamp {
        if t != "lbl/nav" {
            continue;
        }
        let (tla, tlo) = by_stamp[&(*s, "sim/truth".to_string())];
        // 1e-9° is 0.1 mm.
        assert!(
            (la - tla).abs() < 1e-9 && (lo - tlo).abs() < 1e-9,
            "at {s}: export puts lbl/nav at ({la}, {lo}), the truth is at ({tla}, {tlo})"
        );
        compared += 1;
    }
    assert_eq!(compared, 600, "every lbl/nav row compared");
}
