//! The channel files of `nauta import csv`: each one's columns (with the
//! units they may be given in) and how its rows become messages. The
//! README's table lists the same columns.

use anyhow::bail;
use nauta_estimation::frames::{Frd, Ned, Rotation};
use nauta_estimation::local::flat;
use nauta_messages::*;

use super::site::{CsvSite, SOUND_SPEED_RANGE_M_S};
use super::table::{Col, DEG_TO_RAD as DEG, Table};

const RPM: f64 = 2.0 * std::f64::consts::PI / 60.0;
const T: Col = Col::real("t", &[("t_s", 1.0)]);

/// `imu.csv`.
pub const IMU: &[Col] = &[
    T,
    Col::real("gx", &[("gyro_x_rad_s", 1.0), ("gyro_x_deg_s", DEG)]),
    Col::real("gy", &[("gyro_y_rad_s", 1.0), ("gyro_y_deg_s", DEG)]),
    Col::real("gz", &[("gyro_z_rad_s", 1.0), ("gyro_z_deg_s", DEG)]),
    Col::real("ax", &[("accel_x_m_s2", 1.0)]),
    Col::real("ay", &[("accel_y_m_s2", 1.0)]),
    Col::real("az", &[("accel_z_m_s2", 1.0)]),
    Col::real("mx", &[("mag_x_ut", 1.0)]),
    Col::real("my", &[("mag_y_ut", 1.0)]),
    Col::real("mz", &[("mag_z_ut", 1.0)]),
    Col::real("interval", &[("interval_s", 1.0)]),
];

/// `dvl.csv`.
pub const DVL: &[Col] = &[
    T,
    Col::real("vx", &[("vel_x_m_s", 1.0)]),
    Col::real("vy", &[("vel_y_m_s", 1.0)]),
    Col::real("vz", &[("vel_z_m_s", 1.0)]),
    Col::real("altitude", &[("altitude_m", 1.0)]),
    Col::int("lock", &[("bottom_lock", 1.0)], 0, 1),
    Col::int("beams", &[("beams_valid", 1.0)], 0, 15),
    Col::real("fom", &[("figure_of_merit_m_s", 1.0)]),
];

/// `ahrs.csv`.
pub const AHRS: &[Col] = &[
    T,
    Col::real("roll", &[("roll_rad", 1.0), ("roll_deg", DEG)]),
    Col::real("pitch", &[("pitch_rad", 1.0), ("pitch_deg", DEG)]),
    Col::real(
        "heading",
        &[("heading_mag_rad", 1.0), ("heading_mag_deg", DEG)],
    ),
];

/// `depth.csv`.
pub const DEPTH: &[Col] = &[T, Col::real("depth", &[("depth_m", 1.0)])];

/// `gps.csv`.
pub const GPS: &[Col] = &[
    T,
    Col::real("lat", &[("lat_deg", DEG), ("lat_rad", 1.0)]),
    Col::real("lon", &[("lon_deg", DEG), ("lon_rad", 1.0)]),
    Col::real("height", &[("height_m", 1.0)]),
    Col::real("std", &[("horizontal_std_m", 1.0)]),
    Col::int("quality", &[("quality", 1.0)], 0, 5),
    Col::int("satellites", &[("satellites", 1.0)], 0, 255),
    Col::real("vn", &[("vel_n_m_s", 1.0)]),
    Col::real("ve", &[("vel_e_m_s", 1.0)]),
    Col::real("vd", &[("vel_d_m_s", 1.0)]),
    Col::real("vstd", &[("vel_std_m_s", 1.0)]),
];

/// `modem.csv`.
pub const MODEM: &[Col] = &[
    T,
    Col::real("lat", &[("buoy_lat_deg", DEG), ("buoy_lat_rad", 1.0)]),
    Col::real("lon", &[("buoy_lon_deg", DEG), ("buoy_lon_rad", 1.0)]),
    Col::real("depth", &[("buoy_depth_m", 1.0)]),
    Col::real("tof", &[("time_of_flight_s", 1.0)]),
    Col::real("range", &[("range_m", 1.0)]),
    Col::real("c", &[("sound_speed_m_s", 1.0)]),
];

/// `lbl.csv`.
pub const LBL: &[Col] = &[
    T,
    Col::int("id", &[("transponder_id", 1.0)], 0, u32::MAX as i64),
    Col::real("rt", &[("round_trip_s", 1.0)]),
    Col::real("range", &[("range_m", 1.0)]),
    Col::real("ping", &[("interrogation_t_s", 1.0)]),
];

/// `propeller.csv`.
pub const PROPELLER: &[Col] = &[
    T,
    Col::real(
        "speed",
        &[("shaft_speed_rad_s", 1.0), ("shaft_speed_rpm", RPM)],
    ),
];

/// `truth.csv`.
pub const TRUTH: &[Col] = &[
    T,
    Col::real("lat", &[("lat_deg", DEG), ("lat_rad", 1.0)]),
    Col::real("lon", &[("lon_deg", DEG), ("lon_rad", 1.0)]),
    Col::real("depth", &[("depth_m", 1.0)]),
    Col::real("vn", &[("vel_n_m_s", 1.0)]),
    Col::real("ve", &[("vel_e_m_s", 1.0)]),
    Col::real("vd", &[("vel_d_m_s", 1.0)]),
    Col::real("roll", &[("roll_rad", 1.0), ("roll_deg", DEG)]),
    Col::real("pitch", &[("pitch_rad", 1.0), ("pitch_deg", DEG)]),
    Col::real("yaw", &[("yaw_rad", 1.0), ("yaw_deg", DEG)]),
    Col::real("distance", &[("distance_m", 1.0)]),
];

/// Stamps of an import: `t_s` minus the earliest time of every file, plus
/// 1 s (stamp 0 stays free, as `nauta import akit` keeps it), in ns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clock {
    /// The earliest time of every file (and every LBL interrogation), s.
    pub t0_s: f64,
}

/// The longest span an import may cover, s (the manifest's longest
/// duration, less the 2 s the import adds).
pub const MAX_SPAN_S: f64 = nauta_runtime::manifest::MAX_DURATION_S - 2.0;

impl Clock {
    /// The stamp of time `t_s` of row `r` of `table` (`what` names the
    /// column for the error).
    pub fn stamp(&self, t_s: f64, table: &Table, r: usize, key: &str) -> anyhow::Result<u64> {
        let dt = t_s - self.t0_s;
        if !(0.0..=MAX_SPAN_S).contains(&dt) {
            bail!(
                "{}: {t_s} s is {dt} s after the earliest time of the log; at most {MAX_SPAN_S} s are imported",
                table.at(r, key)
            );
        }
        // dt ≤ 30 days: (dt + 1) · 1e9 < 2.6e15, exact in u64.
        Ok(((dt + 1.0) * 1e9).round() as u64)
    }
}

/// Refuses a row whose stamp is not after the previous one's (or, when
/// `ties`, before it); `prev` is updated.
fn sorted(
    table: &Table,
    r: usize,
    stamp: u64,
    prev: &mut Option<(u64, usize)>,
    ties: bool,
) -> anyhow::Result<()> {
    if let Some((p, line)) = *prev
        && (stamp < p || (stamp == p && !ties))
    {
        bail!(
            "{}: time {} s is not after line {line}'s; rows must be sorted by time{}",
            table.at(r, "t"),
            table.get_or(r, "t", f64::NAN),
            if ties { " (equal times allowed)" } else { "" }
        );
    }
    *prev = Some((stamp, table.line(r)));
    Ok(())
}

fn header(stamp: u64, seq: usize) -> Header {
    Header::new(stamp, seq as u64, Role::Sensor, 0)
}

/// The value of column `key` of row `r`; the caller checked the column is there.
fn v(t: &Table, r: usize, key: &str) -> f64 {
    t.get_or(r, key, f64::NAN)
}

/// Every time of `t` (for the clock's origin).
pub fn times(t: &Table) -> impl Iterator<Item = f64> + '_ {
    (0..t.len()).map(|r| v(t, r, "t"))
}

/// `imu.csv` as `sensor/imu`. `interval_s`, when absent, is the time since
/// the previous row (the first row: the next row's).
pub fn imu(t: &Table, clock: &Clock) -> anyhow::Result<Vec<SensorMessage>> {
    t.require(IMU, &["t", "gx", "gy", "gz", "ax", "ay", "az"])?;
    let mag = t.all_or_none(IMU, &["mx", "my", "mz"])?;
    if !t.has("interval") && t.len() < 2 {
        bail!(
            "{}: one row and no interval_s column: the sample's interval is unknown",
            t.path
        );
    }
    let mut out = Vec::with_capacity(t.len());
    let mut prev = None;
    for r in 0..t.len() {
        let s = clock.stamp(v(t, r, "t"), t, r, "t")?;
        sorted(t, r, s, &mut prev, false)?;
        let interval_s = match t.get(r, "interval") {
            Some(i) => i,
            None if r == 0 => v(t, 1, "t") - v(t, 0, "t"),
            None => v(t, r, "t") - v(t, r - 1, "t"),
        };
        if !(interval_s > 0.0 && interval_s <= 10.0) {
            bail!(
                "{}: interval {interval_s} s is outside (0, 10] s",
                t.at(r, if t.has("interval") { "interval" } else { "t" })
            );
        }
        out.push(SensorMessage::Imu(ImuSample {
            header: header(s, r),
            gyro_rad_s: [v(t, r, "gx"), v(t, r, "gy"), v(t, r, "gz")],
            accel_m_s2: [v(t, r, "ax"), v(t, r, "ay"), v(t, r, "az")],
            mag_ut: if mag {
                [v(t, r, "mx"), v(t, r, "my"), v(t, r, "mz")]
            } else {
                [0.0; 3]
            },
            interval_s,
        }));
    }
    Ok(out)
}

/// True when `imu.csv` carries the magnetometer (the attitude's alignment needs it).
pub fn imu_has_magnetometer(t: &Table) -> bool {
    t.has("mx")
}

/// `dvl.csv` as `sensor/dvl`.
pub fn dvl(t: &Table, clock: &Clock) -> anyhow::Result<Vec<SensorMessage>> {
    t.require(DVL, &["t", "vx", "vy", "vz"])?;
    let mut out = Vec::with_capacity(t.len());
    let mut prev = None;
    for r in 0..t.len() {
        let s = clock.stamp(v(t, r, "t"), t, r, "t")?;
        sorted(t, r, s, &mut prev, false)?;
        let fom = t.get_or(r, "fom", 0.0);
        if fom < 0.0 {
            bail!("{}: {fom} is negative", t.at(r, "fom"));
        }
        out.push(SensorMessage::Dvl(DvlSample {
            header: header(s, r),
            velocity_body_m_s: [v(t, r, "vx"), v(t, r, "vy"), v(t, r, "vz")],
            altitude_m: t.get_or(r, "altitude", 0.0),
            beams_valid: t.get_or(r, "beams", 15.0) as u32,
            bottom_lock: t.get_or(r, "lock", 1.0) as u32,
            figure_of_merit_m_s: fom,
        }));
    }
    Ok(out)
}

/// `ahrs.csv` as `sensor/ahrs` (heading wrapped to [0, 2π)).
pub fn ahrs(t: &Table, clock: &Clock) -> anyhow::Result<Vec<SensorMessage>> {
    t.require(AHRS, &["t", "roll", "pitch", "heading"])?;
    let mut out = Vec::with_capacity(t.len());
    let mut prev = None;
    for r in 0..t.len() {
        let s = clock.stamp(v(t, r, "t"), t, r, "t")?;
        sorted(t, r, s, &mut prev, false)?;
        out.push(SensorMessage::Ahrs(AhrsSample {
            header: header(s, r),
            roll_rad: v(t, r, "roll"),
            pitch_rad: v(t, r, "pitch"),
            heading_mag_rad: wrap_2pi(v(t, r, "heading")),
        }));
    }
    Ok(out)
}

/// `x` in [0, 2π).
fn wrap_2pi(x: f64) -> f64 {
    let w = x.rem_euclid(2.0 * std::f64::consts::PI);
    // rem_euclid of a tiny negative number rounds up to 2π itself.
    if w >= 2.0 * std::f64::consts::PI {
        0.0
    } else {
        w
    }
}

/// `depth.csv` as `sensor/depth`.
pub fn depth(t: &Table, clock: &Clock) -> anyhow::Result<Vec<SensorMessage>> {
    t.require(DEPTH, &["t", "depth"])?;
    let mut out = Vec::with_capacity(t.len());
    let mut prev = None;
    for r in 0..t.len() {
        let s = clock.stamp(v(t, r, "t"), t, r, "t")?;
        sorted(t, r, s, &mut prev, false)?;
        out.push(SensorMessage::Depth(DepthSample {
            header: header(s, r),
            depth_m: v(t, r, "depth"),
        }));
    }
    Ok(out)
}

/// Refuses a latitude or longitude out of range (radians here).
fn check_lat_lon(t: &Table, r: usize, lat: &str, lon: &str) -> anyhow::Result<()> {
    let (la, lo) = (v(t, r, lat), v(t, r, lon));
    if !(la.abs() <= std::f64::consts::FRAC_PI_2) {
        bail!("{}: {}° is not a latitude", t.at(r, lat), la.to_degrees());
    }
    if !(lo.abs() <= std::f64::consts::PI) {
        bail!("{}: {}° is not a longitude", t.at(r, lon), lo.to_degrees());
    }
    Ok(())
}

/// `gps.csv` as `sensor/gps` (v2: with the velocity when its four columns are given).
pub fn gps(t: &Table, clock: &Clock) -> anyhow::Result<Vec<SensorMessage>> {
    t.require(GPS, &["t", "lat", "lon", "std"])?;
    let vel = t.all_or_none(GPS, &["vn", "ve", "vd", "vstd"])?;
    let mut out = Vec::with_capacity(t.len());
    let mut prev = None;
    for r in 0..t.len() {
        let s = clock.stamp(v(t, r, "t"), t, r, "t")?;
        sorted(t, r, s, &mut prev, false)?;
        check_lat_lon(t, r, "lat", "lon")?;
        let quality = t.get_or(r, "quality", 1.0) as u32;
        if quality == 3 {
            bail!(
                "{}: 3 is not a fix quality (0 none, 1 GPS, 2 DGPS, 4 RTK fixed, 5 RTK float)",
                t.at(r, "quality")
            );
        }
        for k in ["std", "vstd"] {
            if t.get(r, k).is_some_and(|x| x < 0.0) {
                bail!("{}: a standard deviation is not negative", t.at(r, k));
            }
        }
        out.push(SensorMessage::Gps(GpsFix {
            header: header(s, r),
            lat_rad: v(t, r, "lat"),
            lon_rad: v(t, r, "lon"),
            height_m: t.get_or(r, "height", 0.0),
            horizontal_std_m: v(t, r, "std"),
            quality,
            satellites: t.get_or(r, "satellites", 0.0) as u32,
            vel_ned_m_s: if vel {
                [v(t, r, "vn"), v(t, r, "ve"), v(t, r, "vd")]
            } else {
                [0.0; 3]
            },
            vel_std_m_s: t.get_or(r, "vstd", 0.0),
            velocity_valid: u32::from(vel),
            pad: 0,
        }));
    }
    Ok(out)
}

/// The sound speed of row `r` (its own column, else the site's).
fn sound_speed(t: &Table, r: usize, site: &CsvSite, why: &str) -> anyhow::Result<f64> {
    let (lo, hi) = SOUND_SPEED_RANGE_M_S;
    match t.get(r, "c") {
        Some(c) if (lo..=hi).contains(&c) => Ok(c),
        Some(c) => bail!("{}: {c} m/s is outside [{lo}, {hi}]", t.at(r, "c")),
        None => site.sound_speed_m_s.ok_or_else(|| {
            anyhow::anyhow!(
                "{}: {why} needs a sound speed: give sound_speed_m_s in site.toml",
                t.path
            )
        }),
    }
}

/// `modem.csv` as `sensor/modem`: paper 000's buoy message, the buoy's
/// position and the one-way time of flight (`range_m` / sound speed when
/// the log gives the range).
pub fn modem(t: &Table, clock: &Clock, site: &CsvSite) -> anyhow::Result<Vec<SensorMessage>> {
    t.require(MODEM, &["t", "lat", "lon", "depth"])?;
    let by_time = t.one_of(MODEM, "tof", "range")?;
    let mut out = Vec::with_capacity(t.len());
    let mut prev = None;
    for r in 0..t.len() {
        let s = clock.stamp(v(t, r, "t"), t, r, "t")?;
        sorted(t, r, s, &mut prev, false)?;
        check_lat_lon(t, r, "lat", "lon")?;
        let c = sound_speed(t, r, site, "a buoy message")?;
        let key = if by_time { "tof" } else { "range" };
        let x = v(t, r, key);
        if x < 0.0 {
            bail!("{}: {x} is negative", t.at(r, key));
        }
        out.push(SensorMessage::Modem(BuoyRange {
            header: header(s, r),
            buoy_lat_rad: v(t, r, "lat"),
            buoy_lon_rad: v(t, r, "lon"),
            buoy_depth_m: v(t, r, "depth"),
            time_of_flight_s: if by_time { x } else { x / c },
            sound_speed_m_s: c,
        }));
    }
    Ok(out)
}

/// One LBL reply in seconds, before stamping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LblRow {
    /// Reception time, s.
    pub t_s: f64,
    /// Transponder.
    pub id: u32,
    /// Round trip including the turnaround, s.
    pub round_trip_s: f64,
    /// When the ping was sent, s.
    pub ping_s: f64,
}

/// `lbl.csv`'s rows: the round trip as given, or from `range_m` as
/// `2 range / c + turnaround` (the inverse of paper 003's range from the
/// round trip, `r = c (t_rt − t_ta) / 2`); the ping is `interrogation_t_s`,
/// else the reception less the round trip.
pub fn lbl_rows(t: &Table, site: &CsvSite) -> anyhow::Result<Vec<LblRow>> {
    t.require(LBL, &["t", "id"])?;
    let by_time = t.one_of(LBL, "rt", "range")?;
    let mut out = Vec::with_capacity(t.len());
    for r in 0..t.len() {
        let id = v(t, r, "id") as u32;
        let Some(tp) = site.transponder(id) else {
            bail!(
                "{}: transponder {id} is not in site.toml's transponders{}",
                t.at(r, "id"),
                if site.transponders.is_empty() {
                    " (it has none)"
                } else {
                    ""
                }
            );
        };
        let round_trip_s = if by_time {
            let rt = v(t, r, "rt");
            if !(rt > 0.0) {
                bail!("{}: {rt} s is not a round trip", t.at(r, "rt"));
            }
            rt
        } else {
            let range = v(t, r, "range");
            if range < 0.0 {
                bail!("{}: {range} is negative", t.at(r, "range"));
            }
            let c = site.sound_speed_m_s.ok_or_else(|| {
                anyhow::anyhow!(
                    "{}: range_m needs a sound speed: give sound_speed_m_s in site.toml",
                    t.path
                )
            })?;
            let ta = tp.turnaround_s.or(site.turnaround_s).ok_or_else(|| {
                anyhow::anyhow!(
                    "{}: range_m needs transponder {id}'s turnaround: give turnaround_s in site.toml",
                    t.at(r, "range")
                )
            })?;
            2.0 * range / c + ta
        };
        let t_s = v(t, r, "t");
        let ping_s = t.get(r, "ping").unwrap_or(t_s - round_trip_s);
        if !(ping_s <= t_s) {
            bail!(
                "{}: the ping at {ping_s} s is after the reply at {t_s} s",
                t.at(r, "ping")
            );
        }
        out.push(LblRow {
            t_s,
            id,
            round_trip_s,
            ping_s,
        });
    }
    Ok(out)
}

/// `lbl.csv` as `sensor/lbl`, from [`lbl_rows`]; equal reception times are
/// allowed (two transponders heard at once).
pub fn lbl(t: &Table, rows: &[LblRow], clock: &Clock) -> anyhow::Result<Vec<SensorMessage>> {
    let mut out = Vec::with_capacity(rows.len());
    let mut prev = None;
    for (r, row) in rows.iter().enumerate() {
        let s = clock.stamp(row.t_s, t, r, "t")?;
        sorted(t, r, s, &mut prev, true)?;
        let ping = clock.stamp(row.ping_s, t, r, "ping")?;
        out.push(SensorMessage::Lbl(LblReply {
            header: header(s, r),
            transponder_id: row.id,
            pad: 0,
            interrogation_stamp_ns: ping,
            reply_stamp_ns: s,
            round_trip_s: row.round_trip_s,
        }));
    }
    Ok(out)
}

/// `propeller.csv` as `sensor/propeller`.
pub fn propeller(t: &Table, clock: &Clock) -> anyhow::Result<Vec<SensorMessage>> {
    t.require(PROPELLER, &["t", "speed"])?;
    let mut out = Vec::with_capacity(t.len());
    let mut prev = None;
    for r in 0..t.len() {
        let s = clock.stamp(v(t, r, "t"), t, r, "t")?;
        sorted(t, r, s, &mut prev, false)?;
        out.push(SensorMessage::Propeller(PropellerSample {
            header: header(s, r),
            shaft_speed_rad_s: v(t, r, "speed"),
        }));
    }
    Ok(out)
}

/// `truth.csv` as `sim/truth`: attitude body → NED from roll, pitch and
/// (true) yaw; the distance travelled is `distance_m`, else the horizontal
/// steps between rows summed.
pub fn truth(t: &Table, clock: &Clock) -> anyhow::Result<Vec<SensorMessage>> {
    t.require(
        TRUTH,
        &[
            "t", "lat", "lon", "depth", "vn", "ve", "vd", "roll", "pitch", "yaw",
        ],
    )?;
    let mut out = Vec::with_capacity(t.len());
    let mut prev = None;
    let mut distance_m = 0.0;
    for r in 0..t.len() {
        let s = clock.stamp(v(t, r, "t"), t, r, "t")?;
        sorted(t, r, s, &mut prev, false)?;
        check_lat_lon(t, r, "lat", "lon")?;
        let (lat, lon) = (v(t, r, "lat"), v(t, r, "lon"));
        if r > 0 {
            let (n, e) = flat::to_local(v(t, r - 1, "lat"), v(t, r - 1, "lon"), lat, lon);
            distance_m += n.hypot(e);
        }
        let q = Rotation::<Frd, Ned>::from_euler(v(t, r, "roll"), v(t, r, "pitch"), v(t, r, "yaw"))
            .to_wxyz();
        out.push(SensorMessage::Truth(TruthState {
            header: header(s, r),
            lat_rad: lat,
            lon_rad: lon,
            depth_m: v(t, r, "depth"),
            vel_ned_m_s: [v(t, r, "vn"), v(t, r, "ve"), v(t, r, "vd")],
            quat_nb: q,
            distance_m: t.get_or(r, "distance", distance_m),
            ..Default::default()
        }));
    }
    Ok(out)
}
