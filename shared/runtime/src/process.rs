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
    #[arg(long, required_unless_present_any = ["describe", "check"])]
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
    /// Warm start: the role's latest snapshot message (its bincode encoding,
    /// as the launcher kept it), to initialise from instead of from scratch.
    #[arg(long, value_name = "FILE")]
    pub snapshot: Option<PathBuf>,
    /// Publish nothing stamped at or before this (the previous instance
    /// already did): a restarted estimator replays from its snapshot without
    /// duplicating outputs.
    #[arg(long, value_name = "STAMP_NS")]
    pub resume_after: Option<u64>,
    /// An optional input (see `--describe`) that no process of the run
    /// publishes: not subscribed to and never waited for. The launcher passes
    /// one for each; without it the process waits for that input's publisher.
    #[arg(long, value_name = "SERVICE")]
    pub absent: Vec<String>,
    /// Print the input and output services and types as JSON and exit.
    #[arg(long)]
    pub describe: bool,
    /// Check this process's parameters in the manifest and exit (0: valid);
    /// `nauta check` and `nauta launch` run it before starting anything.
    #[arg(long, conflicts_with = "describe")]
    pub check: bool,
}

/// Installs the tracing subscriber every nauta binary uses: compact lines on
/// stderr, level from `NAUTA_LOG` (default `info`), coloured only when stderr
/// is a terminal and `NO_COLOR` is unset or empty (see [`log_colour`]).
pub fn init_tracing() {
    let filter = tracing_subscriber::EnvFilter::try_from_env("NAUTA_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    let colour = log_colour(
        std::io::IsTerminal::is_terminal(&std::io::stderr()),
        std::env::var_os("NO_COLOR").as_deref(),
    );
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(colour)
        .with_target(false)
        .compact()
        .try_init();
    // iceoryx2 logs on its own; keep it to real problems.
    iceoryx2::prelude::set_log_level(iceoryx2::prelude::LogLevel::Error);
}

/// Whether log lines carry ANSI colour codes: only on a terminal (a pipe or a
/// file, such as a CI log or `2> run.log`, gets plain text), and never when
/// `NO_COLOR` is set to a non-empty value (<https://no-color.org>).
pub fn log_colour(stderr_is_terminal: bool, no_color: Option<&std::ffi::OsStr>) -> bool {
    stderr_is_terminal && no_color.is_none_or(|v| v.is_empty())
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
    service_main_checked(
        role,
        default_variant,
        args,
        describe,
        |_: &CheckTarget| Ok(()),
        serve,
    )
}

/// What `--check` checks: the manifest, this process's name and its variant.
#[derive(Debug)]
pub struct CheckTarget {
    /// The manifest (loaded and checked).
    pub manifest: crate::Manifest,
    /// This process's name in it.
    pub process: String,
    /// The variant that would run.
    pub variant: String,
}

impl CheckTarget {
    /// This process's parameters for its variant (see [`crate::Manifest::params`]).
    pub fn params<T: serde::de::DeserializeOwned>(&self) -> anyhow::Result<T> {
        self.manifest.params(&self.process, Some(&self.variant))
    }
}

/// [`service_main`] with a parameter check for `--check`: `check` validates
/// what `serve` would read from the manifest, without opening any port.
pub fn service_main_checked(
    role: Role,
    default_variant: &str,
    args: &ProcessArgs,
    describe: impl FnOnce() -> Describe,
    check: impl FnOnce(&CheckTarget) -> anyhow::Result<()>,
    serve: impl FnOnce(&mut Context) -> anyhow::Result<()>,
) -> ExitCode {
    init_tracing();
    if args.check {
        let target = args
            .manifest
            .as_deref()
            .ok_or_else(|| anyhow::anyhow!("--check needs --manifest"))
            .and_then(crate::Manifest::load)
            .map(|manifest| {
                let process = args
                    .process
                    .clone()
                    .unwrap_or_else(|| role.name().to_owned());
                let variant = args
                    .variant
                    .clone()
                    .or_else(|| {
                        manifest
                            .processes
                            .get(&process)
                            .and_then(|p| p.variant.clone())
                    })
                    .unwrap_or_else(|| default_variant.to_owned());
                CheckTarget {
                    manifest,
                    process,
                    variant,
                }
            });
        return match target.and_then(|t| check(&t)) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                // One plain line for the launcher to quote.
                eprintln!("{e:#}");
                ExitCode::FAILURE
            }
        };
    }
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

#[cfg(test)]
mod tests {
    use super::log_colour;
    use std::ffi::OsStr;

    #[test]
    fn colour_only_on_a_terminal_without_no_color() {
        assert!(log_colour(true, None));
        assert!(!log_colour(false, None), "a pipe or a file gets no colour");
        assert!(!log_colour(true, Some(OsStr::new("1"))));
        assert!(!log_colour(false, Some(OsStr::new("1"))));
        // no-color.org: an empty NO_COLOR does not disable colour.
        assert!(log_colour(true, Some(OsStr::new(""))));
    }
}
