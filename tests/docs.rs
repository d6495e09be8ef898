//! The docs' example outputs cannot go stale: each is compared with what the command prints now.

mod common;

use assert_cmd::Command;
use common::repo;

/// The lines of the first fenced block that follows `heading` in `text`.
fn block_after(text: &str, heading: &str) -> Vec<String> {
    let start = text.find(heading).unwrap_or_else(|| panic!("no heading `{heading}`"));
    let rest = &text[start..];
    let open = rest.find("```text\n").expect("a text block after the heading") + "```text\n".len();
    let close = rest[open..].find("```").expect("the block ends");
    rest[open..open + close].lines().map(str::to_string).collect()
}

/// A line with the digits of floating-point rounding (the kinematics check's `e-16` errors,
/// which depend on the CPU MuJoCo runs on) masked.
fn masked(line: &str) -> String {
    let mut out = String::new();
    for word in line.split(' ') {
        let rounding = word.contains("e-1") && word.chars().next().is_some_and(|c| c.is_ascii_digit());
        out.push_str(if rounding { "<rounding>" } else { word });
        out.push(' ');
    }
    out
}

#[test]
fn the_readme_main_example_is_what_the_main_command_prints() {
    let readme = std::fs::read_to_string(repo().join("README.md")).expect("README");
    let expected = block_after(&readme, "## Two commands");
    let output = Command::cargo_bin("validate-design")
        .expect("binary is built")
        .current_dir(repo())
        .arg("designs/paper-real-world.json")
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(0));
    let printed: Vec<String> = String::from_utf8_lossy(&output.stdout).lines().map(masked).collect();
    // Every line of the example (`...` stands for lines left out) is printed, in order.
    let mut from = 0;
    for line in expected.iter().filter(|l| l.trim() != "...") {
        let want = masked(line);
        match printed[from..].iter().position(|p| *p == want) {
            Some(at) => from += at + 1,
            None => panic!(
                "README.md's example line is not printed (in order) by `validate-design designs/paper-real-world.json`:\n{line}\nprinted:\n{}",
                printed.join("\n")
            ),
        }
    }
    assert!(expected.len() > 10, "the example is the report: {expected:?}");
}

/// GitHub's anchor of a heading: lower case, punctuation dropped, spaces as hyphens.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

#[test]
fn every_link_between_the_docs_leads_to_a_file_and_a_heading_that_exist() {
    let mut pages = vec![repo().join("README.md")];
    let mut docs: Vec<_> = std::fs::read_dir(repo().join("docs"))
        .expect("docs/")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    assert!(docs.len() >= 10, "the reference pages: {docs:?}");
    pages.extend(docs);
    let anchors = |path: &std::path::Path| -> Vec<String> {
        std::fs::read_to_string(path)
            .unwrap_or_default()
            .lines()
            .filter(|l| l.starts_with('#'))
            .map(|l| anchor(l.trim_start_matches('#')))
            .collect()
    };
    let mut broken = Vec::new();
    for page in &pages {
        let text = std::fs::read_to_string(page).expect("page");
        for link in text.split("](").skip(1).filter_map(|rest| rest.split(')').next()) {
            if link.starts_with("http") || link.contains(' ') {
                continue;
            }
            let (file, fragment) = link.split_once('#').unwrap_or((link, ""));
            let target = if file.is_empty() {
                page.clone()
            } else {
                page.parent().expect("a folder").join(file)
            };
            if !target.exists() {
                broken.push(format!("{}: {link}: no such file", page.display()));
            } else if !fragment.is_empty() && !anchors(&target).iter().any(|a| a == fragment) {
                broken.push(format!("{}: {link}: no such heading", page.display()));
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}
