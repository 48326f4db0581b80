//! Where things are in a scene's text: line and column of a byte offset and of a key path
//! ([`KeyPath`]: `data.f`, `geometry.cracks[1]`, `verification.expected_failure[0].u_space`).
//! Positions come from the spans toml_edit's parser keeps for every key, value and table of the
//! document; lines and columns are 1-based, columns counted in characters.

use toml_edit::{ImDocument, Item, TableLike, Value};

use sdcrack_core::scene::{KeyPath, PathSegment};

use crate::one_line::escape_controls;

/// A line and a column, 1-based (columns in characters).
pub type Position = (usize, usize);

/// One step of a key path as the document is walked: a key and, into an array, an index
/// (`expected_failure[1]`).
type Step<'a> = (&'a str, Option<usize>);

/// 1-based line and column (in characters) of byte `offset` of `text`.
pub(super) fn line_column(text: &str, offset: usize) -> Position {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

/// The steps of `path`: each key with the index that follows it (one level of array). None for
/// a path the document walk cannot follow (two indices in a row, an index first).
fn steps(path: &KeyPath) -> Option<Vec<Step<'_>>> {
    let mut out: Vec<Step<'_>> = Vec::new();
    for s in path.segments() {
        match s {
            PathSegment::Key(k) => out.push((k.as_str(), None)),
            PathSegment::Index(i) => match out.last_mut() {
                Some((_, index @ None)) => *index = Some(*i),
                _ => return None,
            },
        }
    }
    Some(out)
}

/// 1-based line and column of the key `path` in the TOML `text`: the key that sets it (for an
/// index into an inline array, the array's key), or the `[table]` / `[[table]]` header when the
/// path is a table with a header. None when the text is not TOML or does not write the path.
pub(super) fn key_position(text: &str, path: &KeyPath) -> Option<Position> {
    let doc = ImDocument::parse(text).ok()?;
    let steps = steps(path)?;
    let mut table: &dyn TableLike = doc.as_table();
    for (i, (name, index)) in steps.iter().enumerate() {
        let (key, item) = table.get_key_value(name)?;
        let last = i + 1 == steps.len();
        let key_at = key.span().map(|s| s.start);
        let next: &dyn TableLike = match (item, index) {
            (Item::Table(t), None) if last => {
                let header = !t.is_implicit() && !t.is_dotted();
                return offset(text, if header { t.span()?.start } else { key_at? });
            }
            (Item::ArrayOfTables(a), Some(k)) if last => {
                return offset(text, a.get(*k)?.span()?.start)
            }
            (Item::Value(Value::Array(a)), Some(k)) if last => {
                a.get(*k)?;
                return offset(text, key_at?);
            }
            _ if last => return offset(text, key_at?),
            (Item::Table(t), None) => t,
            (Item::Value(Value::InlineTable(t)), None) => t,
            (Item::ArrayOfTables(a), Some(k)) => a.get(*k)?,
            (Item::Value(Value::Array(a)), Some(k)) => a.get(*k)?.as_inline_table()?,
            _ => return None,
        };
        table = next;
    }
    None
}

fn offset(text: &str, at: usize) -> Option<Position> {
    Some(line_column(text, at))
}

/// ` (the table is at line L, column C)` for a table written in `text` (inline tables too),
/// where a missing key belongs; empty when it is not written.
pub(super) fn table_position(text: &str, table: &KeyPath) -> String {
    key_position(text, table)
        .map(|(l, c)| format!(" (the table is at line {l}, column {c})"))
        .unwrap_or_default()
}

/// `in [table]`, or `at the top level` for `""`.
pub(super) fn table_name(table: &str) -> String {
    if table.is_empty() {
        "at the top level".to_string()
    } else {
        // a header may hold a tab or other control character (`[verification.\tx]`)
        format!("in [{}]", escape_controls(table))
    }
}
