//! The size of a value in nauta's recording encoding (bincode 2 serde,
//! fixed-width little-endian integers: `nauta_messages::codec::config()`),
//! counted by a serde serializer instead of encoding, since this crate does
//! not depend on bincode: booleans and `u8` 1 byte, other integers their
//! width, `f32`/`f64` 4/8, `Option` 1 + the value, a sequence or string an
//! 8-byte length then its elements, an enum variant a 4-byte index, structs,
//! tuples and arrays their fields in order.

use serde::ser::{self, Impossible, Serialize};

/// Bytes `value` takes in the encoding.
pub fn encoded_size<T: Serialize>(value: &T) -> usize {
    let mut s = Size(0);
    value.serialize(&mut s).expect("serialisable");
    s.0
}

struct Size(usize);

#[derive(Debug)]
struct Unsupported(String);

impl std::fmt::Display for Unsupported {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Unsupported {}

impl ser::Error for Unsupported {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        Self(msg.to_string())
    }
}

type R = Result<(), Unsupported>;

impl ser::Serializer for &mut Size {
    type Ok = ();
    type Error = Unsupported;
    type SerializeSeq = Self;
    type SerializeTuple = Self;
    type SerializeTupleStruct = Self;
    type SerializeTupleVariant = Self;
    type SerializeMap = Impossible<(), Unsupported>;
    type SerializeStruct = Self;
    type SerializeStructVariant = Self;

    fn serialize_bool(self, _: bool) -> R {
        self.0 += 1;
        Ok(())
    }
    fn serialize_i8(self, _: i8) -> R {
        self.0 += 1;
        Ok(())
    }
    fn serialize_i16(self, _: i16) -> R {
        self.0 += 2;
        Ok(())
    }
    fn serialize_i32(self, _: i32) -> R {
        self.0 += 4;
        Ok(())
    }
    fn serialize_i64(self, _: i64) -> R {
        self.0 += 8;
        Ok(())
    }
    fn serialize_u8(self, _: u8) -> R {
        self.0 += 1;
        Ok(())
    }
    fn serialize_u16(self, _: u16) -> R {
        self.0 += 2;
        Ok(())
    }
    fn serialize_u32(self, _: u32) -> R {
        self.0 += 4;
        Ok(())
    }
    fn serialize_u64(self, _: u64) -> R {
        self.0 += 8;
        Ok(())
    }
    fn serialize_f32(self, _: f32) -> R {
        self.0 += 4;
        Ok(())
    }
    fn serialize_f64(self, _: f64) -> R {
        self.0 += 8;
        Ok(())
    }
    fn serialize_char(self, c: char) -> R {
        self.0 += c.len_utf8();
        Ok(())
    }
    fn serialize_str(self, v: &str) -> R {
        self.0 += 8 + v.len();
        Ok(())
    }
    fn serialize_bytes(self, v: &[u8]) -> R {
        self.0 += 8 + v.len();
        Ok(())
    }
    fn serialize_none(self) -> R {
        self.0 += 1;
        Ok(())
    }
    fn serialize_some<T: ?Sized + Serialize>(self, v: &T) -> R {
        self.0 += 1;
        v.serialize(self)
    }
    fn serialize_unit(self) -> R {
        Ok(())
    }
    fn serialize_unit_struct(self, _: &'static str) -> R {
        Ok(())
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, _: &'static str) -> R {
        self.0 += 4;
        Ok(())
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(self, _: &'static str, v: &T) -> R {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        v: &T,
    ) -> R {
        self.0 += 4;
        v.serialize(self)
    }
    fn serialize_seq(self, len: Option<usize>) -> Result<Self, Unsupported> {
        len.ok_or_else(|| Unsupported("a sequence of unknown length".into()))?;
        self.0 += 8;
        Ok(self)
    }
    fn serialize_tuple(self, _: usize) -> Result<Self, Unsupported> {
        Ok(self)
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Self, Unsupported> {
        Ok(self)
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self, Unsupported> {
        self.0 += 4;
        Ok(self)
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, Unsupported> {
        Err(Unsupported("maps are not counted".into()))
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self, Unsupported> {
        Ok(self)
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self, Unsupported> {
        self.0 += 4;
        Ok(self)
    }
}

macro_rules! compound {
    ($($t:ident :: $m:ident),*) => {$(
        impl ser::$t for &mut Size {
            type Ok = ();
            type Error = Unsupported;
            fn $m<T: ?Sized + Serialize>(&mut self, v: &T) -> R { v.serialize(&mut **self) }
            fn end(self) -> R { Ok(()) }
        }
    )*};
}
compound!(
    SerializeSeq::serialize_element,
    SerializeTuple::serialize_element,
    SerializeTupleStruct::serialize_field,
    SerializeTupleVariant::serialize_field
);

impl ser::SerializeStruct for &mut Size {
    type Ok = ();
    type Error = Unsupported;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, _: &'static str, v: &T) -> R {
        v.serialize(&mut **self)
    }
    fn end(self) -> R {
        Ok(())
    }
}

impl ser::SerializeStructVariant for &mut Size {
    type Ok = ();
    type Error = Unsupported;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, _: &'static str, v: &T) -> R {
        v.serialize(&mut **self)
    }
    fn end(self) -> R {
        Ok(())
    }
}

#[test]
fn sizes_follow_the_fixed_int_layout() {
    assert_eq!(
        encoded_size(&(1u8, 2u32, 3u64, 1.0f64, true)),
        1 + 4 + 8 + 8 + 1
    );
    assert_eq!(encoded_size(&Some([0u64; 2])), 17);
    assert_eq!(encoded_size(&None::<u64>), 1);
    assert_eq!(encoded_size(&vec![0u32; 3]), 8 + 12);
}
