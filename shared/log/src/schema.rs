//! The schema record of a nauta type ([`crate::SCHEMA_ENCODING`]): a JSON object
//! that names the type and lists its fields in wire order, so a reader without
//! nauta's source can decode the bincode payload:
//!
//! ```json
//! {"type": "nauta.DepthSample.v1", "size": 40,
//!  "encoding": "bincode 2: fixed-width little-endian integers, IEEE-754 floats, fields in order, arrays without length",
//!  "fields": [{"name": "header", "type": "Header", "doc": "..."}, {"name": "depth_m", "type": "f64", "doc": "Depth, m."}],
//!  "header": [{"name": "stamp_ns", "type": "u64"}, ...]}
//! ```

use nauta_messages::TypeInfo;
use serde::{Deserialize, Serialize};

/// How the payload is encoded, in words.
pub const ENCODING_TEXT: &str = "bincode 2: fixed-width little-endian integers, IEEE-754 floats, fields in order, arrays without length";

/// One field of a schema.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Field {
    /// Name, with its unit.
    pub name: String,
    /// Rust type as written (`[f64; 3]`).
    #[serde(rename = "type")]
    pub ty: String,
    /// Documentation.
    #[serde(default)]
    pub doc: String,
}

/// A nauta schema record's content.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Schema {
    /// Pinned type name.
    #[serde(rename = "type")]
    pub type_name: String,
    /// Size in shared memory, bytes.
    pub size: usize,
    /// The payload encoding, in words.
    pub encoding: String,
    /// Fields in wire order.
    pub fields: Vec<Field>,
    /// The fields of the common header (the type of the first field).
    pub header: Vec<Field>,
}

impl Schema {
    /// The schema of a registered type.
    pub fn of(t: &TypeInfo) -> Self {
        let header = [
            ("stamp_ns", "u64", "time of validity, run clock, ns"),
            ("seq", "u64", "per-publisher sequence number"),
            ("source", "u32", "producing role"),
            ("instance", "u32", "start count of that role in this run"),
            (
                "flags",
                "u32",
                "bit flags: 1 valid, 2 degraded, 4 end of stream, 8 initialising",
            ),
            ("reserved", "u32", "zero"),
        ];
        Schema {
            type_name: t.type_name.to_owned(),
            size: t.size,
            encoding: ENCODING_TEXT.to_owned(),
            fields: t
                .fields
                .iter()
                .map(|f| Field {
                    name: f.name.to_owned(),
                    ty: f.ty.to_owned(),
                    doc: f.doc.trim().to_owned(),
                })
                .collect(),
            header: header
                .iter()
                .map(|(n, t, d)| Field {
                    name: (*n).to_owned(),
                    ty: (*t).to_owned(),
                    doc: (*d).to_owned(),
                })
                .collect(),
        }
    }

    /// The record's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        serde_json::to_vec(self).unwrap_or_default()
    }

    /// Parses a record's bytes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, serde_json::Error> {
        serde_json::from_slice(bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_registered_type_round_trips() {
        for t in nauta_messages::registry::all_types() {
            let s = Schema::of(&t);
            assert_eq!(s.fields[0].name, "header");
            let back = Schema::from_bytes(&s.to_bytes()).expect("parse");
            assert_eq!(back, s);
        }
    }
}
