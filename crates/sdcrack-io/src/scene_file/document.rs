//! The scene's TOML document into the serde structs of [`super::raw`], with every error as data.
//!
//! toml's own deserializer turns what serde's derive reports (an unknown key, a missing key, a
//! value of the wrong type) into message text. This one walks the document that toml_edit parses
//! (the same parser, keeping the span of every key and value) and has an error type of its own,
//! [`RawError`], that keeps what serde's derive reports as a [`Fault`], with the [`KeyPath`]
//! where it happened and the span of the text concerned: messages are made from that data
//! ([`super::toml_error`]), never from the text of a serde or toml error.
//!
//! It presents values as toml's deserializer does (a string, an i64, an f64, a bool, a datetime
//! as a one-key table, arrays and tables in document order), so a scene is read, and rejected,
//! exactly as before.

use std::fmt;
use std::ops::Range;

use serde::de::{self, DeserializeSeed, IntoDeserializer, MapAccess, Unexpected};
use serde::Deserialize;
use toml_edit::{ArrayOfTables, Item, TableLike, Value};

use sdcrack_core::scene::KeyPath;

/// What serde's derive found wrong, as data.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Fault {
    /// A key the table's struct has no field for.
    UnknownKey(String),
    /// A required key that the table does not have.
    MissingKey(&'static str),
    /// A value of another type than the field's: what was found, in words (`the string "a"`,
    /// `a list`), and serde's sentence for the case.
    WrongType {
        /// What was found, in words.
        found: String,
        /// `invalid type: …, expected …`, as serde words it.
        message: String,
    },
    /// Anything else serde or a `Deserialize` impl reports.
    Other(String),
}

/// An error of reading the document into the structs: the fault, where, and the span of the
/// text concerned (the key for an unknown key, the table for a missing key, the value for a
/// wrong type). `path` and `span` are set by the innermost part of the document that saw it.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct RawError {
    pub(super) fault: Fault,
    pub(super) path: KeyPath,
    pub(super) span: Option<Range<usize>>,
    located: bool,
}

impl RawError {
    fn new(fault: Fault) -> RawError {
        RawError {
            fault,
            path: KeyPath::root(),
            span: None,
            located: false,
        }
    }

    /// This error at `path` and `span`, unless a deeper part of the document placed it already.
    fn at(mut self, path: &KeyPath, span: Option<Range<usize>>) -> RawError {
        if !self.located {
            self.path = path.clone();
            self.span = span;
            self.located = true;
        }
        self
    }
}

impl fmt::Display for RawError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.fault {
            Fault::UnknownKey(k) => write!(f, "{}: unknown key `{k}`", self.path),
            Fault::MissingKey(k) => write!(f, "{}: missing key `{k}`", self.path),
            Fault::WrongType { message, .. } | Fault::Other(message) => {
                write!(f, "{}: {message}", self.path)
            }
        }
    }
}

impl std::error::Error for RawError {}

impl de::Error for RawError {
    fn custom<T: fmt::Display>(msg: T) -> RawError {
        RawError::new(Fault::Other(msg.to_string()))
    }

    fn invalid_type(unexpected: Unexpected<'_>, expected: &dyn de::Expected) -> RawError {
        RawError::new(Fault::WrongType {
            found: found_words(&unexpected),
            message: format!("invalid type: {unexpected}, expected {expected}"),
        })
    }

    fn unknown_field(field: &str, _expected: &'static [&'static str]) -> RawError {
        RawError::new(Fault::UnknownKey(field.to_string()))
    }

    fn missing_field(field: &'static str) -> RawError {
        RawError::new(Fault::MissingKey(field))
    }
}

/// What was found, in the words of a scene message: `the string "a"`, `the integer 5`, `the
/// number 1.5`, `the boolean true`, `a list`, `a table`.
fn found_words(unexpected: &Unexpected<'_>) -> String {
    match *unexpected {
        // a string is shown as Rust writes it, quoted and escaped
        Unexpected::Str(s) => format!(
            "the string {}",
            crate::one_line::escape_controls(&format!("{s:?}"))
        ),
        Unexpected::Signed(i) => format!("the integer {i}"),
        Unexpected::Unsigned(i) => format!("the integer {i}"),
        Unexpected::Float(x) => format!("the number {}", with_decimal_point(x)),
        Unexpected::Bool(b) => format!("the boolean {b}"),
        Unexpected::Seq => "a list".to_string(),
        Unexpected::Map => "a table".to_string(),
        ref other => other.to_string(),
    }
}

/// `x` as serde shows an unexpected float: a finite number always with a decimal point (`2.0`,
/// `1e300` as its digits and `.0`), `inf` and `NaN` as Rust writes them.
fn with_decimal_point(x: f64) -> String {
    let text = x.to_string();
    if x.is_finite() && !text.contains('.') {
        format!("{text}.0")
    } else {
        text
    }
}

/// Reads `T` from the document `doc` (the root table).
pub(super) fn from_document<'de, T: Deserialize<'de>>(
    doc: &toml_edit::ImDocument<&str>,
) -> Result<T, RawError> {
    T::deserialize(Node {
        part: Part::Table(doc.as_table(), doc.as_table().span()),
        path: KeyPath::root(),
    })
}

/// A part of the document: a value, a table (header or inline) or an array of tables.
enum Part<'a> {
    Value(&'a Value),
    Table(&'a dyn TableLike, Option<Range<usize>>),
    Tables(&'a ArrayOfTables),
}

impl<'a> Part<'a> {
    fn of(item: &'a Item) -> Option<Part<'a>> {
        match item {
            Item::None => None,
            Item::Value(Value::InlineTable(t)) => Some(Part::Table(t, t.span())),
            Item::Value(v) => Some(Part::Value(v)),
            Item::Table(t) => Some(Part::Table(t, t.span())),
            Item::ArrayOfTables(a) => Some(Part::Tables(a)),
        }
    }

    fn of_value(value: &'a Value) -> Part<'a> {
        match value {
            Value::InlineTable(t) => Part::Table(t, t.span()),
            v => Part::Value(v),
        }
    }

    fn span(&self) -> Option<Range<usize>> {
        match self {
            Part::Value(v) => v.span(),
            Part::Table(_, span) => span.clone(),
            Part::Tables(a) => a.span(),
        }
    }
}

/// A part of the document at its key path: the `Deserializer` serde's derive reads.
struct Node<'a> {
    part: Part<'a>,
    path: KeyPath,
}

impl<'de> de::Deserializer<'de> for Node<'_> {
    type Error = RawError;

    fn deserialize_any<V: de::Visitor<'de>>(self, visitor: V) -> Result<V::Value, RawError> {
        let span = self.part.span();
        let path = self.path.clone();
        match self.part {
            Part::Value(Value::String(s)) => visitor.visit_str(s.value()),
            Part::Value(Value::Integer(i)) => visitor.visit_i64(*i.value()),
            Part::Value(Value::Float(x)) => visitor.visit_f64(*x.value()),
            Part::Value(Value::Boolean(b)) => visitor.visit_bool(*b.value()),
            // toml shows a datetime as a table of one private key holding its text (an error
            // in it is the datetime's, at its key)
            Part::Value(Value::Datetime(d)) => visitor.visit_map(de::value::MapDeserializer::new(
                std::iter::once((DATETIME_KEY, d.value().to_string())),
            )),
            Part::Value(Value::Array(a)) => {
                visitor.visit_seq(elements(a.iter().map(Part::of_value), &path))
            }
            Part::Value(Value::InlineTable(t)) => visitor.visit_map(Entries::new(t, &path)),
            Part::Table(t, _) => visitor.visit_map(Entries::new(t, &path)),
            Part::Tables(a) => {
                visitor.visit_seq(elements(a.iter().map(|t| Part::Table(t, t.span())), &path))
            }
        }
        .map_err(|e| e.at(&path, span))
    }

    fn deserialize_option<V: de::Visitor<'de>>(self, visitor: V) -> Result<V::Value, RawError> {
        let (span, path) = (self.part.span(), self.path.clone());
        visitor.visit_some(self).map_err(|e| e.at(&path, span))
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        unit unit_struct newtype_struct seq tuple tuple_struct map struct enum identifier
        ignored_any
    }
}

/// The elements of an array (of values or of tables) at `path`, each at its index.
fn elements<'a>(
    parts: impl Iterator<Item = Part<'a>>,
    path: &KeyPath,
) -> de::value::SeqDeserializer<impl Iterator<Item = Node<'a>>, RawError> {
    let path = path.clone();
    de::value::SeqDeserializer::new(parts.enumerate().map(move |(i, part)| Node {
        part,
        path: path.clone().index(i),
    }))
}

impl<'de, 'a> IntoDeserializer<'de, RawError> for Node<'a> {
    type Deserializer = Node<'a>;

    fn into_deserializer(self) -> Node<'a> {
        self
    }
}

/// The entries of a table in document order, each key at its span.
struct Entries<'a, 'p> {
    table: &'a dyn TableLike,
    keys: std::vec::IntoIter<&'a str>,
    value: Option<(&'a str, &'a Item)>,
    path: &'p KeyPath,
}

impl<'a, 'p> Entries<'a, 'p> {
    fn new(table: &'a dyn TableLike, path: &'p KeyPath) -> Entries<'a, 'p> {
        Entries {
            table,
            keys: (table.iter())
                .map(|(k, _)| k)
                .collect::<Vec<_>>()
                .into_iter(),
            value: None,
            path,
        }
    }
}

impl<'de> MapAccess<'de> for Entries<'_, '_> {
    type Error = RawError;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, RawError> {
        let Some(name) = self.keys.next() else {
            return Ok(None);
        };
        let Some((key, item)) = self.table.get_key_value(name) else {
            return Ok(None);
        };
        self.value = Some((name, item));
        let key_deserializer: de::value::StrDeserializer<'_, RawError> = name.into_deserializer();
        seed.deserialize(key_deserializer)
            .map(Some)
            .map_err(|e| e.at(&self.path.clone().key(name), key.span()))
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, RawError> {
        let (name, item) = self
            .value
            .take()
            .ok_or_else(|| de::Error::custom("a value asked for before its key"))?;
        let path = self.path.clone().key(name);
        match Part::of(item) {
            Some(part) => seed.deserialize(Node { part, path }),
            // toml_edit leaves out a table's removed entries, and a parsed document has none
            None => Err(de::Error::custom("an entry without a value")),
        }
    }
}

/// toml's name of the one key of a datetime's table.
const DATETIME_KEY: &str = "$__toml_private_datetime";
