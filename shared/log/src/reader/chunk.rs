//! A chunk's records, decompressed and checked before any is used.
//!
//! A chunk is decompressed into at most the size it declares (and never
//! more than [`MAX_CHUNK_BYTES`], nor more than [`MAX_EXPANSION`] times its
//! compressed size: a small chunk that claims gigabytes is a bomb, refused
//! before anything is allocated); its CRC32 is verified when the writer set
//! one; then every record in it is parsed. Only when all of that holds are
//! its records handed on, so a damaged chunk is skipped whole and nothing
//! from it is used.

use std::io::Read as _;

use super::records::{self, Chunk, Record, RecordError, op};

/// The largest chunk a reader accepts, decompressed: 256 MiB. nauta writes
/// 4 MiB chunks ([`crate::WriterOptions`]); other MCAP writers use a few MiB.
pub const MAX_CHUNK_BYTES: u64 = 256 << 20;

/// The most a chunk may expand when decompressed (declared uncompressed size
/// over compressed size), beyond a 1 MiB allowance. nauta's recordings
/// expand 2.5x, their Foxglove exports (JSON) 4-6x (docs/design-notes.md,
/// "Reading damaged recordings"); zstd reaches thousands on runs of one byte,
/// which no recording holds. 32x also bounds what a hostile file can make a
/// reader hold: 32 times its own size.
pub const MAX_EXPANSION: u64 = 32;

/// Why a chunk was skipped.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ChunkDecodeError {
    /// It declares more than a reader accepts.
    #[error("declares {declared} bytes uncompressed, more than the {limit} a reader accepts")]
    TooLarge {
        /// Declared uncompressed size.
        declared: u64,
        /// The limit.
        limit: u64,
    },
    /// It declares far more than its compressed size can hold.
    #[error(
        "declares {declared} bytes uncompressed from {compressed} compressed, more than {MAX_EXPANSION}x: refused as a decompression bomb"
    )]
    Bomb {
        /// Declared uncompressed size.
        declared: u64,
        /// Compressed size.
        compressed: u64,
    },
    /// An unknown compression.
    #[error("unknown compression {0:?}")]
    Compression(String),
    /// The compressed stream is damaged.
    #[error("{compression} stream damaged: {message}")]
    Stream {
        /// `zstd` or `lz4`.
        compression: &'static str,
        /// The decoder's error.
        message: String,
    },
    /// It decompresses to another size than it declares.
    #[error("decompresses to {got} bytes, declares {declared}")]
    Size {
        /// Declared size.
        declared: u64,
        /// Decompressed size (at most `declared + 1`: decoding stops there).
        got: u64,
    },
    /// Its CRC does not match its records.
    #[error("CRC32 of its records is {computed:08x}, it declares {stored:08x}")]
    Crc {
        /// The chunk's CRC.
        stored: u32,
        /// The records' CRC.
        computed: u32,
    },
    /// A record in it cannot be parsed.
    #[error("record {index} in it: {error}")]
    Record {
        /// Which record (0-based).
        index: usize,
        /// Why.
        error: RecordError,
    },
    /// It holds a record a chunk may not hold (MCAP chunks hold schemas,
    /// channels and messages).
    #[error("record {index} in it has opcode 0x{opcode:02x}, not a schema, channel or message")]
    Opcode {
        /// Which record (0-based).
        index: usize,
        /// Its opcode.
        opcode: u8,
    },
}

/// Decompresses `chunk`'s records into `out` (cleared first), checked
/// against its declared size and CRC.
pub fn decompress(chunk: &Chunk<'_>, out: &mut Vec<u8>) -> Result<(), ChunkDecodeError> {
    let declared = chunk.uncompressed_size;
    let compressed = chunk.records.len() as u64;
    if declared > MAX_CHUNK_BYTES {
        return Err(ChunkDecodeError::TooLarge {
            declared,
            limit: MAX_CHUNK_BYTES,
        });
    }
    if declared
        > compressed
            .saturating_mul(MAX_EXPANSION)
            .saturating_add(1 << 20)
    {
        return Err(ChunkDecodeError::Bomb {
            declared,
            compressed,
        });
    }
    out.clear();
    // `declared` is bounded above, so it fits a usize; reading stops one byte
    // past it, so a stream that holds more is caught without holding it.
    out.reserve(declared as usize);
    let limit = declared + 1;
    let stream = |compression: &'static str| {
        move |e: std::io::Error| ChunkDecodeError::Stream {
            compression,
            message: e.to_string(),
        }
    };
    match chunk.compression {
        "" => out.extend_from_slice(chunk.records),
        "zstd" => {
            zstd::stream::read::Decoder::with_buffer(chunk.records)
                .map_err(stream("zstd"))?
                .take(limit)
                .read_to_end(out)
                .map_err(stream("zstd"))?;
        }
        "lz4" => {
            lz4::Decoder::new(chunk.records)
                .map_err(stream("lz4"))?
                .take(limit)
                .read_to_end(out)
                .map_err(stream("lz4"))?;
        }
        other => return Err(ChunkDecodeError::Compression(other.to_owned())),
    }
    if out.len() as u64 != declared {
        return Err(ChunkDecodeError::Size {
            declared,
            got: out.len() as u64,
        });
    }
    if chunk.uncompressed_crc != 0 {
        let computed = crc32fast::hash(out);
        if computed != chunk.uncompressed_crc {
            return Err(ChunkDecodeError::Crc {
                stored: chunk.uncompressed_crc,
                computed,
            });
        }
    }
    Ok(())
}

/// Every record of decompressed chunk data, all parsed before any is
/// returned: a chunk with one bad record yields none.
pub fn parse_all(data: &[u8]) -> Result<Vec<Record<'_>>, ChunkDecodeError> {
    let mut out = Vec::new();
    for (index, r) in records::split(data).enumerate() {
        let (opcode, body) = r.map_err(|error| ChunkDecodeError::Record { index, error })?;
        if !matches!(opcode, op::SCHEMA | op::CHANNEL | op::MESSAGE) {
            return Err(ChunkDecodeError::Opcode { index, opcode });
        }
        out.push(
            records::parse(opcode, body)
                .map_err(|error| ChunkDecodeError::Record { index, error })?,
        );
    }
    Ok(out)
}
