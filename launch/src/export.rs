//! `nauta export` (work in progress).

use std::process::ExitCode;

/// Arguments of `nauta export`.
#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// The recording.
    pub file: std::path::PathBuf,
}

/// Runs `nauta export`.
pub fn run(_args: &ExportArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("nauta export is not built yet")
}
