//! An ordered JSON tree for the cells of a [`Table`](super::Table) that hold a whole
//! serde value (per-pass timings, counters, a flattened struct): [`Json::of`] captures what
//! a value serializes as, keys in their order and floats at their own width, so that
//! serializing the tree writes exactly what serializing the value itself would have.
//! `serde_json::Value` cannot stand in: without its `preserve_order` feature it sorts keys,
//! and it widens `f32` to `f64` (0.1f32 would print as 0.10000000149011612), both of which
//! would change the bench's files. The tests hold the capture to `serde_json` writing the
//! value itself.

use std::fmt;

use serde::ser::{self, Serialize, Serializer};

/// A captured serde value.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Json {
    Null,
    Bool(bool),
    I64(i64),
    U64(u64),
    I128(i128),
    U128(u128),
    F32(f32),
    F64(f64),
    Str(String),
    Array(Vec<Json>),
    /// Entries in order; a key may repeat (as `#[serde(flatten)]` can write it).
    Object(Vec<(String, Json)>),
    /// A value serde could not capture (a map key that is no string): serializing the
    /// tree fails with this message, as serializing the value would have.
    Invalid(String),
}

impl Json {
    /// What `value` serializes as.
    pub(crate) fn of<T: Serialize + ?Sized>(value: &T) -> Json {
        value
            .serialize(Capture)
            .unwrap_or_else(|e| Json::Invalid(e.0))
    }
}

impl Serialize for Json {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use ser::{Error, SerializeMap, SerializeSeq};
        match self {
            Json::Null => s.serialize_none(),
            Json::Bool(v) => s.serialize_bool(*v),
            Json::I64(v) => s.serialize_i64(*v),
            Json::U64(v) => s.serialize_u64(*v),
            Json::I128(v) => s.serialize_i128(*v),
            Json::U128(v) => s.serialize_u128(*v),
            Json::F32(v) => s.serialize_f32(*v),
            Json::F64(v) => s.serialize_f64(*v),
            Json::Str(v) => s.serialize_str(v),
            Json::Array(items) => {
                let mut seq = s.serialize_seq(Some(items.len()))?;
                for x in items {
                    seq.serialize_element(x)?;
                }
                seq.end()
            }
            Json::Object(entries) => {
                let mut map = s.serialize_map(Some(entries.len()))?;
                for (k, v) in entries {
                    map.serialize_entry(k, v)?;
                }
                map.end()
            }
            Json::Invalid(msg) => Err(S::Error::custom(msg)),
        }
    }
}

/// Why a value could not be captured.
#[derive(Debug)]
pub(crate) struct CaptureError(String);

impl fmt::Display for CaptureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CaptureError {}

impl ser::Error for CaptureError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        CaptureError(msg.to_string())
    }
}

/// The serializer behind [`Json::of`]; it represents values as `serde_json` writes them
/// (unit and `None` as null, an enum variant with data as a one-entry object).
struct Capture;

/// A sequence being captured (`variant`: the enum variant it is the data of).
struct Seq {
    variant: Option<&'static str>,
    items: Vec<Json>,
}

/// A map or struct being captured.
struct Map {
    variant: Option<&'static str>,
    entries: Vec<(String, Json)>,
    key: Option<String>,
}

fn wrap(variant: Option<&'static str>, value: Json) -> Json {
    match variant {
        Some(v) => Json::Object(vec![(v.to_string(), value)]),
        None => value,
    }
}

/// A map key as `serde_json` writes it: strings as they are, numbers and booleans as
/// their text.
fn key_text(key: Json) -> Result<String, CaptureError> {
    Ok(match key {
        Json::Str(s) => s,
        Json::Bool(v) => v.to_string(),
        Json::I64(v) => v.to_string(),
        Json::U64(v) => v.to_string(),
        Json::I128(v) => v.to_string(),
        Json::U128(v) => v.to_string(),
        Json::F32(v) if v.is_finite() => serde_json::to_string(&v).map_err(ser::Error::custom)?,
        Json::F64(v) if v.is_finite() => serde_json::to_string(&v).map_err(ser::Error::custom)?,
        _ => return Err(ser::Error::custom("key must be a string")),
    })
}

impl Serializer for Capture {
    type Ok = Json;
    type Error = CaptureError;
    type SerializeSeq = Seq;
    type SerializeTuple = Seq;
    type SerializeTupleStruct = Seq;
    type SerializeTupleVariant = Seq;
    type SerializeMap = Map;
    type SerializeStruct = Map;
    type SerializeStructVariant = Map;

    fn serialize_bool(self, v: bool) -> Result<Json, CaptureError> {
        Ok(Json::Bool(v))
    }
    fn serialize_i8(self, v: i8) -> Result<Json, CaptureError> {
        Ok(Json::I64(v.into()))
    }
    fn serialize_i16(self, v: i16) -> Result<Json, CaptureError> {
        Ok(Json::I64(v.into()))
    }
    fn serialize_i32(self, v: i32) -> Result<Json, CaptureError> {
        Ok(Json::I64(v.into()))
    }
    fn serialize_i64(self, v: i64) -> Result<Json, CaptureError> {
        Ok(Json::I64(v))
    }
    fn serialize_i128(self, v: i128) -> Result<Json, CaptureError> {
        Ok(Json::I128(v))
    }
    fn serialize_u8(self, v: u8) -> Result<Json, CaptureError> {
        Ok(Json::U64(v.into()))
    }
    fn serialize_u16(self, v: u16) -> Result<Json, CaptureError> {
        Ok(Json::U64(v.into()))
    }
    fn serialize_u32(self, v: u32) -> Result<Json, CaptureError> {
        Ok(Json::U64(v.into()))
    }
    fn serialize_u64(self, v: u64) -> Result<Json, CaptureError> {
        Ok(Json::U64(v))
    }
    fn serialize_u128(self, v: u128) -> Result<Json, CaptureError> {
        Ok(Json::U128(v))
    }
    fn serialize_f32(self, v: f32) -> Result<Json, CaptureError> {
        Ok(Json::F32(v))
    }
    fn serialize_f64(self, v: f64) -> Result<Json, CaptureError> {
        Ok(Json::F64(v))
    }
    fn serialize_char(self, v: char) -> Result<Json, CaptureError> {
        Ok(Json::Str(v.to_string()))
    }
    fn serialize_str(self, v: &str) -> Result<Json, CaptureError> {
        Ok(Json::Str(v.to_string()))
    }
    fn serialize_bytes(self, v: &[u8]) -> Result<Json, CaptureError> {
        Ok(Json::Array(
            v.iter().map(|&b| Json::U64(b.into())).collect(),
        ))
    }
    fn serialize_none(self) -> Result<Json, CaptureError> {
        Ok(Json::Null)
    }
    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result<Json, CaptureError> {
        value.serialize(self)
    }
    fn serialize_unit(self) -> Result<Json, CaptureError> {
        Ok(Json::Null)
    }
    fn serialize_unit_struct(self, _name: &'static str) -> Result<Json, CaptureError> {
        Ok(Json::Null)
    }
    fn serialize_unit_variant(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
    ) -> Result<Json, CaptureError> {
        Ok(Json::Str(variant.to_string()))
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        _name: &'static str,
        value: &T,
    ) -> Result<Json, CaptureError> {
        value.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
        value: &T,
    ) -> Result<Json, CaptureError> {
        Ok(wrap(Some(variant), value.serialize(self)?))
    }
    fn serialize_seq(self, len: Option<usize>) -> Result<Seq, CaptureError> {
        Ok(Seq {
            variant: None,
            items: Vec::with_capacity(len.unwrap_or(0)),
        })
    }
    fn serialize_tuple(self, len: usize) -> Result<Seq, CaptureError> {
        self.serialize_seq(Some(len))
    }
    fn serialize_tuple_struct(self, _name: &'static str, len: usize) -> Result<Seq, CaptureError> {
        self.serialize_seq(Some(len))
    }
    fn serialize_tuple_variant(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<Seq, CaptureError> {
        Ok(Seq {
            variant: Some(variant),
            items: Vec::with_capacity(len),
        })
    }
    fn serialize_map(self, _len: Option<usize>) -> Result<Map, CaptureError> {
        Ok(Map {
            variant: None,
            entries: Vec::new(),
            key: None,
        })
    }
    fn serialize_struct(self, _name: &'static str, len: usize) -> Result<Map, CaptureError> {
        self.serialize_map(Some(len))
    }
    fn serialize_struct_variant(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
        _len: usize,
    ) -> Result<Map, CaptureError> {
        Ok(Map {
            variant: Some(variant),
            entries: Vec::new(),
            key: None,
        })
    }
}

impl Seq {
    fn push<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), CaptureError> {
        self.items.push(value.serialize(Capture)?);
        Ok(())
    }

    fn finish(self) -> Json {
        wrap(self.variant, Json::Array(self.items))
    }
}

impl ser::SerializeSeq for Seq {
    type Ok = Json;
    type Error = CaptureError;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), CaptureError> {
        self.push(v)
    }
    fn end(self) -> Result<Json, CaptureError> {
        Ok(self.finish())
    }
}

impl ser::SerializeTuple for Seq {
    type Ok = Json;
    type Error = CaptureError;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), CaptureError> {
        self.push(v)
    }
    fn end(self) -> Result<Json, CaptureError> {
        Ok(self.finish())
    }
}

impl ser::SerializeTupleStruct for Seq {
    type Ok = Json;
    type Error = CaptureError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), CaptureError> {
        self.push(v)
    }
    fn end(self) -> Result<Json, CaptureError> {
        Ok(self.finish())
    }
}

impl ser::SerializeTupleVariant for Seq {
    type Ok = Json;
    type Error = CaptureError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), CaptureError> {
        self.push(v)
    }
    fn end(self) -> Result<Json, CaptureError> {
        Ok(self.finish())
    }
}

impl Map {
    fn entry<T: Serialize + ?Sized>(&mut self, key: &str, v: &T) -> Result<(), CaptureError> {
        self.entries.push((key.to_string(), v.serialize(Capture)?));
        Ok(())
    }

    fn finish(self) -> Json {
        wrap(self.variant, Json::Object(self.entries))
    }
}

impl ser::SerializeMap for Map {
    type Ok = Json;
    type Error = CaptureError;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, key: &T) -> Result<(), CaptureError> {
        self.key = Some(key_text(key.serialize(Capture)?)?);
        Ok(())
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), CaptureError> {
        let key = self
            .key
            .take()
            .ok_or_else(|| ser::Error::custom("a map value without its key"))?;
        self.entry(&key, v)
    }
    fn end(self) -> Result<Json, CaptureError> {
        Ok(self.finish())
    }
}

impl ser::SerializeStruct for Map {
    type Ok = Json;
    type Error = CaptureError;
    fn serialize_field<T: Serialize + ?Sized>(
        &mut self,
        key: &'static str,
        v: &T,
    ) -> Result<(), CaptureError> {
        self.entry(key, v)
    }
    fn end(self) -> Result<Json, CaptureError> {
        Ok(self.finish())
    }
}

impl ser::SerializeStructVariant for Map {
    type Ok = Json;
    type Error = CaptureError;
    fn serialize_field<T: Serialize + ?Sized>(
        &mut self,
        key: &'static str,
        v: &T,
    ) -> Result<(), CaptureError> {
        self.entry(key, v)
    }
    fn end(self) -> Result<Json, CaptureError> {
        Ok(self.finish())
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;

    #[derive(serde::Serialize)]
    enum E {
        Unit,
        New(u8),
        Tuple(u8, f32),
        Struct { a: f32 },
    }

    #[derive(serde::Serialize)]
    struct Inner {
        z: f32,
        #[serde(skip_serializing_if = "Option::is_none")]
        skipped: Option<u8>,
        a: Option<f64>,
    }

    #[derive(serde::Serialize)]
    struct Outer {
        name: &'static str,
        #[serde(flatten)]
        inner: Inner,
        tuple: (&'static str, f64),
        list: Vec<u32>,
        empty: Vec<u32>,
        map: BTreeMap<u32, i64>,
        enums: [E; 4],
        big: u128,
        c: char,
    }

    fn outer() -> Outer {
        Outer {
            name: "x",
            inner: Inner {
                z: 0.1,
                skipped: None,
                a: None,
            },
            tuple: ("t", 1.0 / 3.0),
            list: vec![1, 2],
            empty: Vec::new(),
            map: BTreeMap::from([(2, -1), (10, 5)]),
            enums: [E::Unit, E::New(3), E::Tuple(1, 0.7), E::Struct { a: 2.5 }],
            big: u128::MAX,
            c: 'é',
        }
    }

    #[test]
    fn captured_values_serialize_as_the_values_do() {
        let v = outer();
        let j = Json::of(&v);
        assert_eq!(
            serde_json::to_string_pretty(&j).unwrap(),
            serde_json::to_string_pretty(&v).unwrap()
        );
        assert_eq!(
            serde_json::to_string(&j).unwrap(),
            serde_json::to_string(&v).unwrap()
        );
    }

    #[test]
    fn keys_keep_their_order_and_floats_their_width() {
        let Json::Object(e) = Json::of(&outer()) else {
            panic!("a struct is an object")
        };
        let keys: Vec<&str> = e.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(
            keys,
            [
                "name", "z", "a", "tuple", "list", "empty", "map", "enums", "big", "c"
            ]
        );
        assert_eq!(e[1].1, Json::F32(0.1));
    }

    #[test]
    fn keys_that_are_no_strings_fail_when_written() {
        let m = BTreeMap::from([((1, 2), 3)]);
        let j = Json::of(&m);
        assert!(matches!(j, Json::Invalid(_)));
        assert!(serde_json::to_string(&j).is_err());
        assert!(serde_json::to_string(&m).is_err());
    }
}
