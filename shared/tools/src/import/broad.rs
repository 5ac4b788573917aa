//! `nauta import broad FILE -o OUT.mcap`: an outside IMU data set as a
//! recording, so that it can be replayed through the running pipeline
//! (`nauta replay OUT.mcap --fast --record RUN.mcap`) and evaluated
//! (`nauta eval RUN.mcap`).
//!
//! A BROAD trial (Laidig et al., "BROAD - A Benchmark for Robust Inertial
//! Orientation Estimation", Data 6(7):72, 2021, CC BY 4.0) becomes:
//! - `sensor/imu`: every sample, stamped `t_s + 0.0035 s` (the end of its
//!   interval, which is the time since the previous sample), in the IMU's own frame (see `nauta_datasets::broad`:
//!   any right-handed body frame will do);
//! - `sim/truth`: the optical reference of every sample where the markers were
//!   seen, as body → NED (`ned_from_enu`), at the site below, still (the
//!   channel nauta's tools take as the truth);
//! - metadata `nauta.run` with a manifest to replay it: the sensor and the
//!   attitude process (`pf`, alignment over the first 400 samples: every
//!   trial starts at rest), by default site Berlin (52.51° N, 13.32° E, where
//!   BROAD was recorded) with declination 0, because the reference frame's
//!   north is magnetic north (`shared/bench/src/attitude.rs` explains the
//!   check); `--site` and `--declination` for other data in BROAD's format;
//!   and `nauta.import` naming the source.

use nauta_estimation::frames::{Frd, Ned, Rotation};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;
use nauta_datasets::broad;
use nauta_log::{LogWriter, WriterOptions};
use nauta_messages::*;

/// Latitude and longitude of the BROAD recordings (Berlin), degrees.
const BROAD_SITE_DEG: (f64, f64) = (52.51, 13.32);

/// Arguments of `nauta import broad`.
#[derive(Debug, clap::Args)]
pub struct ImportBroadArgs {
    /// A BROAD-format trial (`.csv` or `.csv.gz`, e.g. ../shared/data/broad/01_undisturbed_slow_rotation_A.csv.gz).
    pub file: PathBuf,
    /// The recording to write (MCAP).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// The attitude variant the recorded manifest runs on replay.
    #[arg(long, default_value = "pf")]
    pub variant: String,
    /// Where the data were recorded, `LAT,LON` in degrees (default: Berlin,
    /// where BROAD was recorded).
    #[arg(long, value_name = "LAT,LON", allow_hyphen_values = true)]
    pub site: Option<String>,
    /// Magnetic declination of the reference's north, degrees east (default 0:
    /// BROAD's reference frame points its north at magnetic north).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub declination: f64,
}

/// Where a trial was recorded and what its reference's north is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImportSite {
    /// Latitude, degrees.
    pub latitude_deg: f64,
    /// Longitude, degrees.
    pub longitude_deg: f64,
    /// Magnetic declination of the reference's north, degrees east.
    pub declination_deg: f64,
}

impl ImportSite {
    /// BROAD's: Berlin, declination 0.
    pub fn broad() -> Self {
        Self {
            latitude_deg: BROAD_SITE_DEG.0,
            longitude_deg: BROAD_SITE_DEG.1,
            declination_deg: 0.0,
        }
    }

    fn from_args(args: &ImportBroadArgs) -> anyhow::Result<Self> {
        let mut site = Self::broad();
        if let Some(text) = &args.site {
            let (lat, lon) = text
                .split_once(',')
                .with_context(|| format!("--site {text:?}: expected LAT,LON in degrees"))?;
            let num = |s: &str| {
                s.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .with_context(|| format!("--site {text:?}: {s:?} is not a number"))
            };
            site.latitude_deg = num(lat)?;
            site.longitude_deg = num(lon)?;
            anyhow::ensure!(
                site.latitude_deg.abs() <= 90.0 && site.longitude_deg.abs() <= 180.0,
                "--site {text:?}: out of range"
            );
        }
        anyhow::ensure!(
            args.declination.is_finite() && args.declination.abs() <= 180.0,
            "--declination must be in [-180, 180] degrees"
        );
        site.declination_deg = args.declination;
        Ok(site)
    }
}

fn manifest(name: &str, duration_s: f64, variant: &str, site: &ImportSite) -> String {
    let (lat, lon, dec) = (site.latitude_deg, site.longitude_deg, site.declination_deg);
    format!(
        r#"# BROAD trial {name}, imported by `nauta import broad`: replay it with
# `nauta replay FILE --fast --record RUN.mcap`, then `nauta eval RUN.mcap`.
[run]
clock = "sim"
duration_s = {duration_s:.1}
seed = 0

[site]
latitude_deg = {lat}
longitude_deg = {lon}
magnetic_declination_deg = {dec}

[process.sensor]
bin = "nauta-sensor"

[process.attitude]
bin = "nauta-attitude"
variant = "{variant}"
variants.gyro = {{ alignment_samples = 400 }}
variants.mekf = {{ alignment_samples = 400 }}
variants.pf = {{ alignment_samples = 400 }}
"#
    )
}

/// Writes `trial` to `out`; returns (IMU samples, truth samples).
pub fn write_broad(
    trial: &broad::BroadTrial,
    source: &Path,
    out: &Path,
    variant: &str,
    site: &ImportSite,
) -> anyhow::Result<(u64, u64)> {
    let mut w = LogWriter::create(out, WriterOptions::default())?;
    let duration_s = trial.samples.last().map_or(0.0, |s| s.t_s) + 1.0;
    let mut run = BTreeMap::new();
    run.insert(
        "manifest".to_owned(),
        manifest(&trial.name, duration_s, variant, site),
    );
    run.insert("seed".to_owned(), "0".to_owned());
    run.insert("clock".to_owned(), "sim".to_owned());
    run.insert(
        "command_line".to_owned(),
        std::env::args().collect::<Vec<_>>().join(" "),
    );
    run.insert("origin_lat_deg".to_owned(), site.latitude_deg.to_string());
    run.insert("origin_lon_deg".to_owned(), site.longitude_deg.to_string());
    run.insert(
        "magnetic_declination_deg".to_owned(),
        site.declination_deg.to_string(),
    );
    w.metadata(nauta_log::META_RUN, run)?;
    let mut import = BTreeMap::new();
    import.insert("source".to_owned(), source.display().to_string());
    import.insert(
        "dataset".to_owned(),
        "BROAD (Laidig et al., Data 6(7):72, 2021, CC BY 4.0)".to_owned(),
    );
    import.insert("trial".to_owned(), trial.name.clone());
    import.insert(
        "sample_period_s".to_owned(),
        broad::SAMPLE_PERIOD_S.to_string(),
    );
    w.metadata("nauta.import", import)?;

    let (lat, lon) = (
        site.latitude_deg.to_radians(),
        site.longitude_deg.to_radians(),
    );
    let (mut imu_n, mut truth_n) = (0u64, 0u64);
    let mut previous_t = None;
    for s in &trial.samples {
        // Each sample covers the interval since the previous one (BROAD's
        // 3.5 ms; the first, one nominal period).
        let interval_s = match previous_t {
            Some(p) if s.t_s > p => s.t_s - p,
            Some(p) => anyhow::bail!(
                "{}: time goes from {p} s to {} s; it must increase",
                source.display(),
                s.t_s
            ),
            None => broad::SAMPLE_PERIOD_S,
        };
        previous_t = Some(s.t_s);
        let stamp_ns = ((s.t_s + broad::SAMPLE_PERIOD_S) * 1e9).round() as u64;
        // The log time of an import is the sample's own time.
        let log_ns = stamp_ns;
        if let Some(q_enu) = s.reference_enu {
            let q = broad::ned_from_enu(&q_enu);
            let truth = TruthState {
                header: Header::new(stamp_ns, truth_n, Role::Sensor, 0),
                lat_rad: lat,
                lon_rad: lon,
                quat_nb: Rotation::<Frd, Ned>::from_nalgebra(q).to_wxyz(),
                rate_nb_body_rad_s: s.gyro_rad_s.into(),
                ..Default::default()
            };
            w.write_message(TRUTH_SERVICE, log_ns, &truth)?;
            truth_n += 1;
        }
        let imu = ImuSample {
            header: Header::new(stamp_ns, imu_n, Role::Sensor, 0),
            gyro_rad_s: s.gyro_rad_s.into(),
            accel_m_s2: s.accel_m_s2.into(),
            mag_ut: s.mag_ut.into(),
            interval_s,
        };
        w.write_message(IMU_SERVICE, log_ns, &imu)?;
        imu_n += 1;
    }
    w.finish()?;
    Ok((imu_n, truth_n))
}

/// `nauta import broad FILE -o OUT.mcap`.
pub fn broad(args: &ImportBroadArgs) -> anyhow::Result<ExitCode> {
    anyhow::ensure!(
        ["gyro", "mekf", "pf"].contains(&args.variant.as_str()),
        "--variant must be gyro, mekf or pf, not {:?}",
        args.variant
    );
    let trial = broad::read_trial(&args.file)
        .with_context(|| format!("cannot import {}", args.file.display()))?;
    let site = ImportSite::from_args(args)?;
    let (imu, truth) = write_broad(&trial, &args.file, &args.output, &args.variant, &site)?;
    eprintln!(
        "nauta: {} → {}: {} IMU samples, {} reference attitudes ({:.1} s)",
        trial.name,
        args.output.display(),
        imu,
        truth,
        trial.samples.last().map_or(0.0, |s| s.t_s)
    );
    Ok(ExitCode::SUCCESS)
}
