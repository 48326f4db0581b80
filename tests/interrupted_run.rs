//! A run killed with SIGKILL (no clean-up possible) while it solves, and again while it writes its
//! field files: earlier results in the same `--out` stay byte for byte as they were, nothing
//! appears under the killed run's final name (only its staging folder `OUT/.NAME.partial-PID`
//! remains, see crates/sdcrack-io/src/output.rs), and a later run to the same final name
//! succeeds without touching that leftover.

mod common;

use std::collections::BTreeMap;
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::{listing, sdcrack_run, stderr, summary};

/// Every file and folder under `dir` (relative path → bytes; folders end in `/` with no bytes).
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(root).unwrap().to_path_buf();
            if p.is_dir() {
                out.insert(rel.join(""), Vec::new());
                walk(root, &p, out);
            } else {
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

fn spawn(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_sdcrack"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("binary starts")
}

/// Polls every 5 ms until `ready()` or the child exits; panics after 120 s.
fn wait_for(child: &mut Child, what: &str, ready: impl Fn() -> bool) {
    let start = Instant::now();
    while !ready() {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the run ended ({status}) before {what}");
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no {what} after 120 s"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// SIGKILLs `child`, which must still be running, and reaps it.
fn kill(mut child: Child, when: &str) {
    assert!(
        child.try_wait().unwrap().is_none(),
        "the run finished before it could be killed {when}; it needs a bigger case"
    );
    child.kill().unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.signal(), Some(9), "killed {when}: {status}");
}

#[test]
fn killed_runs_leave_earlier_results_alone_and_a_rerun_succeeds() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out_s = out.to_str().unwrap();
    // Complete earlier results in the same --out.
    let earlier_scene = dir.path().join("earlier.toml");
    // earlier, complete results: the small scene with fields, under another name
    let earlier_text = common::SMALL_SCENE.replace("name = \"small\"", "name = \"earlier\"");
    std::fs::write(&earlier_scene, earlier_text).unwrap();
    let o = sdcrack_run(&earlier_scene, &out, &["--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let earlier = out.join("earlier");
    let before = snapshot(&earlier);
    assert!(
        before.contains_key(Path::new("fields.h5"))
            && before.contains_key(Path::new("summary.json")),
        "{:?}",
        before.keys()
    );

    // The big run: the repository's `mixed` scene without its reference solvers (which would be
    // orphaned subprocesses), level 5 only: 36 cases of 66 049 vertices and their fields (~70 MB),
    // a few seconds of solving and ~0.5 s of writing, long enough to be caught in either phase.
    let text = std::fs::read_to_string(common::scene_path("mixed")).unwrap();
    let (head, _) = text
        .split_once("references =")
        .expect("mixed lists references");
    let big = dir.path().join("big.toml");
    std::fs::write(&big, format!("{head}references = []\n")).unwrap();
    let args = [
        "run",
        big.to_str().unwrap(),
        "--level",
        "5",
        "--out",
        out_s,
        "--quiet",
    ];
    let final_path = out.join("mixed");

    // 1. Killed while solving: as soon as its staging folder exists.
    let mut child = spawn(&args);
    let staging1 = out.join(format!(".mixed.partial-{}", child.id()));
    wait_for(&mut child, "the staging folder", || staging1.is_dir());
    std::thread::sleep(Duration::from_millis(200));
    kill(child, "while solving");
    assert!(!final_path.exists(), "no folder under the final name");
    assert_eq!(snapshot(&earlier), before, "earlier results unchanged");
    assert_eq!(
        listing(&out),
        vec![
            staging1.file_name().unwrap().to_string_lossy().into_owned(),
            "earlier".into()
        ]
    );

    // 2. Killed while writing its field files: as soon as the HDF5 file being written (its
    // temporary `.fields.h5.tmp-*`, renamed to fields.h5 once complete) appears in the staging folder.
    let mut child = spawn(&args);
    let staging2 = out.join(format!(".mixed.partial-{}", child.id()));
    wait_for(&mut child, "the field file being written", || {
        std::fs::read_dir(&staging2).is_ok_and(|entries| {
            entries.filter_map(Result::ok).any(|e| {
                e.file_name()
                    .to_string_lossy()
                    .starts_with(".fields.h5.tmp-")
            })
        })
    });
    kill(child, "while writing fields");
    assert!(!final_path.exists(), "no folder under the final name");
    assert_eq!(snapshot(&earlier), before, "earlier results unchanged");
    let leftovers = snapshot(&out);

    // 3. A rerun to the same final name succeeds and leaves the leftovers alone.
    let o = sdcrack_run(&big, &out, &["--level", "0", "--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let summary = summary(&final_path);
    assert_eq!(summary["scene"], "mixed");
    // 2 u spaces × 3 multipliers × 2 p masses × 6 δ
    assert_eq!(summary["cases"].as_array().unwrap().len(), 2 * 3 * 2 * 6);
    assert!(final_path.join("fields.h5").is_file());
    assert_eq!(snapshot(&earlier), before, "earlier results unchanged");
    let after = snapshot(&out);
    for (path, bytes) in &leftovers {
        assert_eq!(after.get(path), Some(bytes), "leftover {path:?} untouched");
    }
    let mut expected = vec![
        staging1.file_name().unwrap().to_string_lossy().into_owned(),
        staging2.file_name().unwrap().to_string_lossy().into_owned(),
        "earlier".to_string(),
        "mixed".to_string(),
    ];
    expected.sort();
    assert_eq!(
        listing(&out),
        expected,
        "only the two staging leftovers besides the results"
    );
}
