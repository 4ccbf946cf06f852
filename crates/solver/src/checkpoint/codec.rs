//! serde over the checkpoint's bytes: a value whose type derives serde
//! (the monitor's events and step history) is written and read with the
//! same schema as its JSON in the summary. Not self-describing: fields in
//! declaration order; unsigned integers, lengths, enum variant indices
//! and option tags as LEB128 varints; signed integers zigzag-encoded;
//! f64 as its little-endian bits (NaN payloads and signed zeros kept).

use super::CheckpointError;
use serde::de::{self, DeserializeSeed, IntoDeserializer, Visitor};
use serde::ser::{self, Serialize};

/// A codec error: a checkpoint error, or serde's own message (a type
/// this format cannot carry, such as a sequence of unknown length).
#[derive(Debug)]
pub enum CodecError {
    Checkpoint(CheckpointError),
    Serde(String),
}

impl std::fmt::Display for CodecError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CodecError::Checkpoint(e) => e.fmt(f),
            CodecError::Serde(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for CodecError {}

impl ser::Error for CodecError {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        CodecError::Serde(msg.to_string())
    }
}

impl de::Error for CodecError {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        CodecError::Serde(msg.to_string())
    }
}

impl From<CheckpointError> for CodecError {
    fn from(e: CheckpointError) -> Self {
        CodecError::Checkpoint(e)
    }
}

/// `value`'s bytes.
pub fn encode<T: Serialize + ?Sized>(value: &T) -> Result<Vec<u8>, CodecError> {
    let mut out = Encoder(Vec::new());
    value.serialize(&mut out)?;
    Ok(out.0)
}

/// The value `bytes` hold, which must be all of them. A decode that serde
/// itself refuses (not one of this format's codes) reads as `Truncated`:
/// the bytes do not hold the type asked for.
pub fn decode<'de, T: de::Deserialize<'de>>(bytes: &'de [u8]) -> Result<T, CheckpointError> {
    let mut d = Decoder(bytes);
    let value = T::deserialize(&mut d).map_err(|e| match e {
        CodecError::Checkpoint(e) => e,
        CodecError::Serde(_) => CheckpointError::Truncated,
    })?;
    match d.0.len() {
        0 => Ok(value),
        count => Err(CheckpointError::TrailingBytes { count }),
    }
}

struct Encoder(Vec<u8>);

impl Encoder {
    fn varint(&mut self, mut v: u64) {
        while v >= 0x80 {
            self.0.push((v as u8) | 0x80);
            v >>= 7;
        }
        self.0.push(v as u8);
    }

    fn signed(&mut self, v: i64) {
        self.varint(((v << 1) ^ (v >> 63)) as u64);
    }
}

type Done = Result<(), CodecError>;

impl ser::Serializer for &mut Encoder {
    type Ok = ();
    type Error = CodecError;
    type SerializeSeq = Self;
    type SerializeTuple = Self;
    type SerializeTupleStruct = Self;
    type SerializeTupleVariant = Self;
    type SerializeMap = Self;
    type SerializeStruct = Self;
    type SerializeStructVariant = Self;

    fn serialize_bool(self, v: bool) -> Done {
        self.varint(v as u64);
        Ok(())
    }
    fn serialize_i8(self, v: i8) -> Done {
        self.serialize_i64(v.into())
    }
    fn serialize_i16(self, v: i16) -> Done {
        self.serialize_i64(v.into())
    }
    fn serialize_i32(self, v: i32) -> Done {
        self.serialize_i64(v.into())
    }
    fn serialize_i64(self, v: i64) -> Done {
        self.signed(v);
        Ok(())
    }
    fn serialize_u8(self, v: u8) -> Done {
        self.serialize_u64(v.into())
    }
    fn serialize_u16(self, v: u16) -> Done {
        self.serialize_u64(v.into())
    }
    fn serialize_u32(self, v: u32) -> Done {
        self.serialize_u64(v.into())
    }
    fn serialize_u64(self, v: u64) -> Done {
        self.varint(v);
        Ok(())
    }
    fn serialize_f32(self, v: f32) -> Done {
        self.serialize_f64(v.into())
    }
    fn serialize_f64(self, v: f64) -> Done {
        self.0.extend_from_slice(&v.to_le_bytes());
        Ok(())
    }
    fn serialize_char(self, v: char) -> Done {
        self.serialize_u64(v as u64)
    }
    fn serialize_str(self, v: &str) -> Done {
        self.serialize_bytes(v.as_bytes())
    }
    fn serialize_bytes(self, v: &[u8]) -> Done {
        self.varint(v.len() as u64);
        self.0.extend_from_slice(v);
        Ok(())
    }
    fn serialize_none(self) -> Done {
        self.varint(0);
        Ok(())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Done {
        self.varint(1);
        value.serialize(self)
    }
    fn serialize_unit(self) -> Done {
        Ok(())
    }
    fn serialize_unit_struct(self, _: &'static str) -> Done {
        Ok(())
    }
    fn serialize_unit_variant(self, _: &'static str, index: u32, _: &'static str) -> Done {
        self.serialize_u64(index.into())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _: &'static str, v: &T) -> Done {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        index: u32,
        _: &'static str,
        v: &T,
    ) -> Done {
        self.varint(index.into());
        v.serialize(self)
    }
    fn serialize_seq(self, len: Option<usize>) -> Result<Self, CodecError> {
        let len = len.ok_or_else(|| {
            CodecError::Serde("a sequence needs its length up front in a checkpoint".into())
        })?;
        self.varint(len as u64);
        Ok(self)
    }
    fn serialize_tuple(self, _: usize) -> Result<Self, CodecError> {
        Ok(self)
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Self, CodecError> {
        Ok(self)
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        index: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self, CodecError> {
        self.varint(index.into());
        Ok(self)
    }
    fn serialize_map(self, len: Option<usize>) -> Result<Self, CodecError> {
        self.serialize_seq(len)
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self, CodecError> {
        Ok(self)
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        index: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self, CodecError> {
        self.varint(index.into());
        Ok(self)
    }
}

/// The compound forms all write their parts in order.
macro_rules! compound {
    ($trait:ident, $method:ident $(, $key:ident)?) => {
        impl ser::$trait for &mut Encoder {
            type Ok = ();
            type Error = CodecError;
            fn $method<T: Serialize + ?Sized>(&mut self, $($key: &'static str,)? value: &T) -> Done {
                $(let _ = $key;)?
                value.serialize(&mut **self)
            }
            fn end(self) -> Done {
                Ok(())
            }
        }
    };
}
compound!(SerializeSeq, serialize_element);
compound!(SerializeTuple, serialize_element);
compound!(SerializeTupleStruct, serialize_field);
compound!(SerializeTupleVariant, serialize_field);
compound!(SerializeStruct, serialize_field, key);
compound!(SerializeStructVariant, serialize_field, key);

impl ser::SerializeMap for &mut Encoder {
    type Ok = ();
    type Error = CodecError;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, key: &T) -> Done {
        key.serialize(&mut **self)
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, value: &T) -> Done {
        value.serialize(&mut **self)
    }
    fn end(self) -> Done {
        Ok(())
    }
}

struct Decoder<'de>(&'de [u8]);

impl<'de> Decoder<'de> {
    fn take(&mut self, n: usize) -> Result<&'de [u8], CodecError> {
        if self.0.len() < n {
            return Err(CheckpointError::Truncated.into());
        }
        let (head, rest) = self.0.split_at(n);
        self.0 = rest;
        Ok(head)
    }

    fn varint(&mut self) -> Result<u64, CodecError> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let byte = self.take(1)?[0];
            v |= u64::from(byte & 0x7f) << shift;
            if byte & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(CheckpointError::UnknownCode {
            what: "varint",
            code: v,
        }
        .into())
    }

    fn signed(&mut self) -> Result<i64, CodecError> {
        let z = self.varint()?;
        Ok(((z >> 1) as i64) ^ -((z & 1) as i64))
    }

    /// A code that must be below `limit` (a flag, an option tag).
    fn code(&mut self, what: &'static str, limit: u64) -> Result<u64, CodecError> {
        match self.varint()? {
            c if c < limit => Ok(c),
            code => Err(CheckpointError::UnknownCode { what, code }.into()),
        }
    }

    fn length(&mut self) -> Result<usize, CodecError> {
        let n = self.varint()?;
        // Every element takes at least a byte, except of zero-sized types,
        // which this format's users have none of in sequences.
        if n > self.0.len() as u64 {
            return Err(CheckpointError::Truncated.into());
        }
        Ok(n as usize)
    }

    fn integer<T: TryFrom<u64>>(&mut self, what: &'static str) -> Result<T, CodecError> {
        let v = self.varint()?;
        T::try_from(v).map_err(|_| CheckpointError::UnknownCode { what, code: v }.into())
    }

    fn signed_integer<T: TryFrom<i64>>(&mut self, what: &'static str) -> Result<T, CodecError> {
        let v = self.signed()?;
        T::try_from(v).map_err(|_| {
            CheckpointError::UnknownCode {
                what,
                code: v as u64,
            }
            .into()
        })
    }
}

type Out<V> = Result<V, CodecError>;

impl<'de> de::Deserializer<'de> for &mut Decoder<'de> {
    type Error = CodecError;

    fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Out<V::Value> {
        Err(CodecError::Serde(
            "a checkpoint is not self-describing: the type must say what it reads".into(),
        ))
    }
    fn deserialize_bool<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_bool(self.code("flag", 2)? == 1)
    }
    fn deserialize_i8<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_i8(self.signed_integer("i8")?)
    }
    fn deserialize_i16<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_i16(self.signed_integer("i16")?)
    }
    fn deserialize_i32<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_i32(self.signed_integer("i32")?)
    }
    fn deserialize_i64<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_i64(self.signed()?)
    }
    fn deserialize_u8<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_u8(self.integer("u8")?)
    }
    fn deserialize_u16<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_u16(self.integer("u16")?)
    }
    fn deserialize_u32<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_u32(self.integer("u32")?)
    }
    fn deserialize_u64<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_u64(self.varint()?)
    }
    fn deserialize_f32<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_f32(f64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")) as f32)
    }
    fn deserialize_f64<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_f64(f64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn deserialize_char<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        let code = self.varint()?;
        let c = u32::try_from(code).ok().and_then(char::from_u32);
        v.visit_char(c.ok_or(CheckpointError::BadUtf8)?)
    }
    fn deserialize_str<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        let n = self.length()?;
        let s = std::str::from_utf8(self.take(n)?).map_err(|_| CheckpointError::BadUtf8)?;
        v.visit_borrowed_str(s)
    }
    fn deserialize_string<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        self.deserialize_str(v)
    }
    fn deserialize_bytes<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        let n = self.length()?;
        v.visit_borrowed_bytes(self.take(n)?)
    }
    fn deserialize_byte_buf<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        self.deserialize_bytes(v)
    }
    fn deserialize_option<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        match self.code("option tag", 2)? {
            0 => v.visit_none(),
            _ => v.visit_some(self),
        }
    }
    fn deserialize_unit<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        v.visit_unit()
    }
    fn deserialize_unit_struct<V: Visitor<'de>>(self, _: &'static str, v: V) -> Out<V::Value> {
        v.visit_unit()
    }
    fn deserialize_newtype_struct<V: Visitor<'de>>(self, _: &'static str, v: V) -> Out<V::Value> {
        v.visit_newtype_struct(self)
    }
    fn deserialize_seq<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        let left = self.length()?;
        v.visit_seq(Parts { d: self, left })
    }
    fn deserialize_tuple<V: Visitor<'de>>(self, len: usize, v: V) -> Out<V::Value> {
        v.visit_seq(Parts { d: self, left: len })
    }
    fn deserialize_tuple_struct<V: Visitor<'de>>(
        self,
        _: &'static str,
        len: usize,
        v: V,
    ) -> Out<V::Value> {
        self.deserialize_tuple(len, v)
    }
    fn deserialize_map<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        let left = self.length()?;
        v.visit_map(Parts { d: self, left })
    }
    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _: &'static str,
        fields: &'static [&'static str],
        v: V,
    ) -> Out<V::Value> {
        self.deserialize_tuple(fields.len(), v)
    }
    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _: &'static str,
        _: &'static [&'static str],
        v: V,
    ) -> Out<V::Value> {
        v.visit_enum(self)
    }
    fn deserialize_identifier<V: Visitor<'de>>(self, _: V) -> Out<V::Value> {
        Err(CodecError::Serde(
            "identifiers are not stored in a checkpoint".into(),
        ))
    }
    fn deserialize_ignored_any<V: Visitor<'de>>(self, v: V) -> Out<V::Value> {
        self.deserialize_any(v)
    }
    fn is_human_readable(&self) -> bool {
        false
    }
}

/// The elements of a sequence, tuple, struct or map still to read.
struct Parts<'a, 'de> {
    d: &'a mut Decoder<'de>,
    left: usize,
}

impl<'de> de::SeqAccess<'de> for Parts<'_, 'de> {
    type Error = CodecError;
    fn next_element_seed<T: DeserializeSeed<'de>>(&mut self, seed: T) -> Out<Option<T::Value>> {
        if self.left == 0 {
            return Ok(None);
        }
        self.left -= 1;
        seed.deserialize(&mut *self.d).map(Some)
    }
    fn size_hint(&self) -> Option<usize> {
        Some(self.left)
    }
}

impl<'de> de::MapAccess<'de> for Parts<'_, 'de> {
    type Error = CodecError;
    fn next_key_seed<K: DeserializeSeed<'de>>(&mut self, seed: K) -> Out<Option<K::Value>> {
        de::SeqAccess::next_element_seed(self, seed)
    }
    fn next_value_seed<T: DeserializeSeed<'de>>(&mut self, seed: T) -> Out<T::Value> {
        seed.deserialize(&mut *self.d)
    }
}

impl<'de> de::EnumAccess<'de> for &mut Decoder<'de> {
    type Error = CodecError;
    type Variant = Self;
    fn variant_seed<T: DeserializeSeed<'de>>(self, seed: T) -> Out<(T::Value, Self)> {
        let index = self.varint()?;
        let known = u32::try_from(index).ok().and_then(|i| {
            let d: de::value::U32Deserializer<CodecError> = i.into_deserializer();
            seed.deserialize(d).ok()
        });
        match known {
            Some(value) => Ok((value, self)),
            None => Err(CheckpointError::UnknownCode {
                what: "variant",
                code: index,
            }
            .into()),
        }
    }
}

impl<'de> de::VariantAccess<'de> for &mut Decoder<'de> {
    type Error = CodecError;
    fn unit_variant(self) -> Out<()> {
        Ok(())
    }
    fn newtype_variant_seed<T: DeserializeSeed<'de>>(self, seed: T) -> Out<T::Value> {
        seed.deserialize(self)
    }
    fn tuple_variant<V: Visitor<'de>>(self, len: usize, v: V) -> Out<V::Value> {
        de::Deserializer::deserialize_tuple(self, len, v)
    }
    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        v: V,
    ) -> Out<V::Value> {
        de::Deserializer::deserialize_tuple(self, fields.len(), v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::{Deserialize, Serialize};

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    enum Kind {
        Quiet,
        Loud(u32),
        Both { a: i16, b: Option<String> },
    }

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Record {
        id: u32,
        flag: bool,
        kinds: Vec<Kind>,
        x: f64,
        pair: (i64, u64),
        #[serde(skip)]
        kept_out: f64,
    }

    fn sample() -> Record {
        Record {
            id: 300,
            flag: true,
            kinds: vec![
                Kind::Quiet,
                Kind::Loud(u32::MAX),
                Kind::Both {
                    a: -2,
                    b: Some("é".into()),
                },
            ],
            x: f64::from_bits(0x7ff8_dead_beef_0001),
            pair: (i64::MIN, u64::MAX),
            kept_out: 0.0,
        }
    }

    #[test]
    fn values_round_trip_bit_for_bit() {
        let r = sample();
        let back: Record = decode(&encode(&r).unwrap()).unwrap();
        assert_eq!(back.x.to_bits(), r.x.to_bits());
        assert_eq!(
            (back.id, back.flag, &back.kinds, back.pair),
            (r.id, r.flag, &r.kinds, r.pair)
        );
        let z: f64 = decode(&encode(&-0.0f64).unwrap()).unwrap();
        assert_eq!(z.to_bits(), (-0.0f64).to_bits());
    }

    #[test]
    fn damaged_bytes_are_refused_with_the_checkpoint_error() {
        let bytes = encode(&sample()).unwrap();
        // id 300 is two varint bytes, then the flag, the length, the first kind.
        assert_eq!(&bytes[..5], &[0xac, 0x02, 1, 3, 0]);
        for cut in [0, 1, bytes.len() / 2, bytes.len() - 1] {
            assert_eq!(
                decode::<Record>(&bytes[..cut]).unwrap_err(),
                CheckpointError::Truncated
            );
        }
        let mut long = bytes.clone();
        long.push(0);
        assert_eq!(
            decode::<Record>(&long).unwrap_err(),
            CheckpointError::TrailingBytes { count: 1 }
        );
        let mut flag = bytes.clone();
        flag[2] = 7;
        assert_eq!(
            decode::<Record>(&flag).unwrap_err(),
            CheckpointError::UnknownCode {
                what: "flag",
                code: 7
            }
        );
        let mut kind = bytes.clone();
        kind[4] = 9;
        assert_eq!(
            decode::<Record>(&kind).unwrap_err(),
            CheckpointError::UnknownCode {
                what: "variant",
                code: 9
            }
        );
    }

    #[test]
    fn a_sequence_of_unknown_length_is_an_error_not_a_panic() {
        struct Unsized;
        impl Serialize for Unsized {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                use serde::ser::SerializeSeq;
                s.serialize_seq(None)?.end()
            }
        }
        assert!(matches!(encode(&Unsized), Err(CodecError::Serde(_))));
    }
}
