//! MCAP records, parsed from untrusted bytes.
//!
//! A record is an opcode (u8), a body length (u64 little-endian) and the body.
//! Every field is read through [`Cursor`], which checks each length against
//! the bytes that are left before it takes anything, so a length field that
//! lies can neither allocate nor index out of bounds: it is a
//! [`RecordError`]. Records borrow from the body; only the strings and maps
//! nauta keeps are copied, and they are no longer than the body.
//!
//! Only the records a reader uses are parsed (header, schema, channel,
//! message, chunk, metadata, data end); the others are [`Record::Other`].

use std::collections::BTreeMap;

/// MCAP opcodes (<https://mcap.dev/spec>, "Records").
pub mod op {
    /// Header: profile, library.
    pub const HEADER: u8 = 0x01;
    /// Footer: summary start, summary offset start, summary CRC.
    pub const FOOTER: u8 = 0x02;
    /// Schema: id, name, encoding, data.
    pub const SCHEMA: u8 = 0x03;
    /// Channel: id, schema id, topic, message encoding, metadata.
    pub const CHANNEL: u8 = 0x04;
    /// Message: channel id, sequence, log time, publish time, data.
    pub const MESSAGE: u8 = 0x05;
    /// Chunk: times, uncompressed size and CRC, compression, records.
    pub const CHUNK: u8 = 0x06;
    /// Message index (after each chunk).
    pub const MESSAGE_INDEX: u8 = 0x07;
    /// Metadata: name, map.
    pub const METADATA: u8 = 0x0c;
    /// Data end: the data section's CRC.
    pub const DATA_END: u8 = 0x0f;
}

/// A record header: opcode and body length.
pub const HEAD_BYTES: u64 = 9;

/// Why a record's body cannot be parsed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RecordError {
    /// A field (or a length it announces) runs past the end of the body.
    #[error("{field} needs {need} bytes at byte {at} of the record, {left} are left")]
    Short {
        /// The field being read.
        field: &'static str,
        /// Bytes it needs.
        need: u64,
        /// Where in the body it starts.
        at: usize,
        /// Bytes left in the body.
        left: usize,
    },
    /// Bytes after the last field (refused only by [`parse_exact`]).
    #[error("{left} bytes after the last field")]
    Trailing {
        /// How many.
        left: usize,
    },
    /// A string field is not UTF-8.
    #[error("{field} is not UTF-8")]
    NotUtf8 {
        /// The field.
        field: &'static str,
    },
}

/// Reads little-endian fields from a record body, every length checked
/// against what is left.
#[derive(Debug)]
pub struct Cursor<'a> {
    body: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `body`.
    pub fn new(body: &'a [u8]) -> Self {
        Cursor { body, at: 0 }
    }

    /// Bytes not yet read.
    pub fn left(&self) -> usize {
        self.body.len() - self.at
    }

    /// The next `n` bytes; an error (not an allocation, not a panic) when the
    /// body has fewer.
    pub fn bytes(&mut self, n: u64, field: &'static str) -> Result<&'a [u8], RecordError> {
        let short = RecordError::Short {
            field,
            need: n,
            at: self.at,
            left: self.left(),
        };
        let n = usize::try_from(n).map_err(|_| short.clone())?;
        let end = self.at.checked_add(n).ok_or_else(|| short.clone())?;
        let out = self.body.get(self.at..end).ok_or(short)?;
        self.at = end;
        Ok(out)
    }

    fn array<const N: usize>(&mut self, field: &'static str) -> Result<[u8; N], RecordError> {
        let b = self.bytes(N as u64, field)?;
        let mut out = [0u8; N];
        out.copy_from_slice(b);
        Ok(out)
    }

    /// A u16.
    pub fn u16(&mut self, field: &'static str) -> Result<u16, RecordError> {
        self.array(field).map(u16::from_le_bytes)
    }

    /// A u32.
    pub fn u32(&mut self, field: &'static str) -> Result<u32, RecordError> {
        self.array(field).map(u32::from_le_bytes)
    }

    /// A u64.
    pub fn u64(&mut self, field: &'static str) -> Result<u64, RecordError> {
        self.array(field).map(u64::from_le_bytes)
    }

    /// A string: u32 byte length, UTF-8 bytes.
    pub fn str(&mut self, field: &'static str) -> Result<&'a str, RecordError> {
        let n = self.u32(field)?;
        let b = self.bytes(u64::from(n), field)?;
        std::str::from_utf8(b).map_err(|_| RecordError::NotUtf8 { field })
    }

    /// A byte array with a u32 length.
    pub fn bytes_u32(&mut self, field: &'static str) -> Result<&'a [u8], RecordError> {
        let n = self.u32(field)?;
        self.bytes(u64::from(n), field)
    }

    /// A byte array with a u64 length.
    pub fn bytes_u64(&mut self, field: &'static str) -> Result<&'a [u8], RecordError> {
        let n = self.u64(field)?;
        self.bytes(n, field)
    }

    /// A `Map<string, string>`: u32 byte length of the entries, then
    /// key and value strings.
    pub fn map(&mut self, field: &'static str) -> Result<BTreeMap<String, String>, RecordError> {
        let mut entries = Cursor::new(self.bytes_u32(field)?);
        let mut out = BTreeMap::new();
        while entries.left() > 0 {
            let k = entries.str(field)?;
            let v = entries.str(field)?;
            out.insert(k.to_owned(), v.to_owned());
        }
        Ok(out)
    }

    /// Everything not yet read.
    pub fn rest(&mut self) -> &'a [u8] {
        let out = &self.body[self.at..];
        self.at = self.body.len();
        out
    }
}

/// A chunk record: the records it holds, compressed.
#[derive(Debug, Clone, Copy)]
pub struct Chunk<'a> {
    /// Earliest message log time, ns.
    pub message_start_time: u64,
    /// Latest message log time, ns.
    pub message_end_time: u64,
    /// Size of the records once decompressed, bytes.
    pub uncompressed_size: u64,
    /// CRC32 of the decompressed records; 0 when the writer did not set it.
    pub uncompressed_crc: u32,
    /// `""` (none), `"zstd"` or `"lz4"`.
    pub compression: &'a str,
    /// The compressed records.
    pub records: &'a [u8],
}

/// A parsed record.
#[derive(Debug, Clone)]
pub enum Record<'a> {
    /// The file header.
    Header {
        /// MCAP profile.
        profile: &'a str,
    },
    /// A schema.
    Schema {
        /// Schema id (0 is not a valid id).
        id: u16,
        /// Type name.
        name: &'a str,
        /// Schema encoding.
        encoding: &'a str,
        /// Schema data.
        data: &'a [u8],
    },
    /// A channel.
    Channel {
        /// Channel id.
        id: u16,
        /// Its schema's id (0: none).
        schema_id: u16,
        /// Topic.
        topic: &'a str,
        /// Message encoding.
        message_encoding: &'a str,
        /// Channel metadata.
        metadata: BTreeMap<String, String>,
    },
    /// A message.
    Message {
        /// Its channel.
        channel_id: u16,
        /// Receive time, ns.
        log_time: u64,
        /// Publish time, ns.
        publish_time: u64,
        /// Payload.
        data: &'a [u8],
    },
    /// A chunk.
    Chunk(Chunk<'a>),
    /// A metadata record.
    Metadata {
        /// Its name.
        name: &'a str,
        /// Its entries.
        entries: BTreeMap<String, String>,
    },
    /// The end of the data section.
    DataEnd,
    /// Any other record (indexes, summary, attachments, unknown opcodes).
    Other,
}

/// Parses the body of a record with opcode `op`. Trailing bytes after the
/// fields are allowed (MCAP lets records grow fields at their end).
pub fn parse(op: u8, body: &[u8]) -> Result<Record<'_>, RecordError> {
    parse_fields(op, &mut Cursor::new(body))
}

/// [`parse`], refusing trailing bytes: how a reader recognises a record
/// when it looks for one after damage.
pub fn parse_exact(op: u8, body: &[u8]) -> Result<Record<'_>, RecordError> {
    let mut c = Cursor::new(body);
    let r = parse_fields(op, &mut c)?;
    match c.left() {
        0 => Ok(r),
        left => Err(RecordError::Trailing { left }),
    }
}

fn parse_fields<'a>(op: u8, c: &mut Cursor<'a>) -> Result<Record<'a>, RecordError> {
    Ok(match op {
        op::HEADER => {
            let profile = c.str("header profile")?;
            c.str("header library")?;
            Record::Header { profile }
        }
        op::SCHEMA => Record::Schema {
            id: c.u16("schema id")?,
            name: c.str("schema name")?,
            encoding: c.str("schema encoding")?,
            data: c.bytes_u32("schema data")?,
        },
        op::CHANNEL => Record::Channel {
            id: c.u16("channel id")?,
            schema_id: c.u16("channel schema id")?,
            topic: c.str("channel topic")?,
            message_encoding: c.str("channel message encoding")?,
            metadata: c.map("channel metadata")?,
        },
        op::MESSAGE => {
            let channel_id = c.u16("message channel id")?;
            c.u32("message sequence")?;
            Record::Message {
                channel_id,
                log_time: c.u64("message log time")?,
                publish_time: c.u64("message publish time")?,
                data: c.rest(),
            }
        }
        op::CHUNK => Record::Chunk(Chunk {
            message_start_time: c.u64("chunk start time")?,
            message_end_time: c.u64("chunk end time")?,
            uncompressed_size: c.u64("chunk uncompressed size")?,
            uncompressed_crc: c.u32("chunk uncompressed crc")?,
            compression: c.str("chunk compression")?,
            records: c.bytes_u64("chunk records")?,
        }),
        op::METADATA => Record::Metadata {
            name: c.str("metadata name")?,
            entries: c.map("metadata map")?,
        },
        op::DATA_END => {
            c.u32("data end crc")?;
            Record::DataEnd
        }
        _ => Record::Other,
    })
}

/// Splits `bytes` (a chunk's decompressed records) into `(opcode, body)`
/// pairs; each length is checked against the bytes that are left before the
/// body is taken.
pub fn split(bytes: &[u8]) -> impl Iterator<Item = Result<(u8, &[u8]), RecordError>> {
    let mut c = Cursor::new(bytes);
    let mut failed = false;
    std::iter::from_fn(move || {
        if failed || c.left() == 0 {
            return None;
        }
        let next = (|| {
            let op = c.bytes(1, "record opcode")?[0];
            let body = c.bytes_u64("record body")?;
            Ok((op, body))
        })();
        failed = next.is_err();
        Some(next)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_length_beyond_the_body_is_an_error_not_an_allocation() {
        // A schema whose data claims 4 GiB in a 20-byte body.
        let mut body = 7u16.to_le_bytes().to_vec();
        for s in ["a", "b"] {
            body.extend_from_slice(&(s.len() as u32).to_le_bytes());
            body.extend_from_slice(s.as_bytes());
        }
        body.extend_from_slice(&u32::MAX.to_le_bytes());
        let e = parse(op::SCHEMA, &body).expect_err("short");
        assert!(
            matches!(
                e,
                RecordError::Short {
                    field: "schema data",
                    ..
                }
            ),
            "{e}"
        );
        // A u64 length that overflows usize arithmetic.
        let mut chunk = vec![0u8; 28];
        chunk.extend_from_slice(&0u32.to_le_bytes());
        chunk.extend_from_slice(&u64::MAX.to_le_bytes());
        assert!(parse(op::CHUNK, &chunk).is_err());
        // Every prefix of a valid record fails cleanly.
        for n in 0..body.len() {
            let _ = parse(op::CHANNEL, &body[..n]);
        }
    }

    #[test]
    fn split_stops_at_the_first_record_that_runs_past_the_end() {
        let mut bytes = vec![op::MESSAGE];
        bytes.extend_from_slice(&2u64.to_le_bytes());
        bytes.extend_from_slice(&[1, 2]);
        bytes.push(op::MESSAGE);
        bytes.extend_from_slice(&u64::MAX.to_le_bytes());
        let got: Vec<_> = split(&bytes).collect();
        assert_eq!(got.len(), 2);
        assert_eq!(got[0], Ok((op::MESSAGE, &[1u8, 2][..])));
        assert!(got[1].is_err());
    }
}
