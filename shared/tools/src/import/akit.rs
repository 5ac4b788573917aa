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
//!   becomes `sensor/imu` in FRD. Measured against the reference
//!   (`docs/analysis/akit_imu_frame.py`, trajectories 1-4): the file's
//!   clock runs [`IMU_CLOCK_SCALE`] times slow against the reference's and
//!   is offset from it by a fraction of a second that differs between
//!   files (+0.40 to +0.48 s on 1-4, −0.50 to −0.46 s on four of the
//!   held-out ones), so each sample is stamped at `scale · t + offset`, the
//!   offset fitted per file to the AHRS channel's heading (see
//!   [`fit_imu_clock_offset`]); its X and Z axes are FRD's, its Y axis points
//!   left (gyro Y against the reference's pitch rate and accelerometer Y
//!   against the centripetal acceleration both −1.0), so both Y channels
//!   are negated. The sense of Y is decided per file from the correlation
//!   of gyro Y with the reference's pitch rate (a file already in FRD is
//!   left as it is), and the import refuses a file whose gyro does not
//!   follow the reference's yaw rate. The metadata give both correlations.
//!   The DVL is put on the same clock ([`DVL_LAG_S`] after its stamp, as
//!   `dr`'s `dvl_delay_s` does without `--imu`).
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
    /// How long after its stamp a DVL sample's velocity belongs on the
    /// reference's clock, s (with `--imu` the DVL is stamped there; without,
    /// the manifest gives it to `dr` as `dvl_delay_s`). Default 1.0, fitted
    /// on trajectories 1-4.
    #[arg(long, default_value_t = DVL_LAG_S)]
    pub dvl_lag_s: f64,
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
    /// The IMU's check against the reference, when read.
    pub imu_check: Option<ImuCheck>,
    /// How long after its stamp a DVL sample belongs on the reference's
    /// clock, s ([`DVL_LAG_S`] unless set).
    pub dvl_lag_s: f64,
}

/// How the IMU file's axes compare with the reference's body rates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuCheck {
    /// The offset of the IMU's clock fitted against the heading, s.
    pub clock_offset_s: f64,
    /// The correlation of the file's gyro Y with the reference's pitch
    /// rate: negative for the data set's Y-left axes.
    pub gyro_y_pitch_correlation: f64,
    /// Whether gyro Y and accelerometer Y were negated (Y left to FRD).
    pub y_negated: bool,
    /// After that: the correlation of gyro X, Y, Z with the reference's
    /// body rates p, q, r over its intervals (each near 1 for FRD).
    pub rate_correlation: [f64; 3],
}

/// The IMU file's clock against the reference's: a sample at file time `t`
/// is at reference time `IMU_CLOCK_SCALE · t + offset`. The reference's
/// rows are 400/399 s apart and the IMU's 400/39999 s: 400 s of file time
/// span 401 s of the reference's (fitted scale 1.00225-1.00250 on
/// trajectories 1-4, a yaw rate residual of 0.2-0.8 mrad per interval with
/// the map against 11-31 without: `docs/analysis/akit_imu_frame.py`).
pub const IMU_CLOCK_SCALE: f64 = 400.0 / 399.0;
/// The offsets [`fit_imu_clock_offset`] searches, s.
const IMU_CLOCK_OFFSET_RANGE_S: (f64, f64) = (-2.0, 2.0);
/// A DVL sample's velocity belongs this long after its stamp on the
/// reference's clock, s (fitted on trajectories 1-4:
/// `docs/analysis/akit_dvl_timing.py`). With `--imu` the import stamps the
/// DVL there; without, `dr`'s `dvl_delay_s` applies it.
pub const DVL_LAG_S: f64 = 1.0;
/// Below this correlation of gyro X, Y or Z with the reference's body
/// rates (after Y's sense is settled) the file's frame is not FRD's and the
/// import refuses it.
const MIN_RATE_CORRELATION: f64 = 0.5;

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
    let (imu, imu_check) = if imu {
        let path = find(dir, "IMU_")?;
        let mut rows: Vec<ImuRow> = read_csv(&path, &IMU_HEADER)?
            .into_iter()
            .map(|r| {
                (
                    IMU_CLOCK_SCALE * r[0],
                    [r[1], r[2], r[3]],
                    [r[4], r[5], r[6]],
                )
            })
            .collect();
        let offset_s = fit_imu_clock_offset(&rows, &reference);
        for r in &mut rows {
            r.0 += offset_s;
        }
        let c = gyro_y_pitch_correlation(&rows, &reference);
        let y_negated = c < 0.0;
        if y_negated {
            for r in &mut rows {
                r.1[1] = -r.1[1];
                r.2[1] = -r.2[1];
            }
        }
        let rate_correlation = rate_correlation(&rows, &reference);
        if rate_correlation
            .iter()
            .any(|c| !(*c >= MIN_RATE_CORRELATION))
        {
            bail!(
                "{}: the gyro does not follow the reference's body rates (correlation of X, Y, Z \
                 with p, q, r: {rate_correlation:.2?}, below {MIN_RATE_CORRELATION}): \
                 not the A-KIT IMU's axes or clock",
                path.display()
            );
        }
        let check = ImuCheck {
            clock_offset_s: offset_s,
            gyro_y_pitch_correlation: c,
            y_negated,
            rate_correlation,
        };
        (Some(rows), Some(check))
    } else {
        (None, None)
    };
    Ok(Trajectory {
        name,
        reference,
        dvl,
        imu,
        imu_check,
        dvl_lag_s: DVL_LAG_S,
    })
}

/// Over each interval of the reference: the gyro's angle increment (each
/// sample's rate over the time since the previous sample) and the
/// reference's, the rotation vector of its attitude from the interval's
/// start to its end in the body (FRD: p, q, r times the interval).
fn angle_increments(imu: &[ImuRow], reference: &[Reference]) -> Vec<([f64; 3], [f64; 3])> {
    let mut out = Vec::with_capacity(reference.len());
    let mut k = 0;
    let mut last_t: Option<f64> = None;
    for w in reference.windows(2) {
        let (a, b) = (w[0].t_s, w[1].t_s);
        let mut gyro = [0.0; 3];
        let mut covered = 0.0;
        while k < imu.len() && imu[k].0 <= b {
            let (t, _, g) = imu[k];
            if t > a
                && let Some(prev) = last_t
            {
                let dt = t - prev;
                covered += dt;
                for (s, x) in gyro.iter_mut().zip(g) {
                    *s += x * dt;
                }
            }
            last_t = Some(t);
            k += 1;
        }
        // Only intervals the IMU covers (its clock starts after the
        // reference's and ends after it).
        if covered < 0.9 * (b - a) {
            continue;
        }
        out.push((gyro, body_increment(&w[0], &w[1])));
    }
    out
}

fn correlation(pairs: impl Iterator<Item = (f64, f64)>) -> f64 {
    let (mut n, mut sx, mut sy, mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (x, y) in pairs {
        n += 1.0;
        sx += x;
        sy += y;
        sxy += x * y;
        sxx += x * x;
        syy += y * y;
    }
    let (vx, vy) = (sxx - sx * sx / n, syy - sy * sy / n);
    if n > 1.0 && vx > 0.0 && vy > 0.0 {
        (sxy - sx * sy / n) / (vx * vy).sqrt()
    } else {
        0.0
    }
}

/// The offset of the IMU's clock (`imu` on [`IMU_CLOCK_SCALE`]'s scale,
/// without offset) against the reference's: the one that makes the gyro Z
/// angle over each reference interval closest (least squares) to the
/// heading's increment there, searched over [`IMU_CLOCK_OFFSET_RANGE_S`]
/// by 0.01 s and then by 0.001 s. A time synchronisation against the AHRS
/// channel, which the navigation takes as input: the files were cut from
/// the logs with offsets that differ by file (no constant fits all 13).
/// Gyro Z and the heading are about the same axis for any sense of Y.
pub fn fit_imu_clock_offset(imu: &[ImuRow], reference: &[Reference]) -> f64 {
    if imu.len() < 2 || reference.len() < 2 {
        return 0.0;
    }
    // The gyro Z angle from the first sample on (trapezoids).
    let mut angle = Vec::with_capacity(imu.len());
    let mut sum = 0.0;
    angle.push(0.0);
    for w in imu.windows(2) {
        sum += 0.5 * (w[0].2[2] + w[1].2[2]) * (w[1].0 - w[0].0);
        angle.push(sum);
    }
    let angle_at = |t: f64| -> Option<f64> {
        let i = imu.partition_point(|r| r.0 < t);
        if i == 0 || i >= imu.len() {
            return None;
        }
        let (t0, t1) = (imu[i - 1].0, imu[i].0);
        let f = (t - t0) / (t1 - t0);
        Some(angle[i - 1] + f * (angle[i] - angle[i - 1]))
    };
    let turns: Vec<f64> = reference
        .windows(2)
        .map(|w| body_increment(&w[0], &w[1])[2])
        .collect();
    let residual = |offset: f64| -> f64 {
        let (mut sum, mut n) = (0.0, 0usize);
        for (w, turn) in reference.windows(2).zip(&turns) {
            if let (Some(a), Some(b)) = (angle_at(w[0].t_s - offset), angle_at(w[1].t_s - offset)) {
                let d = (b - a) - turn;
                sum += d * d;
                n += 1;
            }
        }
        // Fewer than half the intervals covered: not a candidate.
        if 2 * n < reference.len() {
            f64::INFINITY
        } else {
            sum / n as f64
        }
    };
    let best = |from: f64, to: f64, step: f64| -> f64 {
        let n = ((to - from) / step).round() as i64;
        (0..=n)
            .map(|k| from + k as f64 * step)
            .min_by(|a, b| residual(*a).total_cmp(&residual(*b)))
            .unwrap_or(0.0)
    };
    let (lo, hi) = IMU_CLOCK_OFFSET_RANGE_S;
    let coarse = best(lo, hi, 0.01);
    best(coarse - 0.01, coarse + 0.01, 0.001)
}

/// The rotation vector of the attitude from `a` to `b`, in the body (FRD).
fn body_increment(a: &Reference, b: &Reference) -> [f64; 3] {
    let [r0, p0, y0] = a.euler_rad;
    let [r1, p1, y1] = b.euler_rad;
    let c0 = Rotation::<Frd, Ned>::from_euler(r0, p0, y0);
    let c1 = Rotation::<Frd, Ned>::from_euler(r1, p1, y1);
    let [qw, qx, qy, qz] = (c0.inverse() * c1).to_wxyz();
    let v = (qx * qx + qy * qy + qz * qz).sqrt();
    let angle = 2.0 * v.atan2(qw.abs());
    let s = if v > 0.0 {
        angle / v * qw.signum()
    } else {
        2.0
    };
    [s * qx, s * qy, s * qz]
}

/// The correlation, over the reference's intervals, of the gyro Y angle
/// increment with the reference's pitch-rate increment (q, FRD).
pub fn gyro_y_pitch_correlation(imu: &[ImuRow], reference: &[Reference]) -> f64 {
    correlation(
        angle_increments(imu, reference)
            .into_iter()
            .map(|(g, r)| (g[1], r[1])),
    )
}

/// The correlation of gyro X, Y and Z with the reference's body rates p,
/// q, r over its intervals.
pub fn rate_correlation(imu: &[ImuRow], reference: &[Reference]) -> [f64; 3] {
    let inc = angle_increments(imu, reference);
    std::array::from_fn(|i| correlation(inc.iter().map(|(g, r)| (g[i], r[i]))))
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
    let timing = if t.imu.is_some() {
        "# The DVL and the IMU are stamped on the reference's clock (the import:\n\
         # DVL_LAG_S; the IMU's clock fitted to the AHRS heading), so no delay.\n\
         # The AHRS channel is the reference's heading (a FOG INS,\n\
         # post-processed): 0.1 deg white and 0.1 deg slow error for `ekf`\n\
         # (1.0 deg and 2 deg, its defaults for a magnetic AHRS, give 0.553 /\n\
         # 0.420 / 0.362 / 1.446 % on trajectories 1-4 against 0.370 / 0.185 /\n\
         # 0.207 / 0.112 %: BENCHMARKS.md).\n\
         variants.dr = { aiding_timeout_s = 2.5 }\n\
         variants.ekf = { aiding_timeout_s = 2.5, ahrs_heading_std_rad = 0.0017, heading_bias_std_rad = 0.0017 }\n\
         variants.pf = { aiding_timeout_s = 2.5 }"
            .to_owned()
    } else {
        let lag = t.dvl_lag_s;
        format!(
            "# The DVL's velocity belongs {lag:?} s after its stamp against the\n\
             # reference's attitude (fitted on trajectories 1-4:\n\
             # docs/analysis/akit_dvl_timing.py; the held-out 5-13 agree), so it is\n\
             # used from then on.\n\
             variants.dr = {{ aiding_timeout_s = 2.5, dvl_delay_s = {lag:?} }}"
        )
    };
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
# counts as present for 2.5 s.
{timing}
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
    if let Some(c) = t.imu_check {
        import.insert(
            "gyro_y_pitch_correlation".to_owned(),
            format!("{:.3}", c.gyro_y_pitch_correlation),
        );
        import.insert("imu_y_negated".to_owned(), c.y_negated.to_string());
        let [x, y, z] = c.rate_correlation;
        import.insert(
            "imu_rate_correlation".to_owned(),
            format!("{x:.3} {y:.3} {z:.3}"),
        );
        import.insert(
            "imu_clock".to_owned(),
            format!("{IMU_CLOCK_SCALE} t + {:.3} s", c.clock_offset_s),
        );
        import.insert("dvl_lag_s".to_owned(), t.dvl_lag_s.to_string());
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
    // With the IMU, the DVL is stamped on the reference's clock too.
    let dvl_lag_s = if t.imu.is_some() { t.dvl_lag_s } else { 0.0 };
    for (i, (t_s, v)) in t.dvl.iter().enumerate() {
        let s = stamp_ns(t_s + dvl_lag_s);
        messages.push((
            s,
            3,
            SensorMessage::Dvl(DvlSample {
                header: Header::new(s, i as u64, Role::Sensor, 0),
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
    anyhow::ensure!(
        args.dvl_lag_s.is_finite() && (0.0..=10.0).contains(&args.dvl_lag_s),
        "--dvl-lag-s {}: expected 0 to 10 s",
        args.dvl_lag_s
    );
    let mut t = read(&args.dir, args.imu)?;
    t.dvl_lag_s = args.dvl_lag_s;
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
    if let Some(c) = t.imu_check {
        let [x, y, z] = c.rate_correlation;
        eprintln!(
            "nauta: gyro Y against the reference's pitch rate: correlation {:.3}{}; \
             gyro X, Y, Z against p, q, r: {x:.3} {y:.3} {z:.3}",
            c.gyro_y_pitch_correlation,
            if c.y_negated {
                " (Y left: gyro and accelerometer Y negated)"
            } else {
                ""
            }
        );
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests;
