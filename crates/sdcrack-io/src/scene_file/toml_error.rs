//! One-line messages for the errors of reading a scene's TOML: what is wrong, the key or table,
//! line and column, and for an unknown key the closest key of its table ("did you mean") and the
//! keys allowed there.
//!
//! An error of the structs ([`RawError`]: an unknown, missing or mistyped key) comes as data, its
//! key path and span from the document ([`super::document`]), the tables and types from the
//! schema derived from the serde structs ([`super::schema`]). A syntax error leaves no document:
//! toml_edit's message is shown as it is, with its span's line and column, and the key and table
//! read off the scene's text at that span ([`key_on_line`], [`header_before`]). No message text
//! of serde or toml is read.

use sdcrack_core::scene::KeyPath;

use super::document::{Fault, RawError};
use super::position::{line_column, table_name, table_position};
use super::schema::Schema;
use crate::did_you_mean::suggest;
use crate::one_line::escape_controls;

/// One-line message for the syntax error `e` of the scene `text` (the document does not parse).
pub(super) fn syntax_message(e: &toml_edit::TomlError, text: &str) -> String {
    // toml puts a detail on a second line ("invalid string\nexpected `\"`"): join with ": ".
    let msg = e
        .message()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(": ");
    let msg = escape_controls(&msg);
    let Some(start) = e.span().map(|s| s.start) else {
        return msg;
    };
    let at = at_words(text, start);
    match key_on_line(text, start) {
        Some(key) => {
            let table = header_before(text, start);
            if table.is_empty() || key.contains('.') {
                format!("{key}: {msg} (at {at})")
            } else {
                format!("{table}.{key}: {msg} (at {at})")
            }
        }
        None => {
            let (line, _) = line_column(text, start);
            let line_text = text.lines().nth(line - 1).unwrap_or("").trim_start();
            match header_before(text, start) {
                // An error in a header itself, or before any header: the line says it all; a key
                // set twice: toml's message names its table.
                t if t.is_empty()
                    || line_text.starts_with('[')
                    || redefines_key(text, start, &t) =>
                {
                    format!("{msg} (at {at})")
                }
                t => format!("{msg} in [{t}] (at {at})"),
            }
        }
    }
}

/// One-line message for the error `e` of reading the scene `text`'s document into its structs.
pub(super) fn raw_message(e: &RawError, text: &str) -> String {
    let schema = super::schema::schema();
    let start = e.span.as_ref().map(|s| s.start);
    match &e.fault {
        Fault::UnknownKey(key) => unknown_key(&schema, &escape_controls(key), &e.path, start, text),
        Fault::MissingKey(key) => missing_key(&schema, key, &e.path, text),
        Fault::WrongType { found, message } => match start {
            Some(start) => wrong_type(&schema, &e.path, found, message, &at_words(text, start)),
            None => escape_controls(message),
        },
        Fault::Other(message) => {
            let message = escape_controls(message);
            let shown = e.path.to_last_key();
            match start {
                None => message,
                Some(s) if shown.is_root() => format!("{message} (at {})", at_words(text, s)),
                Some(s) => format!("{shown}: {message} (at {})", at_words(text, s)),
            }
        }
    }
}

/// `line L, column C` of byte `offset`.
fn at_words(text: &str, offset: usize) -> String {
    let (line, column) = line_column(text, offset);
    format!("line {line}, column {column}")
}

/// `unknown key `k` in [t] at line L, column C; did you mean …? (allowed: …)`, for the key
/// `key` at `path` (whose parent is its table).
fn unknown_key(
    schema: &Schema,
    key: &str,
    path: &KeyPath,
    start: Option<usize>,
    text: &str,
) -> String {
    let table = path.parent().schema_path();
    let known = schema
        .table(&table)
        .map(|t| t.key_names())
        .unwrap_or_default();
    let hint = if let Some(s) = suggest(key, &known) {
        format!("; did you mean `{s}`?")
    } else if let Some(t) = schema.table_of(key) {
        format!("; `{key}` belongs {}", table_name(&t.table))
    } else {
        String::new()
    };
    let allowed = if known.is_empty() {
        String::new()
    } else {
        format!(" (allowed: {})", known.join(", "))
    };
    let location = start.map_or(String::new(), |s| format!(" at {}", at_words(text, s)));
    format!(
        "unknown key `{key}` {}{location}{hint}{allowed}",
        table_name(&table)
    )
}

/// `missing table [t]`, or `missing key `k` in [t]` (with where the table is) for the key `key`
/// that the table at `table` lacks.
fn missing_key(schema: &Schema, key: &str, table: &KeyPath, text: &str) -> String {
    let full = table.clone().key(key);
    if schema.table(&full.schema_path()).is_some() {
        return format!("missing table [{full}]");
    }
    if table.is_root() {
        return format!("missing key `{key}` at the top level");
    }
    format!(
        "missing key `{key}` in [{table}]{}",
        table_position(text, table)
    )
}

/// A value of the wrong type at `path`: `key must be WORDS, not FOUND (at …)`, the key being
/// the path up to its last key (an element of a list of values is its list's); serde's
/// `message` after the key when the schema has no words for it.
fn wrong_type(schema: &Schema, path: &KeyPath, found: &str, message: &str, at: &str) -> String {
    let shown = path.to_last_key();
    let table = shown.parent().schema_path();
    let key = shown.last_key().unwrap_or("");
    match schema.key(&table, key) {
        Some(k) => format!("{shown} must be {}, not {found} (at {at})", k.words),
        None => format!("{shown}: {} (at {at})", escape_controls(message)),
    }
}

/// For a syntax error at byte `offset`: whether it is at the key that starts its line and the
/// table `table` (the header in force) already has that key in the lines before, i.e. the key
/// is set twice. Read off the document of those lines, which parse (the error is the first).
fn redefines_key(text: &str, offset: usize, table: &str) -> bool {
    let offset = boundary(text, offset);
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let key: String = text[offset..]
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-'))
        .collect();
    // a key set twice is the first thing on its line
    if !text[line_start..offset].trim().is_empty() {
        return false;
    }
    let Ok(before) = toml_edit::ImDocument::parse(&text[..line_start]) else {
        return false;
    };
    let mut at: &dyn toml_edit::TableLike = before.as_table();
    for name in table.split('.').map(str::trim) {
        at = match at.get(name) {
            // `[[t]]`: the last table of the array, the one being written
            Some(toml_edit::Item::ArrayOfTables(a)) => match a.iter().last() {
                Some(t) => t,
                None => return false,
            },
            Some(toml_edit::Item::Table(t)) => t,
            Some(toml_edit::Item::Value(toml_edit::Value::InlineTable(t))) => t,
            _ => return false,
        };
    }
    !key.is_empty() && at.contains_key(&key)
}

/// Byte `offset` snapped down to a character boundary of `text`.
fn boundary(text: &str, offset: usize) -> usize {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    offset
}

/// For a syntax error: the `[table]` header in force at byte `offset` (`""` before the first
/// header); the line holding `offset` counts.
pub(super) fn header_before(text: &str, offset: usize) -> String {
    let offset = boundary(text, offset);
    let end = text[offset..].find('\n').map_or(text.len(), |i| offset + i);
    text[..end]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| {
            l.trim_start_matches('[')
                .split(']')
                .next()
                .unwrap_or("")
                .trim()
                .to_string()
        })
        .unwrap_or_default()
}

/// For a syntax error: the key whose value starts at byte `offset`, when `offset` follows
/// `key =` on its line (also inside an inline table).
pub(super) fn key_on_line(text: &str, offset: usize) -> Option<String> {
    let offset = boundary(text, offset);
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let before = &text[line_start..offset];
    let eq = before.rfind('=')?;
    let key = before[..eq]
        .rsplit(['{', ','])
        .next()
        .unwrap_or("")
        .trim()
        .trim_matches(['"', '\'']);
    let simple = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.');
    simple.then(|| key.to_string())
}
