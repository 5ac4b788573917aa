//! GeoJSON (RFC 7946): a FeatureCollection in WGS84 degrees, longitude first.
//!
//! - one Feature per track with a LineString geometry (`[longitude,
//!   latitude]`, rounded to 1e-8°, about a millimetre; a track with a single
//!   point gets a Point) and properties `name` and `topic` (the topic), `type`
//!   (the pinned type), `kind` = `"track"`, `messages`, `points`,
//!   `start_s`/`end_s` (run-clock stamps) and `stroke` (its colour, as the
//!   simplestyle convention that geojson.io and others read);
//! - one Point Feature per buoy broadcast and LBL transponder, with `name`,
//!   `kind` (`"buoy"`, `"transponder"`), `depth_m` and, for the buoy, `time_s`.
//!
//! Positions are two-dimensional: RFC 7946's third coordinate is height above
//! the ellipsoid, which a depth below the sea surface is not (depth is in the
//! CSV, GPX and KML exports).

use std::io::{self, Write};

use serde_json::{Value, json};

use super::{Landmark, Track};

/// Degrees rounded to 1e-8.
fn r8(x: f64) -> f64 {
    (x * 1e8).round() / 1e8
}

fn position(lon: f64, lat: f64) -> Value {
    json!([r8(lon), r8(lat)])
}

/// Writes the FeatureCollection; returns the number of positions written.
pub fn write(
    w: &mut impl Write,
    name: &str,
    tracks: &[&Track],
    landmarks: &[Landmark],
) -> io::Result<u64> {
    let mut features = Vec::new();
    let mut points = 0u64;
    for (i, t) in tracks.iter().enumerate() {
        let kept: Vec<_> = t.samples.iter().filter(|s| s.has_position()).collect();
        let (Some(first), Some(last)) = (kept.first(), kept.last()) else {
            continue;
        };
        let geometry = if kept.len() == 1 {
            json!({"type": "Point", "coordinates": position(first.lon_deg, first.lat_deg)})
        } else {
            let coords: Vec<Value> = kept
                .iter()
                .map(|s| position(s.lon_deg, s.lat_deg))
                .collect();
            json!({"type": "LineString", "coordinates": coords})
        };
        let [r, g, b] = t.rgb(i);
        features.push(json!({
            "type": "Feature",
            "geometry": geometry,
            "properties": {
                "name": t.topic,
                "topic": t.topic,
                "type": t.type_name,
                "kind": "track",
                "messages": t.messages,
                "points": kept.len(),
                "start_s": first.stamp_ns as f64 * 1e-9,
                "end_s": last.stamp_ns as f64 * 1e-9,
                "stroke": format!("#{r:02x}{g:02x}{b:02x}"),
            },
        }));
        points += kept.len() as u64;
    }
    for l in landmarks {
        let mut props = json!({
            "name": l.name,
            "kind": l.kind.name(),
        });
        if l.depth_m.is_finite() {
            props["depth_m"] = json!(l.depth_m);
        }
        if let Some(t) = l.stamp_ns {
            props["time_s"] = json!(t as f64 * 1e-9);
        }
        features.push(json!({
            "type": "Feature",
            "geometry": {"type": "Point", "coordinates": position(l.lon_deg, l.lat_deg)},
            "properties": props,
        }));
        points += 1;
    }
    let doc = json!({
        "type": "FeatureCollection",
        "name": name,
        "features": features,
    });
    serde_json::to_writer(&mut *w, &doc).map_err(io::Error::other)?;
    writeln!(w)?;
    Ok(points)
}
