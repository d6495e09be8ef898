//! The bad-input corpus: every file in tests/fixtures/bad/ named `design-*.json`, `scenario-*.json`,
//! `urdf-*.urdf` or `mjcf-*.xml` is a malformed, hostile or edge-case input that must exit 2 with a
//! message naming the file and the field, element or line (README, exit codes). Each case has a
//! `<case>.expect` beside it: one substring per line that stderr must contain. See
//! tests/fixtures/bad/README.md.

mod common;

use assert_cmd::Command;
use common::repo;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The corpus folder, relative to the repository root (the binary runs there, so messages name
/// files by this relative path).
const CORPUS: &str = "tests/fixtures/bad";
/// Per case: a case that is (wrongly) accepted runs with `--engines none --mujoco-checks 0`, so
/// even then it should finish well within this.
const TIMEOUT: Duration = Duration::from_secs(20);
/// The corpus must not shrink below this.
const MIN_CASES: usize = 60;
/// Role prefixes and the extension each takes.
const ROLES: [(&str, &str); 4] = [("design-", ".json"), ("scenario-", ".json"), ("urdf-", ".urdf"), ("mjcf-", ".xml")];
/// The design the scenario cases run with.
const SCENARIO_DESIGN: &str = "designs/paper-real-world.json";

/// Every regular file directly in the corpus folder, by name, sorted.
fn corpus_files() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(repo().join(CORPUS))
        .expect("tests/fixtures/bad exists")
        .map(|e| e.expect("readable entry"))
        .filter(|e| e.file_type().expect("file type").is_file())
        .map(|e| e.file_name().into_string().expect("UTF-8 file name"))
        .collect();
    names.sort();
    names
}

/// Whether `name` is a case (has a role prefix and that role's extension).
fn is_case(name: &str) -> bool {
    ROLES.iter().any(|(prefix, ext)| name.starts_with(prefix) && name.ends_with(ext))
}

/// The case files, sorted.
fn cases() -> Vec<String> {
    corpus_files().into_iter().filter(|n| is_case(n)).collect()
}

/// The command line arguments (before the common extras) of a case.
fn arguments(case: &str) -> Vec<String> {
    let path = format!("{CORPUS}/{case}");
    if case.starts_with("scenario-") {
        vec![SCENARIO_DESIGN.to_string(), "--scenario".to_string(), path]
    } else {
        vec![path]
    }
}

/// The expected substrings of a case (non-empty lines of its .expect file).
fn expectations(case: &str) -> Vec<String> {
    let file: PathBuf = repo().join(CORPUS).join(format!("{case}.expect"));
    let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    text.lines().filter(|l| !l.trim().is_empty()).map(str::to_string).collect()
}

/// Runs one case; `None` when it behaves, else what went wrong (with the output).
fn check(case: &str) -> Option<String> {
    let expected = expectations(case);
    let mut cmd = Command::cargo_bin("validate-design").expect("binary is built");
    cmd.current_dir(repo())
        .args(arguments(case))
        .args(["--engines", "none", "--mujoco-checks", "0"])
        .timeout(TIMEOUT);
    let start = Instant::now();
    let output = match cmd.output() {
        Ok(output) => output,
        Err(e) => return Some(format!("cannot run: {e}")),
    };
    let elapsed = start.elapsed();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let mut problems = Vec::new();
    if elapsed >= TIMEOUT {
        problems.push(format!("timed out after {} s (killed)", TIMEOUT.as_secs()));
    }
    match output.status.code() {
        Some(2) => {}
        Some(code) => problems.push(format!("exit code {code}, expected 2")),
        None => problems.push(format!("no exit code ({}), expected 2", output.status)),
    }
    if stderr.trim().is_empty() {
        problems.push("stderr is empty".to_string());
    }
    for panic_text in ["panicked", "RUST_BACKTRACE"] {
        if stderr.contains(panic_text) {
            problems.push(format!("stderr contains `{panic_text}`"));
        }
    }
    for line in &expected {
        if !stderr.contains(line.as_str()) {
            problems.push(format!("stderr lacks `{line}`"));
        }
    }
    if problems.is_empty() {
        return None;
    }
    let mut report = problems.join("; ");
    report.push_str(&format!("\n  stderr: {}", excerpt(&stderr)));
    if !stdout.trim().is_empty() {
        report.push_str(&format!("\n  stdout: {}", excerpt(&stdout)));
    }
    Some(report)
}

/// The first 600 characters of `text`, on one line.
fn excerpt(text: &str) -> String {
    let flat: String = text.trim().replace('\n', " | ");
    match flat.char_indices().nth(600) {
        Some((i, _)) => format!("{} ...", &flat[..i]),
        None => flat,
    }
}

#[test]
fn corpus_is_large_and_every_case_has_an_expectation() {
    let files = corpus_files();
    let cases = cases();
    assert!(
        cases.len() >= MIN_CASES,
        "{} cases in {CORPUS}; expected at least {MIN_CASES}",
        cases.len()
    );
    let mut problems = Vec::new();
    for case in &cases {
        let expect = format!("{case}.expect");
        if !files.contains(&expect) {
            problems.push(format!("{case}: no {expect}"));
        } else if expectations(case).is_empty() {
            problems.push(format!("{expect}: has no expected line"));
        }
    }
    for file in &files {
        if let Some(case) = file.strip_suffix(".expect") {
            if !is_case(case) {
                problems.push(format!(
                    "{file}: `{case}` is not named like a case (design-*.json, scenario-*.json, urdf-*.urdf, mjcf-*.xml)"
                ));
            } else if !files.iter().any(|f| f == case) {
                problems.push(format!("{file}: orphan, no case file `{case}`"));
            }
        } else if !is_case(file) && file != "README.md" {
            problems.push(format!("{file}: neither a case, an .expect file nor README.md"));
        }
    }
    assert!(problems.is_empty(), "corpus layout problems:\n{}", problems.join("\n"));
}

#[test]
fn every_bad_input_exits_2_with_its_expected_message() {
    assert!(Path::new(&repo().join(CORPUS)).is_dir(), "{CORPUS} exists");
    let cases = cases();
    let failures: Vec<String> = cases
        .iter()
        .filter_map(|case| check(case).map(|problem| format!("{case}: {problem}")))
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} bad-input cases misbehave:\n\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n\n")
    );
}
