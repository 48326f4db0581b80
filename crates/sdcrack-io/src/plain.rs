//! Plain words for operating-system errors: one home for what a user reads in a one-line message
//! about a file or a folder (a scene file, a mesh file, a results folder), without the Rust
//! standard library's "(os error N)" suffix.

/// `e` in plain words: "permission denied", "there is no such file or folder", …; other errors
/// in the system's own words, without their "(os error N)" code.
pub fn io_reason(e: &std::io::Error) -> String {
    match e.raw_os_error() {
        Some(1 | 13) => "permission denied".into(),
        Some(2) => "there is no such file or folder".into(),
        Some(17) => "a file of that name exists".into(),
        Some(20) => "a part of the path is a file, not a folder".into(),
        Some(21) => "it is a folder, not a file".into(),
        Some(28) => "no space left on the device".into(),
        Some(30) => "the file system is read-only".into(),
        _ => {
            let text = e.to_string();
            match text.find(" (os error") {
                Some(i) => text[..i].to_string(),
                None => text,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn os_errors_in_plain_words() {
        let missing = std::fs::File::open("/nonexistent/sdcrack/scene.toml").unwrap_err();
        assert_eq!(io_reason(&missing), "there is no such file or folder");
        let code = |n| io_reason(&std::io::Error::from_raw_os_error(n));
        assert_eq!(code(13), "permission denied");
        assert_eq!(code(30), "the file system is read-only");
        // any other code: the system's words, never the "(os error N)" suffix
        let other = code(5);
        assert!(!other.contains("os error") && !other.is_empty(), "{other}");
        let custom = std::io::Error::other("made up");
        assert_eq!(io_reason(&custom), "made up");
    }
}
