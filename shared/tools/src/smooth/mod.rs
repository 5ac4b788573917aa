//! `nauta smooth FILE -o OUT.mcap`: paper 004's post-mission smoother over
//! a recording (DESIGN §9). The recording's logged LBL inputs ([`inputs`],
//! through the one offline reader) run through the LBL filter again with
//! the recording's own manifest parameters ([`filter`]; the forward pass,
//! which records `φ_i` and the priors and posteriors), then paper 004's
//! backward pass (eqs. 7-9, [`track`]); OUT is the recording with the
//! smoothed track on `smoother/lbl/nav` ([`copy`]), an `LblSolution` stream
//! that eval, report and export treat as any other.
//!
//! - [`inputs`]: the filter's inputs from the recording.
//! - [`filter`]: the filter the recording's manifest runs.
//! - [`track`]: the backward pass and the smoothed solutions.
//! - [`copy`]: the output recording.
//! - [`command`]: the command line (progress, notes, no partial output).

pub mod command;
pub mod copy;
pub mod filter;
pub mod inputs;
pub mod track;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use nauta_estimation::lbl::{Lbl, forward_pass};
use serde::Serialize;

pub use track::TOPIC;

/// The metadata record the output gains.
pub const META_SMOOTH: &str = "nauta.smooth";

/// What smoothing a recording did, and how long each part took.
#[derive(Debug, Clone, Serialize)]
pub struct SmoothSummary {
    /// The input.
    pub input: PathBuf,
    /// The output.
    pub output: PathBuf,
    /// Inputs of the filter read from the recording.
    pub inputs: usize,
    /// Inputs the filter refused (counted by kind), as the service would.
    pub refused: BTreeMap<String, usize>,
    /// Inputs refused by their checks when read, per topic.
    pub rejected: BTreeMap<String, usize>,
    /// Steps of the forward pass (the filter's dimension: `state_dim`).
    pub steps: usize,
    /// 4, or 5 with `k` estimated.
    pub state_dim: usize,
    /// Messages on `smoother/lbl/nav`.
    pub smoothed: usize,
    /// Messages of the input copied.
    pub copied: u64,
    /// Per channel, input messages not copied (a type nauta does not know).
    pub not_copied: BTreeMap<String, u64>,
    /// Reading the input's LBL inputs, s.
    pub read_s: f64,
    /// The forward pass (the filter over the inputs), s.
    pub forward_s: f64,
    /// The backward pass (eqs. 7-9), s.
    pub backward_s: f64,
    /// Copying the recording and writing the track, s.
    pub write_s: f64,
    /// Notes: damaged or cut input, skipped channels.
    pub notes: Vec<String>,
}

/// Smooths `input` into `output` (written in place: the command line writes
/// through a part file) with the LBL filter `filter_of` builds from the
/// recording's first read (its manifest; not yet fed).
/// `on_progress(done, total)` in bytes over the two reads.
pub fn smooth_recording(
    input: &Path,
    output: &Path,
    filter_of: impl FnOnce(&nauta_log::Recording) -> anyhow::Result<Lbl>,
    mut on_progress: impl FnMut(u64, u64),
) -> anyhow::Result<SmoothSummary> {
    let start = Instant::now();
    let logged = inputs::read(input, |done, total| on_progress(done, 2 * total))
        .with_context(|| format!("cannot read the recording {}", input.display()))?;
    let read_s = start.elapsed().as_secs_f64();
    let filter = filter_of(&logged.recording)?;
    let file_bytes = logged.recording.recovery.file_bytes;
    anyhow::ensure!(
        !logged.inputs.is_empty(),
        "{} holds none of the LBL filter's inputs ({})",
        input.display(),
        inputs::TOPICS.join(", ")
    );
    let mut notes = logged.recording.recovery.damage_notes();
    if logged.recording.recovery.truncated {
        notes.push(format!(
            "the file was cut short: read up to byte {} of {}",
            logged.recording.recovery.read_bytes, logged.recording.recovery.file_bytes
        ));
    }
    for (topic, n) in &logged.rejected {
        notes.push(format!(
            "{topic}: {n} message(s) failed their checks and were skipped"
        ));
    }

    let start = Instant::now();
    let state_dim = filter.dimension();
    let pass = forward_pass(filter, &logged.inputs);
    let forward_s = start.elapsed().as_secs_f64();
    let mut refused: BTreeMap<String, usize> = BTreeMap::new();
    for (_, e) in &pass.refused {
        *refused.entry(e.kind.to_owned()).or_default() += 1;
    }
    let track = track::smoothed_track(&pass).map_err(|e| {
        anyhow::anyhow!("cannot smooth the forward pass of {}: {e}", input.display())
    })?;
    anyhow::ensure!(
        !track.solutions.is_empty(),
        "the LBL filter never started on {} (no GPS fix at the surface and no initial_position_m): nothing to smooth",
        input.display()
    );

    let start = Instant::now();
    let meta = BTreeMap::from([
        ("source".to_owned(), input.display().to_string()),
        ("steps".to_owned(), track.steps.to_string()),
        ("state_dim".to_owned(), state_dim.to_string()),
        (
            "method".to_owned(),
            "paper 004 eqs. 7-9: fixed-interval RTS over the LBL filter's forward pass".to_owned(),
        ),
    ]);
    let copied = copy::copy_with_track(
        input,
        &logged.recording,
        output,
        TOPIC,
        &track.solutions,
        (META_SMOOTH, meta),
        |done, _| on_progress(file_bytes + done, 2 * file_bytes),
    )?;
    let write_s = start.elapsed().as_secs_f64();
    for (topic, n) in &copied.skipped {
        notes.push(format!(
            "{topic}: {n} message(s) of a type nauta does not know were not copied"
        ));
    }
    if copied.replaced > 0 {
        notes.push(format!(
            "{TOPIC}: the input's {} smoothed message(s) were replaced",
            copied.replaced
        ));
    }
    Ok(SmoothSummary {
        input: input.to_owned(),
        output: output.to_owned(),
        inputs: logged.inputs.len(),
        refused,
        rejected: logged.rejected,
        steps: track.steps,
        state_dim,
        smoothed: track.solutions.len(),
        copied: copied.messages,
        not_copied: copied.skipped,
        read_s,
        forward_s,
        backward_s: track.backward_s,
        write_s,
        notes,
    })
}
