//! The tracks of a recording: every message of a position (or attitude) type,
//! checked ([`crate::checked`]) and turned into a [`Sample`] in the units of the exports (degrees, metres),
//! decimated for the map formats; and the buoy's broadcast positions.

use nauta_estimation::frames::{Frd, Ned, Rotation};
use std::collections::{BTreeMap, HashMap};

use nauta_estimation::attitude::{to_euler, wrap_pi};
use nauta_messages::{
    AttitudeEstimate, BuoyRange, GpsFix, LblSolution, Message, NavSolution, PositionFix, TruthState,
};

use super::{Format, RunInfo};
use crate::checked::{Checked, Rejection, Value};
use crate::reader::{Channel, RecordedMessage, Recording};

/// What a track's type carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TrackKind {
    /// `nauta.TruthState.v1`: the simulator's truth.
    Truth,
    /// `nauta.NavSolution.v1`: aided-INS solution (or a smoothed track).
    Nav,
    /// `nauta.PositionFix.v1`: buoy positioning fix.
    Fix,
    /// `nauta.LblSolution.v1`: LBL solution, local north/east.
    Lbl,
    /// `nauta.GpsFix.v1`: surface GPS fix.
    Gps,
    /// `nauta.AttitudeEstimate.v1`: attitude only (CSV).
    Attitude,
}

impl TrackKind {
    /// The kind of channels of `type_name`, if it is a track.
    pub fn of(type_name: &str) -> Option<TrackKind> {
        Some(match type_name {
            TruthState::TYPE_NAME => TrackKind::Truth,
            NavSolution::TYPE_NAME => TrackKind::Nav,
            PositionFix::TYPE_NAME => TrackKind::Fix,
            LblSolution::TYPE_NAME => TrackKind::Lbl,
            GpsFix::TYPE_NAME | nauta_messages::GpsFixV1::TYPE_NAME => TrackKind::Gps,
            AttitudeEstimate::TYPE_NAME => TrackKind::Attitude,
            _ => return None,
        })
    }

    /// True for the types the export reads: the tracks and the buoy.
    pub fn is_exported(type_name: &str) -> bool {
        TrackKind::of(type_name).is_some() || type_name == BuoyRange::TYPE_NAME
    }

    /// True for the kinds that carry a position.
    pub fn is_position(self) -> bool {
        self != TrackKind::Attitude
    }

    /// True for positions in local north/east metres.
    pub fn is_local(self) -> bool {
        self == TrackKind::Lbl
    }

    /// The position types, for messages.
    pub const POSITION_TYPES: &'static str = "nauta.TruthState.v1, nauta.NavSolution.v1, \
        nauta.PositionFix.v1, nauta.LblSolution.v1 (with an origin), nauta.GpsFix.v1";
}

/// One message of a track in export units. A field that the type does not
/// carry, or that was not finite, is NaN.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// The message's stamp, ns (run clock).
    pub stamp_ns: u64,
    /// When the logger received it, ns since the Unix epoch.
    pub log_time_ns: u64,
    /// The publisher's sequence number.
    pub seq: u64,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees, in [-180, 180).
    pub lon_deg: f64,
    /// Depth, m, positive down.
    pub depth_m: f64,
    /// North of the origin, m (local tracks).
    pub north_m: f64,
    /// East of the origin, m (local tracks).
    pub east_m: f64,
    /// Velocity over ground, NED, m/s.
    pub vel_ned_m_s: [f64; 3],
    /// Roll, pitch, yaw (ZYX), degrees; yaw in [-180, 180].
    pub rpy_deg: [f64; 3],
    /// Position standard deviation north, east, down, m.
    pub pos_std_ned_m: [f64; 3],
    /// Correlation of the north and east position errors.
    pub corr_ne: f64,
    /// Velocity standard deviation north, east, down, m/s.
    pub vel_std_ned_m_s: [f64; 3],
    /// Standard deviation of the attitude error about north, east, down, degrees.
    pub att_std_ned_deg: [f64; 3],
}

const NAN3: [f64; 3] = [f64::NAN; 3];

impl Sample {
    /// A sample with nothing but its times.
    pub fn empty(stamp_ns: u64, log_time_ns: u64, seq: u64) -> Sample {
        Sample {
            stamp_ns,
            log_time_ns,
            seq,
            lat_deg: f64::NAN,
            lon_deg: f64::NAN,
            depth_m: f64::NAN,
            north_m: f64::NAN,
            east_m: f64::NAN,
            vel_ned_m_s: NAN3,
            rpy_deg: NAN3,
            pos_std_ned_m: NAN3,
            corr_ne: f64::NAN,
            vel_std_ned_m_s: NAN3,
            att_std_ned_deg: NAN3,
        }
    }

    /// True when latitude and longitude are usable (finite, within ±90° and ±180°).
    pub fn has_position(&self) -> bool {
        self.lat_deg.is_finite()
            && self.lon_deg.is_finite()
            && self.lat_deg.abs() <= 90.0
            && self.lon_deg.abs() <= 180.0
    }

    /// Sets latitude and longitude from radians (longitude wrapped to [-180, 180)).
    fn set_geodetic(&mut self, lat_rad: f64, lon_rad: f64) {
        self.lat_deg = lat_rad.to_degrees();
        let mut lon = wrap_pi(lon_rad).to_degrees();
        if lon >= 180.0 {
            lon -= 360.0;
        }
        self.lon_deg = lon;
    }
}

/// Roll, pitch and yaw (ZYX) of a body → NED attitude, degrees.
fn rpy_deg(q: &Rotation<Frd, Ned>) -> [f64; 3] {
    let (r, p, y) = to_euler(&q.to_nalgebra());
    [r.to_degrees(), p.to_degrees(), y.to_degrees()]
}

/// The sample of a checked value (`None`: not a track type).
fn sample_of(value: &Value, base: Sample) -> Option<Sample> {
    let mut s = base;
    match value {
        Value::Truth(m) => {
            s.set_geodetic(m.lat_rad, m.lon_rad);
            s.depth_m = m.depth_m;
            s.vel_ned_m_s = m.vel_ned_m_s.to_array();
            s.rpy_deg = rpy_deg(&m.attitude);
        }
        Value::Nav(m) => {
            s.set_geodetic(m.lat_rad, m.lon_rad);
            s.depth_m = m.depth_m;
            s.vel_ned_m_s = m.vel_ned_m_s.to_array();
            if let Some(q) = &m.attitude {
                s.rpy_deg = rpy_deg(q);
            }
            s.pos_std_ned_m = m.pos_std_ned_m.to_array();
            s.vel_std_ned_m_s = m.vel_std_ned_m_s.to_array();
        }
        Value::Fix(m) => {
            s.set_geodetic(m.lat_rad, m.lon_rad);
            s.pos_std_ned_m = [m.std_north_m, m.std_east_m, f64::NAN];
            s.corr_ne = m.corr_ne;
        }
        Value::Gps(m) => {
            s.set_geodetic(m.lat_rad, m.lon_rad);
            // The GPS σ is per horizontal axis.
            s.pos_std_ned_m = [m.horizontal_std_m, m.horizontal_std_m, f64::NAN];
        }
        Value::Lbl(m) => {
            s.north_m = m.x_m;
            s.east_m = m.y_m;
            let (pnn, pee, pne) = (m.p[0][0], m.p[1][1], m.p[0][1]);
            s.pos_std_ned_m = [pnn.sqrt(), pee.sqrt(), f64::NAN];
            s.corr_ne = pne / (pnn * pee).sqrt();
        }
        Value::Attitude(m) => {
            s.rpy_deg = rpy_deg(&m.attitude);
            s.att_std_ned_deg = m.std_rad.to_array().map(f64::to_degrees);
        }
        _ => return None,
    }
    Some(s)
}

/// The messages of one channel of a track type.
#[derive(Debug, Clone)]
pub struct Track {
    /// Topic.
    pub topic: String,
    /// Pinned type name.
    pub type_name: String,
    /// What it carries.
    pub kind: TrackKind,
    /// Samples kept (all of them for CSV; the decimated usable positions
    /// otherwise).
    pub samples: Vec<Sample>,
    /// Messages decoded.
    pub messages: u64,
    /// Messages without a usable position.
    pub invalid: u64,
}

impl Track {
    /// True when at least one sample has a usable position.
    pub fn has_position(&self) -> bool {
        self.samples.iter().any(Sample::has_position)
    }

    /// Samples with a usable position.
    pub fn points(&self) -> u64 {
        self.samples.iter().filter(|s| s.has_position()).count() as u64
    }

    pub(crate) fn summary(&self, written: u64) -> super::TrackSummary {
        super::TrackSummary {
            topic: self.topic.clone(),
            type_name: self.type_name.clone(),
            messages: self.messages,
            invalid: self.invalid,
            written,
        }
    }

    /// The track's colour (red, green, blue), fixed for the well-known topics.
    pub fn rgb(&self, index: usize) -> [u8; 3] {
        match self.topic.as_str() {
            "sim/truth" => [0, 200, 0],
            "ains/nav" => [230, 30, 30],
            "positioning/fix" => [255, 140, 0],
            "lbl/nav" => [200, 0, 200],
            "sensor/gps" => [255, 230, 0],
            _ => {
                const OTHERS: [[u8; 3]; 5] = [
                    [30, 120, 255],
                    [0, 200, 200],
                    [140, 80, 220],
                    [160, 100, 40],
                    [255, 105, 180],
                ];
                OTHERS[index % OTHERS.len()]
            }
        }
    }
}

/// A point of interest: a buoy broadcast or an LBL transponder.
#[derive(Debug, Clone, PartialEq)]
pub struct Landmark {
    /// What it is.
    pub kind: LandmarkKind,
    /// Short name (`buoy 30.0 s`, `transponder 1`).
    pub name: String,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Depth, m (NaN when unknown).
    pub depth_m: f64,
    /// Stamp of the broadcast, ns (buoy).
    pub stamp_ns: Option<u64>,
}

/// Kinds of [`Landmark`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LandmarkKind {
    /// The buoy's broadcast position (`sensor/modem`).
    Buoy,
    /// An LBL transponder (from the run's metadata).
    Transponder,
}

impl LandmarkKind {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            LandmarkKind::Buoy => "buoy",
            LandmarkKind::Transponder => "transponder",
        }
    }
}

#[derive(Debug, Clone, Copy)]
enum Slot {
    Track(usize),
    Buoy,
    Ignore,
}

#[derive(Debug)]
struct Builder {
    track: Track,
    last_kept_ns: Option<u64>,
    tail: Option<Sample>,
}

/// Gathers tracks while a recording is read.
#[derive(Debug)]
pub(crate) struct Collector {
    keep_all: bool,
    period_ns: u64,
    slots: HashMap<u16, Slot>,
    builders: Vec<Builder>,
    buoy: Vec<Landmark>,
    failures: BTreeMap<String, u64>,
}

/// The tracks of a recording, ready to write.
#[derive(Debug)]
pub(crate) struct Collected {
    /// Tracks: truth, estimates, LBL, GPS, attitude; by topic within a kind.
    pub tracks: Vec<Track>,
    /// Buoy broadcasts and transponders.
    pub landmarks: Vec<Landmark>,
    /// Messages of track channels that did not decode, by topic.
    pub decode_failures: BTreeMap<String, u64>,
}

impl Collector {
    /// `keep_all`: every message (CSV); otherwise usable positions at most one
    /// per `period_ns` of stamp, and the last one.
    pub fn new(keep_all: bool, period_ns: u64) -> Self {
        Collector {
            keep_all,
            period_ns,
            slots: HashMap::new(),
            builders: Vec::new(),
            buoy: Vec::new(),
            failures: BTreeMap::new(),
        }
    }

    /// Takes in one recorded message and its checked value.
    pub fn observe(
        &mut self,
        ch: &Channel,
        msg: &RecordedMessage<'_>,
        checked: Option<&Result<Checked, Rejection>>,
    ) {
        let slot = *self.slots.entry(ch.id).or_insert_with(|| {
            if ch.message_encoding != crate::MESSAGE_ENCODING {
                return Slot::Ignore;
            }
            match TrackKind::of(&ch.type_name) {
                Some(TrackKind::Attitude) if !self.keep_all => Slot::Ignore,
                Some(kind) => {
                    self.builders.push(Builder {
                        track: Track {
                            topic: ch.topic.clone(),
                            type_name: ch.type_name.clone(),
                            kind,
                            samples: Vec::new(),
                            messages: 0,
                            invalid: 0,
                        },
                        last_kept_ns: None,
                        tail: None,
                    });
                    Slot::Track(self.builders.len() - 1)
                }
                None if ch.type_name == BuoyRange::TYPE_NAME => Slot::Buoy,
                None => Slot::Ignore,
            }
        });
        let Some(checked) = checked else {
            return;
        };
        let base = Sample::empty(msg.publish_time_ns, msg.log_time_ns, 0);
        match (slot, checked) {
            (Slot::Ignore, _) => {}
            (_, Err(Rejection::Undecodable(_))) => {
                *self.failures.entry(ch.topic.clone()).or_insert(0) += 1
            }
            (
                Slot::Buoy,
                Ok(Checked {
                    value: Value::Buoy(m),
                    ..
                }),
            ) => {
                let mut s = base;
                s.set_geodetic(m.buoy_lat_rad, m.buoy_lon_rad);
                self.buoy.push(Landmark {
                    kind: LandmarkKind::Buoy,
                    name: format!("buoy {:.1} s", m.stamp_ns as f64 * 1e-9),
                    lat_deg: s.lat_deg,
                    lon_deg: s.lon_deg,
                    depth_m: m.buoy_depth_m,
                    stamp_ns: Some(m.stamp_ns),
                });
            }
            (Slot::Buoy, _) => {}
            (Slot::Track(i), checked) => {
                let Some(b) = self.builders.get_mut(i) else {
                    return;
                };
                // A message that failed its checks is a row of its stamp and
                // sequence number with no values (CSV), and no map point.
                let s = match checked {
                    Ok(c) => sample_of(&c.value, Sample { seq: c.seq, ..base }),
                    Err(Rejection::Invalid { stamp_ns, seq, .. }) => Some(Sample {
                        stamp_ns: *stamp_ns,
                        seq: *seq,
                        ..base
                    }),
                    Err(Rejection::Undecodable(_)) => None,
                };
                if let Some(s) = s {
                    b.push(s, checked.is_err(), self.keep_all, self.period_ns);
                }
            }
        }
    }

    /// Ends collection: places local tracks with the run's origin, adds the
    /// transponders, and says in `notes` what the map formats leave out.
    pub fn finish(self, run: &RunInfo, format: Format, notes: &mut Vec<String>) -> Collected {
        let maps = format != Format::Csv;
        let mut tracks: Vec<Track> = self
            .builders
            .into_iter()
            .map(|mut b| {
                if let Some(t) = b.tail.take() {
                    b.track.samples.push(t);
                }
                b.track
            })
            .collect();
        for t in &mut tracks {
            if t.kind.is_local() {
                match run.origin.as_ref().map(|o| &o.value) {
                    Some(o) => {
                        for s in &mut t.samples {
                            if s.north_m.is_finite() && s.east_m.is_finite() {
                                let (lat, lon) = o.to_geodetic(s.north_m, s.east_m);
                                s.set_geodetic(lat, lon);
                            }
                        }
                    }
                    None if maps => notes.push(format!(
                        "{}: local north/east metres and the recording names no origin \
                         (nauta.run origin_lat_deg/origin_lon_deg or the manifest's [site]); \
                         left out of the map tracks: give --origin LAT,LON to place it",
                        t.topic
                    )),
                    None => notes.push(format!(
                        "{}: no origin in the recording (give --origin LAT,LON): its rows \
                         have north_m/east_m but no latitude/longitude",
                        t.topic
                    )),
                }
            }
            if maps && t.kind.is_position() && !t.has_position() && t.messages > 0 {
                if !t.kind.is_local() || run.origin.is_some() {
                    notes.push(format!(
                        "{}: none of its {} messages has a usable position; left out",
                        t.topic, t.messages
                    ));
                }
            } else if t.invalid > 0 {
                notes.push(format!(
                    "{}: {} of {} messages failed their checks (a non-finite or out-of-range field){}",
                    t.topic,
                    t.invalid,
                    t.messages,
                    if maps { " and were left out" } else { "" }
                ));
            }
        }
        tracks.sort_by(|a, b| (a.kind, &a.topic).cmp(&(b.kind, &b.topic)));

        let mut landmarks = self.buoy;
        if !run.transponders.is_empty() && format.is_map() {
            match run.origin.as_ref().map(|o| &o.value) {
                Some(o) => landmarks.extend(run.transponders.iter().map(|t| {
                    let mut s = Sample::empty(0, 0, 0);
                    let (lat, lon) = o.to_geodetic(t.north_m, t.east_m);
                    s.set_geodetic(lat, lon);
                    Landmark {
                        kind: LandmarkKind::Transponder,
                        name: format!("transponder {}", t.id),
                        lat_deg: s.lat_deg,
                        lon_deg: s.lon_deg,
                        depth_m: t.depth_m,
                        stamp_ns: None,
                    }
                })),
                None => notes.push(format!(
                    "{} LBL transponder(s) in the metadata but no origin to place them; left out",
                    run.transponders.len()
                )),
            }
        }
        Collected {
            tracks,
            landmarks,
            decode_failures: self.failures,
        }
    }
}

impl Builder {
    /// Takes a sample; `rejected`: its message failed its checks.
    fn push(&mut self, s: Sample, rejected: bool, keep_all: bool, period_ns: u64) {
        let t = &mut self.track;
        t.messages += 1;
        let usable = !rejected
            && if t.kind.is_local() {
                s.north_m.is_finite() && s.east_m.is_finite()
            } else {
                !t.kind.is_position() || s.has_position()
            };
        if !usable {
            t.invalid += 1;
        }
        if keep_all {
            t.samples.push(s);
            return;
        }
        if !usable {
            return;
        }
        let keep = match self.last_kept_ns {
            None => true,
            // A stamp that goes back (a restarted publisher) starts afresh.
            Some(last) => s.stamp_ns < last || s.stamp_ns >= last.saturating_add(period_ns),
        };
        if keep {
            t.samples.push(s);
            self.last_kept_ns = Some(s.stamp_ns);
            self.tail = None;
        } else {
            self.tail = Some(s);
        }
    }
}

impl Collected {
    /// What the recording holds, for an error that finds no track.
    pub fn describe(&self, rec: &Recording) -> String {
        let mut out = String::new();
        let local_without_origin = self
            .tracks
            .iter()
            .filter(|t| t.kind.is_local() && !t.has_position() && t.messages > 0)
            .map(|t| t.topic.as_str())
            .collect::<Vec<_>>();
        if !local_without_origin.is_empty() {
            out.push_str(&format!(
                "{} is in local metres and there is no origin (give --origin LAT,LON); ",
                local_without_origin.join(", ")
            ));
        }
        let empty: Vec<&str> = self
            .tracks
            .iter()
            .filter(|t| t.kind.is_position() && !t.kind.is_local() && !t.has_position())
            .map(|t| t.topic.as_str())
            .collect();
        if !empty.is_empty() {
            out.push_str(&format!("{} has no usable position; ", empty.join(", ")));
        }
        let mut chans: Vec<String> = rec
            .channels
            .values()
            .map(|c| format!("{} ({})", c.topic, c.type_name))
            .collect();
        chans.sort();
        chans.dedup();
        if chans.is_empty() {
            out.push_str("it has no channels");
        } else {
            out.push_str(&format!("its channels are {}", chans.join(", ")));
        }
        format!("{out}; position types are {}", TrackKind::POSITION_TYPES)
    }
}
