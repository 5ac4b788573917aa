//! The binary contract of DESIGN §5: how the launcher starts a service binary.
//!
//! `nauta-<role> --manifest FILE --process NAME --namespace NS --instance K
//! [--variant V] [--standby]`, or `nauta-<role> --describe`.

use std::path::PathBuf;
use std::process::ExitCode;

use nauta_messages::Role;

use crate::{Context, Describe};

/// Arguments every service binary accepts (flatten into the binary's own parser).
#[derive(Debug, Clone, clap::Args)]
pub struct ProcessArgs {
    /// The (effective) manifest of the run; the process reads its parameters from it.
    #[arg(long, required_unless_present = "describe")]
    pub manifest: Option<PathBuf>,
    /// This process's name in the manifest (defaults to the role's name).
    #[arg(long)]
    pub process: Option<String>,
    /// The run's namespace.
    #[arg(long, required_unless_present = "describe")]
    pub namespace: Option<String>,
    /// How many times the launcher has started this role in this run.
    #[arg(long, default_value_t = 0)]
    pub instance: u32,
    /// The implementation to run (overrides the manifest's `variant`).
    #[arg(long)]
    pub variant: Option<String>,
    /// Start in standby: follow the inputs without publishing (hot swap).
    #[arg(long)]
    pub standby: bool,
    /// Print the input and output services and types as JSON and exit.
    #[arg(long)]
    pub describe: bool,
}

/// Installs the tracing subscriber every nauta binary uses: compact lines on
/// stderr, level from `NAUTA_LOG` (default `info`).
pub fn init_tracing() {
    let filter = tracing_subscriber::EnvFilter::try_from_env("NAUTA_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .compact()
        .try_init();
    // iceoryx2 logs on its own; keep it to real problems.
    iceoryx2::prelude::set_log_level(iceoryx2::prelude::LogLevel::Error);
}

/// The `main` of every service binary: with `--describe`, prints `describe()`;
/// otherwise joins the run ([`Context::from_args`]), runs `serve`, leaves the
/// run ([`Context::finish`], once every port `serve` opened is closed) and turns
/// the outcome into the exit code, logging an error once.
pub fn service_main(
    role: Role,
    default_variant: &str,
    args: &ProcessArgs,
    describe: impl FnOnce() -> Describe,
    serve: impl FnOnce(&mut Context) -> anyhow::Result<()>,
) -> ExitCode {
    init_tracing();
    let result = if args.describe {
        describe().print()
    } else {
        Context::from_args(role, args, default_variant).and_then(|mut ctx| {
            let result = serve(&mut ctx);
            ctx.finish();
            result
        })
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tracing::error!("{e:#}");
            ExitCode::FAILURE
        }
    }
}
