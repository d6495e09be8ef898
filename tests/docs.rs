//! The docs' example outputs cannot go stale: each is compared with what the command prints now.

mod common;

use assert_cmd::Command;
use common::repo;

/// The marker that ties the block below it to the command that prints it: `<!-- output:
/// validate-design ARGS -->` (run in a scratch folder that sees the repo's `designs/` and
/// `scenarios/`) or `<!-- output: example NAME -->` (`cargo run --example NAME`).
const MARKER: &str = "<!-- output: ";

/// One example output in the docs.
struct Example {
    page: String,
    line: usize,
    command: String,
    /// The block's lines: a fenced block's content, or a table's lines up to a blank line.
    lines: Vec<String>,
}

/// Every marked block of README.md and docs/*.md.
fn examples() -> Vec<Example> {
    let mut out = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).expect("page");
        let lines: Vec<&str> = text.lines().collect();
        for (at, line) in lines.iter().enumerate() {
            let Some(command) = line.trim().strip_prefix(MARKER).and_then(|rest| rest.strip_suffix("-->")) else {
                continue;
            };
            let rest = lines[at + 1..].iter().skip_while(|l| l.trim().is_empty());
            let mut block = Vec::new();
            let mut rest = rest.peekable();
            if rest.peek().is_some_and(|l| l.starts_with("```")) {
                rest.next();
                block.extend(rest.take_while(|l| !l.starts_with("```")).map(|l| l.to_string()));
            } else {
                block.extend(rest.take_while(|l| !l.trim().is_empty()).map(|l| l.to_string()));
            }
            out.push(Example {
                page: page.strip_prefix(repo()).unwrap_or(&page).display().to_string(),
                line: at + 1,
                command: command.trim().to_string(),
                lines: block,
            });
        }
    }
    out
}

/// What `command` prints on stdout (it must exit with 0 or with the code the docs promise for
/// an example that fails or is undecided: the output is what is compared).
fn printed(command: &str) -> String {
    let words: Vec<&str> = command.split_whitespace().collect();
    let output = match words.as_slice() {
        ["validate-design", args @ ..] => {
            let scratch = tempfile::tempdir().expect("scratch folder");
            for folder in ["designs", "scenarios"] {
                std::os::unix::fs::symlink(repo().join(folder), scratch.path().join(folder)).expect("link");
            }
            Command::cargo_bin("validate-design")
                .expect("binary is built")
                .current_dir(scratch.path())
                .args(args)
                .output()
                .expect("runs")
        }
        ["example", name] => {
            let profile: &[&str] = if cfg!(debug_assertions) { &[] } else { &["--release"] };
            std::process::Command::new(env!("CARGO"))
                .current_dir(repo())
                .args(["run", "--quiet", "--locked", "--example", name])
                .args(profile)
                .output()
                .expect("cargo runs")
        }
        _ => panic!("unknown example command `{command}`"),
    };
    assert!(
        matches!(output.status.code(), Some(0 | 1 | 3)),
        "`{command}` failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// A line with what varies from run to run masked: durations (`0.17 s`) and the digits of
/// floating-point rounding (the kinematics check's `e-16` errors, which depend on the CPU
/// MuJoCo runs on).
fn masked(line: &str) -> String {
    let words: Vec<&str> = line.split(' ').collect();
    let mut out = Vec::with_capacity(words.len());
    for (k, word) in words.iter().enumerate() {
        let rounding = word.contains("e-1") && word.chars().next().is_some_and(|c| c.is_ascii_digit());
        let seconds = word.parse::<f64>().is_ok() && words.get(k + 1).is_some_and(|next| next.trim_end_matches([';', ',', ')']) == "s");
        out.push(if rounding {
            "<rounding>"
        } else if seconds {
            "<seconds>"
        } else {
            word
        });
    }
    out.join(" ")
}

#[test]
fn every_example_output_in_the_docs_is_what_its_command_prints() {
    let examples = examples();
    assert!(
        examples.iter().any(|e| e.page == "README.md" && e.lines.len() > 10),
        "the README's main example is marked"
    );
    // Each command in its own scratch folder, so they run side by side.
    use rayon::prelude::*;
    let outputs: Vec<String> = examples.par_iter().map(|e| printed(&e.command)).collect();
    let mut stale = Vec::new();
    for (example, output) in examples.iter().zip(&outputs) {
        let printed: Vec<String> = output.lines().map(masked).collect();
        // Every line of the example (`...` stands for lines left out) is printed, in order.
        let mut from = 0;
        for line in example.lines.iter().filter(|l| l.trim() != "...") {
            match printed[from..].iter().position(|p| *p == masked(line)) {
                Some(at) => from += at + 1,
                None => {
                    stale.push(format!(
                        "{}:{}: `{}` no longer prints (in order):\n{line}\nit prints:\n{}",
                        example.page,
                        example.line,
                        example.command,
                        printed.join("\n")
                    ));
                    break;
                }
            }
        }
    }
    assert!(stale.is_empty(), "{}", stale.join("\n\n"));
}

/// README.md and the reference pages in docs/.
fn pages() -> Vec<std::path::PathBuf> {
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
    pages
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
    let pages = pages();
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

/// The `--options` of `validate-design [subcommand] --help`, without `--help` and `--version`.
fn help_options(subcommand: Option<&str>) -> std::collections::BTreeSet<String> {
    let output = Command::cargo_bin("validate-design")
        .expect("binary is built")
        .args(subcommand)
        .arg("--help")
        .output()
        .expect("runs");
    String::from_utf8_lossy(&output.stdout)
        .lines()
        .filter_map(|l| {
            let l = l.trim_start();
            let l = l
                .strip_prefix("-")
                .filter(|r| r.chars().nth(1) == Some(','))
                .map_or(l, |r| r[2..].trim_start());
            l.strip_prefix("--")
                .map(|r| format!("--{}", r.split([' ', '=']).next().unwrap_or_default()))
        })
        .filter(|o| o != "--help" && o != "--version")
        .collect()
}

#[test]
fn the_readme_synopsis_lists_every_option_of_every_subcommand() {
    let readme = std::fs::read_to_string(repo().join("README.md")).expect("README");
    let start = readme.find("## The `validate-design` command").expect("the synopsis's heading");
    let open = start + readme[start..].find("```text\n").expect("a text block") + "```text\n".len();
    let close = open + readme[open..].find("```").expect("the block ends");
    let subcommands = [
        "generate", "convert", "snapshot", "sweep", "merge", "table1", "ga", "optimize", "workflow",
    ];
    // Options per subcommand (None: the validation itself), a line `validate-design X` starting X.
    let mut synopsis: std::collections::BTreeMap<Option<&str>, std::collections::BTreeSet<String>> = Default::default();
    let mut current = None;
    for line in readme[open..close].lines() {
        if let Some(rest) = line.strip_prefix("validate-design ") {
            current = subcommands.iter().find(|s| rest.split(' ').next() == Some(**s)).copied();
        }
        let options = line
            .split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
            .filter(|w| w.starts_with("--") && w.len() > 2)
            .map(str::to_string);
        synopsis.entry(current).or_default().extend(options);
    }
    let mut wrong = Vec::new();
    for subcommand in std::iter::once(None).chain(subcommands.iter().map(|s| Some(*s))) {
        let listed = synopsis.get(&subcommand).cloned().unwrap_or_default();
        let actual = help_options(subcommand);
        let name = subcommand.unwrap_or("(validate)");
        for missing in actual.difference(&listed) {
            wrong.push(format!("{name}: {missing} is an option but not in the README's synopsis"));
        }
        for extra in listed.difference(&actual) {
            wrong.push(format!("{name}: {extra} is in the README's synopsis but not an option"));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The Python package installs the MuJoCo that build.rs pins: one version in the tree.
#[test]
fn the_python_package_pins_the_mujoco_of_mujoco_pin() {
    let pin = std::fs::read_to_string(repo().join("mujoco/PIN")).expect("mujoco/PIN");
    let version = pin
        .lines()
        .find_map(|line| line.strip_prefix("version="))
        .expect("mujoco/PIN has version=");
    let pyproject = std::fs::read_to_string(repo().join("python/pyproject.toml")).expect("pyproject");
    assert!(
        pyproject.contains(&format!("\"mujoco=={version}\"")),
        "python/pyproject.toml must depend on mujoco=={version}"
    );
}
