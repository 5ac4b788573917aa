//! `nauta eval FILE [--json]`: the accuracy of every estimate stream of a
//! recording, against the simulator's truth when the file has it, else
//! against the surface GPS fixes (DESIGN §9; the README's "Evaluating a
//! recording" lists every JSON key).
//!
//! - [`data`]: the recording read through `nauta_log`'s checked values and
//!   run metadata ([`nauta_log::streams`], [`nauta_log::run`]) into sorted
//!   samples;
//! - [`compute`]: matching, per-sample errors and the metrics;
//! - [`live`]: the same evaluation of a running pipeline (`nauta launch`'s summary).
//!
//! `nauta report` shows the same [`Evaluation`], so its table and plots are
//! the figures `nauta eval` prints.

pub mod compute;
pub mod data;
pub mod dives;
pub mod live;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use serde::Serialize;

pub use compute::{ErrorSample, Metrics, Reference};
pub use data::Data;

/// Arguments of `nauta eval`.
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// The recording (MCAP).
    pub file: PathBuf,
    /// Print one JSON object (`{"file", "reference", "streams": {"ains/nav":
    /// {"north_rms_m", ...}, ...}}`; keys in the README) instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// The evaluation of a recording (what `--json` prints).
#[derive(Debug, Clone, Serialize)]
pub struct Evaluation {
    /// The file, as given.
    pub file: String,
    /// What the estimates were compared with.
    pub reference: Reference,
    /// Metrics per estimate stream, by topic.
    pub streams: BTreeMap<String, Metrics>,
    /// Estimate streams present but not evaluated, with the reason.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub skipped: BTreeMap<String, String>,
    /// Per-sample errors of each evaluated stream, by stamp (for `nauta report`).
    #[serde(skip)]
    pub series: BTreeMap<String, Vec<ErrorSample>>,
}

/// Evaluates the streams of `data` (read from `file`).
pub fn evaluate(file: &Path, data: &Data) -> anyhow::Result<Evaluation> {
    anyhow::ensure!(
        !data.streams.is_empty(),
        "{} has no estimate stream (attitude/estimate, ains/nav, positioning/fix, lbl/nav or a smoothed track of those types): nothing to evaluate",
        file.display()
    );
    let reference = if !data.truth.is_empty() {
        Reference::Truth
    } else if !data.gps.is_empty() {
        Reference::Gps
    } else {
        anyhow::bail!(
            "{} has no reference to evaluate against: neither sim/truth nor sensor/gps fixes",
            file.display()
        );
    };
    let frame = compute::local_frame(data);
    let mut eval = Evaluation {
        file: file.display().to_string(),
        reference,
        streams: BTreeMap::new(),
        skipped: BTreeMap::new(),
        series: BTreeMap::new(),
    };
    for (topic, stream) in &data.streams {
        let local = stream
            .samples
            .iter()
            .any(|s| matches!(s.pos, Some(data::Horizontal::Local { .. })));
        let frame = match (&frame, local) {
            (Ok(f), _) => Some(*f),
            (Err(why), true) => {
                eval.skipped.insert(
                    topic.clone(),
                    format!("local north/east positions, and {why}"),
                );
                continue;
            }
            (Err(_), false) => None,
        };
        let (errors, unmatched) = match reference {
            Reference::Truth => compute::errors_against_truth(stream, &data.truth, frame),
            Reference::Gps if !stream.kind.has_position() => {
                eval.skipped.insert(
                    topic.clone(),
                    "attitude only, and GPS fixes give no attitude reference".to_owned(),
                );
                continue;
            }
            Reference::Gps => compute::errors_against_gps(stream, &data.gps, frame),
        };
        let mut metrics = compute::metrics(&errors, unmatched, stream.rejected);
        if reference == Reference::Truth && stream.kind.has_position() {
            let predicted = |t: u64| {
                let i = stream.samples.partition_point(|s| s.stamp_ns < t);
                stream.samples.get(i).and_then(|s| s.predicted_drift_m)
            };
            let d = dives::dives(&errors, &data.gps, predicted);
            if !d.is_empty() {
                let mean =
                    |v: Vec<f64>| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
                metrics.dive_error_pct = mean(d.iter().filter_map(|d| d.error_pct).collect());
                metrics.dive_drift_m_per_km = mean(
                    d.iter()
                        .filter(|d| d.error_pct.is_some())
                        .map(|d| d.error_m / (d.distance_m / 1000.0))
                        .collect(),
                );
                metrics.drift_slope_m_per_km = dives::drift_slope(&errors, &d);
                metrics.dives = Some(d);
            }
        }
        eval.streams.insert(topic.clone(), metrics);
        eval.series.insert(topic.clone(), errors);
    }
    Ok(eval)
}

/// Reads `file` with a progress bar on a terminal.
pub fn read(file: &Path) -> anyhow::Result<Data> {
    let total = std::fs::metadata(file).map(|m| m.len()).unwrap_or(0);
    let bar = crate::progress::progress_bar(total, "reading");
    let data = Data::read(file, |done, _| bar.set_position(done));
    bar.finish_and_clear();
    data
}

/// Notes for stderr: what was left out and why, rejected messages, a cut file.
pub fn notes(data: &Data, eval: &Evaluation) -> Vec<String> {
    let mut notes = Vec::new();
    if data.truncated {
        notes.push(format!(
            "{} was cut short (the logger did not finish it); evaluating what it holds",
            eval.file
        ));
    }
    notes.extend(data.damage.iter().cloned());
    for (topic, why) in &eval.skipped {
        notes.push(format!("{topic} not evaluated: {why}"));
    }
    for (topic, n) in &data.rejected {
        notes.push(format!(
            "{topic}: {n} messages did not decode or failed their checks (skipped)"
        ));
    }
    for (topic, m) in &eval.streams {
        if m.rejected > 0 {
            notes.push(format!(
                "{topic}: {} messages did not decode or failed their checks (skipped)",
                m.rejected
            ));
        }
    }
    notes
}

/// Runs `nauta eval`.
pub fn run(args: &EvalArgs) -> anyhow::Result<ExitCode> {
    let data = read(&args.file)?;
    let eval = evaluate(&args.file, &data)?;
    for n in notes(&data, &eval) {
        eprintln!("nauta eval: {n}");
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&eval)?);
    } else {
        let what = match eval.reference {
            Reference::Truth => "the truth (sim/truth)",
            Reference::Gps => "the surface GPS fixes (sensor/gps)",
        };
        println!("{}: estimates against {what}", eval.file);
        print!("{}", text_table(&eval));
    }
    Ok(ExitCode::SUCCESS)
}

/// One row of the eval table: a label and a formatter of the metric.
pub type Row = (&'static str, fn(&Metrics) -> Option<String>);

fn f(v: Option<f64>, decimals: usize) -> Option<String> {
    v.map(|x| format!("{x:.decimals$}"))
}

/// The rows of the eval table, in order (shared by the text table and the
/// report's HTML table).
pub const ROWS: &[Row] = &[
    ("samples", |m| Some(m.samples.to_string())),
    ("north RMS (m)", |m| f(m.north_rms_m, 3)),
    ("east RMS (m)", |m| f(m.east_rms_m, 3)),
    ("down RMS (m)", |m| f(m.down_rms_m, 3)),
    ("horizontal RMS (m)", |m| f(m.horizontal_rms_m, 3)),
    ("horizontal max (m)", |m| f(m.horizontal_max_m, 3)),
    ("vel north RMS (m/s)", |m| f(m.vel_north_rms_m_s, 4)),
    ("vel east RMS (m/s)", |m| f(m.vel_east_rms_m_s, 4)),
    ("vel down RMS (m/s)", |m| f(m.vel_down_rms_m_s, 4)),
    ("roll RMS (deg)", |m| f(m.roll_rms_deg, 3)),
    ("pitch RMS (deg)", |m| f(m.pitch_rms_deg, 3)),
    ("yaw RMS (deg)", |m| f(m.yaw_rms_deg, 3)),
    ("final error (m)", |m| f(m.final_error_m, 3)),
    ("final error (% dist.)", |m| f(m.final_error_pct, 3)),
    ("drift (m/km)", |m| f(m.drift_m_per_km, 3)),
    ("distance (m)", |m| f(m.distance_m, 1)),
    ("inside 95% (%)", |m| f(m.inside_95_pct, 1)),
    ("  of samples", |m| {
        m.covariance_samples.map(|n| n.to_string())
    }),
    ("unmatched", |m| Some(m.unmatched.to_string())),
    ("rejected", |m| Some(m.rejected.to_string())),
];

/// The eval table as text: one column per stream, one row per metric that
/// applies to at least one stream.
pub fn text_table(eval: &Evaluation) -> String {
    let topics: Vec<&String> = eval.streams.keys().collect();
    let label_w = ROWS.iter().map(|r| r.0.len()).max().unwrap_or(0);
    let widths: Vec<usize> = topics.iter().map(|t| t.len().max(10)).collect();
    let mut out = format!("  {:<label_w$}", "");
    for (t, w) in topics.iter().zip(&widths) {
        out += &format!("  {t:>w$}");
    }
    out += "\n";
    for (label, get) in ROWS {
        let cells: Vec<Option<String>> = eval.streams.values().map(get).collect();
        if cells.iter().all(Option::is_none) {
            continue;
        }
        out += &format!("  {label:<label_w$}");
        for (c, w) in cells.iter().zip(&widths) {
            out += &format!("  {:>w$}", c.as_deref().unwrap_or("-"));
        }
        out += "\n";
    }
    out
}

#[cfg(test)]
mod tests;
