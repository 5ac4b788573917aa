//! `nauta calibrate magnetometer`: paper 000 §IV-A's magnetometer calibration
//! (hard and soft iron), printed as the attitude parameters that apply it.
//!
//! - `MANIFEST`: the run's simulated magnetometer (the sensor section's
//!   preset with its `sensors` overrides, as the sensor process builds it),
//!   turned through 2,000 random attitudes in the site's World Magnetic Model
//!   field (the calibration manoeuvre an operator does on deck, seeded), fitted
//!   with the default method (least squares; `--method pso` for the swarm).
//! - `--from FILE.mcap --field-ut F`: the magnetometer samples of a recording
//!   (`sensor/imu`) of a calibration manoeuvre, fitted to the local field's
//!   norm F (µT).
//!
//! Prints the norm spread before and after (the figure of merit) on stderr and
//! the TOML table for `[process.attitude.params]` on stdout.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use nalgebra::Vector3;
use nauta_estimation::calibration::{self, MagCalibration, MagFitMethod, NormSpread, PsoParams};
use nauta_messages::{IMU_SERVICE, ImuSample, codec};
use nauta_runtime::Manifest;
use nauta_sim::mission::Origin;
use nauta_sim::params::SensorParams;

/// Arguments of `nauta calibrate magnetometer`.
#[derive(Debug, clap::Args)]
pub struct MagnetometerArgs {
    /// A manifest: calibrate its simulated magnetometer at its site.
    #[arg(required_unless_present = "from", conflicts_with = "from")]
    pub manifest: Option<PathBuf>,
    /// The sensor process of the manifest (default: the one running nauta-sensor).
    #[arg(long)]
    pub process: Option<String>,
    /// A recording of a calibration manoeuvre: fit its `sensor/imu` field samples.
    #[arg(long, value_name = "FILE", requires = "field_ut")]
    pub from: Option<PathBuf>,
    /// With `--from`: the local field's norm, µT (e.g. from the World Magnetic Model).
    #[arg(long, value_name = "MICROTESLA")]
    pub field_ut: Option<f64>,
    /// `least-squares` (closed-form ellipsoid fit, the default) or `pso`
    /// (paper 000's particle swarm).
    #[arg(long, default_value = "least-squares")]
    pub method: String,
    /// Seed of the simulated manoeuvre and of the swarm.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
}

fn simulated(
    args: &MagnetometerArgs,
    path: &std::path::Path,
) -> anyhow::Result<(Vec<Vector3<f64>>, f64)> {
    let manifest = Manifest::load(path)?;
    let name = match &args.process {
        Some(p) => p.clone(),
        None => manifest
            .processes
            .iter()
            .find(|(_, p)| p.bin == "nauta-sensor")
            .map(|(n, _)| n.clone())
            .with_context(|| format!("{}: no nauta-sensor process", path.display()))?,
    };
    let section = manifest.process(&name)?;
    let table: toml::Table = manifest.params(&name, section.variant.as_deref())?;
    let place = format!("{}: process.{name}.params", path.display());
    let params = SensorParams::from_table(table, &place)?;
    let site = manifest
        .site
        .clone()
        .with_context(|| format!("{}: no [site]", path.display()))?;
    let origin = Origin::from_degrees(site.latitude_deg, site.longitude_deg);
    let env = params
        .scenario
        .environment(origin)
        .map_err(|e| anyhow::anyhow!("{place}: {e}"))?;
    let field = env.magnetic.ned_t;
    let samples =
        nauta_sim::manoeuvre::magnetometer_manoeuvre(params.sensors.imu.mag, &field, args.seed)?;
    Ok((samples, field.norm() * 1e6))
}

fn recorded(path: &std::path::Path, field_ut: f64) -> anyhow::Result<(Vec<Vector3<f64>>, f64)> {
    anyhow::ensure!(
        field_ut.is_finite() && field_ut > 0.0,
        "--field-ut must be a positive number of µT, got {field_ut}"
    );
    let mut samples = Vec::new();
    let mut bad = 0u64;
    let rec = nauta_log::read(path, |ch, m| {
        if ch.topic == IMU_SERVICE {
            match codec::decode::<ImuSample>(m.data) {
                Ok(s) if s.mag_ut.iter().all(|v| v.is_finite()) => {
                    samples.push(Vector3::from(s.mag_ut))
                }
                _ => bad += 1,
            }
        }
        Ok(())
    })?;
    if rec.recovery.truncated {
        eprintln!(
            "nauta: {} was cut short; using its complete part",
            path.display()
        );
    }
    if bad > 0 {
        eprintln!("nauta: {bad} IMU samples skipped (undecodable or not finite)");
    }
    anyhow::ensure!(
        !samples.is_empty(),
        "{} has no {IMU_SERVICE} samples",
        path.display()
    );
    Ok((samples, field_ut))
}

/// `nauta calibrate magnetometer`.
pub fn magnetometer(args: &MagnetometerArgs) -> anyhow::Result<ExitCode> {
    let method = match args.method.as_str() {
        "least-squares" => MagFitMethod::LeastSquares,
        "pso" => MagFitMethod::Pso,
        other => anyhow::bail!("--method must be least-squares or pso, not {other:?}"),
    };
    let (samples, norm_ut, source) = match (&args.manifest, &args.from) {
        (_, Some(file)) => {
            let (s, n) = recorded(file, args.field_ut.unwrap_or(f64::NAN))?;
            (s, n, file.display().to_string())
        }
        (Some(m), None) => {
            let (s, n) = simulated(args, m)?;
            (
                s,
                n,
                format!("{} (simulated manoeuvre, seed {})", m.display(), args.seed),
            )
        }
        (None, None) => anyhow::bail!("give a manifest or --from FILE"),
    };
    let cal = calibration::fit(&samples, norm_ut, method, &PsoParams::default(), args.seed)
        .map_err(|e| anyhow::anyhow!("the fit failed: {e}"))?;
    let before = NormSpread::of(&samples, &MagCalibration::identity()).context("no samples")?;
    let after = NormSpread::of(&samples, &cal).context("no samples")?;
    eprintln!(
        "nauta: magnetometer calibration from {source}: {} samples, field {norm_ut:.2} µT; norm spread (1σ) {:.3} µT before, {:.3} µT after ({:.0}x)",
        samples.len(),
        before.std_ut,
        after.std_ut,
        before.std_ut / after.std_ut
    );
    let h = cal.hard_iron_ut;
    let w = cal.soft_iron_inv;
    let row = |r: usize| format!("[{:.6}, {:.6}, {:.6}]", w[(r, 0)], w[(r, 1)], w[(r, 2)]);
    println!("# nauta calibrate magnetometer: {source}");
    println!(
        "# norm spread {:.3} µT -> {:.3} µT; put under [process.attitude.params]",
        before.std_ut, after.std_ut
    );
    println!(
        "magnetometer = {{ hard_iron_ut = [{:.4}, {:.4}, {:.4}], soft_iron_inv = [{}, {}, {}] }}",
        h.x,
        h.y,
        h.z,
        row(0),
        row(1),
        row(2)
    );
    Ok(ExitCode::SUCCESS)
}
