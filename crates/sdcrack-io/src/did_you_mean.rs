//! "Did you mean": the known word closest to a mistyped one, for messages about scene keys and
//! values. Closeness is the Levenshtein distance in characters (insertions, deletions and
//! substitutions each count 1; a transposition counts 2), from the `strsim` crate.

/// The largest edit distance at which a known word is suggested.
const MAX_DISTANCE: usize = 2;

/// The closest word of `known` to `word` within edit distance 2, if any; the first of `known`
/// among equally close ones.
pub fn suggest<'a>(word: &str, known: &[&'a str]) -> Option<&'a str> {
    known
        .iter()
        .map(|k| (strsim::levenshtein(word, k), *k))
        .filter(|(d, _)| *d <= MAX_DISTANCE)
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

#[cfg(test)]
mod tests {
    use super::suggest;

    /// Plain Levenshtein in characters: a transposition costs 2, a multi-byte character 1.
    #[test]
    fn suggestions_are_within_two_edits_first_closest_wins() {
        assert_eq!(suggest("levles", &["levels", "deltas"]), Some("levels"));
        assert_eq!(suggest("lamda", &["u", "p", "lambda"]), Some("lambda"));
        assert_eq!(
            strsim::levenshtein("ab", "ba"),
            2,
            "a transposition is 2 edits"
        );
        assert_eq!(suggest("nmae", &["name"]), Some("name"));
        assert_eq!(suggest("δx", &["δy", "zz"]), Some("δy"));
        assert_eq!(suggest("colour", &["fields", "references"]), None);
        assert_eq!(suggest("M2", &["M0", "M1", "M1star"]), Some("M0"));
    }
}
