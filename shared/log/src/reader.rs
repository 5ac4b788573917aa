//! Reading a recording, whole, cut short or damaged.
//!
//! The reader walks the file record by record (MCAP: opcode, 64-bit length,
//! body) instead of trusting its summary, and parses every record itself
//! ([`records`]) with each length checked against the bytes that hold it
//! before anything is allocated, so no file can make it panic or allocate
//! more than its own size (and [`chunk::MAX_CHUNK_BYTES`] per chunk).
//!
//! - A file whose writer died keeps everything up to its last complete
//!   record: every complete chunk is read back, and [`Recovery`] says where
//!   the file ends and how many bytes after that were lost.
//! - A chunk is decompressed to at most the size it declares, its CRC
//!   verified and all its records parsed before any is used ([`chunk`]); a
//!   chunk that fails is skipped whole, counted and named ([`Damage`]: its
//!   offset and index), and reading goes on with the next record.
//! - Bytes that are not a record (a damaged opcode or length) are skipped up
//!   to the next record that is consistent with its length (a chunk, a
//!   metadata record or the data end), also named as a [`Damage`].

use std::collections::BTreeMap;
use std::fs::File;
use std::path::Path;

use anyhow::Context as _;

use crate::schema::Schema;

pub mod chunk;
pub mod records;
mod summary;

use records::{Record, op};

/// The 8 bytes an MCAP file starts with.
pub const MAGIC: [u8; 8] = *b"\x89MCAP0\r\n";

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

/// A stretch of a recording that was skipped as damaged.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Damage {
    /// Where it starts in the file, bytes.
    pub offset: u64,
    /// How many bytes were skipped.
    pub bytes: u64,
    /// The chunk's index in the file (0-based, counting every chunk record
    /// met), when the damage is a chunk whose record could be read; `None`
    /// for bytes that are not a readable record (a damaged length or header),
    /// skipped up to the next intact chunk.
    pub chunk: Option<u64>,
    /// Why.
    pub reason: String,
}

impl std::fmt::Display for Damage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.chunk {
            Some(i) => write!(
                f,
                "damaged chunk #{i} at byte {} ({} bytes) skipped: {}",
                self.offset, self.bytes, self.reason
            ),
            None => write!(
                f,
                "{} damaged bytes at byte {} skipped: {}",
                self.bytes, self.offset, self.reason
            ),
        }
    }
}

/// How much of a file was read.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct Recovery {
    /// File size, bytes.
    pub file_bytes: u64,
    /// Where reading ended: the end of the last complete record (everything
    /// after it is lost with a cut).
    pub read_bytes: u64,
    /// The file does not end with its data-end record: the writer did not
    /// finish (killed, power lost, disk full).
    pub truncated: bool,
    /// Intact chunks read.
    pub chunks: u64,
    /// Damaged stretches skipped (`damaged.len()`).
    pub damaged_chunks: u64,
    /// Each damaged chunk or stretch of bytes, in file order: nothing in it
    /// was used; reading resumed at the next intact record.
    pub damaged: Vec<Damage>,
    /// Messages whose channel record was never read (lost in a damaged
    /// chunk): they cannot be interpreted and are skipped.
    pub unknown_channel_messages: u64,
    /// Why reading stopped before the data end, if it did.
    pub reason: Option<String>,
}

impl Recovery {
    /// Bytes after the last complete record (lost with the cut).
    pub fn lost_bytes(&self) -> u64 {
        self.file_bytes.saturating_sub(self.read_bytes)
    }

    /// One line per damage and for messages without a channel, for the
    /// notes every command prints.
    pub fn damage_notes(&self) -> Vec<String> {
        let mut notes: Vec<String> = self.damaged.iter().map(Damage::to_string).collect();
        if self.unknown_channel_messages > 0 {
            notes.push(format!(
                "{} messages skipped: their channel record was lost",
                self.unknown_channel_messages
            ));
        }
        notes
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
/// Errors only when the file is not an MCAP file, cannot be read, or
/// `on_message` fails; a cut or damaged file is reported in
/// [`Recording::recovery`].
pub fn read(
    path: &Path,
    on_message: impl FnMut(&Channel, &RecordedMessage<'_>) -> anyhow::Result<()>,
) -> anyhow::Result<Recording> {
    read_with_progress(path, |_, _| {}, on_message)
}

/// [`read`], reporting `(bytes read, file bytes)` after every record.
pub fn read_with_progress(
    path: &Path,
    on_progress: impl FnMut(u64, u64),
    on_message: impl FnMut(&Channel, &RecordedMessage<'_>) -> anyhow::Result<()>,
) -> anyhow::Result<Recording> {
    let file = File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let file_bytes = file
        .metadata()
        .with_context(|| format!("cannot read the size of {}", path.display()))?
        .len();
    walk(&file, file_bytes, on_progress, on_message).map_err(|e| match e {
        WalkError::NotMcap => anyhow::anyhow!("{} is not an MCAP file", path.display()),
        WalkError::Io(e) => {
            anyhow::Error::new(e).context(format!("cannot read {}", path.display()))
        }
        WalkError::Consumer(e) => e,
    })
}

/// [`read_with_progress`] of a recording held in memory.
pub fn read_bytes(
    bytes: &[u8],
    on_progress: impl FnMut(u64, u64),
    on_message: impl FnMut(&Channel, &RecordedMessage<'_>) -> anyhow::Result<()>,
) -> anyhow::Result<Recording> {
    walk(bytes, bytes.len() as u64, on_progress, on_message).map_err(|e| match e {
        WalkError::NotMcap => anyhow::anyhow!("not an MCAP file"),
        WalkError::Io(e) => anyhow::Error::new(e),
        WalkError::Consumer(e) => e,
    })
}

/// Random access to the bytes of a recording.
trait Source {
    /// Fills `buf` from `offset`; the caller keeps within the file.
    fn read_at(&self, offset: u64, buf: &mut [u8]) -> std::io::Result<()>;
}

impl Source for File {
    fn read_at(&self, offset: u64, buf: &mut [u8]) -> std::io::Result<()> {
        std::os::unix::fs::FileExt::read_exact_at(self, buf, offset)
    }
}

impl Source for [u8] {
    fn read_at(&self, offset: u64, buf: &mut [u8]) -> std::io::Result<()> {
        let src = usize::try_from(offset)
            .ok()
            .and_then(|o| self.get(o..)?.get(..buf.len()))
            .ok_or(std::io::ErrorKind::UnexpectedEof)?;
        buf.copy_from_slice(src);
        Ok(())
    }
}

#[derive(Debug)]
enum WalkError {
    NotMcap,
    Io(std::io::Error),
    Consumer(anyhow::Error),
}

impl From<std::io::Error> for WalkError {
    fn from(e: std::io::Error) -> Self {
        WalkError::Io(e)
    }
}

/// The largest record body read into memory: a chunk of
/// [`chunk::MAX_CHUNK_BYTES`] (compressed data can be slightly larger than
/// the data) or a metadata record. Larger records of the kinds nauta reads
/// are damage; others (indexes, attachments) are skipped unread.
const MAX_RECORD_BYTES: u64 = chunk::MAX_CHUNK_BYTES + (1 << 20);

/// What is at an offset of the file.
enum Next {
    /// A record: opcode and body length (the body is in the buffer).
    Record(u8, u64),
    /// A record that is skipped unread (one nauta does not use).
    Skip(u64),
    /// The file ends here or inside this record's header or body: a cut.
    Cut(String),
    /// Bytes that are not a record.
    Bad(String),
}

fn next_record<S: Source + ?Sized>(
    src: &S,
    file_bytes: u64,
    offset: u64,
    body: &mut Vec<u8>,
) -> std::io::Result<Next> {
    let left = file_bytes - offset;
    if left < records::HEAD_BYTES {
        return Ok(Next::Cut(format!(
            "the file ends {left} bytes into a record header at byte {offset}"
        )));
    }
    let mut head = [0u8; records::HEAD_BYTES as usize];
    src.read_at(offset, &mut head)?;
    let op = head[0];
    let mut len_bytes = [0u8; 8];
    len_bytes.copy_from_slice(&head[1..]);
    let len = u64::from_le_bytes(len_bytes);
    let room = left - records::HEAD_BYTES;
    // MCAP reserves opcode 0 and 0x10..=0x7f; 0x80 and above are private records.
    if op == 0 || (0x10..0x80).contains(&op) {
        return Ok(Next::Bad(format!(
            "opcode 0x{op:02x} at byte {offset} is not an MCAP record"
        )));
    }
    if len > room {
        return Ok(Next::Cut(format!(
            "the record at byte {offset} (opcode 0x{op:02x}) needs {len} bytes, the file has {room}"
        )));
    }
    let used = matches!(
        op,
        op::HEADER
            | op::SCHEMA
            | op::CHANNEL
            | op::MESSAGE
            | op::CHUNK
            | op::METADATA
            | op::DATA_END
    );
    if !used {
        return Ok(Next::Skip(len));
    }
    if len > MAX_RECORD_BYTES {
        return Ok(Next::Bad(format!(
            "the record at byte {offset} (opcode 0x{op:02x}) declares {len} bytes, more than the {MAX_RECORD_BYTES} a reader accepts"
        )));
    }
    // Bounded by the file and by MAX_RECORD_BYTES, so it fits a usize.
    body.resize(len as usize, 0);
    src.read_at(offset + records::HEAD_BYTES, body)?;
    Ok(Next::Record(op, len))
}

/// The offset of the next plausible record after damage at `from`: a chunk,
/// metadata or data-end record whose header is consistent with its length
/// and lies inside the file. `None` when there is none.
fn resync<S: Source + ?Sized>(src: &S, file_bytes: u64, from: u64) -> std::io::Result<Option<u64>> {
    // A window and enough bytes after it to see a chunk's header.
    const WINDOW: u64 = 1 << 20;
    const PEEK: u64 = records::HEAD_BYTES + 44;
    let mut window = Vec::new();
    let mut pos = from;
    while pos < file_bytes {
        let n = (WINDOW + PEEK).min(file_bytes - pos);
        window.resize(n as usize, 0);
        src.read_at(pos, &mut window)?;
        let scan = WINDOW.min(n) as usize;
        for i in 0..scan {
            if matches!(window[i], op::CHUNK | op::METADATA | op::DATA_END)
                && plausible(src, file_bytes, pos + i as u64, &window[i..])?
            {
                return Ok(Some(pos + i as u64));
            }
        }
        pos += scan as u64;
    }
    Ok(None)
}

fn plausible<S: Source + ?Sized>(
    src: &S,
    file_bytes: u64,
    at: u64,
    peek: &[u8],
) -> std::io::Result<bool> {
    let mut c = records::Cursor::new(peek);
    let (Ok(op), Ok(len)) = (c.bytes(1, "opcode").map(|b| b[0]), c.u64("length")) else {
        return Ok(false);
    };
    let fits = at
        .checked_add(records::HEAD_BYTES)
        .and_then(|b| b.checked_add(len))
        .is_some_and(|end| end <= file_bytes);
    if !fits {
        return Ok(false);
    }
    Ok(match op {
        op::DATA_END => len == 4,
        op::CHUNK => {
            let header = (|| {
                c.bytes(24, "times and size")?;
                c.u32("crc")?;
                let compression = c.str("compression")?;
                let records = c.u64("records length")?;
                Ok::<_, records::RecordError>((compression, records))
            })();
            matches!(header, Ok((compression, records))
                if matches!(compression, "" | "zstd" | "lz4")
                    && records.checked_add(40 + compression.len() as u64) == Some(len))
        }
        op::METADATA if len <= 1 << 20 => {
            let mut body = vec![0u8; len as usize];
            src.read_at(at + records::HEAD_BYTES, &mut body)?;
            records::parse_exact(op, &body).is_ok()
        }
        _ => false,
    })
}

/// The reader's state while it walks a file.
struct Walk<F> {
    rec: Recording,
    schemas: BTreeMap<u16, (String, Option<Schema>)>,
    on_message: F,
    /// The channels of the file's summary section (CRC-checked), for
    /// messages whose own channel record was lost with a damaged chunk.
    summary: BTreeMap<u16, Channel>,
}

fn walk<S, P, F>(
    src: &S,
    file_bytes: u64,
    mut on_progress: P,
    on_message: F,
) -> Result<Recording, WalkError>
where
    S: Source + ?Sized,
    P: FnMut(u64, u64),
    F: FnMut(&Channel, &RecordedMessage<'_>) -> anyhow::Result<()>,
{
    let mut magic = [0u8; 8];
    if file_bytes < 8 || src.read_at(0, &mut magic).is_err() || magic != MAGIC {
        return Err(WalkError::NotMcap);
    }
    let mut w = Walk {
        rec: Recording {
            recovery: Recovery {
                file_bytes,
                read_bytes: 8,
                truncated: true,
                ..Default::default()
            },
            ..Default::default()
        },
        schemas: BTreeMap::new(),
        on_message,
        summary: summary::channels(src, file_bytes)?,
    };
    let mut body = Vec::new();
    let mut chunk_data = Vec::new();
    let mut chunk_index = 0u64;
    let mut offset = 8u64;
    loop {
        let parsed = match next_record(src, file_bytes, offset, &mut body)? {
            Next::Record(op, len) => records::parse(op, &body)
                .map(|r| (r, len))
                .map_err(|e| format!("bad record at byte {offset} (opcode 0x{op:02x}): {e}")),
            Next::Skip(len) => {
                offset += records::HEAD_BYTES + len;
                w.rec.recovery.read_bytes = offset;
                on_progress(offset, file_bytes);
                continue;
            }
            Next::Cut(why) | Next::Bad(why) => Err(why),
        };
        let (record, len) = match parsed {
            Ok(p) => p,
            // Not a record: skip to the next one that is, or stop here.
            Err(why) => match resync(src, file_bytes, offset + 1)? {
                Some(next) => {
                    w.damaged(offset, next - offset, None, why);
                    offset = next;
                    continue;
                }
                None => {
                    w.rec.recovery.reason = Some(why);
                    break;
                }
            },
        };
        let end = offset + records::HEAD_BYTES + len;
        let mut data_end = false;
        match record {
            Record::Chunk(c) => {
                let index = chunk_index;
                chunk_index += 1;
                let decoded = chunk::decompress(&c, &mut chunk_data)
                    .and_then(|()| chunk::parse_all(&chunk_data));
                match decoded {
                    Ok(records) => {
                        w.rec.recovery.chunks += 1;
                        for r in records {
                            w.handle(r).map_err(WalkError::Consumer)?;
                        }
                    }
                    Err(e) => w.damaged(offset, end - offset, Some(index), e.to_string()),
                }
            }
            Record::Header { profile } => w.rec.profile = profile.to_owned(),
            Record::DataEnd => data_end = true,
            r => w.handle(r).map_err(WalkError::Consumer)?,
        }
        offset = end;
        w.rec.recovery.read_bytes = offset;
        on_progress(offset, file_bytes);
        if data_end {
            w.rec.recovery.truncated = false;
            break;
        }
    }
    on_progress(file_bytes, file_bytes);
    Ok(w.rec)
}

impl<F> Walk<F>
where
    F: FnMut(&Channel, &RecordedMessage<'_>) -> anyhow::Result<()>,
{
    fn damaged(&mut self, offset: u64, bytes: u64, chunk: Option<u64>, reason: String) {
        let r = &mut self.rec.recovery;
        r.damaged.push(Damage {
            offset,
            bytes,
            chunk,
            reason,
        });
        r.damaged_chunks = r.damaged.len() as u64;
    }

    fn handle(&mut self, record: Record<'_>) -> anyhow::Result<()> {
        let rec = &mut self.rec;
        match record {
            Record::Schema {
                id,
                name,
                encoding,
                data,
            } => {
                let parsed = (encoding == crate::SCHEMA_ENCODING)
                    .then(|| Schema::from_bytes(data).ok())
                    .flatten();
                self.schemas.insert(id, (name.to_owned(), parsed));
            }
            Record::Channel {
                id,
                schema_id,
                topic,
                message_encoding,
                metadata,
            } => {
                let (type_name, schema) = match self.schemas.get(&schema_id) {
                    Some((name, schema)) => (name.clone(), schema.clone()),
                    None => (metadata.get("type").cloned().unwrap_or_default(), None),
                };
                rec.channels.insert(
                    id,
                    Channel {
                        id,
                        topic: topic.to_owned(),
                        type_name,
                        message_encoding: message_encoding.to_owned(),
                        schema,
                    },
                );
            }
            Record::Message {
                channel_id,
                log_time,
                publish_time,
                data,
            } => {
                // A message whose channel record was lost is interpreted by
                // the summary's channel, or not at all (MCAP writes a channel
                // before its first message).
                if !rec.channels.contains_key(&channel_id)
                    && let Some(ch) = self.summary.remove(&channel_id)
                {
                    rec.channels.insert(channel_id, ch);
                }
                match rec.channels.get(&channel_id) {
                    Some(ch) => (self.on_message)(
                        ch,
                        &RecordedMessage {
                            log_time_ns: log_time,
                            publish_time_ns: publish_time,
                            data,
                        },
                    )?,
                    None => rec.recovery.unknown_channel_messages += 1,
                }
            }
            Record::Metadata { name, entries } => rec.metadata.push((name.to_owned(), entries)),
            _ => {}
        }
        Ok(())
    }
}

#[cfg(test)]
mod damage_tests;
#[cfg(test)]
mod tests;
