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
