//! GPX 1.1 (`http://www.topografix.com/GPX/1/1`).
//!
//! - `metadata`: the recording's name (and `time`, when the UTC start is known);
//! - one `wpt` per buoy broadcast and LBL transponder (`ele = -depth`, `name`,
//!   `type` = `buoy` or `transponder`);
//! - one `trk` per track: `name` = topic, `desc` = type and counts, `type`
//!   (`truth`, `nav`, `fix`, `lbl`, `gps`), and a `trkseg` per stretch of
//!   samples without a gap over [`SEGMENT_GAP_S`] or a stamp going back (a
//!   surface GPS track is two segments around a dive);
//! - `trkpt lat lon` in degrees (8 decimals), `ele = -depth` where the
//!   stream has a depth (omitted otherwise), and `time` = UTC start + stamp
//!   when the UTC time of the run's stamp 0 is known (`--utc-start`, or the
//!   `utc_start` metadata), omitted otherwise: stamps are run-clock times, not
//!   UTC.

use std::io::{self, Write};

use super::xml::escape;
use super::{Landmark, Track, TrackKind, UtcTime};

/// A gap between two kept samples longer than this starts a new segment, s.
pub const SEGMENT_GAP_S: f64 = 60.0;

fn kind_name(k: TrackKind) -> &'static str {
    match k {
        TrackKind::Truth => "truth",
        TrackKind::Nav => "nav",
        TrackKind::Fix => "fix",
        TrackKind::Lbl => "lbl",
        TrackKind::Gps => "gps",
        TrackKind::Attitude => "attitude",
    }
}

fn ele(depth_m: f64) -> String {
    if depth_m.is_finite() {
        format!("<ele>{:.3}</ele>", 0.0 - depth_m)
    } else {
        String::new()
    }
}

/// Longitude as GPX wants it: in [-180, 180) after rounding to 8 decimals.
fn lon_text(lon: f64) -> String {
    let s = format!("{lon:.8}");
    if s == "180.00000000" {
        "-180.00000000".to_owned()
    } else {
        s
    }
}

fn time(utc: Option<&UtcTime>, stamp_ns: u64) -> String {
    utc.map(|u| format!("<time>{}</time>", u.plus_ns(stamp_ns).to_rfc3339_millis()))
        .unwrap_or_default()
}

/// Writes the document; returns the number of points (`trkpt` and `wpt`).
pub fn write(
    w: &mut impl Write,
    name: &str,
    tracks: &[&Track],
    landmarks: &[Landmark],
    utc_start: Option<&UtcTime>,
) -> io::Result<u64> {
    let mut points = 0u64;
    writeln!(w, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>")?;
    writeln!(
        w,
        "<gpx version=\"1.1\" creator=\"nauta export\" xmlns=\"http://www.topografix.com/GPX/1/1\" \
         xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" \
         xsi:schemaLocation=\"http://www.topografix.com/GPX/1/1 http://www.topografix.com/GPX/1/1/gpx.xsd\">"
    )?;
    writeln!(
        w,
        "<metadata><name>{}</name><desc>nauta export: {} track(s); ele = -depth; time {}</desc>{}</metadata>",
        escape(name),
        tracks.len(),
        if utc_start.is_some() {
            "= UTC start + stamp"
        } else {
            "omitted (no UTC start known)"
        },
        utc_start
            .map(|u| format!("<time>{}</time>", u.to_rfc3339_millis()))
            .unwrap_or_default()
    )?;
    for l in landmarks {
        writeln!(
            w,
            "<wpt lat=\"{:.8}\" lon=\"{}\">{}{}<name>{}</name><type>{}</type></wpt>",
            l.lat_deg,
            lon_text(l.lon_deg),
            ele(l.depth_m),
            l.stamp_ns.map(|t| time(utc_start, t)).unwrap_or_default(),
            escape(&l.name),
            l.kind.name()
        )?;
        points += 1;
    }
    for t in tracks {
        let kept: Vec<_> = t.samples.iter().filter(|s| s.has_position()).collect();
        if kept.is_empty() {
            continue;
        }
        writeln!(
            w,
            "<trk><name>{}</name><desc>{}: {} messages, {} points</desc><type>{}</type>",
            escape(&t.topic),
            escape(&t.type_name),
            t.messages,
            kept.len(),
            kind_name(t.kind)
        )?;
        writeln!(w, "<trkseg>")?;
        let gap_ns = (SEGMENT_GAP_S * 1e9) as u64;
        let mut prev: Option<u64> = None;
        for s in &kept {
            if let Some(p) = prev
                && (s.stamp_ns < p || s.stamp_ns - p > gap_ns)
            {
                writeln!(w, "</trkseg>")?;
                writeln!(w, "<trkseg>")?;
            }
            prev = Some(s.stamp_ns);
            writeln!(
                w,
                "<trkpt lat=\"{:.8}\" lon=\"{}\">{}{}</trkpt>",
                s.lat_deg,
                lon_text(s.lon_deg),
                ele(s.depth_m),
                time(utc_start, s.stamp_ns)
            )?;
        }
        writeln!(w, "</trkseg>")?;
        writeln!(w, "</trk>")?;
        points += kept.len() as u64;
    }
    writeln!(w, "</gpx>")?;
    Ok(points)
}
