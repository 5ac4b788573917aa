//! `nauta bench ...`: benchmarks that print figures (JSON with `--json`).

pub mod attitude;
pub mod chaos;
pub mod ipc;
pub mod log;
pub mod sim;
