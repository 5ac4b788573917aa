//! `nauta bench ipc` (being written).

/// Runs the benchmark.
pub fn run(_json: bool) -> anyhow::Result<()> {
    anyhow::bail!("not built yet")
}

/// The peer side.
pub fn peer(_args: &[String]) -> anyhow::Result<()> {
    anyhow::bail!("not built yet")
}
