//! `nauta-ains`: the aided INS role (DESIGN §2). Wiring only: the estimator is
//! [`AinsCore`] (in `nauta-estimation`: `pf`, paper 000 §III-A's particle
//! filters; `dr`, paper 002's dead reckoning; `ekf`, an error-state Kalman
//! filter), its lifecycle the runtime's estimator shell.
//!
//! Inputs (ties at one stamp are taken in this order): IMU, DVL, depth, GPS,
//! AHRS from the sensor, then `attitude/estimate` and `positioning/fix`, both
//! optional (a run without an attitude or a positioning process runs without
//! them: the launcher passes `--absent`). The IMU (`pf`, `ekf`: one solution
//! per sample), the DVL and the AHRS (`dr`) trigger outputs (`ains/nav`), so
//! the role's watermark follows the earliest of the three whatever the
//! variant; the others only correct the state.

use std::process::ExitCode;

use anyhow::Context as _;
use clap::Parser;
use nauta_estimation::ains::dr::Site;
use nauta_estimation::ains::{AinsCore, AinsInput, AinsParams, VARIANTS, advisory};
use nauta_messages::{AinsSnapshot, NavSolution, Role, event_kind};
use nauta_runtime::process::ProcessArgs;
use nauta_runtime::{Manifest, Shell, services};

/// Navigates the vehicle: position and velocity from the aiding sensors.
#[derive(Debug, Parser)]
#[command(name = "nauta-ains", version, about)]
struct Args {
    #[command(flatten)]
    process: ProcessArgs,
}

fn main() -> ExitCode {
    let args = Args::parse();
    Shell::<AinsCore>::new(Role::Ains, &VARIANTS)
        .input(services::imu(), Role::Sensor, AinsInput::Imu)
        .input(services::dvl(), Role::Sensor, AinsInput::Dvl)
        .aiding(services::depth(), Role::Sensor, AinsInput::Depth)
        .aiding(services::gps(), Role::Sensor, AinsInput::Gps)
        .input(services::ahrs(), Role::Sensor, AinsInput::Ahrs)
        .optional_aiding(
            services::attitude_estimate(),
            Role::Attitude,
            AinsInput::Attitude,
        )
        .optional_aiding(services::position_fix(), Role::Positioning, AinsInput::Fix)
        .output(services::nav_solution(), |n| Some(NavSolution::from(n)))
        .advisory(event_kind::SURFACING_ADVISED, "surfacing", |n| {
            n.advisory & advisory::SURFACE != 0
        })
        .snapshot(
            services::snapshot(Role::Ains),
            AinsSnapshot::of_state,
            AinsSnapshot::state,
        )
        .main(&args.process, core_for)
}

/// The core of `variant` with its parameters from the manifest and the
/// site's position and declination.
fn core_for(manifest: &Manifest, process: &str, variant: &str) -> anyhow::Result<AinsCore> {
    // The shell refuses a variant not in VARIANTS.
    let params = match variant {
        "dr" => AinsParams::Dr(manifest.params(process, Some(variant))?),
        "ekf" => AinsParams::Ekf(manifest.params(process, Some(variant))?),
        _ => AinsParams::Pf(manifest.params(process, Some(variant))?),
    };
    let site = manifest.site.clone().with_context(|| {
        format!(
            "{}: the manifest has no [site]: the aided INS needs the position and declination",
            manifest.path.display()
        )
    })?;
    site.log_declination();
    let site = Site {
        lat_rad: site.latitude_deg.to_radians(),
        lon_rad: site.longitude_deg.to_radians(),
        declination_rad: site.magnetic_declination_deg.to_radians(),
    };
    AinsCore::new(&params, site)
        .with_context(|| format!("{}: process.{process}", manifest.path.display()))
}
