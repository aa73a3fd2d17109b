//! A serde value model that keeps what NumPy columns need and JSON drops: integers apart from
//! reals, struct fields with their names in the order they are written, and bt-beams' complex
//! newtype ([`bt_beams::COMPLEX_NEWTYPE`]) as a complex number. Written here because the
//! general-purpose models lose one of these (`serde-value` keeps struct fields in a sorted map,
//! `serde_json::Value` turns the newtype into a plain pair).

use serde::Serialize;
use serde::ser::{self, Impossible};
use std::fmt;

/// One serialized value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// An integer of any width that fits an `i64`.
    Int(i64),
    /// A real number.
    Real(f64),
    /// `None` written as `null`.
    Null,
    /// A string (or a char).
    Text(String),
    /// A complex number (re, im): bt-beams' [`bt_beams::COMPLEX_NEWTYPE`] around a pair.
    Complex(f64, f64),
    /// A sequence, tuple or array.
    Seq(Vec<Value>),
    /// A struct: the fields it writes (not those `skip_serializing_if` skips), in order.
    Struct(Vec<(&'static str, Value)>),
}

/// What the model does not hold (maps, enums, booleans, bytes, unit), as serde's message.
#[derive(Debug)]
pub struct Unsupported(pub String);

impl fmt::Display for Unsupported {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Unsupported {}

impl ser::Error for Unsupported {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        Self(msg.to_string())
    }
}

/// `value` in the model.
pub fn to_value<T: Serialize + ?Sized>(value: &T) -> Result<Value> {
    value.serialize(ValueSerializer)
}

/// The error for a value of kind `what`, which has no column shape.
pub fn unsupported(what: &str) -> Unsupported {
    Unsupported(format!("{what} has no column shape"))
}

/// The `serialize_*` methods of the kinds no column holds (enum variants with data, tuple
/// structs, maps), each an [`unsupported`] error.
macro_rules! no_compound_kinds {
    () => {
        fn serialize_newtype_variant<T: serde::Serialize + ?Sized>(
            self,
            name: &'static str,
            _: u32,
            _: &'static str,
            _: &T,
        ) -> std::result::Result<Self::Ok, Self::Error> {
            Err($crate::record::unsupported(name))
        }
        fn serialize_tuple_struct(
            self,
            name: &'static str,
            _: usize,
        ) -> std::result::Result<Self::SerializeTupleStruct, Self::Error> {
            Err($crate::record::unsupported(name))
        }
        fn serialize_tuple_variant(
            self,
            name: &'static str,
            _: u32,
            _: &'static str,
            _: usize,
        ) -> std::result::Result<Self::SerializeTupleVariant, Self::Error> {
            Err($crate::record::unsupported(name))
        }
        fn serialize_map(
            self,
            _: Option<usize>,
        ) -> std::result::Result<Self::SerializeMap, Self::Error> {
            Err($crate::record::unsupported("a map"))
        }
        fn serialize_struct_variant(
            self,
            name: &'static str,
            _: u32,
            _: &'static str,
            _: usize,
        ) -> std::result::Result<Self::SerializeStructVariant, Self::Error> {
            Err($crate::record::unsupported(name))
        }
    };
}
pub(crate) use no_compound_kinds;

struct ValueSerializer;

/// The elements of a sequence or tuple being written.
struct SeqValues(Vec<Value>);

/// The fields of a struct being written.
struct StructValues(Vec<(&'static str, Value)>);

type Result<T> = std::result::Result<T, Unsupported>;

/// `serialize_*` of the integer types an `i64` holds exactly.
macro_rules! lossless_ints {
    ($($method:ident: $int:ty),* $(,)?) => {$(
        fn $method(self, v: $int) -> Result<Value> {
            Ok(Value::Int(v.into()))
        }
    )*};
}

impl ser::Serializer for ValueSerializer {
    type Ok = Value;
    type Error = Unsupported;
    type SerializeSeq = SeqValues;
    type SerializeTuple = SeqValues;
    type SerializeTupleStruct = Impossible<Value, Unsupported>;
    type SerializeTupleVariant = Impossible<Value, Unsupported>;
    type SerializeMap = Impossible<Value, Unsupported>;
    type SerializeStruct = StructValues;
    type SerializeStructVariant = Impossible<Value, Unsupported>;

    fn serialize_bool(self, _: bool) -> Result<Value> {
        Err(unsupported("a bool"))
    }
    lossless_ints!(
        serialize_i8: i8,
        serialize_i16: i16,
        serialize_i32: i32,
        serialize_u8: u8,
        serialize_u16: u16,
        serialize_u32: u32,
    );
    fn serialize_i64(self, v: i64) -> Result<Value> {
        Ok(Value::Int(v))
    }
    fn serialize_u64(self, v: u64) -> Result<Value> {
        i64::try_from(v)
            .map(Value::Int)
            .map_err(|_| Unsupported(format!("integer {v} does not fit an int64")))
    }
    fn serialize_f32(self, v: f32) -> Result<Value> {
        Ok(Value::Real(v.into()))
    }
    fn serialize_f64(self, v: f64) -> Result<Value> {
        Ok(Value::Real(v))
    }
    fn serialize_char(self, v: char) -> Result<Value> {
        Ok(Value::Text(v.to_string()))
    }
    fn serialize_str(self, v: &str) -> Result<Value> {
        Ok(Value::Text(v.to_string()))
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<Value> {
        Err(unsupported("bytes"))
    }
    fn serialize_none(self) -> Result<Value> {
        Ok(Value::Null)
    }
    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result<Value> {
        value.serialize(self)
    }
    fn serialize_unit(self) -> Result<Value> {
        Err(unsupported("a unit"))
    }
    fn serialize_unit_struct(self, name: &'static str) -> Result<Value> {
        Err(unsupported(name))
    }
    fn serialize_unit_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
    ) -> Result<Value> {
        // A unit variant is written as its (serde-renamed) name, as JSON writes it.
        Ok(Value::Text(variant.to_string()))
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        name: &'static str,
        value: &T,
    ) -> Result<Value> {
        let inner = value.serialize(self)?;
        if name != bt_beams::COMPLEX_NEWTYPE {
            return Ok(inner);
        }
        match inner {
            Value::Seq(pair) => match pair[..] {
                [Value::Real(re), Value::Real(im)] => Ok(Value::Complex(re, im)),
                _ => Err(unsupported("a complex that is not a pair of reals")),
            },
            _ => Err(unsupported("a complex that is not a pair of reals")),
        }
    }
    fn serialize_seq(self, len: Option<usize>) -> Result<SeqValues> {
        Ok(SeqValues(Vec::with_capacity(len.unwrap_or(0))))
    }
    fn serialize_tuple(self, len: usize) -> Result<SeqValues> {
        Ok(SeqValues(Vec::with_capacity(len)))
    }
    no_compound_kinds!();
    fn serialize_struct(self, _: &'static str, len: usize) -> Result<StructValues> {
        Ok(StructValues(Vec::with_capacity(len)))
    }
}

impl ser::SerializeSeq for SeqValues {
    type Ok = Value;
    type Error = Unsupported;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<()> {
        self.0.push(to_value(value)?);
        Ok(())
    }
    fn end(self) -> Result<Value> {
        Ok(Value::Seq(self.0))
    }
}

impl ser::SerializeTuple for SeqValues {
    type Ok = Value;
    type Error = Unsupported;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<()> {
        ser::SerializeSeq::serialize_element(self, value)
    }
    fn end(self) -> Result<Value> {
        ser::SerializeSeq::end(self)
    }
}

impl ser::SerializeStruct for StructValues {
    type Ok = Value;
    type Error = Unsupported;
    fn serialize_field<T: Serialize + ?Sized>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<()> {
        self.0.push((key, to_value(value)?));
        Ok(())
    }
    fn end(self) -> Result<Value> {
        Ok(Value::Struct(self.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Sample {
        count: u32,
        maybe: Option<f64>,
        #[serde(skip_serializing_if = "Option::is_none")]
        skipped: Option<u8>,
        names: Vec<&'static str>,
        pair: (f64, f64),
    }

    #[test]
    fn fields_keep_their_order_types_and_absence() {
        let sample = Sample {
            count: 3,
            maybe: None,
            skipped: None,
            names: vec!["a"],
            pair: (1.0, 2.0),
        };
        let real = |x| Value::Real(x);
        assert_eq!(
            to_value(&sample).unwrap(),
            Value::Struct(vec![
                ("count", Value::Int(3)),
                ("maybe", Value::Null),
                ("names", Value::Seq(vec![Value::Text("a".into())])),
                ("pair", Value::Seq(vec![real(1.0), real(2.0)])),
            ])
        );
    }

    #[test]
    fn the_complex_newtype_is_a_complex_number() {
        struct Gain(f64, f64);
        impl Serialize for Gain {
            fn serialize<S: ser::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
                s.serialize_newtype_struct(bt_beams::COMPLEX_NEWTYPE, &(self.0, self.1))
            }
        }
        assert_eq!(
            to_value(&Gain(0.5, -2.0)).unwrap(),
            Value::Complex(0.5, -2.0)
        );
    }

    #[test]
    fn unsupported_shapes_are_errors() {
        assert!(to_value(&true).is_err());
        assert!(to_value(&u64::MAX).is_err());
        assert!(to_value(&std::collections::BTreeMap::<u8, u8>::new()).is_err());
    }
}
