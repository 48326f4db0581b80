//! Records the git commit the binary is built from, and whether its sources differ from it, as
//! the compile-time variables `SDCRACK_GIT_COMMIT` (40 hex digits, empty outside a git checkout)
//! and `SDCRACK_GIT_DIRTY` (`true`, `false`, or empty outside a git checkout). "Dirty" means a
//! tracked or untracked file under `src/`, `crates/` (the workspace's sdcrack-core and sdcrack-io),
//! `Cargo.toml`, `Cargo.lock` or `build.rs` differs from the commit: the files the binary is
//! compiled from, not the docs or scripts beside them.

use std::process::Command;

/// Paths the binary is compiled from (relative to the workspace root, this package's folder).
const SOURCES: [&str; 5] = ["src", "crates", "Cargo.toml", "Cargo.lock", "build.rs"];

/// Runs git without its optional locks: a plain `git status` refreshes the index and rewrites
/// `.git/index` (a watched path below) when the files' stat data is racy, as right after a clone,
/// so the second build of a fresh clone recompiled the crate (74 s).
fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .arg("--no-optional-locks")
        .args(args)
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    for path in SOURCES {
        println!("cargo:rerun-if-changed={path}");
    }
    let commit = git(&["rev-parse", "--verify", "HEAD"]);
    let dirty = commit.as_ref().and_then(|_| {
        let mut args = vec!["status", "--porcelain", "--untracked-files=all", "--"];
        args.extend(SOURCES);
        git(&args).map(|s| !s.is_empty())
    });
    if commit.is_some() {
        // A commit, a checkout or a staged change moves these files. Only those that exist are
        // watched: cargo reruns a build script whose watched path is missing on every build (a
        // checkout without .git/packed-refs rebuilt the crate each time, ~40 s).
        let mut watched: Vec<String> = ["HEAD", "index", "packed-refs"]
            .iter()
            .filter_map(|name| git(&["rev-parse", "--git-path", name]))
            .collect();
        if let Some(r) = git(&["symbolic-ref", "-q", "HEAD"]) {
            watched.extend(git(&["rev-parse", "--git-path", &r]));
        }
        for p in watched.iter().filter(|p| std::path::Path::new(p).exists()) {
            println!("cargo:rerun-if-changed={p}");
        }
    }
    println!(
        "cargo:rustc-env=SDCRACK_GIT_COMMIT={}",
        commit.unwrap_or_default()
    );
    println!(
        "cargo:rustc-env=SDCRACK_GIT_DIRTY={}",
        dirty.map_or("", |d| if d { "true" } else { "false" })
    );
}
