//! MCAP for Foxglove: every channel of the recording as JSON.
//!
//! - each source channel keeps its topic (`sim/truth`), with message encoding
//!   `json` and a `jsonschema` schema named by the pinned type
//!   (`nauta.TruthState.v1`) and generated from the recorded field list
//!   ([`super::jsonschema`]); every message keeps its log time (the logger's
//!   receive time) and publish time (its stamp), and its channel metadata
//!   says `nauta_type`;
//! - every track is also published as `foxglove.LocationFix` on
//!   `/map/<topic>` (decimated like the map formats), which Foxglove's Map
//!   panel draws: `timestamp` = stamp (run clock), `frame_id` = topic,
//!   latitude/longitude in degrees, `altitude = -depth` (0 where unknown),
//!   `position_covariance` in east-north-up from the published standard
//!   deviations (type DIAGONAL_KNOWN for `ains/nav`, APPROXIMATED where only
//!   the horizontal is known, UNKNOWN for the truth), `heading` = yaw (rad,
//!   clockwise from north) where known, and the track's `color`;
//! - the recording's metadata records are copied.
//!
//! A channel whose messages cannot be read (not nauta's encoding, no schema
//! in the file or this build, an unsupported field type) is left out with a
//! note; a message that does not match its schema is skipped and counted.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use mcap::records::{MessageHeader, Metadata};
use serde_json::{Value, json};

use super::jsonschema::Layout;
use super::{ExportError, Track};
use crate::reader::{Channel, RecordedMessage, Recording};
use crate::schema::Schema;

/// Schema name of Foxglove's location fix (must be exactly this).
pub const LOCATION_FIX: &str = "foxglove.LocationFix";

/// Prefix of the location-fix topics.
pub const MAP_PREFIX: &str = "/map/";

#[derive(Debug, Clone)]
enum Out {
    Json { id: u16, layout: Arc<Layout> },
    Skip,
}

/// Writes the Foxglove file while the recording is read.
pub(crate) struct Converter {
    writer: mcap::Writer<BufWriter<File>>,
    output: PathBuf,
    schemas: HashMap<String, Result<(u16, Arc<Layout>), String>>,
    channels: HashMap<u16, Out>,
    skipped: BTreeMap<String, String>,
    buf: Vec<u8>,
    written: u64,
    non_finite: u64,
    failures: BTreeMap<String, u64>,
}

impl std::fmt::Debug for Converter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Converter")
            .field("output", &self.output)
            .field("channels", &self.channels.len())
            .field("written", &self.written)
            .finish()
    }
}

/// What the conversion wrote.
#[derive(Debug, Default)]
pub(crate) struct Done {
    /// Messages written (JSON copies and location fixes).
    pub written: u64,
    /// Non-finite fields left out.
    pub non_finite_left_out: u64,
    /// Messages that did not match their schema, by topic.
    pub decode_failures: BTreeMap<String, u64>,
    /// Location fixes per track topic.
    pub map_points: BTreeMap<String, u64>,
}

impl Converter {
    /// Starts the MCAP file on `file` (which will become `output`).
    pub fn new(file: File, output: &Path) -> Result<Self, ExportError> {
        let writer = mcap::WriteOptions::new()
            .profile("")
            .library(concat!("nauta export ", env!("CARGO_PKG_VERSION")))
            .compression(Some(mcap::Compression::Zstd))
            .create(BufWriter::with_capacity(1 << 20, file))
            .map_err(|source| ExportError::Mcap {
                path: output.to_owned(),
                source,
            })?;
        Ok(Converter {
            writer,
            output: output.to_owned(),
            schemas: HashMap::new(),
            channels: HashMap::new(),
            skipped: BTreeMap::new(),
            buf: Vec::with_capacity(4096),
            written: 0,
            non_finite: 0,
            failures: BTreeMap::new(),
        })
    }

    fn mcap_error(&self, source: mcap::McapError) -> ExportError {
        ExportError::Mcap {
            path: self.output.clone(),
            source,
        }
    }

    /// The JSON schema of `ch`'s type, added on first use.
    fn schema_for(&mut self, ch: &Channel) -> Result<(u16, Arc<Layout>), String> {
        if let Some(s) = self.schemas.get(&ch.type_name) {
            return s.clone();
        }
        let made = (|| {
            let schema = match &ch.schema {
                Some(s) => s.clone(),
                None => nauta_messages::registry::type_info(&ch.type_name)
                    .map(|t| Schema::of(&t))
                    .ok_or_else(|| {
                        format!(
                            "no nauta schema for type {:?} in the file or in this build",
                            ch.type_name
                        )
                    })?,
            };
            let layout = Layout::new(&schema).map_err(|e| e.to_string())?;
            let json = serde_json::to_vec(&layout.json_schema()).map_err(|e| e.to_string())?;
            let id = self
                .writer
                .add_schema(&schema.type_name, "jsonschema", &json)
                .map_err(|e| e.to_string())?;
            Ok((id, Arc::new(layout)))
        })();
        self.schemas.insert(ch.type_name.clone(), made.clone());
        made
    }

    /// The output channel of source channel `ch`, added on first use.
    fn channel_for(&mut self, ch: &Channel) -> Result<Out, ExportError> {
        if let Some(o) = self.channels.get(&ch.id) {
            return Ok(o.clone());
        }
        let out = if ch.message_encoding != crate::MESSAGE_ENCODING {
            self.skipped.insert(
                ch.topic.clone(),
                format!("message encoding {:?} is not nauta's", ch.message_encoding),
            );
            Out::Skip
        } else {
            match self.schema_for(ch) {
                Ok((schema_id, layout)) => {
                    let mut meta = BTreeMap::new();
                    meta.insert("nauta_type".to_owned(), ch.type_name.clone());
                    let id = self
                        .writer
                        .add_channel(schema_id, &ch.topic, "json", &meta)
                        .map_err(|e| self.mcap_error(e))?;
                    Out::Json { id, layout }
                }
                Err(why) => {
                    self.skipped.insert(ch.topic.clone(), why);
                    Out::Skip
                }
            }
        };
        self.channels.insert(ch.id, out.clone());
        Ok(out)
    }

    /// Converts and writes one message.
    pub fn message(&mut self, ch: &Channel, msg: &RecordedMessage<'_>) -> Result<(), ExportError> {
        let Out::Json { id, layout } = self.channel_for(ch)? else {
            return Ok(());
        };
        self.buf.clear();
        match layout.to_json(msg.data, &mut self.buf) {
            Ok(n) => self.non_finite += n,
            Err(_) => {
                *self.failures.entry(ch.topic.clone()).or_insert(0) += 1;
                return Ok(());
            }
        }
        let seq = crate::header_of(msg.data)
            .map(|h| h.seq as u32)
            .unwrap_or(0);
        self.writer
            .write_to_known_channel(
                &MessageHeader {
                    channel_id: id,
                    sequence: seq,
                    log_time: msg.log_time_ns,
                    publish_time: msg.publish_time_ns,
                },
                &self.buf,
            )
            .map_err(|e| self.mcap_error(e))?;
        self.written += 1;
        Ok(())
    }

    /// Adds the channels without messages, the location fixes of `tracks` and
    /// the metadata, and closes the file.
    pub fn finish(
        mut self,
        rec: &Recording,
        tracks: &[Track],
        notes: &mut Vec<String>,
    ) -> Result<Done, ExportError> {
        for ch in rec.channels.values() {
            self.channel_for(ch)?;
        }
        for (topic, why) in &self.skipped {
            notes.push(format!("{topic}: left out of the Foxglove file: {why}"));
        }
        let mut map_points = BTreeMap::new();
        let with_position: Vec<&Track> = tracks
            .iter()
            .filter(|t| t.kind.is_position() && t.has_position())
            .collect();
        if !with_position.is_empty() {
            let schema = serde_json::to_vec(&location_fix_schema())
                .map_err(|e| ExportError::Internal(e.to_string()))?;
            let schema_id = self
                .writer
                .add_schema(LOCATION_FIX, "jsonschema", &schema)
                .map_err(|e| self.mcap_error(e))?;
            for (i, t) in with_position.iter().enumerate() {
                let mut meta = BTreeMap::new();
                meta.insert("nauta_source_topic".to_owned(), t.topic.clone());
                let topic = format!("{MAP_PREFIX}{}", t.topic);
                let id = self
                    .writer
                    .add_channel(schema_id, &topic, "json", &meta)
                    .map_err(|e| self.mcap_error(e))?;
                let rgb = t.rgb(i);
                let mut n = 0u64;
                for s in t.samples.iter().filter(|s| s.has_position()) {
                    let fix = location_fix(t, s, rgb);
                    self.buf.clear();
                    serde_json::to_writer(&mut self.buf, &fix)
                        .map_err(|e| ExportError::Internal(e.to_string()))?;
                    self.writer
                        .write_to_known_channel(
                            &MessageHeader {
                                channel_id: id,
                                sequence: s.seq as u32,
                                log_time: s.log_time_ns,
                                publish_time: s.stamp_ns,
                            },
                            &self.buf,
                        )
                        .map_err(|e| self.mcap_error(e))?;
                    n += 1;
                }
                self.written += n;
                map_points.insert(t.topic.clone(), n);
            }
        }
        for (name, entries) in &rec.metadata {
            self.writer
                .write_metadata(&Metadata {
                    name: name.clone(),
                    metadata: entries.clone(),
                })
                .map_err(|e| self.mcap_error(e))?;
        }
        self.writer.finish().map_err(|e| self.mcap_error(e))?;
        let output = self.output.clone();
        let mut inner = self.writer.into_inner();
        inner.flush().map_err(|source| ExportError::Write {
            path: output.clone(),
            source,
        })?;
        Ok(Done {
            written: self.written,
            non_finite_left_out: self.non_finite,
            decode_failures: self.failures,
            map_points,
        })
    }
}

/// Foxglove's `foxglove.LocationFix` as a JSON Schema (fields and meaning from
/// Foxglove's schema documentation).
pub fn location_fix_schema() -> Value {
    let number = |d: &str| json!({"type": "number", "description": d});
    json!({
        "title": LOCATION_FIX,
        "description": "A navigation satellite fix for any Global Navigation Satellite System \
                        (here: a nauta track, one message per kept sample)",
        "type": "object",
        "properties": {
            "timestamp": {
                "type": "object",
                "title": "time",
                "description": "Stamp of the sample (nauta run clock)",
                "properties": {
                    "sec": {"type": "integer", "minimum": 0},
                    "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
                },
                "required": ["sec", "nsec"],
            },
            "frame_id": {"type": "string", "description": "The nauta topic of the track"},
            "latitude": number("Latitude in degrees"),
            "longitude": number("Longitude in degrees"),
            "altitude": number("Altitude in metres: minus the depth (0 where the stream has none)"),
            "position_covariance": {
                "type": "array",
                "items": {"type": "number"},
                "minItems": 9,
                "maxItems": 9,
                "description": "Position covariance (m^2) in a tangent plane through the position, \
                                East, North, Up, row-major",
            },
            "position_covariance_type": {
                "title": "foxglove.PositionCovarianceType",
                "description": "How much of position_covariance is known",
                "oneOf": [
                    {"title": "UNKNOWN", "const": 0},
                    {"title": "APPROXIMATED", "const": 1},
                    {"title": "DIAGONAL_KNOWN", "const": 2},
                    {"title": "KNOWN", "const": 3},
                ],
            },
            "heading": number("Heading (yaw), radians, clockwise from north"),
            "color": {
                "title": "foxglove.Color",
                "description": "Colour of the track",
                "type": "object",
                "properties": {
                    "r": number("Red, 0 to 1"),
                    "g": number("Green, 0 to 1"),
                    "b": number("Blue, 0 to 1"),
                    "a": number("Alpha, 0 to 1"),
                },
                "required": ["r", "g", "b", "a"],
            },
        },
        "required": [
            "timestamp",
            "frame_id",
            "latitude",
            "longitude",
            "altitude",
            "position_covariance",
            "position_covariance_type",
        ],
    })
}

/// `position_covariance_type` values.
const UNKNOWN: u8 = 0;
const APPROXIMATED: u8 = 1;
const DIAGONAL_KNOWN: u8 = 2;

/// The location fix of one sample.
fn location_fix(t: &Track, s: &super::Sample, rgb: [u8; 3]) -> Value {
    let [sn, se, sd] = s.pos_std_ned_m;
    let mut cov = [0.0f64; 9];
    let mut kind = UNKNOWN;
    if sn.is_finite() && se.is_finite() {
        cov[0] = se * se;
        cov[4] = sn * sn;
        if s.corr_ne.is_finite() {
            cov[1] = s.corr_ne * se * sn;
            cov[3] = cov[1];
        }
        kind = APPROXIMATED;
        if sd.is_finite() {
            cov[8] = sd * sd;
            if !s.corr_ne.is_finite() {
                kind = DIAGONAL_KNOWN;
            }
        }
    }
    if !cov.iter().all(|c| c.is_finite()) {
        cov = [0.0; 9];
        kind = UNKNOWN;
    }
    let mut fix = json!({
        "timestamp": {"sec": s.stamp_ns / 1_000_000_000, "nsec": s.stamp_ns % 1_000_000_000},
        "frame_id": t.topic,
        "latitude": s.lat_deg,
        "longitude": s.lon_deg,
        "altitude": if s.depth_m.is_finite() { 0.0 - s.depth_m } else { 0.0 },
        "position_covariance": cov,
        "position_covariance_type": kind,
        "color": {
            "r": f64::from(rgb[0]) / 255.0,
            "g": f64::from(rgb[1]) / 255.0,
            "b": f64::from(rgb[2]) / 255.0,
            "a": 1.0,
        },
    });
    let yaw = s.rpy_deg[2];
    if yaw.is_finite() {
        fix["heading"] = json!(yaw.to_radians().rem_euclid(std::f64::consts::TAU));
    }
    fix
}
