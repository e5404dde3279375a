//! A scene given as a table of values (a Python dict) instead of TOML text: the scene's raw form
//! is deserialised from the [`toml::Table`] itself, so the checks of a scene file run unchanged
//! and their messages name the dotted key (a table has no lines to point at).
//!
//! The raw form keeps the span of every value for messages about text; here each value comes
//! with an empty span, which [`serde_spanned::de::SpannedDeserializer`] hands to it.

use serde::de::{self, DeserializeSeed, IntoDeserializer, MapAccess, SeqAccess, Visitor};
use std::fmt;
use toml::Value;

/// Why a table is not a scene's raw form: the dotted key and what is wrong there.
#[derive(Debug)]
pub(crate) struct TableError {
    /// The dotted key (`shapes[0].semi_axes`); empty until the value that failed names it.
    pub key: String,
    /// What serde said.
    pub message: String,
}

impl TableError {
    /// The error at `key` unless an inner value already named itself.
    fn at(mut self, key: &str) -> Self {
        if self.key.is_empty() {
            self.key = key.to_string();
        }
        self
    }
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "`{}`: {}", self.key, self.message)
    }
}

impl std::error::Error for TableError {}

impl de::Error for TableError {
    fn custom<T: fmt::Display>(message: T) -> Self {
        TableError {
            key: String::new(),
            message: message.to_string(),
        }
    }
}

/// The names serde passes a deserializer: of a struct or enum, and of its fields or variants.
type Name = &'static str;
type Names = &'static [&'static str];
/// What a deserializer method returns.
type Out<'de, V> = Result<<V as Visitor<'de>>::Value, TableError>;
/// What a seed gives: the next element or key of a sequence or map (`Next`), a map's value.
type Next<'de, T> = Result<Option<<T as DeserializeSeed<'de>>::Value>, TableError>;
type Seeded<'de, T> = Result<<T as DeserializeSeed<'de>>::Value, TableError>;

/// The value at a dotted key of the table.
pub(crate) struct At<'a> {
    value: &'a Value,
    key: String,
}

impl<'a> At<'a> {
    /// The whole table, a value with an empty key.
    pub fn root(table: &'a Value) -> Self {
        At {
            value: table,
            key: String::new(),
        }
    }
}

/// The dotted key of entry `name` of the table at `key`.
fn child(key: &str, name: &str) -> String {
    if key.is_empty() {
        name.to_string()
    } else {
        format!("{key}.{name}")
    }
}

impl<'de> IntoDeserializer<'de, TableError> for At<'_> {
    type Deserializer = Self;

    fn into_deserializer(self) -> Self {
        self
    }
}

impl<'de> de::Deserializer<'de> for At<'_> {
    type Error = TableError;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Out<'de, V> {
        let key = self.key.clone();
        let value = match self.value {
            Value::String(s) => visitor.visit_str(s),
            Value::Integer(i) => visitor.visit_i64(*i),
            Value::Float(x) => visitor.visit_f64(*x),
            Value::Boolean(b) => visitor.visit_bool(*b),
            Value::Datetime(d) => visitor.visit_string(d.to_string()),
            Value::Array(items) => visitor.visit_seq(Elements {
                items: items.iter().enumerate(),
                key: &key,
            }),
            Value::Table(table) => visitor.visit_map(Entries {
                entries: table.iter(),
                key: &key,
                value: None,
            }),
        };
        value.map_err(|e| e.at(&key))
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Out<'de, V> {
        visitor.visit_some(self)
    }

    fn deserialize_struct<V: Visitor<'de>>(self, name: Name, _: Names, visitor: V) -> Out<'de, V> {
        if serde_spanned::de::is_spanned(name) {
            return visitor.visit_map(serde_spanned::de::SpannedDeserializer::new(self, 0..0));
        }
        self.deserialize_any(visitor)
    }

    fn deserialize_enum<V: Visitor<'de>>(self, _: Name, _: Names, visitor: V) -> Out<'de, V> {
        match self.value {
            Value::String(s) => visitor
                .visit_enum(s.as_str().into_deserializer())
                .map_err(|e: TableError| e.at(&self.key)),
            _ => self.deserialize_any(visitor),
        }
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(self, _: Name, visitor: V) -> Out<'de, V> {
        visitor.visit_newtype_struct(self)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        unit unit_struct seq tuple tuple_struct map identifier ignored_any
    }
}

/// The elements of an array, at `key[i]`.
struct Elements<'a, I> {
    items: I,
    key: &'a str,
}

impl<'de, 'a, I: Iterator<Item = (usize, &'a Value)>> SeqAccess<'de> for Elements<'_, I> {
    type Error = TableError;

    fn next_element_seed<T: DeserializeSeed<'de>>(&mut self, seed: T) -> Next<'de, T> {
        let Some((i, value)) = self.items.next() else {
            return Ok(None);
        };
        let key = format!("{}[{i}]", self.key);
        seed.deserialize(At { value, key }).map(Some)
    }
}

/// The entries of a table, each value at `key.name`.
struct Entries<'a, 'b, I> {
    entries: I,
    key: &'b str,
    value: Option<(String, &'a Value)>,
}

impl<'de, 'a, I: Iterator<Item = (&'a String, &'a Value)>> MapAccess<'de> for Entries<'a, '_, I> {
    type Error = TableError;

    fn next_key_seed<K: DeserializeSeed<'de>>(&mut self, seed: K) -> Next<'de, K> {
        let Some((name, value)) = self.entries.next() else {
            return Ok(None);
        };
        let key = child(self.key, name);
        let read = seed.deserialize(name.as_str().into_deserializer());
        self.value = Some((key.clone(), value));
        read.map(Some).map_err(|e: TableError| e.at(&key))
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Seeded<'de, V> {
        let (key, value) = self
            .value
            .take()
            .ok_or_else(|| de::Error::custom("a value without its key"))?;
        seed.deserialize(At { value, key })
    }
}
