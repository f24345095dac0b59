//! A serde `Deserializer` over a parsed `toml::Value` that remembers the dotted key path of the
//! first error (unknown key, wrong type, bad value), so that every message can name its key.

use std::fmt;

use serde::de::value::BorrowedStrDeserializer;
use serde::de::{self, DeserializeSeed, IntoDeserializer, Visitor};
use serde::forward_to_deserialize_any;
use toml::Value;

/// A deserialization error with the key path where it happened (outermost first).
#[derive(Debug)]
pub(crate) struct PathError {
    /// Path segments from the root; `None` until the error has passed through a table.
    pub(crate) path: Option<Vec<Segment>>,
    pub(crate) message: String,
}

/// One step of a key path.
#[derive(Debug, Clone)]
pub(crate) enum Segment {
    Key(String),
    Index(usize),
}

impl PathError {
    fn at(mut self, parent: &[Segment], last: Segment) -> Self {
        if self.path.is_none() {
            let mut p = parent.to_vec();
            p.push(last);
            self.path = Some(p);
        }
        self
    }
}

impl fmt::Display for PathError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for PathError {}

impl de::Error for PathError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        PathError {
            path: None,
            message: msg.to_string(),
        }
    }
}

/// Formats a key path TOML-style: `render.tile_size`, `"odd key".x`, `layers[2].name`.
pub(crate) fn dotted(path: &[Segment]) -> String {
    let mut out = String::new();
    for seg in path {
        match seg {
            Segment::Key(k) => {
                if !out.is_empty() {
                    out.push('.');
                }
                let bare = !k.is_empty()
                    && k.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
                if bare {
                    out.push_str(k);
                } else {
                    out.push('"');
                    for c in k.chars() {
                        match c {
                            '"' => out.push_str("\\\""),
                            '\\' => out.push_str("\\\\"),
                            c if c.is_control() => out.push_str(&c.escape_default().to_string()),
                            c => out.push(c),
                        }
                    }
                    out.push('"');
                }
            }
            Segment::Index(i) => out.push_str(&format!("[{i}]")),
        }
    }
    out
}

/// Deserializes `T` from `value`, tracking the key path of any error.
pub(crate) fn from_value<'de, T: de::Deserialize<'de>>(value: &'de Value) -> Result<T, PathError> {
    // An error raised by the root table itself (no key on the way) belongs to the empty path.
    T::deserialize(PathDeserializer { value, path: &[] }).map_err(|mut e| {
        e.path.get_or_insert_with(Vec::new);
        e
    })
}

struct PathDeserializer<'de, 'p> {
    value: &'de Value,
    path: &'p [Segment],
}

impl<'de> de::Deserializer<'de> for PathDeserializer<'de, '_> {
    type Error = PathError;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, PathError> {
        match self.value {
            Value::String(s) => visitor.visit_borrowed_str(s),
            Value::Integer(i) => visitor.visit_i64(*i),
            Value::Float(f) => visitor.visit_f64(*f),
            Value::Boolean(b) => visitor.visit_bool(*b),
            Value::Datetime(d) => visitor.visit_string(d.to_string()),
            Value::Array(items) => visitor.visit_seq(SeqAccess {
                items: items.iter().enumerate(),
                path: self.path,
            }),
            Value::Table(table) => visitor.visit_map(MapAccess {
                entries: table.iter(),
                pending: None,
                path: self.path,
            }),
        }
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, PathError> {
        // TOML has no null: a present key is always `Some`.
        visitor.visit_some(self)
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        visitor: V,
    ) -> Result<V::Value, PathError> {
        visitor.visit_newtype_struct(self)
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, PathError> {
        match self.value {
            // Unit variants written as strings, the usual TOML spelling.
            Value::String(s) => visitor.visit_enum(s.as_str().into_deserializer()),
            other => Err(de::Error::invalid_type(unexpected(other), &visitor)),
        }
    }

    forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
        bytes byte_buf unit unit_struct seq tuple tuple_struct map struct
        identifier ignored_any
    }
}

fn unexpected(v: &Value) -> de::Unexpected<'_> {
    match v {
        Value::String(s) => de::Unexpected::Str(s),
        Value::Integer(i) => de::Unexpected::Signed(*i),
        Value::Float(f) => de::Unexpected::Float(*f),
        Value::Boolean(b) => de::Unexpected::Bool(*b),
        Value::Datetime(_) => de::Unexpected::Other("datetime"),
        Value::Array(_) => de::Unexpected::Seq,
        Value::Table(_) => de::Unexpected::Map,
    }
}

struct SeqAccess<'p, I> {
    items: I,
    path: &'p [Segment],
}

impl<'de, I> de::SeqAccess<'de> for SeqAccess<'_, I>
where
    I: Iterator<Item = (usize, &'de Value)>,
{
    type Error = PathError;

    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, PathError> {
        let Some((i, value)) = self.items.next() else {
            return Ok(None);
        };
        let mut path = self.path.to_vec();
        path.push(Segment::Index(i));
        seed.deserialize(PathDeserializer { value, path: &path })
            .map(Some)
            .map_err(|e| e.at(self.path, Segment::Index(i)))
    }
}

struct MapAccess<'de, 'p, I> {
    entries: I,
    pending: Option<(&'de String, &'de Value)>,
    path: &'p [Segment],
}

impl<'de, I> de::MapAccess<'de> for MapAccess<'de, '_, I>
where
    I: Iterator<Item = (&'de String, &'de Value)>,
{
    type Error = PathError;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, PathError> {
        let Some((key, value)) = self.entries.next() else {
            return Ok(None);
        };
        self.pending = Some((key, value));
        // Unknown keys fail here (deny_unknown_fields): the path is the key itself.
        seed.deserialize(BorrowedStrDeserializer::<PathError>::new(key))
            .map(Some)
            .map_err(|e| e.at(self.path, Segment::Key(key.clone())))
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, PathError> {
        let (key, value) = self
            .pending
            .take()
            .ok_or_else(|| <PathError as de::Error>::custom("value requested before key"))?;
        let mut path = self.path.to_vec();
        path.push(Segment::Key(key.clone()));
        seed.deserialize(PathDeserializer { value, path: &path })
            .map_err(|e| e.at(self.path, Segment::Key(key.clone())))
    }
}
