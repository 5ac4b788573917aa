//! KML 2.2 for Google Earth (paper 002 drew its manoeuvres there).
//!
//! A Document with one Style per track and, in folders:
//! - *Tracks*: one Placemark per track, named by its topic, holding one
//!   LineString (`lon,lat,alt` with `alt = -depth`, 0 where the stream has no
//!   depth); `altitudeMode` is `clampToGround` (drawn on the sea surface, the
//!   default) or `absolute` (at `-depth` below sea level). A track with a
//!   single point is a Point instead (a line needs two).
//! - *GPS fixes*: one small point per kept `sensor/gps` fix.
//! - *Buoy*: the buoy's broadcast positions (`sensor/modem`).
//! - *LBL transponders*: from the run's metadata.
//!
//! Colours (`aabbggrr`): truth green, `ains/nav` red, `positioning/fix`
//! orange, `lbl/nav` magenta, GPS yellow, others blue, cyan, purple...

use std::io::{self, Write};

use super::xml::escape;
use super::{KmlAltitude, Landmark, LandmarkKind, Track, TrackKind};

/// What goes into the file.
#[derive(Debug)]
pub struct Document<'a> {
    /// Document name.
    pub name: String,
    /// Tracks with at least one usable position.
    pub tracks: &'a [&'a Track],
    /// Buoy broadcasts and transponders.
    pub landmarks: &'a [Landmark],
    /// Altitude mode of the tracks.
    pub altitude: KmlAltitude,
}

/// `aabbggrr`, opaque.
fn kml_color(rgb: [u8; 3]) -> String {
    format!("ff{:02x}{:02x}{:02x}", rgb[2], rgb[1], rgb[0])
}

fn mode(a: KmlAltitude) -> &'static str {
    match a {
        KmlAltitude::ClampToGround => "clampToGround",
        KmlAltitude::Absolute => "absolute",
    }
}

/// `-depth` (0 where unknown), never `-0`.
fn altitude(depth_m: f64) -> f64 {
    if depth_m.is_finite() {
        0.0 - depth_m
    } else {
        0.0
    }
}

fn coord(lon: f64, lat: f64, alt: f64) -> String {
    format!("{lon:.8},{lat:.8},{alt:.3}")
}

fn point_style(
    w: &mut impl Write,
    id: &str,
    rgb: [u8; 3],
    scale: f64,
    icon: &str,
) -> io::Result<()> {
    writeln!(
        w,
        "<Style id=\"{id}\"><IconStyle><color>{}</color><scale>{scale}</scale>\
         <Icon><href>http://maps.google.com/mapfiles/kml/shapes/{icon}.png</href></Icon></IconStyle>\
         <LabelStyle><scale>0</scale></LabelStyle></Style>",
        kml_color(rgb)
    )
}

/// Writes the document; returns the number of points written.
pub fn write(w: &mut impl Write, doc: &Document<'_>) -> io::Result<u64> {
    let mut points = 0u64;
    writeln!(w, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>")?;
    writeln!(w, "<kml xmlns=\"http://www.opengis.net/kml/2.2\">")?;
    writeln!(w, "<Document>")?;
    writeln!(w, "<name>{}</name>", escape(&doc.name))?;
    writeln!(
        w,
        "<description>nauta export: {} track(s); altitude -depth, {}</description>",
        doc.tracks.len(),
        mode(doc.altitude)
    )?;
    for (i, t) in doc.tracks.iter().enumerate() {
        writeln!(
            w,
            "<Style id=\"track{i}\"><LineStyle><color>{}</color><width>3</width></LineStyle></Style>",
            kml_color(t.rgb(i))
        )?;
    }
    point_style(w, "gps", [255, 230, 0], 0.5, "placemark_circle")?;
    point_style(w, "buoy", [0, 170, 255], 0.9, "triangle")?;
    point_style(w, "transponder", [255, 60, 60], 0.9, "square")?;

    writeln!(w, "<Folder><name>Tracks</name>")?;
    for (i, t) in doc.tracks.iter().enumerate() {
        let kept: Vec<_> = t.samples.iter().filter(|s| s.has_position()).collect();
        let (Some(first), Some(last)) = (kept.first(), kept.last()) else {
            continue;
        };
        writeln!(
            w,
            "<Placemark><name>{}</name><description>{}: {} messages, {} points, stamps {:.1}-{:.1} s</description><styleUrl>#track{i}</styleUrl>",
            escape(&t.topic),
            escape(&t.type_name),
            t.messages,
            kept.len(),
            first.stamp_ns as f64 * 1e-9,
            last.stamp_ns as f64 * 1e-9,
        )?;
        if kept.len() == 1 {
            writeln!(
                w,
                "<Point><altitudeMode>{}</altitudeMode><coordinates>{}</coordinates></Point>",
                mode(doc.altitude),
                coord(first.lon_deg, first.lat_deg, altitude(first.depth_m))
            )?;
        } else {
            writeln!(
                w,
                "<LineString><tessellate>1</tessellate><altitudeMode>{}</altitudeMode><coordinates>",
                mode(doc.altitude)
            )?;
            for s in &kept {
                writeln!(w, "{}", coord(s.lon_deg, s.lat_deg, altitude(s.depth_m)))?;
            }
            writeln!(w, "</coordinates></LineString>")?;
        }
        writeln!(w, "</Placemark>")?;
        points += kept.len() as u64;
    }
    writeln!(w, "</Folder>")?;

    for t in doc.tracks.iter().filter(|t| t.kind == TrackKind::Gps) {
        writeln!(w, "<Folder><name>GPS fixes ({})</name>", escape(&t.topic))?;
        for s in t.samples.iter().filter(|s| s.has_position()) {
            writeln!(
                w,
                "<Placemark><description>t = {:.1} s, σ = {:.1} m</description><styleUrl>#gps</styleUrl>\
                 <Point><coordinates>{}</coordinates></Point></Placemark>",
                s.stamp_ns as f64 * 1e-9,
                s.pos_std_ned_m[0],
                coord(s.lon_deg, s.lat_deg, 0.0)
            )?;
            points += 1;
        }
        writeln!(w, "</Folder>")?;
    }

    for (kind, folder) in [
        (LandmarkKind::Buoy, "Buoy"),
        (LandmarkKind::Transponder, "LBL transponders"),
    ] {
        let of_kind: Vec<_> = doc.landmarks.iter().filter(|l| l.kind == kind).collect();
        if of_kind.is_empty() {
            continue;
        }
        writeln!(w, "<Folder><name>{folder}</name>")?;
        for l in of_kind {
            let depth = if l.depth_m.is_finite() {
                format!(", depth {:.1} m", l.depth_m)
            } else {
                String::new()
            };
            writeln!(
                w,
                "<Placemark><name>{}</name><description>{}{depth}</description><styleUrl>#{}</styleUrl>\
                 <Point><altitudeMode>{}</altitudeMode><coordinates>{}</coordinates></Point></Placemark>",
                escape(&l.name),
                escape(&l.name),
                kind.name(),
                mode(doc.altitude),
                coord(l.lon_deg, l.lat_deg, altitude(l.depth_m))
            )?;
            points += 1;
        }
        writeln!(w, "</Folder>")?;
    }
    writeln!(w, "</Document>")?;
    writeln!(w, "</kml>")?;
    Ok(points)
}
