//! The message contract between nauta's processes (DESIGN §4).
//!
//! Every message is `#[repr(C)]`, `Copy`, holds only fixed-width numbers and fixed
//! arrays, starts with the common [`Header`], carries a pinned, versioned type name
//! (`nauta.ImuSample.v1`) and has a compile-time size assertion. Field names carry
//! their units. Quaternions are `[w, x, y, z]` (Hamilton) and rotate body (FRD)
//! vectors into the navigation frame (NED).
//!
//! Raw messages are what travels; [`checked`] turns them into validated domain
//! values so that estimators never see a NaN, an out-of-range value or a stamp
//! that goes backwards.

#[macro_use]
mod macros;

pub mod checked;
pub mod codec;
pub mod control;
pub mod domain;
pub mod estimates;
pub mod header;
pub mod lbl;
pub mod positioning;
pub mod registry;
pub mod sensors;
pub mod snapshots;

pub use header::{Flags, GapCounter, Header, Role};
pub use registry::{FieldInfo, Message, MessageVisitor, TypeInfo};

pub use control::*;
pub use estimates::*;
pub use sensors::*;
pub use snapshots::*;

/// Decodes a fixed, NUL-padded byte array into a string (lossy, up to the first NUL).
pub fn fixed_str(bytes: &[u8]) -> String {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}

/// Encodes `s` into a fixed, NUL-padded byte array, truncating at a character boundary.
pub fn to_fixed_str<const N: usize>(s: &str) -> [u8; N] {
    let mut out = [0u8; N];
    let mut len = 0;
    for (i, c) in s.char_indices() {
        let end = i + c.len_utf8();
        if end > N {
            break;
        }
        len = end;
    }
    out[..len].copy_from_slice(&s.as_bytes()[..len]);
    out
}
