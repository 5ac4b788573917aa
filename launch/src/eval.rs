//! `nauta eval` (work in progress).

use std::process::ExitCode;

/// Arguments of `nauta eval`.
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// The recording.
    pub file: std::path::PathBuf,
}

/// Runs `nauta eval`.
pub fn run(_args: &EvalArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("nauta eval is not built yet")
}
