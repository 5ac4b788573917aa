//! `nauta bench pacing`: how closely a `wall` clock run follows real time (or
//! a multiple of it). It runs the survey with `--clock wall --duration S` at
//! each `--rate` (by default 1 and 10, the runs `tests/tests/scenarios.rs`
//! makes) and reads each launcher's JSON summary: the wall time from the
//! first to the last sensor sample as the launcher received them, against
//! the expected `simulated span / rate`. The sensor paces every step to an
//! absolute target (docs/design-notes.md, "Wall clock"), so the error does
//! not grow with the duration; what moves it is the machine's load. A wall
//! span is a benchmark figure, never a test assertion.

use std::path::PathBuf;
use std::process::{Command, Stdio};

use anyhow::Context as _;
use serde_json::json;

/// Options of `nauta bench pacing`.
#[derive(Debug, Clone, clap::Args)]
pub struct PacingArgs {
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// The manifest to run.
    #[arg(long, default_value = "launch/survey.toml")]
    pub manifest: PathBuf,
    /// Mission seconds of each run.
    #[arg(long, default_value_t = 30.0)]
    pub duration: f64,
    /// Multiples of real time to run at, one run each (default: 1 and 10).
    #[arg(long = "rate")]
    pub rates: Vec<f64>,
}

/// The tolerance the old scenario test asserted, s: ±0.5 s at real time,
/// ±0.05 s at 10x: 0.5 s divided by the rate.
fn target_s(rate: f64) -> f64 {
    0.5 / rate
}

/// One paced run: (simulated span, wall span), s.
fn run_one(a: &PacingArgs, rate: f64) -> anyhow::Result<(f64, f64)> {
    let exe = std::env::current_exe()?;
    let out = Command::new(exe)
        .args([
            "launch".into(),
            a.manifest.display().to_string(),
            "--json".into(),
            "--clock".into(),
            "wall".into(),
            "--rate".into(),
            format!("{rate:?}"),
            "--duration".into(),
            format!("{:?}", a.duration),
        ])
        .stdin(Stdio::null())
        .stderr(Stdio::null())
        .output()
        .context("cannot run nauta launch")?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let summary = super::summary(&stdout).with_context(|| format!("the run at rate {rate}"))?;
    anyhow::ensure!(
        out.status.success() && summary["exit"] == "ok",
        "the run at rate {rate} failed ({}): {summary:#}",
        out.status
    );
    let span = &summary["sensor_span"];
    let num = |k: &str| {
        span[k]
            .as_f64()
            .with_context(|| format!("no sensor_span.{k} in the summary: {summary:#}"))
    };
    Ok((num("simulated_s")?, num("wall_s")?))
}

/// Runs the benchmark.
pub fn run(a: &PacingArgs) -> anyhow::Result<()> {
    let rates = if a.rates.is_empty() {
        vec![1.0, 10.0]
    } else {
        a.rates.clone()
    };
    for r in &rates {
        anyhow::ensure!(
            r.is_finite() && *r > 0.0,
            "--rate must be a positive number, got {r}"
        );
    }
    anyhow::ensure!(
        a.duration.is_finite() && a.duration > 0.0,
        "--duration must be a positive number of seconds, got {}",
        a.duration
    );
    let mut runs = Vec::new();
    for &rate in &rates {
        if !a.json {
            eprintln!(
                "nauta bench pacing: {} s of mission at {rate}x real time",
                a.duration
            );
        }
        let (sim, wall) = run_one(a, rate)?;
        let expected = sim / rate;
        runs.push(json!({
            "rate": rate,
            "simulated_span_s": sim,
            "wall_span_s": wall,
            "expected_wall_s": expected,
            "error_s": wall - expected,
            "error_pct": 100.0 * (wall - expected) / expected,
            "target_s": target_s(rate),
            "within_target": (wall - expected).abs() <= target_s(rate),
        }));
    }
    if a.json {
        println!("{}", json!({ "duration_s": a.duration, "runs": runs }));
        return Ok(());
    }
    println!(
        "{:>6} {:>12} {:>12} {:>12} {:>10} {:>9} {:>10}",
        "rate", "simulated s", "expected s", "wall s", "error ms", "error %", "target ms"
    );
    for r in &runs {
        let f = |k: &str| r[k].as_f64().unwrap_or(f64::NAN);
        println!(
            "{:>6} {:>12.3} {:>12.3} {:>12.3} {:>10.1} {:>9.3} {:>10.0}",
            f("rate"),
            f("simulated_span_s"),
            f("expected_wall_s"),
            f("wall_span_s"),
            f("error_s") * 1e3,
            f("error_pct"),
            f("target_s") * 1e3
        );
    }
    Ok(())
}
