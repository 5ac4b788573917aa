//! `nauta-lbl`: the LBL role (DESIGN §2; paper 003 §V). Wiring only: the
//! estimator is [`Lbl`] (in `nauta-estimation`: `ekf`, paper 003's EKF of
//! position and current from transponder ranges and propeller dead
//! reckoning), its lifecycle the runtime's estimator shell.
//!
//! Inputs (ties at one stamp are taken in this order, the AHRS first so that
//! the 10 Hz step at a grid point is taken before anything else of its
//! stamp): the sensor's AHRS, depth, propeller, DVL (used with
//! `velocity_source = "dvl"`), LBL replies and GPS. Outputs: `lbl/nav` at
//! every step (10 Hz) and `lbl/interrogate`, stamped at the step it is
//! decided (the sensor's lock step: the interrogator pings at its "now").
//! The transponders, the sound speed, the declination and the local origin
//! are the manifest's `[site]`.

use std::process::ExitCode;

use clap::Parser;
use nauta_estimation::lbl::{Lbl, LblInput, LblOutput, VARIANTS};
use nauta_messages::{LblInterrogation, LblSnapshot, LblSolution, Role};
use nauta_runtime::process::ProcessArgs;
use nauta_runtime::{Manifest, Shell, services};

/// Navigates by ranges to long-baseline transponders.
#[derive(Debug, Parser)]
#[command(name = "nauta-lbl", version, about)]
struct Args {
    #[command(flatten)]
    process: ProcessArgs,
}

fn main() -> ExitCode {
    let args = Args::parse();
    Shell::<Lbl>::new(Role::Lbl, &VARIANTS)
        .input(services::ahrs(), Role::Sensor, LblInput::Ahrs)
        .input(services::depth(), Role::Sensor, LblInput::Depth)
        .input(services::propeller(), Role::Sensor, LblInput::Propeller)
        .input(services::dvl(), Role::Sensor, LblInput::Dvl)
        .input(services::lbl_reply(), Role::Sensor, LblInput::Reply)
        .input(services::gps(), Role::Sensor, LblInput::Gps)
        .output(services::lbl_solution(), |o| match o {
            LblOutput::Nav(n) => Some(LblSolution::from(n)),
            LblOutput::Ping(_) => None,
        })
        .output(services::lbl_interrogate(), |o| match o {
            LblOutput::Ping(p) => Some(LblInterrogation::from(p)),
            LblOutput::Nav(_) => None,
        })
        .snapshot(
            services::snapshot(Role::Lbl),
            LblSnapshot::of_saved,
            LblSnapshot::saved,
        )
        .main(&args.process, core_for)
}

/// The core with its parameters from the manifest and its site
/// ([`Manifest::lbl_core`], as `nauta smooth` builds it); the site's
/// declination logged first.
fn core_for(manifest: &Manifest, process: &str, variant: &str) -> anyhow::Result<Lbl> {
    if let Some(site) = &manifest.site {
        site.log_declination();
    }
    manifest.lbl_core(process, variant)
}
