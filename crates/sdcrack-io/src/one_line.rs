//! Text shown on the terminal as one line: every message of sdcrack is one line on stderr, so
//! text that comes from a scene file, a path or an operating-system error has its control
//! characters (newlines, tabs, escape sequences, …) written as escapes before it is shown.

/// `s` with control characters (newlines, tabs, …) written as escapes, so that text from a scene
/// file or a path cannot break a one-line message.
pub fn escape_controls(s: &str) -> String {
    if !s.chars().any(char::is_control) {
        return s.to_string();
    }
    s.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::escape_controls;

    #[test]
    fn control_characters_are_escaped_and_other_text_kept() {
        assert_eq!(escape_controls("a\nb\tc"), "a\\nb\\tc");
        assert_eq!(escape_controls("δ ≥ 0"), "δ ≥ 0");
    }
}
