//! `nauta smooth FILE -o OUT.mcap [--json]`: the command line around
//! [`super::smooth_recording`]: the filter of the recording's manifest, a
//! progress bar on a terminal, notes on stderr, no partial output.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;

use super::filter::{ManifestSource, lbl_filter, lbl_process, manifest};
use super::{SmoothSummary, TOPIC};

/// Arguments of `nauta smooth`.
#[derive(Debug, clap::Args)]
pub struct SmoothArgs {
    /// The recording (MCAP) of a run with an LBL navigator (`nauta-lbl`).
    pub file: PathBuf,
    /// The output: the recording with the smoothed track on `smoother/lbl/nav`.
    #[arg(short = 'o', long = "output", value_name = "OUT.mcap")]
    pub output: PathBuf,
    /// The manifest whose LBL filter to run, instead of the recorded one
    /// (for a recording without one, such as an import's).
    #[arg(long, value_name = "FILE")]
    pub manifest: Option<PathBuf>,
    /// The manifest's process that runs `nauta-lbl`, when it has several.
    #[arg(long, value_name = "NAME")]
    pub process: Option<String>,
    /// Override a manifest value, as `nauta launch --set`
    /// (e.g. `--set lbl.params.range_sigma_m=0.5`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Print one JSON object (what was read, refused, written; the seconds
    /// of each part) instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Runs `nauta smooth`.
pub fn run(args: &SmoothArgs) -> anyhow::Result<ExitCode> {
    anyhow::ensure!(
        !nauta_log::export::same_file(&args.file, &args.output),
        "-o {} is the input recording; choose another output file",
        args.output.display()
    );
    let source = match &args.manifest {
        Some(path) => ManifestSource::File(path),
        None => ManifestSource::Recorded,
    };
    // Two reads of the input: its inputs, then the copy.
    let size = std::fs::metadata(&args.file).map_or(0, |m| m.len());
    let bar = crate::progress::progress_bar(2 * size, "smoothing");
    let mut done = None;
    let result = crate::part_file::write_via_part(&args.output, |part| {
        done = Some(super::smooth_recording(
            &args.file,
            part,
            |recording| {
                let m = manifest(source, recording, &args.file, &args.set)?;
                let process = lbl_process(&m, args.process.as_deref())?;
                lbl_filter(&m, &process)
            },
            |done, total| {
                bar.set_length(total);
                bar.set_position(done);
            },
        )?);
        Ok(())
    });
    bar.finish_and_clear();
    result?;
    let summary = SmoothSummary {
        output: args.output.clone(),
        ..done.context("the smoother wrote no summary")?
    };
    let mut err = std::io::stderr().lock();
    for n in &summary.notes {
        let _ = writeln!(err, "nauta smooth: note: {n}");
    }
    drop(err);
    let text = if args.json {
        format!("{}\n", serde_json::to_string_pretty(&summary)?)
    } else {
        text(&summary)
    };
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(anyhow::Error::new(e).context("cannot write to stdout"))
        }
        _ => Ok(ExitCode::SUCCESS),
    }
}

fn counts(m: &std::collections::BTreeMap<String, usize>) -> String {
    if m.is_empty() {
        return "none".to_owned();
    }
    m.iter()
        .map(|(k, n)| format!("{n} {k}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The table `nauta smooth` prints.
pub fn text(s: &SmoothSummary) -> String {
    format!(
        "smoothed {} -> {}\n\
         inputs read      {} ({} failed their checks: {})\n\
         refused          {}\n\
         forward steps    {} ({}-state filter)\n\
         {TOPIC:<16} {} messages\n\
         copied           {} messages\n\
         read             {:.3} s\n\
         forward pass     {:.3} s\n\
         backward pass    {:.3} s\n\
         write            {:.3} s\n",
        s.input.display(),
        s.output.display(),
        s.inputs,
        s.rejected.values().sum::<usize>(),
        counts(&s.rejected),
        counts(&s.refused),
        s.steps,
        s.state_dim,
        s.smoothed,
        s.copied,
        s.read_s,
        s.forward_s,
        s.backward_s,
        s.write_s,
    )
}
