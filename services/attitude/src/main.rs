//! `nauta-attitude`: the attitude role. Wiring only: the estimator is
//! [`AttitudeCore`] (alignment, then the `pf`, `gyro` or `mekf` variant, in
//! `nauta-estimation`), and its lifecycle is the runtime's estimator shell.

use std::process::ExitCode;

use anyhow::Context as _;
use clap::Parser;
use nauta_estimation::attitude_core::{AttitudeCore, VARIANTS, VariantParams};
use nauta_messages::{AttitudeEstimate, AttitudeSnapshot, Role};
use nauta_runtime::process::ProcessArgs;
use nauta_runtime::{Manifest, Shell, services};

/// Estimates the vehicle's attitude from the IMU.
#[derive(Debug, Parser)]
#[command(name = "nauta-attitude", version, about)]
struct Args {
    #[command(flatten)]
    process: ProcessArgs,
}

fn main() -> ExitCode {
    let args = Args::parse();
    Shell::<AttitudeCore>::new(Role::Attitude, &VARIANTS)
        .input(services::imu(), Role::Sensor, std::convert::identity)
        .output(services::attitude_estimate(), |r| {
            Some(AttitudeEstimate::from(r))
        })
        .snapshot(
            services::snapshot(Role::Attitude),
            AttitudeSnapshot::of_state,
            AttitudeSnapshot::state,
        )
        .main(&args.process, core_for)
}

/// The core of `variant` with its parameters from the manifest and the
/// site's latitude and declination.
fn core_for(manifest: &Manifest, process: &str, variant: &str) -> anyhow::Result<AttitudeCore> {
    let params = match variant {
        "mekf" => VariantParams::Mekf(manifest.params(process, Some(variant))?),
        "pf" => VariantParams::Pf(manifest.params(process, Some(variant))?),
        _ => VariantParams::Gyro(manifest.params(process, Some(variant))?),
    };
    let site = manifest.site.clone().with_context(|| {
        format!(
            "{}: the manifest has no [site]: the attitude needs the latitude and declination",
            manifest.path.display()
        )
    })?;
    site.log_declination();
    AttitudeCore::new(
        &params,
        site.latitude_deg.to_radians(),
        site.magnetic_declination_deg.to_radians(),
    )
    .with_context(|| format!("{}: process.{process}", manifest.path.display()))
}
