//! `nauta export FILE --format kml|geojson|csv|gpx|foxglove -o OUT` (DESIGN §9):
//! a recording for Google Earth, GIS, spreadsheets or Foxglove. The formats
//! are [`nauta_log::export`]'s; this is the command line around it: options,
//! a progress bar, notes on stderr and a summary on stdout.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use nauta_log::export::{self, ExportOptions, Format, GeoOrigin, KmlAltitude, UtcTime};

/// Export formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FormatArg {
    /// KML for Google Earth: a line per track, GPS fixes, buoy and transponders.
    Kml,
    /// GeoJSON (RFC 7946): a LineString Feature per track, longitude first.
    Geojson,
    /// CSV: one row per message of every track and attitude channel.
    Csv,
    /// GPX 1.1: a trk per track, buoy and transponders as waypoints.
    Gpx,
    /// MCAP with JSON messages and JSON Schemas, plus foxglove.LocationFix on /map/...
    Foxglove,
}

impl From<FormatArg> for Format {
    fn from(f: FormatArg) -> Format {
        match f {
            FormatArg::Kml => Format::Kml,
            FormatArg::Geojson => Format::GeoJson,
            FormatArg::Csv => Format::Csv,
            FormatArg::Gpx => Format::Gpx,
            FormatArg::Foxglove => Format::Foxglove,
        }
    }
}

/// KML altitude modes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AltitudeArg {
    /// On the sea surface (clampToGround): visible from above.
    Clamp,
    /// At -depth below sea level (absolute): seen from under water.
    Absolute,
}

/// Arguments of `nauta export`.
#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// The recording (MCAP).
    pub file: PathBuf,
    /// Output format; without it, taken from OUT's extension (.kml, .geojson,
    /// .csv, .gpx, .mcap for foxglove).
    #[arg(short = 'f', long, value_enum)]
    pub format: Option<FormatArg>,
    /// Output file (written to a hidden file beside it and renamed when
    /// complete: a failed export leaves nothing).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub output: PathBuf,
    /// Points per second of stamp kept on map tracks (kml, geojson, gpx and
    /// foxglove's /map/... channels): 100 Hz streams are decimated to this,
    /// the last sample is always kept; 0 keeps every sample. csv and
    /// foxglove's JSON channels always keep every message.
    #[arg(long, value_name = "HZ", default_value_t = export::DEFAULT_TRACK_HZ)]
    pub track_hz: f64,
    /// KML altitude: clamp (tracks on the sea surface) or absolute (at -depth).
    #[arg(long, value_enum, default_value = "clamp")]
    pub altitude: AltitudeArg,
    /// Origin of lbl/nav's local north/east metres, LAT,LON in degrees
    /// (default: the recording's nauta.run metadata).
    #[arg(long, value_name = "LAT,LON", allow_hyphen_values = true)]
    pub origin: Option<String>,
    /// UTC time of the run clock's zero, RFC 3339 (2026-06-21T09:30:00Z):
    /// gives GPX points a time (default: the recording's utc_start metadata;
    /// otherwise GPX has no times).
    #[arg(long, value_name = "TIME")]
    pub utc_start: Option<String>,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

fn parse_origin(text: &str) -> anyhow::Result<GeoOrigin> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [lat, lon] = parts.as_slice() else {
        anyhow::bail!("--origin {text:?}: expected LAT,LON in degrees, e.g. 38.6,-9.3");
    };
    let num = |s: &str, what: &str| {
        s.parse::<f64>()
            .with_context(|| format!("--origin {text:?}: {what} {s:?} is not a number"))
    };
    GeoOrigin::from_degrees(num(lat, "latitude")?, num(lon, "longitude")?)
        .map_err(|e| anyhow::anyhow!("--origin {text:?}: {e}"))
}

/// Runs `nauta export`.
pub fn run(args: &ExportArgs) -> anyhow::Result<ExitCode> {
    let format = match args.format {
        Some(f) => Format::from(f),
        None => Format::from_extension(&args.output).ok_or_else(|| {
            anyhow::anyhow!(
                "cannot tell the format from {}: give --format kml|geojson|csv|gpx|foxglove",
                args.output.display()
            )
        })?,
    };
    let mut options = ExportOptions::new(format);
    options.track_hz = args.track_hz;
    options.kml_altitude = match args.altitude {
        AltitudeArg::Clamp => KmlAltitude::ClampToGround,
        AltitudeArg::Absolute => KmlAltitude::Absolute,
    };
    options.origin = args.origin.as_deref().map(parse_origin).transpose()?;
    options.utc_start = args
        .utc_start
        .as_deref()
        .map(|t| UtcTime::parse(t).map_err(|e| anyhow::anyhow!("--utc-start: {e}")))
        .transpose()?;
    options.presets = Some(crate::presets::simulated);

    crate::part_file::remove_part_file_on_signal(&args.output)?;
    let total = std::fs::metadata(&args.file).map(|m| m.len()).unwrap_or(0);
    let bar = crate::progress::progress_bar(total, "exporting");
    let result = export::export(&args.file, &args.output, &options, |done, _| {
        bar.set_position(done)
    });
    bar.finish_and_clear();
    let summary = result?;
    let mut err = std::io::stderr().lock();
    for n in &summary.notes {
        let _ = writeln!(err, "nauta export: note: {n}");
    }
    drop(err);
    let text = if args.json {
        format!("{}\n", serde_json::to_string_pretty(&summary)?)
    } else {
        summary_text(&summary)
    };
    // A closed stdout (`| head`) is not an error of the export.
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            return Err(anyhow::Error::new(e).context("cannot write to stdout"));
        }
        _ => {}
    }
    Ok(ExitCode::SUCCESS)
}

/// The summary for people: one line, then one per track.
fn summary_text(summary: &export::ExportSummary) -> String {
    use std::fmt::Write as _;
    let unit = match summary.format {
        Format::Csv => "rows",
        Format::Foxglove => "location fixes",
        _ => "points",
    };
    let mut out = format!(
        "{} ({}): {} messages read, {} written\n",
        summary.output.display(),
        summary.format,
        summary.messages_read,
        summary.written
    );
    for t in &summary.tracks {
        let _ = writeln!(
            out,
            "  {:<20} {:>8} messages  {:>8} {unit}{}",
            t.topic,
            t.messages,
            t.written,
            if t.invalid > 0 {
                format!("  ({} without a usable position)", t.invalid)
            } else {
                String::new()
            }
        );
    }
    if summary.landmarks > 0 {
        let _ = writeln!(out, "  {} buoy and transponder points", summary.landmarks);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn origins_parse_with_clear_errors() {
        let o = parse_origin("-12.5, 170.25").expect("origin");
        assert!((o.lat_rad.to_degrees() + 12.5).abs() < 1e-12);
        for bad in ["38.6", "a,b", "91,0", "1,2,3"] {
            assert!(parse_origin(bad).is_err(), "{bad}");
        }
    }
}
