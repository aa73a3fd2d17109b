//! A path record serialized straight into flat column buffers: each field's leaves (integers,
//! reals, texts) are appended to its column's buffer, with no value tree in between. A
//! receiver's report takes ~45 records, so this runs ~45,000 times in a 1,000-receiver
//! `trace_many`; the value model of [`crate::record`] stays for deriving the column table from
//! one example.
//!
//! The sink does not know the shapes: [`crate::columns`] checks after each record that every
//! column received what its shape asks for.

use crate::record::{Unsupported, no_compound_kinds, unsupported};
use rustc_hash::FxHashMap;
use serde::Serialize;
use serde::ser::{self, Impossible};

/// The leaves one column received, flat, in path order.
#[derive(Debug, Default)]
pub struct Buffer {
    /// Integer leaves.
    pub ints: Vec<i64>,
    /// Real leaves; `None` (JSON's `null`) as −inf.
    pub reals: Vec<f64>,
    /// Text leaves (strings, unit variants), as indices into the batch's [`Texts`].
    pub texts: Vec<u32>,
}

impl Buffer {
    /// How many leaves of each kind it holds: (integers, reals, texts).
    pub fn counts(&self) -> (usize, usize, usize) {
        (self.ints.len(), self.reals.len(), self.texts.len())
    }

    /// No leaf, the memory kept.
    pub fn clear(&mut self) {
        self.ints.clear();
        self.reals.clear();
        self.texts.clear();
    }

    /// The bytes it holds (its capacity).
    pub fn bytes(&self) -> usize {
        self.ints.capacity() * size_of::<i64>()
            + self.reals.capacity() * size_of::<f64>()
            + self.texts.capacity() * size_of::<u32>()
    }
}

/// The distinct texts of a batch, each stored once and referred to by index.
#[derive(Debug, Default)]
pub struct Texts {
    /// The texts, by index.
    pub list: Vec<String>,
    index: FxHashMap<String, u32>,
    /// The `'static` texts met, by address.
    statics: Vec<(&'static str, u32)>,
}

impl Texts {
    /// No text.
    pub fn clear(&mut self) {
        self.list.clear();
        self.index.clear();
        self.statics.clear();
    }

    /// The index of `text`, added on first use.
    pub fn code(&mut self, text: &str) -> Result<u32> {
        if let Some(&code) = self.index.get(text) {
            return Ok(code);
        }
        self.add(text)
    }

    /// The index of a `'static` text (an enum's variant name), remembered by address: the
    /// same literal comes again and again.
    pub fn code_static(&mut self, text: &'static str) -> Result<u32> {
        if let Some(&(_, code)) = self.statics.iter().find(|(t, _)| std::ptr::eq(*t, text)) {
            return Ok(code);
        }
        let code = self.code(text)?;
        self.statics.push((text, code));
        Ok(code)
    }

    fn add(&mut self, text: &str) -> Result<u32> {
        let code = u32::try_from(self.list.len())
            .map_err(|_| Unsupported("more than 2^32 distinct texts".into()))?;
        self.list.push(text.to_owned());
        self.index.insert(text.to_owned(), code);
        Ok(code)
    }
}

/// Serializes one field's value into `buffer`.
pub struct Leaves<'a> {
    /// The column's buffer.
    pub buffer: &'a mut Buffer,
    /// The batch's texts.
    pub texts: &'a mut Texts,
}

type Result<T = ()> = std::result::Result<T, Unsupported>;

/// `serialize_*` of the integer types an `i64` holds exactly.
macro_rules! lossless_ints {
    ($($method:ident: $int:ty),* $(,)?) => {$(
        fn $method(self, v: $int) -> Result {
            self.buffer.ints.push(v.into());
            Ok(())
        }
    )*};
}

impl<'a> ser::Serializer for Leaves<'a> {
    type Ok = ();
    type Error = Unsupported;
    type SerializeSeq = Self;
    type SerializeTuple = Self;
    type SerializeTupleStruct = Impossible<(), Unsupported>;
    type SerializeTupleVariant = Impossible<(), Unsupported>;
    type SerializeMap = Impossible<(), Unsupported>;
    type SerializeStruct = Self;
    type SerializeStructVariant = Impossible<(), Unsupported>;

    fn serialize_bool(self, _: bool) -> Result {
        Err(unsupported("a bool"))
    }
    lossless_ints!(
        serialize_i8: i8,
        serialize_i16: i16,
        serialize_i32: i32,
        serialize_i64: i64,
        serialize_u8: u8,
        serialize_u16: u16,
        serialize_u32: u32,
    );
    fn serialize_u64(self, v: u64) -> Result {
        let v = i64::try_from(v)
            .map_err(|_| Unsupported(format!("integer {v} does not fit an int64")))?;
        self.buffer.ints.push(v);
        Ok(())
    }
    fn serialize_f32(self, v: f32) -> Result {
        self.serialize_f64(v.into())
    }
    fn serialize_f64(self, v: f64) -> Result {
        self.buffer.reals.push(v);
        Ok(())
    }
    fn serialize_char(self, v: char) -> Result {
        self.serialize_str(v.encode_utf8(&mut [0; 4]))
    }
    fn serialize_str(self, v: &str) -> Result {
        let code = self.texts.code(v)?;
        self.buffer.texts.push(code);
        Ok(())
    }
    fn serialize_bytes(self, _: &[u8]) -> Result {
        Err(unsupported("bytes"))
    }
    fn serialize_none(self) -> Result {
        // Only real columns may be null (a path carrying no power has no dB); in another
        // column the real is a leaf of the wrong kind, which the shape check reports.
        self.serialize_f64(f64::NEG_INFINITY)
    }
    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result {
        value.serialize(self)
    }
    fn serialize_unit(self) -> Result {
        Err(unsupported("a unit"))
    }
    fn serialize_unit_struct(self, name: &'static str) -> Result {
        Err(unsupported(name))
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, variant: &'static str) -> Result {
        // A unit variant is written as its (serde-renamed) name, as JSON writes it.
        let code = self.texts.code_static(variant)?;
        self.buffer.texts.push(code);
        Ok(())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _: &'static str, value: &T) -> Result {
        // The complex newtype is its pair of reals; the column's shape says it is complex.
        value.serialize(self)
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Self> {
        Ok(self)
    }
    fn serialize_tuple(self, _: usize) -> Result<Self> {
        Ok(self)
    }
    no_compound_kinds!();
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self> {
        Ok(self)
    }
}

impl Leaves<'_> {
    fn element<T: Serialize + ?Sized>(&mut self, value: &T) -> Result {
        value.serialize(Leaves {
            buffer: self.buffer,
            texts: self.texts,
        })
    }
}

/// A sequence's or a tuple's elements go to the same buffer, in order.
macro_rules! elements_to_the_buffer {
    ($($kind:ident),*) => {$(
        impl ser::$kind for Leaves<'_> {
            type Ok = ();
            type Error = Unsupported;
            fn serialize_element<T: Serialize + ?Sized>(&mut self, value: &T) -> Result {
                self.element(value)
            }
            fn end(self) -> Result {
                Ok(())
            }
        }
    )*};
}

elements_to_the_buffer!(SerializeSeq, SerializeTuple);

impl ser::SerializeStruct for Leaves<'_> {
    type Ok = ();
    type Error = Unsupported;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, _: &'static str, value: &T) -> Result {
        self.element(value)
    }
    fn end(self) -> Result {
        Ok(())
    }
}

/// Serializes a record's fields, each into the buffer of the column of its name: the
/// columns are in the record's field order, so the search only moves forward (fields the
/// record skips are passed over).
pub struct Fields<'a> {
    /// The column names, in field order.
    pub names: &'a [&'static str],
    /// One buffer per column.
    pub buffers: &'a mut [Buffer],
    /// How many records wrote each column.
    pub written: &'a mut [usize],
    /// The batch's texts.
    pub texts: &'a mut Texts,
    /// The next column to look at.
    pub next: usize,
}

impl ser::SerializeStruct for Fields<'_> {
    type Ok = ();
    type Error = Unsupported;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, key: &'static str, value: &T) -> Result {
        // The record's field names are the very literals the table was derived from: equal
        // pointers are the common case, and content the fallback.
        let same = |name: &str| std::ptr::eq(name, key) || name == key;
        let Some(at) = (self.next..self.names.len()).find(|&c| same(self.names[c])) else {
            return Err(Unsupported(format!(
                "path field {key} is not written by PathReport::example() (or not in its order)"
            )));
        };
        self.next = at + 1;
        self.written[at] += 1;
        value.serialize(Leaves {
            buffer: &mut self.buffers[at],
            texts: self.texts,
        })
    }
    fn end(self) -> Result {
        Ok(())
    }
}

fn not_a_record() -> Unsupported {
    Unsupported("a path record that is not a struct".into())
}

/// `serialize_*` of the scalars, each refused: a record is a struct.
macro_rules! refuse {
    ($($method:ident: $t:ty),* $(,)?) => {$(
        fn $method(self, _: $t) -> Result {
            Err(not_a_record())
        }
    )*};
}

/// The serializer of a whole record: a struct, whose fields go to [`Fields`].
pub struct Record<'a>(pub Fields<'a>);

impl<'a> ser::Serializer for Record<'a> {
    type Ok = ();
    type Error = Unsupported;
    type SerializeSeq = Impossible<(), Unsupported>;
    type SerializeTuple = Impossible<(), Unsupported>;
    type SerializeTupleStruct = Impossible<(), Unsupported>;
    type SerializeTupleVariant = Impossible<(), Unsupported>;
    type SerializeMap = Impossible<(), Unsupported>;
    type SerializeStruct = Fields<'a>;
    type SerializeStructVariant = Impossible<(), Unsupported>;

    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Fields<'a>> {
        Ok(self.0)
    }

    fn serialize_bool(self, _: bool) -> Result {
        Err(not_a_record())
    }
    refuse!(
        serialize_i8: i8, serialize_i16: i16, serialize_i32: i32, serialize_i64: i64,
        serialize_u8: u8, serialize_u16: u16, serialize_u32: u32, serialize_u64: u64,
        serialize_f32: f32, serialize_f64: f64, serialize_char: char, serialize_str: &str,
        serialize_bytes: &[u8], serialize_unit_struct: &'static str,
    );
    fn serialize_none(self) -> Result {
        Err(not_a_record())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, _: &T) -> Result {
        Err(not_a_record())
    }
    fn serialize_unit(self) -> Result {
        Err(not_a_record())
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, _: &'static str) -> Result {
        Err(not_a_record())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _: &'static str, _: &T) -> Result {
        Err(not_a_record())
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result {
        Err(not_a_record())
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Self::SerializeSeq> {
        Err(not_a_record())
    }
    fn serialize_tuple(self, _: usize) -> Result<Self::SerializeTuple> {
        Err(not_a_record())
    }
    fn serialize_tuple_struct(
        self,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleStruct> {
        Err(not_a_record())
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant> {
        Err(not_a_record())
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap> {
        Err(not_a_record())
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant> {
        Err(not_a_record())
    }
}
