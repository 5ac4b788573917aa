//! `nauta-positioning`: the positioning role (DESIGN §2; paper 000
//! §III-B-2). Wiring only: the estimator is [`Positioning`] (in
//! `nauta-estimation`: `pf`, the paper's buoy time-of-flight particle
//! filter; `ekf`, a range-only EKF), its lifecycle the runtime's estimator
//! shell.
//!
//! Inputs (ties at one stamp are taken in this order): `ains/nav` (an
//! aiding input: its velocity moves the filter, it never makes it
//! publish, so the cycle ains ↔ positioning waits on neither side), then
//! the sensor's depth, GPS and modem, which trigger `positioning/fix`: one
//! per buoy message and per GPS fix at the surface, and one with the depth
//! reading that ends a silence, so the role's watermark moves with the
//! sensor's.

use std::process::ExitCode;

use anyhow::Context as _;
use clap::Parser;
use nauta_estimation::positioning::{Positioning, PositioningInput, VARIANTS};
use nauta_messages::{PositionFix, PositioningSnapshot, Role};
use nauta_runtime::process::ProcessArgs;
use nauta_runtime::{Manifest, Shell, services};

/// Positions the vehicle from the buoy's acoustic broadcasts.
#[derive(Debug, Parser)]
#[command(name = "nauta-positioning", version, about)]
struct Args {
    #[command(flatten)]
    process: ProcessArgs,
}

fn main() -> ExitCode {
    let args = Args::parse();
    Shell::<Positioning>::new(Role::Positioning, &VARIANTS)
        .aiding(services::nav_solution(), Role::Ains, PositioningInput::Nav)
        .input(services::depth(), Role::Sensor, PositioningInput::Depth)
        .input(services::gps(), Role::Sensor, PositioningInput::Gps)
        .input(services::modem(), Role::Sensor, PositioningInput::Modem)
        .output(services::position_fix(), |f| Some(PositionFix::from(f)))
        .snapshot(
            services::snapshot(Role::Positioning),
            PositioningSnapshot::of_saved,
            PositioningSnapshot::saved,
        )
        .main(&args.process, core_for)
}

/// The core of `variant` with its parameters from the manifest.
fn core_for(manifest: &Manifest, process: &str, variant: &str) -> anyhow::Result<Positioning> {
    // The shell refuses a variant not in VARIANTS.
    let core = match variant {
        "ekf" => Positioning::ekf(&manifest.params(process, Some(variant))?),
        _ => Positioning::pf(&manifest.params(process, Some(variant))?),
    };
    core.with_context(|| format!("{}: process.{process}", manifest.path.display()))
}
