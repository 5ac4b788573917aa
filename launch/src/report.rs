//! `nauta report` (work in progress).

use std::process::ExitCode;

/// Arguments of `nauta report`.
#[derive(Debug, clap::Args)]
pub struct ReportArgs {
    /// The recording.
    pub file: std::path::PathBuf,
}

/// Runs `nauta report`.
pub fn run(_args: &ReportArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("nauta report is not built yet")
}
