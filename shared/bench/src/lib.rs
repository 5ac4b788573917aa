//! `nauta bench ...` as a library: benchmarks that print figures (JSON with
//! `--json`). The `nauta` binary dispatches to them.

pub mod attitude;
pub mod chaos;
pub mod ipc;
pub mod lbl;
pub mod log;
pub mod nav;
pub mod pacing;
pub mod sim;
pub mod smooth;

use anyhow::Context as _;

/// The run summary a `nauta launch --json` printed: its stdout, one JSON object.
pub fn summary(stdout: &str) -> anyhow::Result<serde_json::Value> {
    let v: serde_json::Value = serde_json::from_str(stdout.trim())
        .with_context(|| format!("the launcher did not print one JSON summary: {stdout:?}"))?;
    anyhow::ensure!(
        v.is_object(),
        "the launcher's summary is not a JSON object: {v}"
    );
    Ok(v)
}
