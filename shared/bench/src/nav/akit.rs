//! `nauta bench nav --akit DIR`: the Snapir AUV's A-KIT trajectories (github
//! `ansfl/A-KIT`, Cohen and Klein 2025; read from a local copy, never
//! committed) in process, as `nauta import akit` and `nauta replay` run them:
//! the same messages ([`akit::messages`]), the same manifest's `dr`
//! parameters ([`akit::manifest`]), the service's tie order, and `nauta
//! eval`'s code for the score. Beside it, naive 1 Hz dead reckoning with the
//! same reference attitude: each DVL sample rotated by the reference's
//! attitude at or before it and held until the next (a rectangle forward),
//! from the reference's first position, scored by the same code. (Applying
//! each sample to the interval before it instead gives 0.663 / 0.312 / 0.366
//! / 0.994 % on trajectories 1-4; held forward gives the 0.57 /
//! 0.25 / 0.36 / 0.93 %, so that is the baseline.) Where a trajectory has
//! its IMU file, `ekf` on the `--imu` import's messages and manifest too.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use serde_json::{Map, Value, json};

use nauta_estimation::Estimator;
use nauta_estimation::ains::AinsInput;
use nauta_estimation::ains::dr::{DeadReckoning, DrParams, Site};
use nauta_estimation::ains::ekf::{Ekf, EkfParams};
use nauta_estimation::frames::{Frd, Ned, Rotation, Vector};
use nauta_estimation::local::geodetic_of;
use nauta_estimation::readings::Nav;
use nauta_messages::{GPS_SERVICE, NavSolution, SensorMessage, TRUTH_SERVICE, TruthState};
use nauta_runtime::Manifest;
use nauta_tools::eval::{self, Data, Metrics};
use nauta_tools::import::akit;

use super::{input_of, take};

/// The trajectory directories under `dir` (`Trajectory1`, `Trajectory2`,
/// ...), in their number's order.
fn trajectories(dir: &Path) -> anyhow::Result<Vec<(u32, PathBuf)>> {
    let mut found = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| format!("{}", dir.display()))? {
        let e = e?;
        let name = e.file_name().to_string_lossy().into_owned();
        if let Some(n) = name.strip_prefix("Trajectory").and_then(|n| n.parse().ok())
            && e.file_type()?.is_dir()
        {
            found.push((n, e.path()));
        }
    }
    found.sort();
    anyhow::ensure!(
        !found.is_empty(),
        "{}: no TrajectoryN directories (A-KIT's Data/)",
        dir.display()
    );
    Ok(found)
}

/// Whether `dir` holds the trajectory's IMU file (`IMU_*.csv`).
fn has_imu(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|entries| {
        entries.flatten().any(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.starts_with("IMU_") && name.ends_with(".csv")
        })
    })
}

fn score(mut data: Data) -> anyhow::Result<Metrics> {
    eval::live::sort(&mut data);
    eval::evaluate(Path::new("(in process)"), &data)?
        .streams
        .get("ains/nav")
        .cloned()
        .context("no solution")
}

/// The reference and the initial fix, as eval reads them from a recording.
fn reference(data: &mut Data, m: &SensorMessage) -> anyhow::Result<()> {
    match m {
        SensorMessage::Truth(t) => take::<TruthState>(data, TRUTH_SERVICE, t),
        SensorMessage::Gps(f) => take(data, GPS_SERVICE, f),
        _ => Ok(()),
    }
}

/// A variant (`dr`, `ekf`) on the messages, the service's order at each
/// stamp.
fn run_variant<E: Estimator<Input = AinsInput, Output = Nav>>(
    messages: &[(u64, usize, SensorMessage)],
    mut dr: E,
) -> anyhow::Result<Metrics> {
    let mut data = Data::default();
    let (mut inputs, mut out) = (Vec::new(), Vec::<Nav>::new());
    let mut k = 0;
    while k < messages.len() {
        let stamp = messages[k].0;
        inputs.clear();
        while k < messages.len() && messages[k].0 == stamp {
            let m = &messages[k].2;
            reference(&mut data, m)?;
            inputs.extend(input_of(m));
            k += 1;
        }
        inputs.sort_by_key(|(order, _)| *order);
        for (_, input) in &inputs {
            out.clear();
            // A refused input (a spike) is counted by the service; here it
            // is only not used.
            let _ = dr.on_input(input, &mut out);
            for o in &out {
                take(&mut data, "ains/nav", &NavSolution::from(o))?;
            }
        }
    }
    score(data)
}

/// Naive 1 Hz dead reckoning with the reference attitude.
fn run_naive(messages: &[(u64, usize, SensorMessage)]) -> anyhow::Result<Metrics> {
    let mut data = Data::default();
    let mut attitude: Option<Rotation<Frd, Ned>> = None;
    let (mut origin, mut depth_m) = (None, 0.0);
    let (mut north, mut east, mut last_ns) = (0.0, 0.0, None::<u64>);
    let mut held: Option<Vector<Ned>> = None;
    for (stamp, _, m) in messages {
        reference(&mut data, m)?;
        match m {
            SensorMessage::Truth(t) => {
                origin.get_or_insert((t.lat_rad, t.lon_rad));
                depth_m = t.depth_m;
                attitude = Rotation::from_wxyz(t.quat_nb).ok();
            }
            SensorMessage::Dvl(d) => {
                let (Some((lat0, lon0)), Some(r)) = (origin, attitude) else {
                    continue;
                };
                // The previous sample's velocity over the interval since it
                // (each sample held until the next), then this one's.
                if let (Some(last), Some(v)) = (last_ns, held) {
                    let dt = (*stamp - last) as f64 * 1e-9;
                    north += v.x() * dt;
                    east += v.y() * dt;
                }
                let v = r * Vector::<Frd>::from_array(d.velocity_body_m_s);
                held = Some(v);
                last_ns = Some(*stamp);
                let (lat_rad, lon_rad) = geodetic_of(lat0, lon0, north, east);
                let mut n = NavSolution {
                    lat_rad,
                    lon_rad,
                    depth_m,
                    vel_ned_m_s: [v.x(), v.y(), v.z()],
                    ..Default::default()
                };
                n.header.stamp_ns = *stamp;
                take(&mut data, "ains/nav", &n)?;
            }
            _ => {}
        }
    }
    score(data)
}

/// Every trajectory under `dir`: `dr`'s and naive dead reckoning's final
/// error, % of the distance.
pub fn akit_trajectories(dir: &Path, progress: bool) -> anyhow::Result<Map<String, Value>> {
    let mut out = Map::new();
    for (n, path) in trajectories(dir)? {
        let t = akit::read(&path, false)?;
        let messages = akit::messages(&t);
        let duration_s = t.reference.last().map_or(0.0, |r| r.t_s) + 2.0;
        let manifest_text = akit::manifest(&t, "dr", duration_s);
        let manifest = Manifest::parse(&path.join("(imported manifest)"), &manifest_text)?;
        let params: DrParams = manifest.params("ains", Some("dr"))?;
        let r0 = t.reference.first().context("an empty trajectory")?;
        let site = Site {
            lat_rad: r0.lat_rad,
            lon_rad: r0.lon_rad,
            declination_rad: 0.0,
        };
        let dr = run_variant(&messages, DeadReckoning::new(&params, site)?)?;
        let naive = run_naive(&messages)?;
        let (d, v) = (
            dr.final_error_pct.context("dr: no final error")?,
            naive.final_error_pct.context("naive: no final error")?,
        );
        if progress {
            eprintln!(
                "  A-KIT trajectory {n}: dr {d:.3} %, naive 1 Hz DR {v:.3} % of the distance"
            );
        }
        let mut entry = json!({ "dr": { "final_error_pct": d }, "naive_dr_pct": v });
        if has_imu(&path) {
            let t = akit::read(&path, true)?;
            let manifest_text = akit::manifest(&t, "ekf", duration_s);
            let manifest = Manifest::parse(&path.join("(imported manifest)"), &manifest_text)?;
            let params: EkfParams = manifest.params("ains", Some("ekf"))?;
            let ekf = run_variant(&akit::messages(&t), Ekf::new(&params, site)?)?;
            let e = ekf.final_error_pct.context("ekf: no final error")?;
            if progress {
                eprintln!("  A-KIT trajectory {n}: ekf with the IMU {e:.3} %");
            }
            entry["ekf_imu"] = json!({ "final_error_pct": e });
        }
        out.insert(n.to_string(), entry);
    }
    Ok(out)
}
