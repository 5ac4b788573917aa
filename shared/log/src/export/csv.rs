//! CSV: one file, a header line ([`COLUMNS`]) and one row per message of every
//! track and attitude channel, never decimated. Rows are grouped by channel
//! (truth, estimates, LBL, GPS, attitude; by topic within each) and in
//! recording order within a channel. A cell is empty where the channel's type
//! does not carry the value; a message that fails its checks
//! ([`crate::checked`]: a non-finite or out-of-range field) is a row of its
//! stamp and type with every value empty. Numbers are written in the shortest
//! form that reads back to the same `f64`.
//!
//! Columns:
//! - `time_s`: stamp, s (run clock); `stamp_ns`: the same, exact; `topic`;
//! - `lat_deg`, `lon_deg` (WGS84), `depth_m` (positive down);
//! - `north_m`, `east_m`: local position from the run's origin (`lbl/nav`
//!   natively; the other tracks when the origin is known);
//! - `vel_north_m_s`, `vel_east_m_s`, `vel_down_m_s`: velocity over ground;
//! - `roll_deg`, `pitch_deg`, `yaw_deg`: ZYX Euler angles of `q_nb`, yaw in
//!   [-180, 180];
//! - `std_north_m`, `std_east_m`, `std_down_m`, `corr_north_east`: position
//!   standard deviations (GPS: its per-axis horizontal σ) and the north-east
//!   correlation (`positioning/fix`, `lbl/nav`);
//! - `std_vel_north_m_s`, `std_vel_east_m_s`, `std_vel_down_m_s`;
//! - `std_att_north_deg`, `std_att_east_deg`, `std_att_down_deg`: attitude
//!   error about north, east, down (`attitude/estimate`);
//! - `type`: the channel's pinned type name.

use std::io::{self, Write};

use super::{GeoOrigin, Sample, Track};

/// The header line's columns, in order.
pub const COLUMNS: [&str; 25] = [
    "time_s",
    "stamp_ns",
    "topic",
    "lat_deg",
    "lon_deg",
    "depth_m",
    "north_m",
    "east_m",
    "vel_north_m_s",
    "vel_east_m_s",
    "vel_down_m_s",
    "roll_deg",
    "pitch_deg",
    "yaw_deg",
    "std_north_m",
    "std_east_m",
    "std_down_m",
    "corr_north_east",
    "std_vel_north_m_s",
    "std_vel_east_m_s",
    "std_vel_down_m_s",
    "std_att_north_deg",
    "std_att_east_deg",
    "std_att_down_deg",
    "type",
];

/// A field as RFC 4180 wants it (quoted when it holds a comma, quote or line break).
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

fn push_num(row: &mut String, x: f64) {
    row.push(',');
    if x.is_finite() {
        // `+ 0.0` turns -0 into 0.
        row.push_str(&(x + 0.0).to_string());
    }
}

fn row(topic: &str, type_name: &str, s: &Sample, origin: Option<&GeoOrigin>) -> String {
    let mut r = String::with_capacity(256);
    r.push_str(&(s.stamp_ns as f64 * 1e-9).to_string());
    r.push(',');
    r.push_str(&s.stamp_ns.to_string());
    r.push(',');
    r.push_str(topic);
    push_num(&mut r, s.lat_deg);
    push_num(&mut r, s.lon_deg);
    push_num(&mut r, s.depth_m);
    let (north, east) = match origin {
        Some(o) if !s.north_m.is_finite() && s.has_position() => {
            o.to_local(s.lat_deg.to_radians(), s.lon_deg.to_radians())
        }
        _ => (s.north_m, s.east_m),
    };
    push_num(&mut r, north);
    push_num(&mut r, east);
    for v in s.vel_ned_m_s {
        push_num(&mut r, v);
    }
    for v in s.rpy_deg {
        push_num(&mut r, v);
    }
    for v in s.pos_std_ned_m {
        push_num(&mut r, v);
    }
    push_num(&mut r, s.corr_ne);
    for v in s.vel_std_ned_m_s {
        push_num(&mut r, v);
    }
    for v in s.att_std_ned_deg {
        push_num(&mut r, v);
    }
    r.push(',');
    r.push_str(type_name);
    r.push('\n');
    r
}

/// Writes the header and every sample of `tracks`; returns the number of rows.
pub fn write(w: &mut impl Write, tracks: &[Track], origin: Option<&GeoOrigin>) -> io::Result<u64> {
    writeln!(w, "{}", COLUMNS.join(","))?;
    let mut rows = 0u64;
    for t in tracks {
        let topic = field(&t.topic);
        let type_name = field(&t.type_name);
        for s in &t.samples {
            w.write_all(row(&topic, &type_name, s, origin).as_bytes())?;
            rows += 1;
        }
    }
    Ok(rows)
}
