//! `validate-design snapshot --suite`: a user's own golden suite, end to end through the binary.

mod common;

use assert_cmd::Command;
use common::repo;
use std::path::Path;

fn snapshot(dir: &Path, extra: &[&str]) -> (Option<i32>, String) {
    let output = Command::cargo_bin("validate-design")
        .expect("binary built")
        .current_dir(dir)
        .args(["snapshot", "--suite", "suite.json"])
        .args(extra)
        .output()
        .expect("runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    (output.status.code(), text)
}

fn write_suite(dir: &Path, seed: u64) {
    let suite = format!(
        r#"{{"snapshots": "golden", "designs": ["ur5e.json", {{"path": "paper-real-world.json", "name": "paper"}}],
            "scenarios": ["task-00.json"], "options": {{"reach_only": true, "seed": {seed}}}}}"#
    );
    std::fs::write(dir.join("suite.json"), suite).expect("write suite");
}

/// A folder with the suite of [`write_suite`] (seed 0) and the files it names.
fn suite_folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    for (from, to) in [
        ("designs/ur5e.json", "ur5e.json"),
        ("designs/paper-real-world.json", "paper-real-world.json"),
        ("scenarios/cluttered/task-00.json", "task-00.json"),
    ] {
        std::fs::copy(repo().join(from), dir.path().join(to)).expect("copy");
    }
    write_suite(dir.path(), 0);
    dir
}

#[test]
fn a_suite_records_compares_and_reports_differences_and_orphans() {
    let dir = suite_folder();
    let golden = dir.path().join("golden");

    // No snapshots yet: both new, written as insta's pending files, exit 1.
    let (code, text) = snapshot(dir.path(), &[]);
    assert_eq!(code, Some(1), "{text}");
    assert!(
        text.contains("NEW      ur5e__task-00") && text.contains("NEW      paper__task-00"),
        "{text}"
    );
    assert!(golden.join("ur5e__task-00.snap.new").is_file());
    assert!(!golden.join("ur5e__task-00.snap").exists());

    // Accepted, then the same run matches byte for byte.
    let (code, text) = snapshot(dir.path(), &["--accept"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(!golden.join("ur5e__task-00.snap.new").exists());
    let recorded = std::fs::read_to_string(golden.join("ur5e__task-00.snap")).expect("snapshot written");
    assert!(
        recorded.starts_with("---\nsource: validate-design snapshot --suite suite.json\ndescription: \"design ur5e"),
        "{recorded}"
    );
    assert!(recorded.contains("---\nsummary:\n  verdict: "), "{recorded}");
    let (code, text) = snapshot(dir.path(), &[]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("2 snapshots: 2 same"), "{text}");

    // Another seed changes the reports: a unified diff, exit 1, the recorded snapshot untouched.
    write_suite(dir.path(), 3);
    let (code, text) = snapshot(dir.path(), &[]);
    assert_eq!(code, Some(1), "{text}");
    assert!(
        text.contains("CHANGED") && text.contains("-    seed: 0") && text.contains("+    seed: 3"),
        "{text}"
    );
    assert_eq!(std::fs::read_to_string(golden.join("ur5e__task-00.snap")).expect("read"), recorded);
    // --summary: the status lines with the verdict old -> new (or unchanged), no diff.
    let (code, summary) = snapshot(dir.path(), &["--summary"]);
    assert_eq!(code, Some(1), "{summary}");
    let changed: Vec<&str> = summary.lines().filter(|l| l.starts_with("CHANGED")).collect();
    assert!(!changed.is_empty(), "{summary}");
    assert!(
        changed.iter().all(|l| l.contains(" -> ") || l.contains("(verdict unchanged)")),
        "{summary}"
    );
    assert!(!summary.contains("seed: 3"), "{summary}");

    // A snapshot no run writes is an orphan; --accept removes it.
    write_suite(dir.path(), 0);
    std::fs::write(golden.join("gone__task-00.snap"), "---\nsource: x\n---\nsummary:\n").expect("write");
    let (code, text) = snapshot(dir.path(), &[]);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("ORPHAN") && text.contains("gone__task-00.snap"), "{text}");
    let (code, _) = snapshot(dir.path(), &["--accept"]);
    assert_eq!(code, Some(0));
    assert!(!golden.join("gone__task-00.snap").exists());
}

/// The snapshot folder's files, sorted by name, with their bytes.
fn folder_files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .expect("list")
        .map(|e| {
            let entry = e.expect("entry");
            (
                entry.file_name().to_string_lossy().into_owned(),
                std::fs::read(entry.path()).expect("read"),
            )
        })
        .collect();
    files.sort();
    files
}

#[test]
fn a_crash_at_any_write_step_of_accept_is_repaired_by_accepting_again() {
    let dir = suite_folder();
    let golden = dir.path().join("golden");
    let (code, text) = snapshot(dir.path(), &["--accept"]);
    assert_eq!(code, Some(0), "{text}");
    let accepted = folder_files(&golden);
    assert_eq!(accepted.len(), 2, "two snapshots, no lock file left: {accepted:?}");
    for at in 1.. {
        assert!(at < 50, "still crashing at step {at}");
        std::fs::remove_dir_all(&golden).expect("start over");
        let crashed = Command::cargo_bin("validate-design")
            .expect("binary built")
            .current_dir(dir.path())
            .args(["snapshot", "--suite", "suite.json", "--accept"])
            .env(proving_ground::files::CRASH_AT, at.to_string())
            .output()
            .expect("runs");
        if crashed.status.code() == Some(0) {
            break;
        }
        assert_eq!(crashed.status.code(), Some(137), "{}", String::from_utf8_lossy(&crashed.stderr));
        let (code, text) = snapshot(dir.path(), &["--accept"]);
        assert_eq!(code, Some(0), "after a crash at step {at}: {text}");
        assert_eq!(folder_files(&golden), accepted, "after a crash at step {at}");
    }
}

#[test]
fn a_bad_suite_exits_2_naming_the_field() {
    let dir = tempfile::tempdir().expect("temp dir");
    for (suite, field) in [
        (r#"{"designs": [], "scenarios": ["s.json"]}"#, "designs"),
        (
            r#"{"designs": ["d.json"], "scenarios": ["s.json"], "options": {"engines": ["bullet"]}}"#,
            "options.engines",
        ),
        (
            r#"{"designs": ["d.json"], "scenarios": ["s.json"], "options": {"ik_seeds": 0}}"#,
            "options.ik_seeds",
        ),
        (
            r#"{"designs": ["d.json"], "scenarios": ["s.json"], "extra": 1}"#,
            "unknown field `extra`",
        ),
        (
            r#"{"designs": ["d.json"], "scenarios": ["s.json"], "options": {"srdf": "r.srdf"}}"#,
            "options.srdf",
        ),
        (
            r#"{"designs": ["d.json"], "scenarios": ["s.json"], "options": {"mujoco_checks": 5}}"#,
            "options.mujoco_checks",
        ),
        (
            r#"{"designs": ["d.json"], "scenarios": ["s.json"], "options": {"margin": -1}}"#,
            "options.margin",
        ),
        (
            r#"{"designs": ["d.json"], "scenarios": ["s.json"], "options": {"reach_only": true, "engines": "mujoco"}}"#,
            "options.engines",
        ),
        // Runs that would share one snapshot, refused before any design is read.
        (
            r#"{"designs": ["a/d.json", "b/d.json"], "scenarios": ["s.json"]}"#,
            "designs[0] on scenarios[0] and designs[1] on scenarios[0] would share the snapshot `d__s.snap`",
        ),
        (
            r#"{"designs": ["d.json"], "scenarios": ["s.json", "other/s.json"]}"#,
            "designs[0] on scenarios[0] and designs[0] on scenarios[1] would share the snapshot `d__s.snap`",
        ),
        (
            r#"{"designs": ["e.json", {"path": "d.json", "name": "e"}], "scenarios": ["s.json"]}"#,
            "would share the snapshot `e__s.snap`",
        ),
        (
            r#"{"designs": [{"path": "d.json", "name": "x__y"}, {"path": "d.json", "name": "x"}], "scenarios": ["z.json", "y__z.json"]}"#,
            "would share the snapshot `x__y__z.snap`",
        ),
    ] {
        std::fs::write(dir.path().join("suite.json"), suite).expect("write");
        let (code, text) = snapshot(dir.path(), &[]);
        assert_eq!(code, Some(2), "{suite}: {text}");
        assert!(text.contains("suite.json") && text.contains(field), "{suite}: {text}");
    }
    assert!(!dir.path().join("snapshots").exists(), "refused before anything was written");
}
