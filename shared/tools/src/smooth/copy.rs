//! The output recording: every message of the input (its channels, in file
//! order, with their log times) and its metadata, plus a track of extra
//! messages interleaved by stamp (each written just before the first input
//! message stamped after it, with that message's log time).

use std::collections::BTreeMap;
use std::path::Path;

use nauta_log::reader::Recording;
use nauta_log::writer::{LogWriter, WriterOptions};
use nauta_messages::{Message, TypeInfo, codec, registry};

/// What the copy wrote.
#[derive(Debug, Clone, Default)]
pub struct Copied {
    /// Messages of the input written.
    pub messages: u64,
    /// Messages of the track written.
    pub track: u64,
    /// Per channel, messages of the input not copied because their type is
    /// not one nauta knows (no schema to write them with).
    pub skipped: BTreeMap<String, u64>,
    /// Messages of the input on the track's own topic, replaced by the track
    /// (a recording smoothed again).
    pub replaced: u64,
}

/// Copies `input` (whose first read gave `recording`) to `output`, with
/// `track` (in stamp order) on `topic` (replacing the input's messages on
/// it) and `extra` as one more metadata record (replacing the input's of
/// that name); `on_progress(bytes read, file bytes)`.
pub fn copy_with_track<M: Message>(
    input: &Path,
    recording: &Recording,
    output: &Path,
    topic: &str,
    track: &[M],
    extra: (&str, BTreeMap<String, String>),
    on_progress: impl FnMut(u64, u64),
) -> anyhow::Result<Copied> {
    let mut w = LogWriter::create(output, WriterOptions::default())?;
    for (name, entries) in recording.metadata.iter().filter(|(n, _)| n != extra.0) {
        w.metadata(name, entries.clone())?;
    }
    w.metadata(extra.0, extra.1)?;
    let track_channel = w.channel(topic, &TypeInfo::of::<M>())?;
    let mut copied = Copied::default();
    let mut next = 0;
    let mut last_log_ns = 0;
    let mut types: BTreeMap<u16, Option<TypeInfo>> = BTreeMap::new();
    let mut write_track_until =
        |w: &mut LogWriter, stamp: Option<u64>, log_ns: u64, n: &mut u64| -> anyhow::Result<()> {
            while let Some(m) = track.get(next) {
                if stamp.is_some_and(|s| m.header().stamp_ns > s) {
                    break;
                }
                w.write(track_channel, log_ns, &codec::encode(m)?)?;
                next += 1;
                *n += 1;
            }
            Ok(())
        };
    let mut track_written = 0;
    nauta_log::reader::read_with_progress(input, on_progress, |ch, m| {
        if ch.topic == topic {
            copied.replaced += 1;
            return Ok(());
        }
        let info = *types.entry(ch.id).or_insert_with(|| {
            (ch.message_encoding == nauta_log::MESSAGE_ENCODING)
                .then(|| registry::type_info(&ch.type_name))
                .flatten()
        });
        let Some(info) = info else {
            *copied.skipped.entry(ch.topic.clone()).or_default() += 1;
            return Ok(());
        };
        write_track_until(
            &mut w,
            Some(m.publish_time_ns),
            m.log_time_ns,
            &mut track_written,
        )?;
        let id = w.channel(&ch.topic, &info)?;
        w.write(id, m.log_time_ns, m.data)?;
        last_log_ns = m.log_time_ns;
        copied.messages += 1;
        Ok(())
    })?;
    write_track_until(&mut w, None, last_log_ns, &mut track_written)?;
    copied.track = track_written;
    w.finish()?;
    Ok(copied)
}
