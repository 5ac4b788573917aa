//! The one place that knows the recording encoding: bincode 2 with serde,
//! fixed-width integers, little-endian (DESIGN §8). Keep every use of bincode
//! behind this module so it can be swapped.

use crate::Message;

/// Encoding failed.
#[derive(Debug, thiserror::Error)]
#[error("cannot encode {type_name}: {source}")]
pub struct EncodeError {
    /// Type being encoded.
    pub type_name: &'static str,
    /// Underlying bincode error.
    #[source]
    pub source: bincode::error::EncodeError,
}

/// Decoding failed.
#[derive(Debug, thiserror::Error)]
pub enum DecodeError {
    /// The bytes are not a valid encoding of the type.
    #[error("cannot decode {type_name}: {source}")]
    Invalid {
        /// Type being decoded.
        type_name: &'static str,
        /// Underlying bincode error.
        #[source]
        source: bincode::error::DecodeError,
    },
    /// The bytes hold more than one message.
    #[error("cannot decode {type_name}: {extra} trailing bytes")]
    TrailingBytes {
        /// Type being decoded.
        type_name: &'static str,
        /// Bytes left over.
        extra: usize,
    },
}

/// The bincode configuration of every encoding nauta writes (wire messages,
/// and the opaque estimator states inside snapshots).
pub fn config() -> impl bincode::config::Config {
    bincode::config::standard()
        .with_fixed_int_encoding()
        .with_little_endian()
}

/// Encodes a message.
pub fn encode<M: Message>(msg: &M) -> Result<Vec<u8>, EncodeError> {
    bincode::serde::encode_to_vec(msg, config()).map_err(|source| EncodeError {
        type_name: M::TYPE_NAME,
        source,
    })
}

/// Decodes a message; the bytes must hold exactly one.
pub fn decode<M: Message>(bytes: &[u8]) -> Result<M, DecodeError> {
    let (msg, used) = bincode::serde::decode_from_slice(bytes, config()).map_err(|source| {
        DecodeError::Invalid {
            type_name: M::TYPE_NAME,
            source,
        }
    })?;
    if used != bytes.len() {
        return Err(DecodeError::TrailingBytes {
            type_name: M::TYPE_NAME,
            extra: bytes.len() - used,
        });
    }
    Ok(msg)
}
