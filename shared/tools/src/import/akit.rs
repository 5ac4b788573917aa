//! `nauta import akit DIR -o OUT.mcap [--imu]`: one trajectory of the Snapir
//! AUV data set (A-KIT: Cohen and Klein, Engineering Applications of AI 146,
//! 2025; github `ansfl/A-KIT`, no licence file: read, never committed) as a
//! recording that `nauta replay` runs the aided INS on.
//!
//! `DIR` is one `Data/TrajectoryN/` directory:
//! - `GT_trajectoryN.csv` (`Time [s]`, `Longitude [rad]`, `Latitude [rad]`,
//!   `Altitude [m]`, `V North/East/Down [m/s]`, `Roll/Pitch/Yaw [rad]`): the
//!   reference, a Delph-post-processed PHINS FOG INS, becomes `sim/truth`
//!   (depth = −altitude, the distance travelled summed from its positions),
//!   its attitude `sensor/ahrs` (true heading: the manifest's declination is
//!   0) and its depth `sensor/depth`;
//! - `DVL_trajectoryN.csv` (`Time [s]`, `DVL X/Y/Z [m/s]`, body velocity at
//!   1 Hz) becomes `sensor/dvl` (bottom lock on every sample);
//! - with `--imu`, `IMU_trajectoryN.csv` (100 Hz, `ACC X/Y/Z [m/s^2]`,
//!   `GYRO X/Y/Z [rad/s]`; whole only at the repository's commit c2168ed)
//!   becomes `sensor/imu`. Its gyro Y axis is checked against the
//!   reference's pitch rate (the data set's own README warns of a sign
//!   change): if the two are anti-correlated, gyro Y is negated, and the
//!   import's metadata says so with the correlation.
//!
//! The sections have no GPS and start under way: the import writes one fix
//! from the reference at the first sample (σ 0.1 m, satellites 0, and
//! `nauta.import` says `initial_fix = reference`), so the navigation starts
//! where the reference does. Stamps are the file's times plus 1 s (stamp 0
//! is kept free). The recording carries a manifest that replays the sensor
//! channels and runs the aided INS (`dr` by default, `--variant`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context as _, bail};
use nauta_estimation::frames::{Frd, Ned, Rotation};
use nauta_estimation::local::flat;
use nauta_log::{LogWriter, WriterOptions};
use nauta_messages::*;

/// Arguments of `nauta import akit`.
#[derive(Debug, clap::Args)]
pub struct ImportAkitArgs {
    /// One trajectory directory of the data set (`Data/TrajectoryN/`).
    pub dir: PathBuf,
    /// The recording to write (MCAP).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Import the 100 Hz IMU too (`IMU_trajectoryN.csv`).
    #[arg(long)]
    pub imu: bool,
    /// The aided INS variant the recorded manifest runs on replay.
    #[arg(long, default_value = "dr")]
    pub variant: String,
}

/// One reference sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reference {
    /// Time, s.
    pub t_s: f64,
    /// Latitude and longitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Depth, m (−altitude).
    pub depth_m: f64,
    /// Velocity NED, m/s.
    pub vel_ned_m_s: [f64; 3],
    /// Roll, pitch, yaw, rad.
    pub euler_rad: [f64; 3],
}

/// One DVL sample: time, s, and body velocity, m/s.
pub type DvlRow = (f64, [f64; 3]);

/// One IMU sample: time, s, specific force, m/s², angular rate, rad/s.
pub type ImuRow = (f64, [f64; 3], [f64; 3]);

/// A trajectory read from its directory.
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// `TrajectoryN`.
    pub name: String,
    /// The reference.
    pub reference: Vec<Reference>,
    /// The DVL.
    pub dvl: Vec<DvlRow>,
    /// The IMU, when asked for.
    pub imu: Option<Vec<ImuRow>>,
    /// The correlation of gyro Y with the reference's pitch rate, and
    /// whether gyro Y was negated.
    pub gyro_y_check: Option<(f64, bool)>,
}

/// Reads a CSV with the expected header; each row's `n` numbers. Errors
/// name the file, the line and the column.
fn read_csv(path: &Path, header: &[&str]) -> anyhow::Result<Vec<Vec<f64>>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut lines = text.lines().enumerate();
    let (_, first) = lines
        .next()
        .with_context(|| format!("{}: empty file", path.display()))?;
    let got: Vec<&str> = first.split(',').map(str::trim).collect();
    if got != header {
        bail!("{}:1: header {got:?}, expected {header:?}", path.display());
    }
    let mut rows = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() != header.len() {
            bail!(
                "{}:{}: {} fields, expected {}",
                path.display(),
                i + 1,
                fields.len(),
                header.len()
            );
        }
        let mut row = Vec::with_capacity(fields.len());
        for (c, f) in fields.iter().enumerate() {
            let x: f64 = f.trim().parse().map_err(|_| {
                anyhow::anyhow!(
                    "{}:{}: column {} ({}) is not a number: {f:?}",
                    path.display(),
                    i + 1,
                    c + 1,
                    header[c]
                )
            })?;
            if !x.is_finite() {
                bail!(
                    "{}:{}: column {} ({}) is not finite",
                    path.display(),
                    i + 1,
                    c + 1,
                    header[c]
                );
            }
            row.push(x);
        }
        if let Some(prev) = rows.last().map(|r: &Vec<f64>| r[0])
            && row[0] <= prev
        {
            bail!(
                "{}:{}: time {} s after {prev} s; it must increase",
                path.display(),
                i + 1,
                row[0]
            );
        }
        rows.push(row);
    }
    anyhow::ensure!(!rows.is_empty(), "{}: no data rows", path.display());
    Ok(rows)
}

/// The one file of `dir` named `PREFIX_*.csv`.
fn find(dir: &Path, prefix: &str) -> anyhow::Result<PathBuf> {
    let mut found = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| format!("cannot read {}", dir.display()))? {
        let p = e?.path();
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.starts_with(prefix) && name.ends_with(".csv") {
            found.push(p);
        }
    }
    match found.len() {
        1 => Ok(found.remove(0)),
        0 => bail!(
            "{}: no {prefix}*.csv (an A-KIT Data/TrajectoryN directory?)",
            dir.display()
        ),
        _ => bail!("{}: several {prefix}*.csv", dir.display()),
    }
}

const GT_HEADER: [&str; 10] = [
    "Time [s]",
    "Longitude [rad]",
    "Latitude [rad]",
    "Altitude [m]",
    "V North [m/s]",
    "V East [m/s]",
    "V Down [m/s]",
    "Roll [rad]",
    "Pitch [rad]",
    "Yaw [rad]",
];
const DVL_HEADER: [&str; 4] = ["Time [s]", "DVL X [m/s]", "DVL Y [m/s]", "DVL Z [m/s]"];
const IMU_HEADER: [&str; 7] = [
    "Time [s]",
    "ACC X [m/s^2]",
    "ACC Y [m/s^2]",
    "ACC Z [m/s^2]",
    "GYRO X [rad/s]",
    "GYRO Y [rad/s]",
    "GYRO Z [rad/s]",
];

/// Reads the trajectory in `dir` (with its IMU when `imu`).
pub fn read(dir: &Path, imu: bool) -> anyhow::Result<Trajectory> {
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "trajectory".to_owned());
    let gt_path = find(dir, "GT_")?;
    let reference: Vec<Reference> = read_csv(&gt_path, &GT_HEADER)?
        .into_iter()
        .map(|r| Reference {
            t_s: r[0],
            lon_rad: r[1],
            lat_rad: r[2],
            depth_m: -r[3],
            vel_ned_m_s: [r[4], r[5], r[6]],
            euler_rad: [r[7], r[8], r[9]],
        })
        .collect();
    for (i, r) in reference.iter().enumerate() {
        if !(r.lat_rad.abs() <= std::f64::consts::FRAC_PI_2
            && r.lon_rad.abs() <= std::f64::consts::PI)
        {
            bail!(
                "{}:{}: latitude or longitude out of range (radians expected)",
                gt_path.display(),
                i + 2
            );
        }
    }
    let dvl = read_csv(&find(dir, "DVL_")?, &DVL_HEADER)?
        .into_iter()
        .map(|r| (r[0], [r[1], r[2], r[3]]))
        .collect();
    let (imu, gyro_y_check) = if imu {
        let mut rows: Vec<ImuRow> = read_csv(&find(dir, "IMU_")?, &IMU_HEADER)?
            .into_iter()
            .map(|r| (r[0], [r[1], r[2], r[3]], [r[4], r[5], r[6]]))
            .collect();
        let c = gyro_y_pitch_correlation(&rows, &reference);
        let flip = c < 0.0;
        if flip {
            for r in &mut rows {
                r.2[1] = -r.2[1];
            }
        }
        (Some(rows), Some((c, flip)))
    } else {
        (None, None)
    };
    Ok(Trajectory {
        name,
        reference,
        dvl,
        imu,
        gyro_y_check,
    })
}

/// The correlation, over the reference's intervals, of the gyro Y angle
/// increment with the reference's pitch increment (nearly the same for
/// small roll: `θ̇ = q cos φ − r sin φ`).
pub fn gyro_y_pitch_correlation(imu: &[ImuRow], reference: &[Reference]) -> f64 {
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    let mut k = 0;
    for w in reference.windows(2) {
        let (a, b) = (w[0].t_s, w[1].t_s);
        let mut gyro = 0.0;
        let mut last_t = None;
        while k < imu.len() && imu[k].0 <= b {
            if imu[k].0 > a {
                let dt = last_t.map_or(0.0, |t| imu[k].0 - t);
                gyro += imu[k].2[1] * dt;
            }
            last_t = Some(imu[k].0);
            k += 1;
        }
        let pitch = b_minus_a(w[1].euler_rad[1], w[0].euler_rad[1]);
        sxy += gyro * pitch;
        sxx += gyro * gyro;
        syy += pitch * pitch;
    }
    if sxx > 0.0 && syy > 0.0 {
        sxy / (sxx * syy).sqrt()
    } else {
        0.0
    }
}

fn b_minus_a(b: f64, a: f64) -> f64 {
    let d = b - a;
    (d + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI
}

fn stamp_ns(t_s: f64) -> u64 {
    ((t_s + 1.0) * 1e9).round() as u64
}

/// The manifest a recording of `t` carries: the ains (`variant`) on its
/// channels, the site at the first reference sample, declination 0.
pub fn manifest(t: &Trajectory, variant: &str, duration_s: f64) -> String {
    let r0 = &t.reference[0];
    let (lat, lon) = (r0.lat_rad.to_degrees(), r0.lon_rad.to_degrees());
    let name = &t.name;
    format!(
        r#"# A-KIT {name} (Snapir AUV), imported by `nauta import akit`: replay it with
# `nauta replay FILE --fast --record RUN.mcap`, then `nauta eval RUN.mcap`.
[run]
clock = "sim"
duration_s = {duration_s:.1}
seed = 0

[site]
latitude_deg = {lat}
longitude_deg = {lon}
# The reference's yaw, which the AHRS channel carries, is a true heading.
magnetic_declination_deg = 0.0

[process.sensor]
bin = "nauta-sensor"

[process.ains]
bin = "nauta-ains"
variant = "{variant}"
# The data are 1 Hz (AHRS, DVL, depth every 1.0025 s): an aiding stream
# counts as present for 2.5 s. The DVL's velocity belongs about 1 s after
# its stamp against the reference's attitude (fitted on trajectories 1-4:
# docs/analysis/akit_dvl_timing.py; the held-out 5-13 agree), so it is used
# from then on.
variants.dr = {{ aiding_timeout_s = 2.5, dvl_delay_s = 1.0 }}
"#
    )
}

/// Writes `t` to `out`; returns the number of messages written.
pub fn write(t: &Trajectory, source: &Path, out: &Path, variant: &str) -> anyhow::Result<u64> {
    let duration_s = t.reference.last().map_or(0.0, |r| r.t_s) + 2.0;
    let mut w = LogWriter::create(out, WriterOptions::default())?;
    let r0 = t.reference[0];
    let mut run = BTreeMap::new();
    run.insert("manifest".to_owned(), manifest(t, variant, duration_s));
    run.insert("seed".to_owned(), "0".to_owned());
    run.insert("clock".to_owned(), "sim".to_owned());
    run.insert(
        "command_line".to_owned(),
        std::env::args().collect::<Vec<_>>().join(" "),
    );
    run.insert(
        "origin_lat_deg".to_owned(),
        r0.lat_rad.to_degrees().to_string(),
    );
    run.insert(
        "origin_lon_deg".to_owned(),
        r0.lon_rad.to_degrees().to_string(),
    );
    run.insert("magnetic_declination_deg".to_owned(), "0".to_owned());
    w.metadata(nauta_log::META_RUN, run)?;
    let mut import = BTreeMap::new();
    import.insert("source".to_owned(), source.display().to_string());
    import.insert(
        "dataset".to_owned(),
        "A-KIT, Snapir AUV (Cohen and Klein, Engineering Applications of AI 146, 2025; github ansfl/A-KIT)".to_owned(),
    );
    import.insert("trajectory".to_owned(), t.name.clone());
    import.insert("initial_fix".to_owned(), "reference".to_owned());
    if let Some((c, flipped)) = t.gyro_y_check {
        import.insert("gyro_y_pitch_correlation".to_owned(), format!("{c:.3}"));
        import.insert("gyro_y_negated".to_owned(), flipped.to_string());
    }
    w.metadata("nauta.import", import)?;

    let messages = messages(t);
    for (s, _, m) in &messages {
        match m {
            SensorMessage::Truth(x) => w.write_message(TRUTH_SERVICE, *s, x)?,
            SensorMessage::Ahrs(x) => w.write_message(AHRS_SERVICE, *s, x)?,
            SensorMessage::Depth(x) => w.write_message(DEPTH_SERVICE, *s, x)?,
            SensorMessage::Gps(x) => w.write_message(GPS_SERVICE, *s, x)?,
            SensorMessage::Dvl(x) => w.write_message(DVL_SERVICE, *s, x)?,
            SensorMessage::Imu(x) => w.write_message(IMU_SERVICE, *s, x)?,
            _ => {}
        }
    }
    w.finish()?;
    Ok(messages.len() as u64)
}

/// The messages of `t` as a recording of it holds them: (stamp, the
/// sensor's publishing order, message), in stamp order (ties: that order).
/// The reference on `sim/truth`, its attitude on `sensor/ahrs`, its depth on
/// `sensor/depth`, one initial fix from it on `sensor/gps`, the DVL, and the
/// IMU when read.
pub fn messages(t: &Trajectory) -> Vec<(u64, usize, SensorMessage)> {
    let mut messages: Vec<(u64, usize, SensorMessage)> = Vec::new();
    let mut distance_m = 0.0;
    let mut prev: Option<Reference> = None;
    for (i, r) in t.reference.iter().enumerate() {
        if let Some(p) = prev {
            let (n, e) = flat::to_local(p.lat_rad, p.lon_rad, r.lat_rad, r.lon_rad);
            distance_m += n.hypot(e);
        }
        prev = Some(*r);
        let s = stamp_ns(r.t_s);
        let [roll, pitch, yaw] = r.euler_rad;
        let q = Rotation::<Frd, Ned>::from_euler(roll, pitch, yaw).to_wxyz();
        let header = Header::new(s, i as u64, Role::Sensor, 0);
        messages.push((
            s,
            0,
            SensorMessage::Truth(TruthState {
                header,
                lat_rad: r.lat_rad,
                lon_rad: r.lon_rad,
                depth_m: r.depth_m,
                vel_ned_m_s: r.vel_ned_m_s,
                quat_nb: q,
                distance_m,
                ..Default::default()
            }),
        ));
        messages.push((
            s,
            2,
            SensorMessage::Ahrs(AhrsSample {
                header,
                roll_rad: roll,
                pitch_rad: pitch,
                heading_mag_rad: yaw.rem_euclid(2.0 * std::f64::consts::PI),
            }),
        ));
        messages.push((
            s,
            4,
            SensorMessage::Depth(DepthSample {
                header,
                depth_m: r.depth_m,
            }),
        ));
        if i == 0 {
            messages.push((
                s,
                5,
                SensorMessage::Gps(GpsFix {
                    header,
                    lat_rad: r.lat_rad,
                    lon_rad: r.lon_rad,
                    height_m: -r.depth_m,
                    horizontal_std_m: 0.1,
                    quality: 1,
                    satellites: 0,
                    ..Default::default()
                }),
            ));
        }
    }
    for (i, (t_s, v)) in t.dvl.iter().enumerate() {
        messages.push((
            stamp_ns(*t_s),
            3,
            SensorMessage::Dvl(DvlSample {
                header: Header::new(stamp_ns(*t_s), i as u64, Role::Sensor, 0),
                velocity_body_m_s: *v,
                altitude_m: 0.0,
                beams_valid: 0b1111,
                bottom_lock: 1,
                figure_of_merit_m_s: 0.0,
            }),
        ));
    }
    if let Some(imu) = &t.imu {
        let mut previous = None;
        for (i, (t_s, f, g)) in imu.iter().enumerate() {
            let interval_s = previous.map_or(0.01, |p| t_s - p);
            previous = Some(*t_s);
            messages.push((
                stamp_ns(*t_s),
                1,
                SensorMessage::Imu(ImuSample {
                    header: Header::new(stamp_ns(*t_s), i as u64, Role::Sensor, 0),
                    gyro_rad_s: *g,
                    accel_m_s2: *f,
                    mag_ut: [0.0; 3],
                    interval_s,
                }),
            ));
        }
    }
    messages.sort_by_key(|(s, order, _)| (*s, *order));
    messages
}

/// `nauta import akit`.
pub fn akit(args: &ImportAkitArgs) -> anyhow::Result<ExitCode> {
    let t = read(&args.dir, args.imu)?;
    let n = write(&t, &args.dir, &args.output, &args.variant)?;
    let span = t.reference.last().map_or(0.0, |r| r.t_s) - t.reference[0].t_s;
    eprintln!(
        "nauta: {}: {n} messages over {span:.0} s ({} reference, {} DVL{}) -> {}",
        t.name,
        t.reference.len(),
        t.dvl.len(),
        t.imu
            .as_ref()
            .map_or(String::new(), |i| format!(", {} IMU", i.len())),
        args.output.display()
    );
    if let Some((c, flipped)) = t.gyro_y_check {
        eprintln!(
            "nauta: gyro Y against the reference's pitch rate: correlation {c:.3}{}",
            if flipped { ", negated" } else { "" }
        );
    }
    Ok(ExitCode::SUCCESS)
}
