//! Flat serde structs (fields of numbers, booleans, strings or options of them) as Python
//! dicts, directly: no JSON values in between, and the field names made into Python strings
//! once per process, not once per call. Every extraction returns its [`rmt_extract::Stats`]
//! this way; through `serde_json::Value` the dict cost about as much as the rest of the
//! binding's fixed work together.

use std::sync::Mutex;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use pyo3::IntoPyObjectExt;
use serde::ser::{self, Impossible, Serialize};

/// Field names seen so far, as Python strings, in the order first met (a struct's fields come
/// in the same order on every call, so the lookup usually hits at the expected position).
static KEYS: Mutex<Vec<(&'static str, Py<PyString>)>> = Mutex::new(Vec::new());

/// `value` (a struct whose fields are numbers, booleans, strings or options of them) as a
/// dict from field name to value, in field order.
pub fn to_dict<'py, T: Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    // Without the cache when another call holds it (the GIL is held throughout, so only a
    // re-entrant call could: nothing here runs Python code, but a finaliser might).
    let mut scratch = Vec::new();
    let mut guard = KEYS.try_lock().ok();
    let keys = match guard.as_deref_mut() {
        Some(keys) => keys,
        None => &mut scratch,
    };
    value
        .serialize(StructSer {
            py,
            dict: &dict,
            keys,
            at: 0,
        })
        .map_err(|e| PyValueError::new_err(e.0))?;
    Ok(dict)
}

/// A serialisation error: a shape this module does not turn into a flat dict.
#[derive(Debug)]
pub struct Error(String);

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Error {}

impl ser::Error for Error {
    fn custom<M: std::fmt::Display>(msg: M) -> Self {
        Error(msg.to_string())
    }
}

impl From<PyErr> for Error {
    fn from(e: PyErr) -> Self {
        Error(e.to_string())
    }
}

fn unsupported<T>(what: &str) -> Result<T, Error> {
    Err(Error(format!("not a flat struct: {what}")))
}

/// The top level: a struct only.
struct StructSer<'a, 'py> {
    py: Python<'py>,
    dict: &'a Bound<'py, PyDict>,
    keys: &'a mut Vec<(&'static str, Py<PyString>)>,
    at: usize,
}

impl<'py> StructSer<'_, 'py> {
    /// The Python string of field name `key`, made once.
    fn key(&mut self, key: &'static str) -> Bound<'py, PyString> {
        let found = match self.keys.get(self.at) {
            Some((k, _)) if std::ptr::eq(*k, key) => Some(self.at),
            _ => self.keys.iter().position(|(k, _)| *k == key),
        };
        let at = found.unwrap_or_else(|| {
            self.keys.push((key, PyString::new(self.py, key).unbind()));
            self.keys.len() - 1
        });
        self.at = at + 1;
        self.keys[at].1.bind(self.py).clone()
    }
}

impl ser::SerializeStruct for StructSer<'_, '_> {
    type Ok = ();
    type Error = Error;

    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<(), Error> {
        let k = self.key(key);
        let v = value.serialize(ValueSer(self.py))?;
        self.dict.set_item(k, v)?;
        Ok(())
    }

    fn end(self) -> Result<(), Error> {
        Ok(())
    }
}

/// Writes the serialiser methods that refuse a shape.
macro_rules! refuse {
    ($($name:ident($($arg:ty),*) -> $ret:ty;)*) => {
        $(fn $name(self, $(_: $arg),*) -> Result<$ret, Error> {
            unsupported(stringify!($name))
        })*
    };
}

impl<'a, 'py> ser::Serializer for StructSer<'a, 'py> {
    type Ok = ();
    type Error = Error;
    type SerializeSeq = Impossible<(), Error>;
    type SerializeTuple = Impossible<(), Error>;
    type SerializeTupleStruct = Impossible<(), Error>;
    type SerializeTupleVariant = Impossible<(), Error>;
    type SerializeMap = Impossible<(), Error>;
    type SerializeStruct = Self;
    type SerializeStructVariant = Impossible<(), Error>;

    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self, Error> {
        Ok(self)
    }

    refuse! {
        serialize_bool(bool) -> ();
        serialize_i8(i8) -> ();
        serialize_i16(i16) -> ();
        serialize_i32(i32) -> ();
        serialize_i64(i64) -> ();
        serialize_u8(u8) -> ();
        serialize_u16(u16) -> ();
        serialize_u32(u32) -> ();
        serialize_u64(u64) -> ();
        serialize_f32(f32) -> ();
        serialize_f64(f64) -> ();
        serialize_char(char) -> ();
        serialize_str(&str) -> ();
        serialize_bytes(&[u8]) -> ();
        serialize_none() -> ();
        serialize_unit() -> ();
        serialize_unit_struct(&'static str) -> ();
        serialize_unit_variant(&'static str, u32, &'static str) -> ();
        serialize_seq(Option<usize>) -> Self::SerializeSeq;
        serialize_tuple(usize) -> Self::SerializeTuple;
        serialize_tuple_struct(&'static str, usize) -> Self::SerializeTupleStruct;
        serialize_tuple_variant(&'static str, u32, &'static str, usize) -> Self::SerializeTupleVariant;
        serialize_map(Option<usize>) -> Self::SerializeMap;
        serialize_struct_variant(&'static str, u32, &'static str, usize) -> Self::SerializeStructVariant;
    }

    fn serialize_some<T: ?Sized + Serialize>(self, _: &T) -> Result<(), Error> {
        unsupported("serialize_some")
    }

    fn serialize_newtype_struct<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: &T,
    ) -> Result<(), Error> {
        unsupported("serialize_newtype_struct")
    }

    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<(), Error> {
        unsupported("serialize_newtype_variant")
    }
}

/// A field's value: a number, boolean, string, or None.
struct ValueSer<'py>(Python<'py>);

impl<'py> ValueSer<'py> {
    fn any<T>(self, v: T) -> Result<Bound<'py, PyAny>, Error>
    where
        T: IntoPyObject<'py>,
    {
        v.into_bound_py_any(self.0).map_err(Error::from)
    }
}

impl<'py> ser::Serializer for ValueSer<'py> {
    type Ok = Bound<'py, PyAny>;
    type Error = Error;
    type SerializeSeq = Impossible<Self::Ok, Error>;
    type SerializeTuple = Impossible<Self::Ok, Error>;
    type SerializeTupleStruct = Impossible<Self::Ok, Error>;
    type SerializeTupleVariant = Impossible<Self::Ok, Error>;
    type SerializeMap = Impossible<Self::Ok, Error>;
    type SerializeStruct = Impossible<Self::Ok, Error>;
    type SerializeStructVariant = Impossible<Self::Ok, Error>;

    fn serialize_bool(self, v: bool) -> Result<Self::Ok, Error> {
        self.any(v)
    }
    fn serialize_i8(self, v: i8) -> Result<Self::Ok, Error> {
        self.any(v)
    }
    fn serialize_i16(self, v: i16) -> Result<Self::Ok, Error> {
        self.any(v)
    }
    fn serialize_i32(self, v: i32) -> Result<Self::Ok, Error> {
        self.any(v)
    }
    fn serialize_i64(self, v: i64) -> Result<Self::Ok, Error> {
        self.any(v)
    }
    fn serialize_u8(self, v: u8) -> Result<Self::Ok, Error> {
        self.any(v)
    }
    fn serialize_u16(self, v: u16) -> Result<Self::Ok, Error> {
        self.any(v)
    }
    fn serialize_u32(self, v: u32) -> Result<Self::Ok, Error> {
        self.any(v)
    }
    fn serialize_u64(self, v: u64) -> Result<Self::Ok, Error> {
        self.any(v)
    }
    fn serialize_f32(self, v: f32) -> Result<Self::Ok, Error> {
        // As serde_json would: the float32 widened to a double.
        self.any(f64::from(v))
    }
    fn serialize_f64(self, v: f64) -> Result<Self::Ok, Error> {
        self.any(v)
    }
    fn serialize_char(self, v: char) -> Result<Self::Ok, Error> {
        self.any(v.to_string())
    }
    fn serialize_str(self, v: &str) -> Result<Self::Ok, Error> {
        self.any(v)
    }
    fn serialize_none(self) -> Result<Self::Ok, Error> {
        Ok(self.0.None().into_bound(self.0))
    }
    fn serialize_some<T: ?Sized + Serialize>(self, v: &T) -> Result<Self::Ok, Error> {
        v.serialize(self)
    }
    fn serialize_unit(self) -> Result<Self::Ok, Error> {
        self.serialize_none()
    }
    fn serialize_unit_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
    ) -> Result<Self::Ok, Error> {
        self.any(variant)
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        v: &T,
    ) -> Result<Self::Ok, Error> {
        v.serialize(self)
    }

    refuse! {
        serialize_bytes(&[u8]) -> Self::Ok;
        serialize_unit_struct(&'static str) -> Self::Ok;
        serialize_seq(Option<usize>) -> Self::SerializeSeq;
        serialize_tuple(usize) -> Self::SerializeTuple;
        serialize_tuple_struct(&'static str, usize) -> Self::SerializeTupleStruct;
        serialize_tuple_variant(&'static str, u32, &'static str, usize) -> Self::SerializeTupleVariant;
        serialize_map(Option<usize>) -> Self::SerializeMap;
        serialize_struct(&'static str, usize) -> Self::SerializeStruct;
        serialize_struct_variant(&'static str, u32, &'static str, usize) -> Self::SerializeStructVariant;
    }

    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<Self::Ok, Error> {
        unsupported("serialize_newtype_variant")
    }
}
