//! `nauta bench log` (work in progress).

/// Runs the benchmark.
pub fn run(_json: bool) -> anyhow::Result<()> {
    anyhow::bail!("nauta bench log is not built yet")
}
