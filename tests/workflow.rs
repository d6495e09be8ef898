//! The paper's workflow in one command: a cluttered task from candidates to a summary page, each
//! finalist's verdict what a separate validation of its written design gives, the page loading
//! with every picture in headless Chromium.

mod common;

use common::repo;
use std::path::Path;

use common::CHROMIUM;
const TASK: &str = "scenarios/cluttered/task-00.json";

fn validate_design() -> assert_cmd::Command {
    let mut command = assert_cmd::Command::cargo_bin("validate-design").expect("binary is built");
    command.current_dir(repo());
    command
}

/// The verdict word `validate-design DESIGN --scenario TASK --engines none --quiet` prints.
fn verdict_of(design: &Path) -> String {
    let output = validate_design()
        .arg(design)
        .args(["--scenario", TASK, "--engines", "none", "--quiet", "--mujoco-checks", "0"])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    stdout
        .split_whitespace()
        .nth(1)
        .unwrap_or_default()
        .trim_end_matches(':')
        .to_string()
}

#[test]
fn a_cluttered_task_goes_from_candidates_to_a_summary_page() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("wf");
    let output = validate_design()
        .args(["workflow", TASK, "--top", "2", "--engines", "none", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    assert!(
        output.status.code().is_some_and(|c| c <= 3),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        stdout.contains("task cluttered-task-00:") && stdout.contains("candidates (every design the GA evaluated"),
        "{stdout}"
    );
    let page = out.join("summary.html");
    let html = std::fs::read_to_string(&page).expect("summary.html");
    let task = out.join("cluttered-task-00");
    let mut designs: Vec<_> = std::fs::read_dir(&task)
        .expect("the task's folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    designs.sort();
    assert_eq!(designs.len(), 2, "two finalists' design files");
    for design in &designs {
        let stem = design.file_stem().expect("stem").to_string_lossy().into_owned();
        for file in [format!("{stem}.html"), format!("{stem}-scene.png")] {
            assert!(task.join(&file).is_file(), "{file}");
            assert!(html.contains(&format!("cluttered-task-00/{file}")), "the page links {file}");
        }
        // The verdict the page gives is what a separate validation of the written file gives.
        let verdict = verdict_of(design);
        assert!(["PASS", "FAIL", "UNDECIDED"].contains(&verdict.as_str()), "{verdict}");
        let line = stdout
            .lines()
            .find(|l| l.contains(&format!("{stem}.html")))
            .expect("a line per finalist");
        assert!(
            line.contains(&format!("verdict {verdict} ")),
            "{line} vs a separate run's {verdict}"
        );
    }
    // An existing workflow is kept unless --force.
    let again = validate_design()
        .args(["workflow", TASK, "--top", "1", "--engines", "none", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(again.status.code(), Some(2), "{}", String::from_utf8_lossy(&again.stderr));
    assert!(String::from_utf8_lossy(&again.stderr).contains("pass --force"));

    if !Path::new(CHROMIUM).exists() {
        println!("skipped the browser check: {CHROMIUM} is not installed (apt-get install chromium; .ci/run installs it)");
        return;
    }
    let (dom, stderr) = common::chromium(&page, &["--dump-dom"]);
    let title = dom.split("<title>").nth(1).and_then(|t| t.split("</title>").next()).unwrap_or("");
    assert_eq!(title, "ok 2 of 2 pictures", "chromium stderr:\n{stderr}");
}
