//! A recording read into what `nauta eval` and `nauta report` use: the truth,
//! the GPS fixes, every estimate stream, the LBL replies and the buoy
//! positions, each checked (DESIGN §4: a value that fails its check is
//! counted, never trusted) and sorted by stamp.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Matrix2, UnitQuaternion, Vector3};
use nauta_log::checked::{self as logged, Checked, Rejection, Value};
use nauta_log::run::RunInfo;
use nauta_messages::checked::{Attitude, Fix, Gps, LblNav, Nav, Truth};
use nauta_messages::{AttitudeEstimate, LblSolution, Message, NavSolution, PositionFix};

/// The kind of an estimate stream: which message type it carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StreamKind {
    /// `NavSolution` (`ains/nav`, or a smoothed track of that type).
    Nav,
    /// `AttitudeEstimate` (`attitude/estimate`).
    Attitude,
    /// `PositionFix` (`positioning/fix`).
    Fix,
    /// `LblSolution` (`lbl/nav`, or a smoothed LBL track).
    Lbl,
}

impl StreamKind {
    /// The kind of channels of `type_name`, if it is an estimate.
    pub fn of(type_name: &str) -> Option<Self> {
        match type_name {
            NavSolution::TYPE_NAME => Some(Self::Nav),
            AttitudeEstimate::TYPE_NAME => Some(Self::Attitude),
            PositionFix::TYPE_NAME => Some(Self::Fix),
            LblSolution::TYPE_NAME => Some(Self::Lbl),
            _ => None,
        }
    }

    /// Whether the stream has a horizontal position.
    pub fn has_position(self) -> bool {
        self != Self::Attitude
    }
}

/// A horizontal position as the stream publishes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Horizontal {
    /// Geodetic latitude and longitude, rad.
    Geodetic {
        /// Latitude, rad.
        lat_rad: f64,
        /// Longitude, rad.
        lon_rad: f64,
    },
    /// North/east of the run's local origin, m (`lbl/nav`).
    Local {
        /// North, m.
        north_m: f64,
        /// East, m.
        east_m: f64,
    },
}

/// The last range an LBL filter processed, as it reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Innovation {
    /// Measured minus predicted range, m (paper 003, `r - r*`).
    pub residual_m: f64,
    /// Transponder.
    pub transponder_id: u32,
    /// Passed the Mahalanobis gate.
    pub accepted: bool,
}

/// One checked estimate; what its type does not carry is `None`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimateSample {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Horizontal position.
    pub pos: Option<Horizontal>,
    /// Depth, m.
    pub depth_m: Option<f64>,
    /// Velocity NED, m/s.
    pub vel_ned_m_s: Option<Vector3<f64>>,
    /// Attitude body → NED (a `NavSolution` with an all-zero quaternion has none).
    pub attitude: Option<UnitQuaternion<f64>>,
    /// Horizontal position covariance, north/east, m², when published.
    pub cov_ne_m2: Option<Matrix2<f64>>,
    /// Attitude error standard deviation about N, E, D, rad, when published.
    pub att_std_rad: Option<Vector3<f64>>,
    /// LBL: the last range innovation.
    pub innovation: Option<Innovation>,
    /// The estimate's own predicted horizontal error (`ains/nav`'s
    /// `predicted_drift_m`, paper 002), m.
    pub predicted_drift_m: Option<f64>,
}

/// An estimate stream.
#[derive(Debug, Clone)]
pub struct Stream {
    /// Channel topic (`ains/nav`).
    pub topic: String,
    /// Message type.
    pub kind: StreamKind,
    /// Checked samples, by stamp.
    pub samples: Vec<EstimateSample>,
    /// Messages that did not decode or failed their checks.
    pub rejected: u64,
}

/// A checked true state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthSample {
    /// Stamp, ns.
    pub stamp_ns: u64,
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
    /// Depth, m.
    pub depth_m: f64,
    /// Velocity NED, m/s.
    pub vel_ned_m_s: Vector3<f64>,
    /// Attitude body → NED.
    pub attitude: UnitQuaternion<f64>,
    /// Distance travelled over ground since the start, m.
    pub distance_m: f64,
}

/// An LBL reply (`sensor/lbl`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LblRange {
    /// Reply stamp, ns.
    pub stamp_ns: u64,
    /// Interrogation stamp, ns.
    pub interrogation_ns: u64,
    /// Transponder.
    pub transponder_id: u32,
    /// Round-trip time, s.
    pub round_trip_s: f64,
}

/// A buoy position broadcast over the modem (`sensor/modem`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuoyFix {
    /// Reception stamp, ns.
    pub stamp_ns: u64,
    /// Latitude, rad.
    pub lat_rad: f64,
    /// Longitude, rad.
    pub lon_rad: f64,
}

/// Everything eval and report take from a recording.
#[derive(Debug, Clone, Default)]
pub struct Data {
    /// `sim/truth`, by stamp, one sample per stamp.
    pub truth: Vec<TruthSample>,
    /// `sensor/gps` fixes with a fix (quality > 0), by stamp.
    pub gps: Vec<Gps>,
    /// Estimate streams by topic.
    pub streams: BTreeMap<String, Stream>,
    /// `sensor/lbl` replies, by stamp.
    pub lbl_replies: Vec<LblRange>,
    /// `sensor/modem` buoy positions, by stamp.
    pub buoy: Vec<BuoyFix>,
    /// Reference messages (truth, GPS, LBL replies, buoy) that did not decode
    /// or failed their checks, by topic.
    pub rejected: BTreeMap<String, u64>,
    /// The `nauta.run` metadata, read.
    pub run: RunInfo,
    /// Earliest stamp in the file, ns (the time axis of the report).
    pub first_stamp_ns: u64,
    /// The file was cut short (logger killed): what it holds is read.
    pub truncated: bool,
    /// The damaged chunks that were skipped, one line each (and messages
    /// whose channel was lost with one).
    pub damage: Vec<String>,
}

impl Data {
    /// Reads `path` through `nauta_log`'s checked values and run metadata;
    /// `on_progress(bytes read, file bytes)`.
    pub fn read(path: &Path, on_progress: impl FnMut(u64, u64)) -> anyhow::Result<Self> {
        let mut d = Data {
            first_stamp_ns: u64::MAX,
            ..Default::default()
        };
        let rec = nauta_log::streams::visit(
            path,
            on_progress,
            |ch| reads(&ch.type_name),
            |m| {
                d.first_stamp_ns = d.first_stamp_ns.min(m.recorded.publish_time_ns);
                if let Some(checked) = m.checked {
                    d.take_checked(&m.channel.topic, &m.channel.type_name, checked);
                }
                Ok(())
            },
        )?;
        if d.first_stamp_ns == u64::MAX {
            d.first_stamp_ns = 0;
        }
        d.truncated = rec.recovery.truncated;
        d.damage = rec.recovery.damage_notes();
        d.run = RunInfo::read(
            rec.metadata(nauta_log::META_RUN),
            &Default::default(),
            Some(crate::presets::simulated),
        );
        d.truth.sort_by_key(|t| t.stamp_ns);
        d.truth.dedup_by_key(|t| t.stamp_ns);
        d.gps.sort_by_key(|g| g.stamp_ns);
        d.lbl_replies.sort_by_key(|r| r.stamp_ns);
        d.buoy.sort_by_key(|b| b.stamp_ns);
        for s in d.streams.values_mut() {
            s.samples.sort_by_key(|e| e.stamp_ns);
        }
        Ok(d)
    }

    /// Takes one message's bytes (a live tap); what fails to decode or
    /// check is counted.
    pub fn take(&mut self, topic: &str, type_name: &str, data: &[u8]) {
        if !reads(type_name) {
            return;
        }
        if let Some(checked) = logged::decode(type_name, data) {
            self.take_checked(topic, type_name, &checked);
        }
    }

    /// Takes one checked message of a channel of `type_name`.
    fn take_checked(&mut self, topic: &str, type_name: &str, checked: &Result<Checked, Rejection>) {
        if let Some(kind) = StreamKind::of(type_name) {
            let stream = self
                .streams
                .entry(topic.to_owned())
                .or_insert_with(|| Stream {
                    topic: topic.to_owned(),
                    kind,
                    samples: Vec::new(),
                    rejected: 0,
                });
            match checked.as_ref().ok().and_then(|c| estimate(&c.value)) {
                Some(s) => stream.samples.push(s),
                None => stream.rejected += 1,
            }
            return;
        }
        let value = match checked {
            Ok(c) => &c.value,
            Err(_) => {
                if is_reference(topic, type_name) {
                    *self.rejected.entry(topic.to_owned()).or_default() += 1;
                }
                return;
            }
        };
        match (topic, value) {
            (nauta_messages::TRUTH_SERVICE, Value::Truth(t)) => self.truth.push(truth(t)),
            (nauta_messages::GPS_SERVICE, Value::Gps(g)) if g.quality > 0 => self.gps.push(*g),
            (_, Value::LblReply(r)) => self.lbl_replies.push(LblRange {
                stamp_ns: r.stamp_ns,
                interrogation_ns: r.interrogation_stamp_ns,
                transponder_id: r.transponder_id,
                round_trip_s: r.round_trip_s,
            }),
            (_, Value::Buoy(b)) => self.buoy.push(BuoyFix {
                stamp_ns: b.stamp_ns,
                lat_rad: b.buoy_lat_rad,
                lon_rad: b.buoy_lon_rad,
            }),
            _ => {}
        }
    }

    /// Seconds since the first stamp of the file.
    pub fn t_s(&self, stamp_ns: u64) -> f64 {
        (stamp_ns as f64 - self.first_stamp_ns as f64) * 1e-9
    }
}

/// The types eval uses: the estimates and the references (the sensors'
/// other channels, the bulk of a recording, are not decoded).
fn reads(type_name: &str) -> bool {
    use nauta_messages::{BuoyRange, GpsFix, GpsFixV1, LblReply, TruthState};
    StreamKind::of(type_name).is_some()
        || [
            TruthState::TYPE_NAME,
            GpsFix::TYPE_NAME,
            GpsFixV1::TYPE_NAME,
            LblReply::TYPE_NAME,
            BuoyRange::TYPE_NAME,
        ]
        .contains(&type_name)
}

/// The reference channels whose rejections eval reports.
fn is_reference(topic: &str, type_name: &str) -> bool {
    use nauta_messages::{BuoyRange, GpsFix, GpsFixV1, LblReply, TruthState};
    matches!(
        (topic, type_name),
        (nauta_messages::TRUTH_SERVICE, TruthState::TYPE_NAME)
            | (nauta_messages::GPS_SERVICE, GpsFix::TYPE_NAME)
            | (nauta_messages::GPS_SERVICE, GpsFixV1::TYPE_NAME)
            | (_, LblReply::TYPE_NAME)
            | (_, BuoyRange::TYPE_NAME)
    )
}

fn truth(t: &Truth) -> TruthSample {
    TruthSample {
        stamp_ns: t.stamp_ns,
        lat_rad: t.lat_rad,
        lon_rad: t.lon_rad,
        depth_m: t.depth_m,
        vel_ned_m_s: t.vel_ned_m_s.to_nalgebra(),
        attitude: t.attitude.to_nalgebra(),
        distance_m: t.distance_m,
    }
}

fn estimate(value: &Value) -> Option<EstimateSample> {
    match value {
        Value::Nav(m) => Some(nav(m)),
        Value::Attitude(m) => Some(attitude(m)),
        Value::Fix(m) => Some(fix(m)),
        Value::Lbl(m) => Some(lbl(m)),
        _ => None,
    }
}

/// A sample at `stamp_ns` that carries nothing yet.
pub(crate) fn empty(stamp_ns: u64) -> EstimateSample {
    EstimateSample {
        stamp_ns,
        pos: None,
        depth_m: None,
        vel_ned_m_s: None,
        attitude: None,
        cov_ne_m2: None,
        att_std_rad: None,
        innovation: None,
        predicted_drift_m: None,
    }
}

/// A diagonal or correlated north/east covariance from standard deviations;
/// `None` when either is zero (unknown) or the correlation is degenerate.
fn cov_ne(std_n: f64, std_e: f64, corr: f64) -> Option<Matrix2<f64>> {
    (std_n > 0.0 && std_e > 0.0 && corr.abs() < 1.0).then(|| {
        let c = corr * std_n * std_e;
        Matrix2::new(std_n * std_n, c, c, std_e * std_e)
    })
}

fn nav(m: &Nav) -> EstimateSample {
    EstimateSample {
        pos: Some(Horizontal::Geodetic {
            lat_rad: m.lat_rad,
            lon_rad: m.lon_rad,
        }),
        depth_m: Some(m.depth_m),
        vel_ned_m_s: Some(m.vel_ned_m_s.to_nalgebra()),
        attitude: m.attitude.map(|q| q.to_nalgebra()),
        cov_ne_m2: cov_ne(m.pos_std_ned_m.x(), m.pos_std_ned_m.y(), 0.0),
        predicted_drift_m: Some(m.predicted_drift_m),
        ..empty(m.stamp_ns)
    }
}

fn attitude(a: &Attitude) -> EstimateSample {
    EstimateSample {
        attitude: Some(a.attitude.to_nalgebra()),
        att_std_rad: (a.std_rad.iter().all(|s| *s > 0.0)).then_some(a.std_rad.to_nalgebra()),
        ..empty(a.stamp_ns)
    }
}

fn fix(m: &Fix) -> EstimateSample {
    EstimateSample {
        pos: Some(Horizontal::Geodetic {
            lat_rad: m.lat_rad,
            lon_rad: m.lon_rad,
        }),
        cov_ne_m2: cov_ne(m.std_north_m, m.std_east_m, m.corr_ne),
        ..empty(m.stamp_ns)
    }
}

fn lbl(m: &LblNav) -> EstimateSample {
    let (pxx, pyy) = (m.p[0][0], m.p[1][1]);
    // Paper 003 §V-A: P_xy, the x-y block of P, is the position covariance.
    let sym = 0.5 * (m.p[0][1] + m.p[1][0]);
    let cov = (pxx > 0.0 && pyy > 0.0 && pxx * pyy - sym * sym > 0.0)
        .then(|| Matrix2::new(pxx, sym, sym, pyy));
    let innovation = m.last_innovation_m.is_finite().then_some(Innovation {
        residual_m: m.last_innovation_m,
        transponder_id: m.transponder_id,
        accepted: m.accepted,
    });
    EstimateSample {
        pos: Some(Horizontal::Local {
            north_m: m.x_m,
            east_m: m.y_m,
        }),
        cov_ne_m2: cov,
        innovation,
        ..empty(m.stamp_ns)
    }
}
