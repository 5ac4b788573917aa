//! `nauta-fake`: a service binary for the launcher's tests. `--describe`
//! prints the JSON in the environment variable `NAUTA_FAKE_DESCRIBE`;
//! `--check` accepts anything. Started for real it refuses to run, unless
//! `NAUTA_FAKE_RUN=exit-early`: then it joins the run as the described role,
//! subscribes to `sensor/imu`, reports ready, and exits 0 after its first
//! sample, long before the sensor ends its stream (an estimator that stops
//! by itself too early).

use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use nauta_messages::Role;
use nauta_runtime::process::{ProcessArgs, service_main};
use nauta_runtime::{Context, Describe, services};

#[derive(Debug, Parser)]
struct Args {
    #[command(flatten)]
    process: ProcessArgs,
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let describe = std::env::var("NAUTA_FAKE_DESCRIBE");
    if args.iter().any(|a| a == "--describe") {
        match describe {
            Ok(json) => {
                println!("{json}");
                ExitCode::SUCCESS
            }
            Err(_) => {
                eprintln!("nauta-fake: set NAUTA_FAKE_DESCRIBE to the JSON to describe");
                ExitCode::FAILURE
            }
        }
    } else if args.iter().any(|a| a == "--check") {
        ExitCode::SUCCESS
    } else if std::env::var("NAUTA_FAKE_RUN").as_deref() == Ok("exit-early") {
        let role = describe
            .ok()
            .and_then(|j| serde_json::from_str::<Describe>(&j).ok())
            .and_then(|d| Role::from_name(&d.role))
            .unwrap_or(Role::Attitude);
        let args = Args::parse();
        service_main(
            role,
            "fake",
            &args.process,
            // Not called: `--describe` is answered above.
            || Describe {
                role: role.name().to_owned(),
                inputs: Vec::new(),
                outputs: Vec::new(),
                variants: vec!["fake".into()],
                source: false,
            },
            exit_early,
        )
    } else {
        eprintln!("nauta-fake: describes itself only");
        ExitCode::FAILURE
    }
}

/// Opens its health port, waits for the first IMU sample, then returns
/// (exit 0).
fn exit_early(ctx: &mut Context) -> anyhow::Result<()> {
    // The launcher taps every role's health.
    let _health = ctx.publisher(&services::health(ctx.role))?;
    let (mut imu, inbox) = ctx.subscriber(&services::imu())?;
    if !ctx.connect_and_ready(&[&imu])? {
        return Ok(());
    }
    loop {
        if imu.receive()?.is_some() {
            eprintln!("nauta-fake: first sample received; exiting 0 before the end of the stream");
            return Ok(());
        }
        inbox.wait(Duration::from_millis(10));
        if ctx.termination_requested() {
            return Ok(());
        }
    }
}
