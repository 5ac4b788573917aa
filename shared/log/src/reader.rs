//! Reading a recording, whole or cut short.
//!
//! The reader walks the file record by record (MCAP: opcode, 64-bit length,
//! body) instead of trusting its summary, so a file whose writer died keeps
//! everything up to its last complete record: every complete chunk is read back,
//! and [`Recovery`] says where the file ends and how many bytes after that were
//! lost. A chunk that is complete but damaged (bad compression stream) is
//! skipped and counted; reading goes on with the next one.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

use anyhow::Context as _;
use mcap::records::Record;

use crate::schema::Schema;

/// A channel of a recording.
#[derive(Debug, Clone)]
pub struct Channel {
    /// MCAP channel id.
    pub id: u16,
    /// Service name without namespace (`sensor/imu`).
    pub topic: String,
    /// Pinned type name (`nauta.ImuSample.v1`), empty if the file has none.
    pub type_name: String,
    /// Message encoding.
    pub message_encoding: String,
    /// The parsed schema, when it is a nauta schema.
    pub schema: Option<Schema>,
}

/// One recorded message.
#[derive(Debug, Clone, Copy)]
pub struct RecordedMessage<'a> {
    /// When the logger received it, ns since the Unix epoch.
    pub log_time_ns: u64,
    /// The message's stamp, ns (run clock).
    pub publish_time_ns: u64,
    /// Encoded payload.
    pub data: &'a [u8],
}

/// How much of a file was read.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct Recovery {
    /// File size, bytes.
    pub file_bytes: u64,
    /// Bytes read as complete records (everything before the cut).
    pub read_bytes: u64,
    /// The file does not end with its data-end record: the writer did not
    /// finish (killed, power lost, disk full).
    pub truncated: bool,
    /// Complete chunks read.
    pub chunks: u64,
    /// Complete chunks that could not be decoded (skipped).
    pub damaged_chunks: u64,
    /// Why reading stopped early, if it did.
    pub reason: Option<String>,
}

impl Recovery {
    /// Bytes after the last complete record (lost with the cut).
    pub fn lost_bytes(&self) -> u64 {
        self.file_bytes - self.read_bytes
    }
}

/// What a recording holds besides its messages.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    /// Channels by id.
    pub channels: BTreeMap<u16, Channel>,
    /// Metadata records, in file order.
    pub metadata: Vec<(String, BTreeMap<String, String>)>,
    /// The MCAP profile.
    pub profile: String,
    /// How much was read.
    pub recovery: Recovery,
}

impl Recording {
    /// The first metadata record called `name`.
    pub fn metadata(&self, name: &str) -> Option<&BTreeMap<String, String>> {
        self.metadata
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, m)| m)
    }
}

/// Reads `path`, calling `on_message` with each message in file order.
/// Errors only when the file is not an MCAP file or `on_message` fails; a
/// cut or damaged file is reported in [`Recording::recovery`].
pub fn read(
    path: &Path,
    on_message: impl FnMut(&Channel, &RecordedMessage<'_>) -> anyhow::Result<()>,
) -> anyhow::Result<Recording> {
    read_with_progress(path, |_, _| {}, on_message)
}

/// [`read`], reporting `(bytes read, file bytes)` after every record.
pub fn read_with_progress(
    path: &Path,
    mut on_progress: impl FnMut(u64, u64),
    mut on_message: impl FnMut(&Channel, &RecordedMessage<'_>) -> anyhow::Result<()>,
) -> anyhow::Result<Recording> {
    let file = File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let file_bytes = file
        .metadata()
        .with_context(|| format!("cannot read the size of {}", path.display()))?
        .len();
    let mut input = BufReader::with_capacity(1 << 20, file);
    let mut magic = [0u8; 8];
    input
        .read_exact(&mut magic)
        .ok()
        .filter(|_| magic == mcap::MAGIC)
        .ok_or_else(|| anyhow::anyhow!("{} is not an MCAP file", path.display()))?;

    let mut rec = Recording {
        recovery: Recovery {
            file_bytes,
            read_bytes: 8,
            truncated: true,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut schemas: BTreeMap<u16, (String, Option<Schema>)> = BTreeMap::new();
    let mut body = Vec::new();
    loop {
        let offset = rec.recovery.read_bytes;
        let mut head = [0u8; 9];
        if file_bytes - offset < 9 {
            rec.recovery.reason = Some(format!(
                "the file ends {} bytes into a record header at byte {offset}",
                file_bytes - offset
            ));
            break;
        }
        input
            .read_exact(&mut head)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let op = head[0];
        let len = u64::from_le_bytes(head[1..9].try_into().unwrap_or([0; 8]));
        if len > file_bytes - offset - 9 {
            rec.recovery.reason = Some(format!(
                "the record at byte {offset} (opcode 0x{op:02x}) needs {len} bytes, the file has {}",
                file_bytes - offset - 9
            ));
            break;
        }
        body.resize(len as usize, 0);
        input
            .read_exact(&mut body)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let record = match mcap::read::parse_record(op, &body) {
            Ok(r) => r,
            Err(e) => {
                rec.recovery.reason = Some(format!("bad record at byte {offset}: {e}"));
                break;
            }
        };
        rec.recovery.read_bytes = offset + 9 + len;
        let mut end = false;
        match record {
            Record::Chunk { header, data } => {
                let records = mcap::read::ChunkReader::new(header, &data);
                let mut damaged = None;
                match records {
                    Ok(records) => {
                        for r in records {
                            match r {
                                Ok(r) => handle(r, &mut rec, &mut schemas, &mut on_message)?,
                                Err(e) => {
                                    damaged = Some(e.to_string());
                                    break;
                                }
                            }
                        }
                    }
                    Err(e) => damaged = Some(e.to_string()),
                }
                match damaged {
                    Some(why) => {
                        rec.recovery.damaged_chunks += 1;
                        rec.recovery.reason =
                            Some(format!("damaged chunk at byte {offset}: {why}"));
                    }
                    None => rec.recovery.chunks += 1,
                }
            }
            Record::Header(h) => rec.profile = h.profile,
            Record::DataEnd(_) => end = true,
            r => handle(r, &mut rec, &mut schemas, &mut on_message)?,
        }
        on_progress(rec.recovery.read_bytes, file_bytes);
        if end {
            rec.recovery.truncated = false;
            break;
        }
    }
    on_progress(file_bytes, file_bytes);
    Ok(rec)
}

fn handle(
    record: Record<'_>,
    rec: &mut Recording,
    schemas: &mut BTreeMap<u16, (String, Option<Schema>)>,
    on_message: &mut impl FnMut(&Channel, &RecordedMessage<'_>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    match record {
        Record::Schema { header, data } => {
            let parsed = (header.encoding == crate::SCHEMA_ENCODING)
                .then(|| Schema::from_bytes(&data).ok())
                .flatten();
            schemas.insert(header.id, (header.name, parsed));
        }
        Record::Channel(c) => {
            let (type_name, schema) = match schemas.get(&c.schema_id) {
                Some((name, schema)) => (name.clone(), schema.clone()),
                None => (c.metadata.get("type").cloned().unwrap_or_default(), None),
            };
            rec.channels.insert(
                c.id,
                Channel {
                    id: c.id,
                    topic: c.topic,
                    type_name,
                    message_encoding: c.message_encoding,
                    schema,
                },
            );
        }
        Record::Message { header, data } => {
            // A message whose channel record was lost is skipped: it cannot be
            // interpreted (MCAP writes a channel before its first message).
            if let Some(ch) = rec.channels.get(&header.channel_id) {
                on_message(
                    ch,
                    &RecordedMessage {
                        log_time_ns: header.log_time,
                        publish_time_ns: header.publish_time,
                        data: &data,
                    },
                )?;
            }
        }
        Record::Metadata(m) => rec.metadata.push((m.name, m.metadata)),
        _ => {}
    }
    Ok(())
}

#[cfg(test)]
mod tests;
