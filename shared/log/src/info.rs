//! What a recording holds (`nauta log info`): channels, counts, rates, time
//! span, sequence gaps, metadata, lifecycle events, and how much of the file
//! could be read.

use std::collections::BTreeMap;
use std::path::Path;

use nauta_messages::{GapCounter, RunEvent, codec, event_kind, fixed_str};
use serde::Serialize;

use crate::reader::{self, Channel, RecordedMessage, Recovery};

/// One channel's summary.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ChannelSummary {
    /// Service name without namespace.
    pub topic: String,
    /// Pinned type name.
    #[serde(rename = "type")]
    pub type_name: String,
    /// Messages read.
    pub count: u64,
    /// Messages missing between consecutive sequence numbers of the same
    /// (source, instance): lost before or by the logger. A restart is not a gap.
    pub gaps: u64,
    /// Messages whose sequence number did not increase.
    pub out_of_order: u64,
    /// Publisher instances seen (a restart or swap adds one).
    pub instances: u64,
    /// First and last stamp, ns (run clock).
    pub first_stamp_ns: u64,
    /// Last stamp, ns.
    pub last_stamp_ns: u64,
    /// Mean rate over the stamps, Hz (0 with fewer than two messages).
    pub rate_hz: f64,
    /// Payload bytes (uncompressed).
    pub bytes: u64,
}

/// A lifecycle event of the run (`run/events`).
#[derive(Debug, Clone, Serialize)]
pub struct EventSummary {
    /// Run-clock stamp, ns.
    pub stamp_ns: u64,
    /// `started`, `ready`, `exited`, `restarted`, `swapped`, `run_ended`,
    /// `surfacing_advised`.
    pub kind: String,
    /// Process name in the manifest.
    pub process: String,
    /// Instance.
    pub instance: u32,
    /// Process id.
    pub pid: u32,
    /// Variant.
    pub variant: String,
    /// Exit code (`exited`; -signal when killed).
    pub exit_code: i32,
}

/// The summary of a recording.
#[derive(Debug, Clone, Serialize)]
pub struct LogInfo {
    /// The file.
    pub file: String,
    /// Channels, by topic.
    pub channels: Vec<ChannelSummary>,
    /// Messages read, all channels.
    pub messages: u64,
    /// Sequence gaps, all channels.
    pub gaps: u64,
    /// Earliest and latest stamp over all channels, ns.
    pub start_stamp_ns: u64,
    /// Latest stamp, ns.
    pub end_stamp_ns: u64,
    /// `end - start`, s.
    pub duration_s: f64,
    /// The writer did not finish the file (see `recovery`).
    pub truncated: bool,
    /// How much of the file was read.
    pub recovery: Recovery,
    /// Metadata records by name.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Lifecycle events, in order.
    pub events: Vec<EventSummary>,
}

fn kind_name(kind: u32) -> String {
    match kind {
        event_kind::STARTED => "started",
        event_kind::READY => "ready",
        event_kind::EXITED => "exited",
        event_kind::RESTARTED => "restarted",
        event_kind::SWAPPED => "swapped",
        event_kind::RUN_ENDED => "run_ended",
        event_kind::SURFACING_ADVISED => "surfacing_advised",
        _ => "unknown",
    }
    .to_owned()
}

/// Reads `path` and summarises it; `on_progress(bytes read, file bytes)`.
pub fn summarise(path: &Path, on_progress: impl FnMut(u64, u64)) -> anyhow::Result<LogInfo> {
    summarise_with(path.display().to_string(), |on_message| {
        reader::read_with_progress(path, on_progress, on_message)
    })
}

/// [`summarise`] of a recording held in memory, named `file`.
pub fn summarise_bytes(file: &str, bytes: &[u8]) -> anyhow::Result<LogInfo> {
    summarise_with(file.to_owned(), |on_message| {
        reader::read_bytes(bytes, |_, _| {}, on_message)
    })
}

type OnMessage<'a> = &'a mut dyn FnMut(&Channel, &RecordedMessage<'_>) -> anyhow::Result<()>;

fn summarise_with(
    file: String,
    read: impl FnOnce(OnMessage<'_>) -> anyhow::Result<reader::Recording>,
) -> anyhow::Result<LogInfo> {
    struct Acc {
        summary: ChannelSummary,
        gaps: GapCounter,
        instances: std::collections::BTreeSet<(u32, u32)>,
    }
    let mut acc: BTreeMap<u16, Acc> = BTreeMap::new();
    let mut events = Vec::new();
    let rec = read(&mut |ch, m| {
        let a = acc.entry(ch.id).or_insert_with(|| Acc {
            summary: ChannelSummary {
                topic: ch.topic.clone(),
                type_name: ch.type_name.clone(),
                first_stamp_ns: u64::MAX,
                ..Default::default()
            },
            gaps: GapCounter::default(),
            instances: Default::default(),
        });
        let s = &mut a.summary;
        s.count += 1;
        s.bytes += m.data.len() as u64;
        if let Some(h) = crate::header_of(m.data) {
            a.gaps.record(h.source, h.instance, h.seq);
            a.instances.insert((h.source, h.instance));
            s.first_stamp_ns = s.first_stamp_ns.min(h.stamp_ns);
            s.last_stamp_ns = s.last_stamp_ns.max(h.stamp_ns);
        }
        if ch.type_name == <RunEvent as nauta_messages::Message>::TYPE_NAME
            && let Ok(e) = codec::decode::<RunEvent>(m.data)
        {
            events.push(EventSummary {
                stamp_ns: e.header.stamp_ns,
                kind: kind_name(e.kind),
                process: fixed_str(&e.process),
                instance: e.instance,
                pid: e.pid,
                variant: fixed_str(&e.variant),
                exit_code: e.exit_code,
            });
        }
        Ok(())
    })?;
    let mut channels: Vec<ChannelSummary> = acc
        .into_values()
        .map(|a| {
            let mut s = a.summary;
            s.gaps = a.gaps.missing;
            s.out_of_order = a.gaps.out_of_order;
            s.instances = a.instances.len() as u64;
            if s.count == 0 || s.first_stamp_ns == u64::MAX {
                s.first_stamp_ns = 0;
            }
            let span = s.last_stamp_ns.saturating_sub(s.first_stamp_ns) as f64 * 1e-9;
            s.rate_hz = if s.count > 1 && span > 0.0 {
                (s.count - 1) as f64 / span
            } else {
                0.0
            };
            s
        })
        .collect();
    // Channels that were announced but carry no message.
    for ch in rec.channels.values() {
        if !channels.iter().any(|c| c.topic == ch.topic) {
            channels.push(ChannelSummary {
                topic: ch.topic.clone(),
                type_name: ch.type_name.clone(),
                ..Default::default()
            });
        }
    }
    channels.sort_by(|a, b| a.topic.cmp(&b.topic));
    let with_data = channels.iter().filter(|c| c.count > 0);
    let start = with_data
        .clone()
        .map(|c| c.first_stamp_ns)
        .min()
        .unwrap_or(0);
    let end = with_data.map(|c| c.last_stamp_ns).max().unwrap_or(0);
    Ok(LogInfo {
        file,
        messages: channels.iter().map(|c| c.count).sum(),
        gaps: channels.iter().map(|c| c.gaps).sum(),
        channels,
        start_stamp_ns: start,
        end_stamp_ns: end,
        duration_s: end.saturating_sub(start) as f64 * 1e-9,
        truncated: rec.recovery.truncated,
        recovery: rec.recovery.clone(),
        metadata: rec.metadata.iter().cloned().collect(),
        events,
    })
}
