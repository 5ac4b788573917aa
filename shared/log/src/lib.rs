//! nauta's recording format (DESIGN §8): one MCAP file per run.
//!
//! - every message is stored as its bincode encoding ([`nauta_messages::codec`]:
//!   fixed-width little-endian integers, fields in declaration order), on a
//!   channel named by its service (`sensor/imu`, without the run's namespace);
//! - each type has a schema record ([`SCHEMA_ENCODING`]) that names and orders
//!   its fields with their types, units and documentation, so the file
//!   describes itself;
//! - log time is the logger's receive time (ns since the Unix epoch), publish
//!   time the message's `stamp_ns` (run clock);
//! - chunks are zstd-compressed and written whole: a file cut short (a logger
//!   killed with `kill -9`, a full disk) keeps every chunk written before the
//!   cut, and [`reader`] recovers them and says how much was lost.
//!
//! Metadata records: [`META_RUN`] (manifest, command line, seed, git revision,
//! sensor configuration) at the start, [`META_STATS`] (the logger's own
//! per-channel counts) at the end.

pub mod checked;
pub mod export;
pub mod info;
pub mod reader;
pub mod run;
pub mod schema;
pub mod streams;
pub mod utc;
pub mod writer;

pub use info::{ChannelSummary, LogInfo};
pub use reader::{Channel, Recording, Recovery, read};
pub use writer::{LogWriter, WriterOptions};

/// Message encoding of every nauta channel.
pub const MESSAGE_ENCODING: &str = "nauta-bincode2";
/// Schema encoding of nauta's schema records (see [`schema`]).
pub const SCHEMA_ENCODING: &str = "nauta-fields-json";
/// MCAP profile.
pub const PROFILE: &str = "nauta";
/// Metadata record written at the start: how the run was made.
pub const META_RUN: &str = "nauta.run";
/// Metadata record written at the end by the logger: what it received.
pub const META_STATS: &str = "nauta.logger.stats";

/// The common header of a recorded message: its first 32 bytes (the bincode
/// fixed-int little-endian encoding of [`nauta_messages::Header`]).
pub fn header_of(data: &[u8]) -> Option<nauta_messages::Header> {
    let b = data.get(..32)?;
    let u64_at = |i: usize| u64::from_le_bytes(b[i..i + 8].try_into().unwrap_or([0; 8]));
    let u32_at = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap_or([0; 4]));
    Some(nauta_messages::Header {
        stamp_ns: u64_at(0),
        seq: u64_at(8),
        source: u32_at(16),
        instance: u32_at(20),
        flags: u32_at(24),
        reserved: u32_at(28),
    })
}

#[cfg(test)]
mod tests {
    use nauta_messages::*;

    #[test]
    fn header_is_the_first_32_bytes_of_the_encoding() {
        let mut m = ImuSample {
            header: Header::new(123_456_789, 42, Role::Sensor, 3),
            ..Default::default()
        };
        m.header.flags |= Flags::END_OF_STREAM.0;
        let bytes = codec::encode(&m).expect("encode");
        assert_eq!(super::header_of(&bytes), Some(m.header));
        assert_eq!(super::header_of(&bytes[..31]), None);
    }
}
