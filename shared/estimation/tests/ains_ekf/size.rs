//! The size of a value in nauta's recording encoding (bincode 2 with serde,
//! fixed-width little-endian integers: `nauta_messages::codec::config()`),
//! counted by a serde serializer that writes nothing: 1 byte for a bool,
//! u8 or i8, 2/4/8/16 for the wider integers, 4/8 for f32/f64, `u64`
//! lengths for sequences, maps, strings and bytes, a `u32` variant index
//! for enums, 1 byte for an `Option`'s tag. (`nauta-estimation` has no
//! bincode dependency and this test may not add one; the lead can swap
//! this for `nauta_messages::codec::encode` where both are at hand.)

use serde::ser::{self, Serialize};

/// Why counting failed (never, for plain data).
#[derive(Debug)]
pub struct Never(String);

impl std::fmt::Display for Never {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Never {}

impl ser::Error for Never {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        Never(msg.to_string())
    }
}

/// The byte counter.
#[derive(Debug)]
pub struct Size(pub usize);

/// The encoded size of `v`, bytes.
pub fn encoded_size<T: Serialize>(v: &T) -> usize {
    let mut s = Size(0);
    v.serialize(&mut s).expect("plain data");
    s.0
}

macro_rules! fixed {
    ($($f:ident: $t:ty = $n:expr),* $(,)?) => {
        $(fn $f(self, _: $t) -> Result<(), Never> { self.0 += $n; Ok(()) })*
    };
}

impl ser::Serializer for &mut Size {
    type Ok = ();
    type Error = Never;
    type SerializeSeq = Self;
    type SerializeTuple = Self;
    type SerializeTupleStruct = Self;
    type SerializeTupleVariant = Self;
    type SerializeMap = Self;
    type SerializeStruct = Self;
    type SerializeStructVariant = Self;

    fixed!(
        serialize_bool: bool = 1,
        serialize_i8: i8 = 1,
        serialize_i16: i16 = 2,
        serialize_i32: i32 = 4,
        serialize_i64: i64 = 8,
        serialize_i128: i128 = 16,
        serialize_u8: u8 = 1,
        serialize_u16: u16 = 2,
        serialize_u32: u32 = 4,
        serialize_u64: u64 = 8,
        serialize_u128: u128 = 16,
        serialize_f32: f32 = 4,
        serialize_f64: f64 = 8,
        serialize_char: char = 4,
    );

    fn serialize_str(self, v: &str) -> Result<(), Never> {
        self.0 += 8 + v.len();
        Ok(())
    }
    fn serialize_bytes(self, v: &[u8]) -> Result<(), Never> {
        self.0 += 8 + v.len();
        Ok(())
    }
    fn serialize_none(self) -> Result<(), Never> {
        self.0 += 1;
        Ok(())
    }
    fn serialize_some<T: ?Sized + Serialize>(self, v: &T) -> Result<(), Never> {
        self.0 += 1;
        v.serialize(self)
    }
    fn serialize_unit(self) -> Result<(), Never> {
        Ok(())
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<(), Never> {
        Ok(())
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, _: &'static str) -> Result<(), Never> {
        self.0 += 4;
        Ok(())
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        v: &T,
    ) -> Result<(), Never> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        v: &T,
    ) -> Result<(), Never> {
        self.0 += 4;
        v.serialize(self)
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Self, Never> {
        self.0 += 8;
        Ok(self)
    }
    fn serialize_tuple(self, _: usize) -> Result<Self, Never> {
        Ok(self)
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Self, Never> {
        Ok(self)
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self, Never> {
        self.0 += 4;
        Ok(self)
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self, Never> {
        self.0 += 8;
        Ok(self)
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self, Never> {
        Ok(self)
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self, Never> {
        self.0 += 4;
        Ok(self)
    }
}

macro_rules! compound {
    ($tr:ident, $m:ident) => {
        impl ser::$tr for &mut Size {
            type Ok = ();
            type Error = Never;
            fn $m<T: ?Sized + Serialize>(&mut self, v: &T) -> Result<(), Never> {
                v.serialize(&mut **self)
            }
            fn end(self) -> Result<(), Never> {
                Ok(())
            }
        }
    };
}

compound!(SerializeSeq, serialize_element);
compound!(SerializeTuple, serialize_element);
compound!(SerializeTupleStruct, serialize_field);
compound!(SerializeTupleVariant, serialize_field);

impl ser::SerializeMap for &mut Size {
    type Ok = ();
    type Error = Never;
    fn serialize_key<T: ?Sized + Serialize>(&mut self, k: &T) -> Result<(), Never> {
        k.serialize(&mut **self)
    }
    fn serialize_value<T: ?Sized + Serialize>(&mut self, v: &T) -> Result<(), Never> {
        v.serialize(&mut **self)
    }
    fn end(self) -> Result<(), Never> {
        Ok(())
    }
}

impl ser::SerializeStruct for &mut Size {
    type Ok = ();
    type Error = Never;
    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        _: &'static str,
        v: &T,
    ) -> Result<(), Never> {
        v.serialize(&mut **self)
    }
    fn end(self) -> Result<(), Never> {
        Ok(())
    }
}

impl ser::SerializeStructVariant for &mut Size {
    type Ok = ();
    type Error = Never;
    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        _: &'static str,
        v: &T,
    ) -> Result<(), Never> {
        v.serialize(&mut **self)
    }
    fn end(self) -> Result<(), Never> {
        Ok(())
    }
}

#[test]
fn the_counter_counts_as_bincode_fixed_int() {
    assert_eq!(encoded_size(&1.0f64), 8);
    assert_eq!(encoded_size(&Some(3u64)), 9);
    assert_eq!(encoded_size(&None::<u64>), 1);
    assert_eq!(encoded_size(&vec![1.0f64; 3]), 8 + 24);
    assert_eq!(encoded_size(&[0u32; 4]), 16);
    assert_eq!(encoded_size(&(true, 2u8)), 2);
}
