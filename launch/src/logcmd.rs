//! `nauta log info`, `nauta record`, `nauta replay`: recordings (DESIGN §8).

use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `nauta log info`.
#[derive(Debug, clap::Args)]
pub struct InfoArgs {
    /// The recording (MCAP).
    pub file: PathBuf,
    /// Print one JSON object (`{"channels": [...], "truncated": ..., ...}`).
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `nauta record`.
#[derive(Debug, clap::Args)]
pub struct RecordArgs {
    /// Output file (MCAP).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// The run to record, when several are running.
    #[arg(long)]
    pub namespace: Option<String>,
}

/// Arguments of `nauta replay`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// The recording to replay.
    pub file: PathBuf,
    /// Pace at X times the recorded speed (wall clock).
    #[arg(long, conflicts_with = "fast")]
    pub rate: Option<f64>,
    /// As fast as the pipeline consumes (sim clock, deterministic).
    #[arg(long)]
    pub fast: bool,
}

/// A progress bar on stderr for reading `total` bytes, shown only on a terminal.
pub fn progress_bar(total: u64, what: &str) -> indicatif::ProgressBar {
    let bar = if std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        indicatif::ProgressBar::new(total)
    } else {
        indicatif::ProgressBar::hidden()
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{msg} [{bar:30}] {bytes}/{total_bytes} {bytes_per_sec} eta {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar.set_message(what.to_owned());
    bar
}

/// `nauta log info FILE [--json]`.
pub fn info(args: &InfoArgs) -> anyhow::Result<ExitCode> {
    let total = std::fs::metadata(&args.file).map(|m| m.len()).unwrap_or(0);
    let bar = progress_bar(total, "reading");
    let info = nauta_log::info::summarise(&args.file, |done, _| bar.set_position(done))?;
    bar.finish_and_clear();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&info)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!("{}", info.file);
    let r = &info.recovery;
    if info.truncated {
        println!(
            "  TRUNCATED: read {} of {} bytes ({} lost), {} complete chunks{}",
            r.read_bytes,
            r.file_bytes,
            r.lost_bytes(),
            r.chunks,
            r.reason
                .as_ref()
                .map(|w| format!(": {w}"))
                .unwrap_or_default()
        );
    } else {
        println!("  complete: {} bytes, {} chunks", r.file_bytes, r.chunks);
    }
    if r.damaged_chunks > 0 {
        println!(
            "  DAMAGED: {} chunks could not be decoded",
            r.damaged_chunks
        );
    }
    println!(
        "  span {:.3} s .. {:.3} s ({:.1} s), {} messages, {} gaps",
        info.start_stamp_ns as f64 * 1e-9,
        info.end_stamp_ns as f64 * 1e-9,
        info.duration_s,
        info.messages,
        info.gaps
    );
    println!(
        "  {:<22} {:<28} {:>9} {:>9} {:>6} {:>9}",
        "channel", "type", "count", "rate Hz", "gaps", "instances"
    );
    for c in &info.channels {
        println!(
            "  {:<22} {:<28} {:>9} {:>9.2} {:>6} {:>9}",
            c.topic, c.type_name, c.count, c.rate_hz, c.gaps, c.instances
        );
    }
    for (name, entries) in &info.metadata {
        println!("  metadata {name}:");
        for (k, v) in entries {
            let first = v.lines().next().unwrap_or("");
            let more = v.lines().count() > 1;
            println!("    {k}: {first}{}", if more { " ..." } else { "" });
        }
    }
    if !info.events.is_empty() {
        println!("  events:");
        for e in &info.events {
            println!(
                "    {:>10.3} s {:<10} {} #{} pid {} {}{}",
                e.stamp_ns as f64 * 1e-9,
                e.kind,
                e.process,
                e.instance,
                e.pid,
                e.variant,
                if e.kind == "exited" {
                    format!(" exit {}", e.exit_code)
                } else {
                    String::new()
                }
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// `nauta record -o FILE`.
pub fn record(_args: &RecordArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("nauta record is not built yet")
}

/// `nauta replay FILE`.
pub fn replay(_args: &ReplayArgs) -> anyhow::Result<ExitCode> {
    anyhow::bail!("nauta replay is not built yet")
}
