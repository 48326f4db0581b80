//! Files and folders written whole: under a temporary name beside the final one, then renamed.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, flushed, renamed.
pub fn atomic_write(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_then_rename(path, &beside(path, "tmp"), std::convert::identity, |tmp| {
        let mut f = fs::File::create(tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })
}

/// `.NAME.KIND-PID` in the folder of `path` (named `NAME`): where `path` is written before it
/// is renamed into place.
pub fn beside(path: &Path, kind: &str) -> PathBuf {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    dir.join(format!(".{name}.{kind}-{}", std::process::id()))
}

/// Write-then-rename, the one way sdcrack replaces a file or a folder: `write` makes `tmp` (a
/// file or a folder in the same folder as `path`), which is then renamed to `path`, so that a
/// reader sees the entry whole or not at all. On any error `tmp` is removed (`rename_error`
/// turns the rename's error into the caller's) and `path` is left as it was.
pub fn write_then_rename<E>(
    path: &Path,
    tmp: &Path,
    rename_error: impl FnOnce(std::io::Error) -> E,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let result = write(tmp).and_then(|()| fs::rename(tmp, path).map_err(rename_error));
    if result.is_err() {
        let _ = if tmp.is_dir() {
            fs::remove_dir_all(tmp)
        } else {
            fs::remove_file(tmp)
        };
    }
    result
}
