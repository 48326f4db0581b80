//! One-line messages for the errors of toml's deserializer: what is wrong, the key or table,
//! line and column (from the error's own span), and for an unknown key the closest key of its
//! table ("did you mean") and the keys allowed there.
//!
//! Where the document parses (an unknown, missing or mistyped key), the key path comes from the
//! document's spans ([`super::position::path_at`]) and the tables and types from the schema
//! derived from the serde structs ([`super::schema`]). A syntax error leaves no document: its
//! key and table are read off the error's line ([`key_on_line`], [`header_before`]).

use super::position::{line_column, path_at, path_text, schema_path, table_name, table_position};
use super::schema::Schema;
use crate::did_you_mean::suggest;
use crate::one_line::escape_controls;

/// One-line message for a TOML/serde error `e` of the scene `text`.
pub(super) fn toml_message(e: &toml::de::Error, text: &str) -> String {
    // toml puts a detail on a second line ("invalid string\nexpected `\"`"): join with ": ".
    let msg = e
        .message()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(": ");
    let msg = escape_controls(&msg);
    let schema = super::schema::schema();
    let start = e.span().map(|s| s.start);
    if let Some(rest) = msg.strip_prefix("unknown field `") {
        return unknown_key(&schema, rest, start, text);
    }
    if let Some(rest) = msg.strip_prefix("missing field `") {
        let key = rest.split('`').next().unwrap_or("");
        return missing_key(&schema, key, start, text);
    }
    let Some(start) = start else {
        return msg;
    };
    let at = at_words(text, start);
    if let Some(steps) = path_at(text, start) {
        return value_message(&schema, &steps, &msg, &at);
    }
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
                // An error in a header itself, or before any header: the line says it all.
                t if t.is_empty() || line_text.starts_with('[') || msg.contains("table `") => {
                    format!("{msg} (at {at})")
                }
                t => format!("{msg} in [{t}] (at {at})"),
            }
        }
    }
}

/// `line L, column C` of byte `offset`.
fn at_words(text: &str, offset: usize) -> String {
    let (line, column) = line_column(text, offset);
    format!("line {line}, column {column}")
}

/// `unknown key `k` in [t] at line L, column C; did you mean …? (allowed: …)`. `rest` follows
/// serde's "unknown field `": the key, then the fields the struct expected.
fn unknown_key(schema: &Schema, rest: &str, start: Option<usize>, text: &str) -> String {
    let key = rest.split('`').next().unwrap_or("");
    let table = start
        .and_then(|s| path_at(text, s))
        .map(|mut steps| {
            steps.pop();
            schema_path(&steps)
        })
        .filter(|t| schema.table(t).is_some())
        .unwrap_or_else(|| table_expecting(schema, rest));
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

/// The table whose keys are the fields serde expected (`…, expected one of `a`, `b``), where the
/// document does not say: the first such table of the schema, or the top level.
fn table_expecting(schema: &Schema, rest: &str) -> String {
    let expected: Vec<&str> = rest
        .split_once("expected")
        .map(|(_, list)| list.split('`').skip(1).step_by(2).collect())
        .unwrap_or_default();
    schema
        .tables
        .iter()
        .find(|t| t.key_names() == expected)
        .map(|t| t.table.clone())
        .unwrap_or_default()
}

/// `missing table [t]` or `missing key `k` in [t]` (with where the table is).
fn missing_key(schema: &Schema, key: &str, start: Option<usize>, text: &str) -> String {
    if schema.table(key).is_some() {
        return format!("missing table [{key}]");
    }
    let owners: Vec<&str> = (schema.tables.iter())
        .filter(|t| t.keys.iter().any(|k| k.key == key))
        .map(|t| t.table.as_str())
        .collect();
    // The error's span is the table that lacks the key.
    let spanned = start
        .and_then(|s| path_at(text, s))
        .map(|steps| (schema_path(&steps), path_text(&steps)))
        .filter(|(t, _)| owners.contains(&t.as_str()));
    match (owners.as_slice(), spanned) {
        ([""], _) => format!("missing key `{key}` at the top level"),
        (_, Some((_, shown))) => {
            format!(
                "missing key `{key}` in [{shown}]{}",
                table_position(text, &shown)
            )
        }
        ([t, ..], None) => format!("missing key `{key}` in [{t}]{}", table_position(text, t)),
        ([], None) => format!("missing key `{key}`"),
    }
}

/// A wrong value of the key at `steps`: `path must be WORDS, not GOT (at …)`, or the error's own
/// words after the path.
fn value_message(schema: &Schema, steps: &[super::position::Step], msg: &str, at: &str) -> String {
    let shown = path_text(steps);
    let table = schema_path(&steps[..steps.len().saturating_sub(1)]);
    let key = steps.last().map_or("", |(name, _)| name.as_str());
    match (schema.key(&table, key), got(msg)) {
        (Some(k), Some(got)) => format!("{shown} must be {}, not {got} (at {at})", k.words),
        _ => format!("{shown}: {msg} (at {at})"),
    }
}

/// What was found, in words, from serde's "invalid type: string \"a\", expected i64".
fn got(msg: &str) -> Option<String> {
    let found = msg
        .strip_prefix("invalid type: ")?
        .split(", expected")
        .next()?;
    let (kind, value) = found.split_once(' ').unwrap_or((found, ""));
    let value = value.trim_matches('`');
    Some(match kind {
        "string" => format!("the string {value}"),
        "integer" => format!("the integer {value}"),
        "floating" => format!("the number {}", value.trim_start_matches("point `")),
        "boolean" => format!("the boolean {value}"),
        "sequence" => "a list".to_string(),
        "map" => "a table".to_string(),
        _ => found.to_string(),
    })
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
