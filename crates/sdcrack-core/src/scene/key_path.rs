//! Where a value is in a scene: the path of table keys and array indices that leads to it
//! (`geometry.cracks[1].segment`, `verification.expected_rate[0].rate`). Errors about a scene
//! carry their key as a [`KeyPath`], so that the scene's reader (sdcrack-io) can say where it is
//! written in the file (line and column) without reading it back out of a message.

use std::fmt;

/// One step of a [`KeyPath`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PathSegment {
    /// A key of a table.
    Key(String),
    /// An element of an array (of tables or of values), 0-based.
    Index(usize),
}

/// A path of table keys and array indices from the top of a scene; written
/// `geometry.cracks[1].segment`. The empty path is the top level.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct KeyPath(Vec<PathSegment>);

impl KeyPath {
    /// The top level.
    pub fn root() -> KeyPath {
        KeyPath(Vec::new())
    }

    /// The path of the keys `dotted` names (`"discretization.grading.beta"`), one key per
    /// `.`-separated part: for the names the program writes itself (no indices, no quotes).
    pub fn keys(dotted: &str) -> KeyPath {
        KeyPath(
            dotted
                .split('.')
                .filter(|k| !k.is_empty())
                .map(|k| PathSegment::Key(k.to_string()))
                .collect(),
        )
    }

    /// This path, then the key `key`.
    pub fn key(mut self, key: &str) -> KeyPath {
        self.0.push(PathSegment::Key(key.to_string()));
        self
    }

    /// This path, then element `index` of the array it leads to.
    pub fn index(mut self, index: usize) -> KeyPath {
        self.0.push(PathSegment::Index(index));
        self
    }

    /// The steps, from the top.
    pub fn segments(&self) -> &[PathSegment] {
        &self.0
    }

    /// True for the top level.
    pub fn is_root(&self) -> bool {
        self.0.is_empty()
    }

    /// The last key of the path (`segment` of `geometry.cracks[1].segment`), if any.
    pub fn last_key(&self) -> Option<&str> {
        self.0.iter().rev().find_map(|s| match s {
            PathSegment::Key(k) => Some(k.as_str()),
            PathSegment::Index(_) => None,
        })
    }

    /// The path up to and with its last key: the indices into a key's array of values are
    /// dropped (`discretization.levels[2]` → `discretization.levels`), the key is what a message
    /// names.
    pub fn to_last_key(&self) -> KeyPath {
        let end = (self.0.iter())
            .rposition(|s| matches!(s, PathSegment::Key(_)))
            .map_or(0, |i| i + 1);
        KeyPath(self.0[..end].to_vec())
    }

    /// The path without its last key (and what follows it): the table the key is in.
    pub fn parent(&self) -> KeyPath {
        let end = (self.0.iter())
            .rposition(|s| matches!(s, PathSegment::Key(_)))
            .unwrap_or(0);
        KeyPath(self.0[..end].to_vec())
    }

    /// The keys without the indices, dotted: the path of a table or key of the schema
    /// (`verification.expected_rate` for `verification.expected_rate[1]`).
    pub fn schema_path(&self) -> String {
        (self.0.iter())
            .filter_map(|s| match s {
                PathSegment::Key(k) => Some(k.as_str()),
                PathSegment::Index(_) => None,
            })
            .collect::<Vec<_>>()
            .join(".")
    }
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, s) in self.0.iter().enumerate() {
            match s {
                PathSegment::Key(k) if i == 0 => write!(f, "{k}")?,
                PathSegment::Key(k) => write!(f, ".{k}")?,
                PathSegment::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::KeyPath;

    #[test]
    fn a_path_is_written_with_dots_and_indices() {
        let p = KeyPath::keys("geometry.cracks")
            .index(1)
            .key("segment")
            .index(0);
        assert_eq!(p.to_string(), "geometry.cracks[1].segment[0]");
        assert_eq!(p.to_last_key().to_string(), "geometry.cracks[1].segment");
        assert_eq!(p.parent().to_string(), "geometry.cracks[1]");
        assert_eq!(p.schema_path(), "geometry.cracks.segment");
        assert_eq!(p.last_key(), Some("segment"));
        assert_eq!(KeyPath::root().to_string(), "");
        assert!(KeyPath::keys("").is_root());
        assert_eq!(KeyPath::keys("name").parent(), KeyPath::root());
    }
}
