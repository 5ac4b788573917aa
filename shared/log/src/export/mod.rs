//! Exports of a recording (`nauta export`, DESIGN §9): for Google Earth (KML),
//! GIS (GeoJSON, GPX), spreadsheets (CSV) and Foxglove (MCAP with JSON).
//!
//! **Tracks.** Every channel whose type carries a position is a track, named by
//! its topic: `nauta.TruthState.v1` (`sim/truth`), `nauta.NavSolution.v1`
//! (`ains/nav`, and a smoothed track published with that type),
//! `nauta.PositionFix.v1` (`positioning/fix`), `nauta.GpsFix.v1`
//! (`sensor/gps`) and `nauta.LblSolution.v1` (`lbl/nav`). `lbl/nav` is in
//! local north/east metres; it is placed on the globe with the run's origin
//! ([`crate::run`]: `--origin`, else the `nauta.run` metadata) and left out of the
//! map formats, with a note, when there is none. Latitude and longitude are
//! radians on the wire and degrees in every export (DESIGN §4).
//!
//! **Decimation.** KML, GeoJSON, GPX and Foxglove's `/map/...` channels keep
//! one point per [`ExportOptions::track_hz`]⁻¹ seconds of stamp (1 Hz by
//! default; 0 keeps every sample) and always the last one. CSV and the JSON
//! copies of the channels in the Foxglove file keep every message.
//!
//! **Formats** (one module each):
//! - [`kml`]: one Placemark with one LineString per track, styled per track,
//!   clamped to the sea surface or at `-depth` (absolute); GPS fixes, buoy
//!   broadcasts and LBL transponders as points.
//! - [`geojson`]: RFC 7946 FeatureCollection, one LineString Feature per
//!   track (`[longitude, latitude]`, WGS84 degrees), buoy and transponders as
//!   Point Features.
//! - [`gpx`]: GPX 1.1, one `trk` per track (a `trkseg` per stretch without a
//!   gap over a minute), `ele = -depth`, `time` when the run's UTC start is
//!   known; buoy and transponders as `wpt`.
//! - [`csv`]: one file, one row per message of every track and attitude
//!   channel ([`csv::COLUMNS`]).
//! - [`foxglove`]: MCAP with `json` messages and `jsonschema` schemas for every
//!   channel ([`jsonschema`]), plus `foxglove.LocationFix` on `/map/<topic>`.
//!
//! The output is written next to its destination and renamed into place when
//! complete, so a failed export leaves no partial file. A message that does not
//! decode is skipped and counted; nothing in a recording makes the export panic.

pub mod csv;
pub mod foxglove;
pub mod geojson;
pub mod gpx;
pub mod jsonschema;
pub mod kml;
pub mod tracks;
mod xml;

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub use crate::run::{GeoOrigin, Presets, Resolver, RunInfo, Transponder};
pub use crate::utc::UtcTime;
pub use tracks::{Landmark, LandmarkKind, Sample, Track, TrackKind};

/// Track points per second of the map formats unless told otherwise.
pub const DEFAULT_TRACK_HZ: f64 = 1.0;

/// An export format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// KML 2.2 for Google Earth.
    Kml,
    /// GeoJSON (RFC 7946).
    GeoJson,
    /// Comma-separated values, one row per message.
    Csv,
    /// GPX 1.1.
    Gpx,
    /// MCAP with JSON messages and JSON Schemas, for Foxglove.
    Foxglove,
}

impl Format {
    /// Every format.
    pub const ALL: [Format; 5] = [
        Format::Kml,
        Format::GeoJson,
        Format::Csv,
        Format::Gpx,
        Format::Foxglove,
    ];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Format::Kml => "kml",
            Format::GeoJson => "geojson",
            Format::Csv => "csv",
            Format::Gpx => "gpx",
            Format::Foxglove => "foxglove",
        }
    }

    /// The format called `name`.
    pub fn parse(name: &str) -> Result<Format, ExportError> {
        Format::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(name))
            .ok_or_else(|| ExportError::UnknownFormat(name.to_owned()))
    }

    /// The format that a file name's extension suggests (`.kml`, `.geojson`
    /// or `.json`, `.csv`, `.gpx`, `.mcap`).
    pub fn from_extension(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "kml" => Some(Format::Kml),
            "geojson" | "json" => Some(Format::GeoJson),
            "csv" => Some(Format::Csv),
            "gpx" => Some(Format::Gpx),
            "mcap" => Some(Format::Foxglove),
            _ => None,
        }
    }

    /// True for the formats that draw tracks on a map.
    pub fn is_map(self) -> bool {
        matches!(self, Format::Kml | Format::GeoJson | Format::Gpx)
    }
}

impl std::fmt::Display for Format {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Where KML puts a track vertically.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum KmlAltitude {
    /// `clampToGround`: drawn on the sea surface, visible from above in Google
    /// Earth (the coordinates still carry `-depth`).
    #[default]
    ClampToGround,
    /// `absolute`: at `-depth` metres from sea level (below the surface;
    /// Google Earth shows it from under water).
    Absolute,
}

/// How to export.
#[derive(Debug, Clone)]
pub struct ExportOptions {
    /// The format.
    pub format: Format,
    /// Points per second of stamp kept on map tracks (KML, GeoJSON, GPX and
    /// Foxglove's `/map/...` channels); 0 keeps every sample.
    pub track_hz: f64,
    /// KML altitude mode.
    pub kml_altitude: KmlAltitude,
    /// The local origin of `lbl/nav`, overriding the recording's metadata.
    pub origin: Option<GeoOrigin>,
    /// UTC time of run-clock stamp 0, overriding the recording's metadata
    /// (GPX `time`).
    pub utc_start: Option<UtcTime>,
    /// What the simulator's scenarios add to the `nauta.run` metadata (the
    /// front end knows the simulator's layouts; this library only reads
    /// explicit `transponders` lists, see [`crate::run`]).
    pub presets: Option<Resolver>,
}

impl ExportOptions {
    /// The defaults for `format`.
    pub fn new(format: Format) -> Self {
        ExportOptions {
            format,
            track_hz: DEFAULT_TRACK_HZ,
            kml_altitude: KmlAltitude::default(),
            origin: None,
            utc_start: None,
            presets: None,
        }
    }

    /// Minimum spacing of kept track points, ns (0: keep all).
    fn period_ns(&self) -> Result<u64, ExportError> {
        if !(self.track_hz.is_finite() && self.track_hz >= 0.0) {
            return Err(ExportError::InvalidOption(format!(
                "the track rate must be a number of Hz >= 0 (0 keeps every sample), got {}",
                self.track_hz
            )));
        }
        if self.track_hz == 0.0 {
            return Ok(0);
        }
        Ok((1e9 / self.track_hz).round().min(u64::MAX as f64) as u64)
    }
}

/// What went wrong in an export.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// No such format.
    #[error("unknown export format {0:?}: use kml, geojson, csv, gpx or foxglove")]
    UnknownFormat(String),
    /// An option is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// The output path is the recording.
    #[error("the output {0} is the recording itself")]
    OutputIsInput(PathBuf),
    /// The recording cannot be read (missing, not MCAP).
    #[error("cannot read {path}: {message}")]
    Read {
        /// The recording.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// A map format was asked of a recording without a usable position stream.
    #[error("{path} has no position stream to export as {format}: {detail}")]
    NoPositionStream {
        /// The recording.
        path: PathBuf,
        /// The format asked for.
        format: Format,
        /// What the recording has instead.
        detail: String,
    },
    /// CSV was asked of a recording without track or attitude channels, or
    /// Foxglove of one without any channel.
    #[error("{path} has nothing to export: {detail} (--format foxglove takes every channel)")]
    NothingToExport {
        /// The recording.
        path: PathBuf,
        /// What it holds instead.
        detail: String,
    },
    /// The output cannot be written.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The output.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        source: std::io::Error,
    },
    /// A bug: something this module guarantees did not hold.
    #[error("internal error: {0}")]
    Internal(String),
    /// The MCAP writer failed.
    #[error("cannot write the MCAP file {path}: {source}")]
    Mcap {
        /// The output.
        path: PathBuf,
        /// The writer's reason.
        #[source]
        source: mcap::McapError,
    },
}

/// One track as exported.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TrackSummary {
    /// Topic.
    pub topic: String,
    /// Pinned type name.
    #[serde(rename = "type")]
    pub type_name: String,
    /// Messages decoded.
    pub messages: u64,
    /// Messages without a usable position (non-finite or out of range).
    pub invalid: u64,
    /// Points or rows written for this track (0: left out, see the notes).
    pub written: u64,
}

/// What an export did.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ExportSummary {
    /// The format.
    #[serde(serialize_with = "ser_format")]
    pub format: Format,
    /// The output file.
    pub output: PathBuf,
    /// Tracks (and, for CSV, attitude channels) in output order.
    pub tracks: Vec<TrackSummary>,
    /// Buoy and transponder points written.
    pub landmarks: u64,
    /// Messages read from the recording.
    pub messages_read: u64,
    /// Messages (Foxglove), rows (CSV) or points (map formats) written.
    pub written: u64,
    /// Messages that did not decode, by topic (skipped).
    pub decode_failures: BTreeMap<String, u64>,
    /// Foxglove: fields left out of a JSON message because they held a
    /// non-finite number (JSON has none).
    pub non_finite_left_out: u64,
    /// The recording was cut short (everything recovered was exported).
    pub truncated: bool,
    /// Things the user should know (what was left out and why).
    pub notes: Vec<String>,
}

fn ser_format<S: serde::Serializer>(f: &Format, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(f.name())
}

/// Exports the recording at `input` to `output`, reporting `(bytes read,
/// file bytes)` while reading.
pub fn export(
    input: &Path,
    output: &Path,
    options: &ExportOptions,
    mut on_progress: impl FnMut(u64, u64),
) -> Result<ExportSummary, ExportError> {
    let period_ns = options.period_ns()?;
    if same_file(input, output) {
        return Err(ExportError::OutputIsInput(output.to_owned()));
    }
    if !input.is_file() {
        return Err(ExportError::Read {
            path: input.to_owned(),
            message: if input.exists() {
                "not a file".to_owned()
            } else {
                "no such file".to_owned()
            },
        });
    }
    let mut part = PartFile::create(output)?;
    let format = options.format;
    let mut collector = tracks::Collector::new(format == Format::Csv, period_ns);
    let mut fox = match format {
        Format::Foxglove => Some(foxglove::Converter::new(part.take_file()?, output)?),
        _ => None,
    };
    let mut messages_read = 0u64;
    let mut failed: Option<ExportError> = None;
    let wanted = |ch: &crate::Channel| TrackKind::is_exported(&ch.type_name);
    let rec = crate::streams::visit(input, &mut on_progress, wanted, |m| {
        messages_read += 1;
        collector.observe(m.channel, m.recorded, m.checked);
        if let Some(f) = fox.as_mut()
            && let Err(e) = f.message(m.channel, m.recorded)
        {
            failed = Some(e);
            anyhow::bail!("export stopped");
        }
        Ok(())
    });
    if let Some(e) = failed {
        return Err(e);
    }
    let rec = rec.map_err(|e| ExportError::Read {
        path: input.to_owned(),
        message: format!("{e:#}"),
    })?;

    let mut notes = Vec::new();
    if rec.recovery.truncated {
        notes.push(format!(
            "the recording was cut short: exported what {} of its {} bytes hold{}",
            rec.recovery.read_bytes,
            rec.recovery.file_bytes,
            rec.recovery
                .reason
                .as_ref()
                .map(|r| format!(" ({r})"))
                .unwrap_or_default()
        ));
    }
    notes.extend(rec.recovery.damage_notes());
    let run = RunInfo::read(
        rec.metadata(crate::META_RUN),
        &crate::run::Overrides {
            origin: options.origin,
            utc_start: options.utc_start,
        },
        options.presets,
    );
    notes.extend(run.notes.iter().cloned());
    let collected = collector.finish(&run, format, &mut notes);
    let mut decode_failures = collected.decode_failures.clone();

    let mut summary = ExportSummary {
        format,
        output: output.to_owned(),
        tracks: Vec::new(),
        landmarks: 0,
        messages_read,
        written: 0,
        decode_failures: BTreeMap::new(),
        non_finite_left_out: 0,
        truncated: rec.recovery.truncated,
        notes: Vec::new(),
    };
    let landmarks = &collected.landmarks;
    let no_position = |detail: String| ExportError::NoPositionStream {
        path: input.to_owned(),
        format,
        detail,
    };
    match format {
        Format::Kml | Format::GeoJson | Format::Gpx => {
            let tracks: Vec<&Track> = collected
                .tracks
                .iter()
                .filter(|t| t.kind.is_position() && t.has_position())
                .collect();
            if tracks.is_empty() {
                return Err(no_position(collected.describe(&rec)));
            }
            let file = part.take_file()?;
            let mut w = BufWriter::new(file);
            let written = match format {
                Format::Kml => kml::write(
                    &mut w,
                    &kml::Document {
                        name: stem(input),
                        tracks: &tracks,
                        landmarks,
                        altitude: options.kml_altitude,
                    },
                ),
                Format::GeoJson => geojson::write(&mut w, &stem(input), &tracks, landmarks),
                _ => gpx::write(
                    &mut w,
                    &stem(input),
                    &tracks,
                    landmarks,
                    run.utc_start.as_ref(),
                ),
            }
            .and_then(|n| w.flush().map(|()| n))
            .map_err(|e| part.write_error(e))?;
            summary.written = written;
            summary.landmarks = landmarks.len() as u64;
            summary.tracks = collected
                .tracks
                .iter()
                .filter(|t| t.kind.is_position())
                .map(|t| {
                    let drawn = tracks.iter().any(|d| std::ptr::eq(*d, t));
                    t.summary(if drawn { t.points() } else { 0 })
                })
                .collect();
        }
        Format::Csv => {
            if collected.tracks.is_empty() {
                return Err(ExportError::NothingToExport {
                    path: input.to_owned(),
                    detail: collected.describe(&rec),
                });
            }
            let file = part.take_file()?;
            let mut w = BufWriter::new(file);
            let written = csv::write(
                &mut w,
                &collected.tracks,
                run.origin.as_ref().map(|o| &o.value),
            )
            .and_then(|n| w.flush().map(|()| n))
            .map_err(|e| part.write_error(e))?;
            summary.written = written;
            summary.tracks = collected
                .tracks
                .iter()
                .map(|t| t.summary(t.samples.len() as u64))
                .collect();
        }
        Format::Foxglove => {
            // A file with no channel is not a recording worth a Foxglove
            // file (a junk file that happens to parse as an empty MCAP).
            if rec.channels.is_empty() {
                return Err(ExportError::NothingToExport {
                    path: input.to_owned(),
                    detail: "it has no channel at all".to_owned(),
                });
            }
            let Some(f) = fox.take() else {
                return Err(ExportError::Internal(
                    "the Foxglove converter is missing".to_owned(),
                ));
            };
            let done = f.finish(&rec, &collected.tracks, &mut notes)?;
            summary.written = done.written;
            summary.non_finite_left_out = done.non_finite_left_out;
            for (topic, n) in done.decode_failures {
                let e = decode_failures.entry(topic).or_insert(0);
                *e = (*e).max(n);
            }
            summary.tracks = collected
                .tracks
                .iter()
                .filter(|t| t.kind.is_position())
                .map(|t| {
                    let n = done.map_points.get(&t.topic).copied().unwrap_or(0);
                    t.summary(n)
                })
                .collect();
        }
    }
    for (topic, n) in &decode_failures {
        notes.push(format!(
            "{topic}: {n} message(s) did not decode and were skipped"
        ));
    }
    summary.decode_failures = decode_failures;
    summary.notes = notes;
    part.commit()?;
    Ok(summary)
}

/// The file name up to its first dot (DESIGN §9), for document names.
fn stem(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    match name.split('.').next() {
        Some(s) if !s.is_empty() => s.to_owned(),
        _ => name,
    }
}

/// Whether `a` and `b` name the same existing file (symbolic links resolved).
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// The output being written: a hidden file beside the destination, renamed
/// into place by [`PartFile::commit`] and removed if the export fails.
///
/// A signal ends a process without running destructors: a command that
/// exports installs a handler that removes [`part_path`] first.
struct PartFile {
    path: PathBuf,
    output: PathBuf,
    file: Option<File>,
    committed: bool,
}

/// The hidden file an export to `output` writes before it is complete:
/// `.NAME.PID.part` beside `output` (`None` when `output` names no file).
pub fn part_path(output: &Path) -> Option<PathBuf> {
    let name = output.file_name()?;
    let mut part_name = std::ffi::OsString::from(".");
    part_name.push(name);
    part_name.push(format!(".{}.part", std::process::id()));
    Some(output.with_file_name(part_name))
}

impl PartFile {
    fn create(output: &Path) -> Result<Self, ExportError> {
        let write_error = |source| ExportError::Write {
            path: output.to_owned(),
            source,
        };
        if output.is_dir() {
            return Err(write_error(std::io::Error::new(
                std::io::ErrorKind::IsADirectory,
                "it is a directory",
            )));
        }
        let path = part_path(output).ok_or_else(|| {
            write_error(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "the output path names no file",
            ))
        })?;
        let file = File::create(&path).map_err(write_error)?;
        Ok(PartFile {
            path,
            output: output.to_owned(),
            file: Some(file),
            committed: false,
        })
    }

    fn take_file(&mut self) -> Result<File, ExportError> {
        self.file.take().ok_or_else(|| ExportError::Write {
            path: self.output.clone(),
            source: std::io::Error::other("internal: the output was taken twice"),
        })
    }

    fn write_error(&self, source: std::io::Error) -> ExportError {
        ExportError::Write {
            path: self.output.clone(),
            source,
        }
    }

    fn commit(mut self) -> Result<(), ExportError> {
        drop(self.file.take());
        std::fs::rename(&self.path, &self.output).map_err(|source| ExportError::Write {
            path: self.output.clone(),
            source,
        })?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for PartFile {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

#[cfg(test)]
mod tests;
