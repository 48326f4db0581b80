//! Where things are in a scene's text: line and column of a byte offset, of a key path
//! (`data.f`, `geometry.cracks[1]`, `verification.expected_failure[0].u_space`), and the key path
//! at a byte offset. Positions come from the spans toml_edit's parser keeps for every key, value
//! and table of the document; lines and columns are 1-based, columns counted in characters.

use toml_edit::{ImDocument, Item, TableLike, Value};

use crate::one_line::escape_controls;

/// One step of a key path: a name and, into an array, an index (`expected_failure[1]`).
pub(super) type Step = (String, Option<usize>);

/// 1-based line and column (in characters) of byte `offset` of `text`.
pub(super) fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

/// The steps of a key path.
pub(super) fn key_steps(path: &str) -> Vec<Step> {
    path.split('.')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| match s.split_once('[') {
            Some((name, rest)) => (
                name.to_string(),
                rest.trim_end_matches(']').parse::<usize>().ok(),
            ),
            None => (s.to_string(), None),
        })
        .collect()
}

/// `steps` written back as a path, `geometry.cracks[1].segment`.
pub(super) fn path_text(steps: &[Step]) -> String {
    steps
        .iter()
        .map(|(name, index)| match index {
            Some(i) => format!("{name}[{i}]"),
            None => name.clone(),
        })
        .collect::<Vec<_>>()
        .join(".")
}

/// `steps` without indices, the path of a schema table or key (`verification.expected_rate`).
pub(super) fn schema_path(steps: &[Step]) -> String {
    steps
        .iter()
        .map(|(name, _)| name.as_str())
        .collect::<Vec<_>>()
        .join(".")
}

/// 1-based line and column of the key `path` in the TOML `text`: the key that sets it (for an
/// index into an inline array, the array's key), or the `[table]` / `[[table]]` header when the
/// path is a table with a header. None when the text is not TOML or does not write the path.
pub(super) fn key_position(text: &str, path: &str) -> Option<(usize, usize)> {
    let doc = ImDocument::parse(text).ok()?;
    let steps = key_steps(path);
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

fn offset(text: &str, at: usize) -> Option<(usize, usize)> {
    Some(line_column(text, at))
}

/// The key path at byte `offset` of the TOML `text`: the deepest key whose name or value holds
/// it (into arrays of tables and inline tables of arrays, with their index). None when the text
/// is not TOML or nothing is there.
pub(super) fn path_at(text: &str, offset: usize) -> Option<Vec<Step>> {
    let doc = ImDocument::parse(text).ok()?;
    let mut path = Vec::new();
    descend(doc.as_table(), offset, &mut path).then_some(path)
}

fn holds(span: Option<std::ops::Range<usize>>, offset: usize) -> bool {
    span.is_some_and(|s| s.contains(&offset))
}

/// Appends to `path` the steps of `table` that lead to `offset`; whether one does.
fn descend(table: &dyn TableLike, offset: usize, path: &mut Vec<Step>) -> bool {
    for (name, _) in table.iter() {
        let Some((key, item)) = table.get_key_value(name) else {
            continue;
        };
        path.push((name.to_string(), None));
        if holds(key.span(), offset) || within(item, offset, path) {
            return true;
        }
        path.pop();
    }
    false
}

/// Whether `item` (whose step ends `path`) holds `offset`; extends `path` inside it.
fn within(item: &Item, offset: usize, path: &mut Vec<Step>) -> bool {
    match item {
        Item::Table(t) => descend(t, offset, path) || holds(t.span(), offset),
        Item::ArrayOfTables(a) => a.iter().enumerate().any(|(i, t)| {
            holds(t.span(), offset) && {
                if let Some(last) = path.last_mut() {
                    last.1 = Some(i);
                }
                descend(t, offset, path);
                true
            }
        }),
        Item::Value(Value::InlineTable(t)) => descend(t, offset, path) || holds(t.span(), offset),
        Item::Value(Value::Array(a)) => {
            if !holds(a.span(), offset) {
                return false;
            }
            for (i, v) in a.iter().enumerate() {
                if let (Value::InlineTable(t), true) = (v, holds(v.span(), offset)) {
                    if let Some(last) = path.last_mut() {
                        last.1 = Some(i);
                    }
                    descend(t, offset, path);
                    break;
                }
            }
            true
        }
        Item::Value(v) => holds(v.span(), offset),
        Item::None => false,
    }
}

/// ` (the table is at line L, column C)` for a table written in `text` (inline tables too),
/// where a missing key belongs; empty when it is not written.
pub(super) fn table_position(text: &str, table: &str) -> String {
    key_position(text, table)
        .map(|(l, c)| format!(" (the table is at line {l}, column {c})"))
        .unwrap_or_default()
}

/// `message`, which names a scene key first (`discretization.levels: …`, `data.f = …`,
/// `geometry.cracks[1]: …`, `[geometry] must …`) as the scene's messages do, with the key's
/// line and column in the TOML `text` appended as ` (at line L, column C)`; for `missing key
/// `k` in [t]`, where the table is. Unchanged when the text does not write that key.
pub(super) fn locate_message(message: String, text: &str) -> String {
    if let Some(rest) = message.strip_prefix("missing key `") {
        // a key that is not there: where its table is
        let table = rest
            .split_once(" in [")
            .and_then(|(_, t)| t.split_once(']'));
        return match table {
            Some((t, _)) => format!("{message}{}", table_position(text, t)),
            None => message,
        };
    }
    let key: String = match message.strip_prefix('[') {
        // `[geometry] must be left out …`: a table
        Some(rest) => rest.split(']').next().unwrap_or("").to_string(),
        None => message
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '[' | ']'))
            .collect(),
    };
    match key_position(text, key.trim_end_matches('.')) {
        Some((l, c)) => format!("{message} (at line {l}, column {c})"),
        None => message,
    }
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
