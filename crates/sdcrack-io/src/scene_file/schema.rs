//! The scene schema, derived from the serde structs of [`super::raw`]: every table with its keys,
//! in the structs' order, each key with the type of its value, the words messages use for it
//! and, for names, the values allowed.
//!
//! The structs are read by deserializing [`super::raw::SceneToml`] from a [`Recorder`], a serde
//! `Deserializer` that answers every struct with all of its fields (the names serde passes to
//! `deserialize_struct`) and every list with one element, noting what each field asks for
//! (string, integer, number, bool, list, table). Adding a field to a struct adds it here, to the
//! "unknown key" messages, to `sdcrack schema`, to the fuzzer's tokens and to the docs test.
//!
//! What the structs cannot say is kept beside it, by key name: the allowed names of a key
//! ([`ALLOWED`]) and, for a few keys, better words than the type's ([`WORDS`]); unit tests check
//! that each names a key of the schema.

use serde::de::{self, value::Error, DeserializeSeed, IntoDeserializer, MapAccess, SeqAccess};
use serde::{Deserialize, Serialize};

use super::raw::SceneToml;
use sdcrack_core::case::{AxisSchema, CaseKey};
use sdcrack_core::elasticity::{Component, PlaneModel};
use sdcrack_core::norms::Quantity;
use sdcrack_core::problem::{MultiplierSpace, PMass, PSpace, USpace};
use sdcrack_core::scene::verification::NOT_APPLICABLE_CHECKS;
use sdcrack_core::scene::ProblemKind;

/// Reference tools the project knows how to run.
pub const KNOWN_REFERENCES: [&str; 2] = ["dolfinx", "freefem"];

/// What a key's value is, as its struct field declares it (an `Option` is its content).
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// A TOML string.
    String,
    /// A TOML integer.
    Integer,
    /// A TOML number (integer or float).
    Number,
    /// `true` or `false`.
    Bool,
    /// An array of values of one kind.
    List(Box<Kind>),
    /// A table whose keys are names the scene chooses (boundary parts), each holding a value
    /// of one kind.
    Map(Box<Kind>),
    /// A table (a `[header]`, an inline table, or each of an array of tables).
    Table,
}

impl Kind {
    /// The kind in three forms: its type name for `sdcrack schema`, a value of it in words and
    /// several values of it in words (`integer`, `an integer`, `integers`; `list of integer`,
    /// `a list of integers`, `lists of integers`).
    fn forms(&self) -> [String; 3] {
        let forms = match self {
            Kind::String => ["string", "a string", "strings"],
            Kind::Integer => ["integer", "an integer", "integers"],
            Kind::Number => ["number", "a number", "numbers"],
            Kind::Bool => ["bool", "true or false", "booleans"],
            Kind::Table => ["table", "a table", "tables"],
            Kind::List(item) => {
                let [name, _, many] = item.forms();
                return [
                    format!("list of {name}"),
                    format!("a list of {many}"),
                    format!("lists of {many}"),
                ];
            }
            Kind::Map(item) => {
                let [name, _, many] = item.forms();
                return [
                    format!("table of {name}"),
                    format!("a table of {many}"),
                    format!("tables of {many}"),
                ];
            }
        };
        forms.map(str::to_string)
    }

    /// The type as `sdcrack schema` writes it: `string`, `list of list of number`, …
    pub fn name(&self) -> String {
        let [name, _, _] = self.forms();
        name
    }

    /// A value of this kind in words for a message, "a list of integers".
    fn words(&self) -> String {
        let [_, one, _] = self.forms();
        one
    }
}

/// One key of a table.
#[derive(Clone, Debug, Serialize)]
pub struct KeySchema {
    /// The key's name.
    pub key: &'static str,
    /// Its type ([`Kind::name`]).
    #[serde(rename = "type")]
    pub type_name: String,
    /// What its value must be, in the words of messages.
    pub words: String,
    /// The names it may hold (each, for a list), empty when any value of its type goes.
    pub values: Vec<String>,
    #[serde(skip)]
    kind: Kind,
}

/// One table of a scene: `""` for the top level, `geometry.domain` for an inline table,
/// `verification.expected_failure` for (each of) an array of tables.
#[derive(Clone, Debug, Serialize)]
pub struct TableSchema {
    /// Dotted path of the table, without array indices.
    pub table: String,
    /// Its keys, in the struct's order.
    pub keys: Vec<KeySchema>,
}

impl TableSchema {
    /// The names of its keys.
    pub fn key_names(&self) -> Vec<&'static str> {
        self.keys.iter().map(|k| k.key).collect()
    }
}

/// The names the compare tool and the scene share beyond keys: the error quantities, the checks
/// a scene may declare not applicable, and the reference tools.
#[derive(Clone, Debug, Serialize)]
pub struct Vocabulary {
    /// Error quantities of a series (summary.json's `errors` keys).
    pub quantities: Vec<&'static str>,
    /// Checks a `[[verification.not_applicable]]` may name.
    pub not_applicable_checks: Vec<&'static str>,
    /// Reference solvers a scene may list.
    pub references: Vec<&'static str>,
}

/// Every table of a scene and the shared vocabulary: what `sdcrack schema` prints.
#[derive(Clone, Debug, Serialize)]
pub struct Schema {
    /// The tables, in the structs' order (a table before the tables inside it).
    pub tables: Vec<TableSchema>,
    /// The names shared with the compare tool.
    pub vocabulary: Vocabulary,
    /// The axes of a case (summary.json's keys of a case, in order), with their values' names
    /// and the value a summary without the axis means.
    pub case_key: Vec<AxisSchema>,
}

/// Names of the fields `[outputs] fields` may list.
pub const FIELDS: &[&str] = &["u", "p", "lambda"];

/// The fields an elastic scene's `[outputs] fields` may list (the references' u and stress).
pub const ELASTIC_FIELDS: &[&str] = &["u"];

/// The names a key may hold, by `table.key` (the verification patterns also take `"*"`).
pub const ALLOWED: &[(&str, &[&str])] = &[
    ("problem.kind", ProblemKind::NAMES),
    ("problem.plane", PlaneModel::NAMES),
    ("data.fixed.components", Component::NAMES),
    ("discretization.u_spaces", USpace::NAMES),
    ("discretization.multipliers", MultiplierSpace::NAMES),
    ("discretization.p_mass", PMass::NAMES),
    ("discretization.p_spaces", PSpace::NAMES),
    ("outputs.fields", FIELDS),
    ("outputs.references", &KNOWN_REFERENCES),
    ("verification.expected_failure.u_space", USpace::NAMES),
    (
        "verification.expected_failure.multiplier",
        MultiplierSpace::NAMES,
    ),
    ("verification.expected_failure.quantity", Quantity::NAMES),
    ("verification.expected_rate.u_space", USpace::NAMES),
    (
        "verification.expected_rate.multiplier",
        MultiplierSpace::NAMES,
    ),
    ("verification.expected_rate.p_mass", PMass::NAMES),
    ("verification.expected_rate.p_space", PSpace::NAMES),
    ("verification.expected_rate.quantity", Quantity::NAMES),
    ("verification.not_applicable.check", &NOT_APPLICABLE_CHECKS),
];

/// Words of docs/scenes.md for keys whose type alone says too little, by key name (a name means
/// the same in every table that has it).
pub(super) const WORDS: &[(&str, &str)] = &[
    (
        "rectangle",
        "two corner points [[x0, y0], [x1, y1]] of numbers",
    ),
    ("segment", "two end points [[xa, ya], [xb, yb]] of numbers"),
    (
        "polygon",
        "a list of at least three points [[x, y], ...] of numbers",
    ),
    (
        "polyline",
        "a list of at least two points [[x, y], ...] of numbers",
    ),
    (
        "cracks",
        "a list of cracks, each { segment = [[xa, ya], [xb, yb]] } or { polyline = [[x, y], ...] }",
    ),
    (
        "mesh_size",
        "a positive number (the coarse mesh's target edge length)",
    ),
    ("gmsh", "the path of a .msh file in quotes"),
    ("f", "an expression in quotes, e.g. \"sin(pi*x)\""),
    ("g", "an expression in quotes, e.g. \"0\""),
    ("u", "an expression in quotes"),
    ("px", "an expression in quotes"),
    ("py", "an expression in quotes"),
    ("jump", "an expression in quotes"),
    ("fx", "an expression in quotes, e.g. \"0\""),
    ("fy", "an expression in quotes, e.g. \"0\""),
    ("gx", "an expression in quotes"),
    ("gy", "an expression in quotes"),
    (
        "traction",
        "a table of boundary parts, each [\"tx\", \"ty\"]: two expressions in quotes",
    ),
    ("point", "a point [x, y] of numbers"),
    ("ux", "an expression in quotes"),
    ("uy", "an expression in quotes"),
    ("sxx", "an expression in quotes"),
    ("syy", "an expression in quotes"),
    ("sxy", "an expression in quotes"),
    ("opening", "an expression in quotes"),
    ("slip", "an expression in quotes"),
    ("pressure", "an expression in quotes"),
    (
        "sif",
        "a list of pairs [K_I, K_II] of numbers, one per crack tip",
    ),
    ("cells", "two integers [nx, ny]"),
    ("deltas", "a list of numbers ≥ 0"),
];

/// The scene schema: every table and key of [`SceneToml`], and the vocabulary.
pub fn schema() -> Schema {
    let mut tables = Vec::new();
    let mut kind = Kind::Table;
    let recorder = Recorder {
        path: String::new(),
        kind: &mut kind,
        tables: &mut tables,
    };
    // The recorder answers every request; failing here is a defect of the structs, not input.
    if let Err(e) = SceneToml::deserialize(recorder) {
        panic!("the scene structs cannot be recorded: {e}");
    }
    Schema {
        tables,
        vocabulary: Vocabulary {
            quantities: Quantity::NAMES.to_vec(),
            not_applicable_checks: NOT_APPLICABLE_CHECKS.to_vec(),
            references: KNOWN_REFERENCES.to_vec(),
        },
        case_key: CaseKey::schema(),
    }
}

impl Schema {
    /// The table at `path` (dotted, without indices).
    pub fn table(&self, path: &str) -> Option<&TableSchema> {
        self.tables.iter().find(|t| t.table == path)
    }

    /// The key `key` of table `table`.
    pub fn key(&self, table: &str, key: &str) -> Option<&KeySchema> {
        self.table(table)?.keys.iter().find(|k| k.key == key)
    }

    /// The first table (in schema order) that has a key named `key`.
    pub fn table_of(&self, key: &str) -> Option<&TableSchema> {
        self.tables
            .iter()
            .find(|t| t.keys.iter().any(|k| k.key == key))
    }

    /// Every distinct key name, in schema order.
    pub fn key_names(&self) -> Vec<&'static str> {
        let mut out: Vec<&'static str> = Vec::new();
        for k in self.tables.iter().flat_map(|t| &t.keys) {
            if !out.contains(&k.key) {
                out.push(k.key);
            }
        }
        out
    }

    /// `sdcrack schema`'s JSON text.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}

/// What `table.key`'s value must be, in words: [`WORDS`], the allowed names, or the type's.
fn words_of(table: &str, key: &'static str, kind: &Kind) -> String {
    if let Some((_, w)) = WORDS.iter().find(|(k, _)| *k == key) {
        return (*w).to_string();
    }
    match (allowed(table, key), kind) {
        (Some(names), Kind::List(_)) => format!("a list of names from {}", quoted(names)),
        _ => kind.words(),
    }
}

/// The names `table.key` may hold, if it is a key of names.
pub fn allowed(table: &str, key: &str) -> Option<&'static [&'static str]> {
    ALLOWED
        .iter()
        .find(|(path, _)| path.strip_prefix(table).and_then(|r| r.strip_prefix('.')) == Some(key))
        .map(|(_, names)| *names)
}

/// `"a", "b"`.
fn quoted(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A `Deserializer` that records what the structs ask for: at `path`, the kind it was asked
/// for goes to `kind`, and each struct becomes a table of `tables`.
struct Recorder<'a> {
    path: String,
    kind: &'a mut Kind,
    tables: &'a mut Vec<TableSchema>,
}

impl<'de> de::Deserializer<'de> for Recorder<'_> {
    type Error = Error;

    fn deserialize_any<V: de::Visitor<'de>>(self, _: V) -> Result<V::Value, Error> {
        Err(de::Error::custom(format!(
            "{}: a scene value must have a declared type",
            self.path
        )))
    }

    fn deserialize_bool<V: de::Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        *self.kind = Kind::Bool;
        visitor.visit_bool(false)
    }

    fn deserialize_i64<V: de::Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        *self.kind = Kind::Integer;
        visitor.visit_i64(0)
    }

    fn deserialize_f64<V: de::Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        *self.kind = Kind::Number;
        visitor.visit_f64(0.0)
    }

    fn deserialize_str<V: de::Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        *self.kind = Kind::String;
        visitor.visit_str("")
    }

    fn deserialize_string<V: de::Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        self.deserialize_str(visitor)
    }

    fn deserialize_option<V: de::Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_some(self)
    }

    fn deserialize_seq<V: de::Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        let mut item = Kind::Table;
        let value = visitor.visit_seq(OneItem {
            recorder: Some(Recorder {
                path: self.path,
                kind: &mut item,
                tables: self.tables,
            }),
        })?;
        *self.kind = Kind::List(Box::new(item));
        Ok(value)
    }

    fn deserialize_struct<V: de::Visitor<'de>>(
        self,
        _name: &'static str,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Error> {
        let index = self.tables.len();
        self.tables.push(TableSchema {
            table: self.path.clone(),
            keys: Vec::new(),
        });
        let mut kinds = vec![Kind::Table; fields.len()];
        let value = visitor.visit_map(EveryField {
            path: &self.path,
            fields,
            next: 0,
            kinds: &mut kinds,
            tables: self.tables,
        })?;
        let table = self.path;
        self.tables[index].keys = fields
            .iter()
            .zip(kinds)
            .map(|(&key, kind)| KeySchema {
                key,
                type_name: kind.name(),
                words: words_of(&table, key, &kind),
                values: allowed(&table, key)
                    .unwrap_or(&[])
                    .iter()
                    .map(|s| s.to_string())
                    .collect(),
                kind,
            })
            .collect();
        *self.kind = Kind::Table;
        Ok(value)
    }

    fn deserialize_map<V: de::Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        let mut item = Kind::Table;
        let value = visitor.visit_map(OneEntry {
            recorder: Some(Recorder {
                path: self.path,
                kind: &mut item,
                tables: self.tables,
            }),
        })?;
        *self.kind = Kind::Map(Box::new(item));
        Ok(value)
    }

    serde::forward_to_deserialize_any! {
        i8 i16 i32 i128 u8 u16 u32 u64 u128 f32 char bytes byte_buf unit unit_struct
        newtype_struct tuple tuple_struct enum identifier ignored_any
    }
}

/// A table of names of exactly one entry (named `name`), its value recorded.
struct OneEntry<'a> {
    recorder: Option<Recorder<'a>>,
}

impl<'de> MapAccess<'de> for OneEntry<'_> {
    type Error = Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, Error> {
        if self.recorder.is_none() {
            return Ok(None);
        }
        seed.deserialize("name".into_deserializer()).map(Some)
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, Error> {
        match self.recorder.take() {
            Some(r) => seed.deserialize(r),
            None => Err(de::Error::custom("a value asked for before its key")),
        }
    }
}

/// A list of exactly one element, recorded.
struct OneItem<'a> {
    recorder: Option<Recorder<'a>>,
}

impl<'de> SeqAccess<'de> for OneItem<'_> {
    type Error = Error;

    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, Error> {
        self.recorder
            .take()
            .map(|r| seed.deserialize(r))
            .transpose()
    }
}

/// A table holding every field of its struct, each recorded.
struct EveryField<'a, 'k> {
    path: &'a str,
    fields: &'static [&'static str],
    next: usize,
    kinds: &'k mut [Kind],
    tables: &'a mut Vec<TableSchema>,
}

impl<'de> MapAccess<'de> for EveryField<'_, '_> {
    type Error = Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, Error> {
        let Some(&field) = self.fields.get(self.next) else {
            return Ok(None);
        };
        seed.deserialize(field.into_deserializer()).map(Some)
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, Error> {
        let field = self.fields[self.next];
        let path = if self.path.is_empty() {
            field.to_string()
        } else {
            format!("{}.{field}", self.path)
        };
        let kind = &mut self.kinds[self.next];
        self.next += 1;
        seed.deserialize(Recorder {
            path,
            kind,
            tables: self.tables,
        })
    }
}

impl KeySchema {
    /// The type of the key's value.
    pub fn kind(&self) -> &Kind {
        &self.kind
    }
}
