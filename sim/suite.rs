//! Users' own golden suites: `validate-design snapshot --suite FILE` runs every design of a small
//! JSON file on every scenario of it, writes each report as an insta-compatible snapshot into the
//! user's repository, and fails on a difference with a readable diff; `--accept` records the new
//! snapshots. Snapshot text is [`crate::report::snapshot::snapshot_text`], as in our own goldens.
//!
//! ```json
//! {
//!   "snapshots": "golden",
//!   "designs": ["designs/ur5e.json", {"path": "robots/panda.urdf", "tip": "panda_hand", "srdf": "robots/panda.srdf"}],
//!   "scenarios": ["scenarios/course.json"],
//!   "options": {"seed": 0, "engines": ["rapier", "mujoco"], "plan_budget": 20000, "tolerance": "z_symmetric", "search_boxes": 1000}
//! }
//! ```
//! Paths are relative to the suite file; `snapshots` defaults to `snapshots`. Each run is
//! [`crate::run::validate_loaded`]: what `validate-design` runs with the same options, without
//! MuJoCo's kinematics check.

use crate::error::Error;
use crate::pipeline::{self, LoadOptions};
use crate::report::{self, snapshot};
use crate::{files, limits, run};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A suite file, as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SuiteFile {
    snapshots: Option<PathBuf>,
    designs: Vec<DesignEntry>,
    scenarios: Vec<PathBuf>,
    #[serde(default)]
    options: run::Named,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum DesignEntry {
    Path(PathBuf),
    Full(DesignFull),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DesignFull {
    path: PathBuf,
    name: Option<String>,
    base: Option<String>,
    tip: Option<String>,
    #[serde(default)]
    package_paths: Vec<PathBuf>,
    srdf: Option<PathBuf>,
}

/// Most runs one suite may ask for.
pub const MAX_SUITE_RUNS: usize = 10_000;

/// What one run of the suite found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    /// The snapshot matches.
    Same,
    /// There was no snapshot (written as `.snap.new`, or `.snap` with accept).
    New,
    /// The snapshot differs.
    Changed {
        /// The unified diff.
        diff: String,
        /// The lines of the report's summary that changed, `key: old -> new` (the verdict first
        /// when it changed); empty when only the details moved.
        summary: Vec<String>,
    },
}

/// One snapshot of the suite.
#[derive(Debug, Clone)]
pub struct Entry {
    /// `DESIGN__SCENARIO`.
    pub name: String,
    /// The snapshot file.
    pub file: PathBuf,
    /// The run's verdict line.
    pub verdict: String,
    /// Against the recorded snapshot.
    pub outcome: Outcome,
}

/// The whole suite's result.
#[derive(Debug, Clone)]
pub struct SuiteResult {
    /// Per run, suite order.
    pub entries: Vec<Entry>,
    /// Snapshots in the folder that no run of the suite writes (deleted with accept).
    pub orphans: Vec<PathBuf>,
    /// Whether the snapshots were accepted.
    pub accepted: bool,
}

impl SuiteResult {
    /// Whether every snapshot matched and none is an orphan (always true after accept).
    pub fn passed(&self) -> bool {
        self.accepted || (self.orphans.is_empty() && self.entries.iter().all(|e| e.outcome == Outcome::Same))
    }
}

/// Why a suite could not run.
#[derive(Debug, thiserror::Error)]
pub enum SuiteError {
    /// The suite file is unusable.
    #[error("{path}: {field}: {message}")]
    Invalid {
        /// The suite file.
        path: PathBuf,
        /// The field.
        field: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A design, scenario or run it names failed, or a snapshot could not be written.
    #[error(transparent)]
    Run(#[from] Error),
}

fn invalid(path: &Path, field: &str, message: String) -> SuiteError {
    SuiteError::Invalid {
        path: path.to_path_buf(),
        field: field.into(),
        message,
    }
}

/// A run's options from the suite's `options` (named as on the command line), checked as the
/// command line checks them.
fn options(path: &Path, named: &run::Named) -> Result<run::Options, SuiteError> {
    let per_design = [
        ("base", "base", named.base.is_some()),
        ("tip", "tip", named.tip.is_some()),
        ("srdf", "srdf", named.srdf.is_some()),
        ("package_path", "package_paths", !named.package_path.is_empty()),
    ];
    if let Some((name, field, _)) = per_design.iter().find(|(_, _, given)| *given) {
        return Err(invalid(
            path,
            &format!("options.{name}"),
            format!("is given per design (`designs[k].{field}`), not for the whole suite"),
        ));
    }
    if named.mujoco_checks.is_some() {
        return Err(invalid(
            path,
            "options.mujoco_checks",
            "snapshots do not run MuJoCo's kinematics check; run `validate-design` for it".into(),
        ));
    }
    named.options().map_err(|e| match e {
        Error::Option { name, message } => invalid(path, &format!("options.{name}"), message),
        other => SuiteError::from(other),
    })
}

/// Runs the suite at `suite_path`, compares with (or, with `accept`, records) its snapshots.
///
/// # Errors
/// [`SuiteError::Invalid`] for a bad suite file; any stage's error for a design or scenario it
/// names ([`SuiteError::Run`]).
pub fn run(suite_path: &Path, accept: bool) -> Result<SuiteResult, SuiteError> {
    let text = files::read_text(suite_path, limits::MAX_TEXT_BYTES)
        .map_err(|e| invalid(suite_path, "the file", format!("cannot read it: {e}")))?;
    let suite: SuiteFile = serde_json::from_str(&text).map_err(|e| invalid(suite_path, "the JSON", e.to_string()))?;
    let dir = suite_path.parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    if suite.designs.is_empty() || suite.scenarios.is_empty() {
        return Err(invalid(suite_path, "designs, scenarios", "need at least one entry each".into()));
    }
    if suite.designs.len() * suite.scenarios.len() > MAX_SUITE_RUNS {
        return Err(invalid(
            suite_path,
            "designs, scenarios",
            format!("more than {MAX_SUITE_RUNS} runs (the limit)"),
        ));
    }
    let opts = options(suite_path, &suite.options)?;
    // Every snapshot's name before any run: two runs sharing one would leave one file and a
    // suite that fails forever with nothing to review.
    let design_names = suite
        .designs
        .iter()
        .enumerate()
        .map(|(index, design)| {
            let name = match design {
                DesignEntry::Path(p) => stem(p),
                DesignEntry::Full(full) => full.name.clone().unwrap_or_else(|| stem(&full.path)),
            };
            if name.is_empty() || name.contains(['/', '\\']) || name.starts_with('.') {
                return Err(invalid(
                    suite_path,
                    &format!("designs[{index}].name"),
                    format!("`{name}`: expected a file-name-safe name (no slashes, not starting with a dot)"),
                ));
            }
            Ok(name)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let scenario_names: Vec<String> = suite.scenarios.iter().map(|p| stem(p)).collect();
    let mut taken: std::collections::HashMap<String, (usize, usize)> = std::collections::HashMap::new();
    for (d, design) in design_names.iter().enumerate() {
        for (s, scenario) in scenario_names.iter().enumerate() {
            if let Some((d0, s0)) = taken.insert(format!("{design}__{scenario}"), (d, s)) {
                return Err(invalid(
                    suite_path,
                    "designs, scenarios",
                    format!(
                        "designs[{d0}] on scenarios[{s0}] and designs[{d}] on scenarios[{s}] would share the snapshot `{design}__{scenario}.snap`: give the designs distinct `name`s, and list each scenario once under distinct file names"
                    ),
                ));
            }
        }
    }
    let folder = dir.join(suite.snapshots.clone().unwrap_or_else(|| PathBuf::from("snapshots")));
    // Held for the whole run: one writer per snapshot folder.
    let _lock = files::lock_folder(&folder).map_err(|e| invalid(suite_path, "snapshots", format!("{}: {e}", folder.display())))?;
    // Temporaries of writes a kill cut short (the names this suite writes, and nothing else).
    let targets: Vec<String> = taken
        .keys()
        .flat_map(|name| [format!("{name}.snap"), format!("{name}.snap.new")])
        .collect();
    let targets: Vec<&str> = targets.iter().map(String::as_str).collect();
    files::remove_temporaries(&folder, &targets).map_err(|source| Error::Write {
        path: folder.clone(),
        source,
    })?;
    let source_line = format!(
        "validate-design snapshot --suite {}",
        suite_path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
    );

    let scenarios = suite
        .scenarios
        .iter()
        .map(|p| {
            let scenario = pipeline::load_scenario(&dir.join(p))?;
            Ok((stem(p), scenario))
        })
        .collect::<Result<Vec<_>, Error>>()?;
    let mut entries = Vec::new();
    for (design, name) in suite.designs.iter().zip(design_names) {
        let (path, load_opts, srdf) = match design {
            // A catalog id names no file: it is not relative to the suite.
            DesignEntry::Path(p)
                if !dir.join(p).exists() && crate::design::Design::from_catalog_id(&p.to_string_lossy()).is_ok_and(|d| d.is_some()) =>
            {
                (p.clone(), LoadOptions::default(), None)
            }
            DesignEntry::Path(p) => (dir.join(p), LoadOptions::default(), None),
            DesignEntry::Full(full) => (
                dir.join(&full.path),
                LoadOptions {
                    base_link: full.base.clone(),
                    tip_link: full.tip.clone(),
                    package_paths: full.package_paths.iter().map(|p| dir.join(p)).collect(),
                },
                full.srdf.as_ref().map(|p| dir.join(p)),
            ),
        };
        let loaded = pipeline::load(&path, &load_opts)?;
        // The snapshot is the report: no exports, and MuJoCo's kinematics check is the CLI's.
        let run_opts = run::Options {
            srdf,
            kinematics_checks: 0,
            ..opts.clone()
        };
        for (scenario_name, scenario) in &scenarios {
            let (_, built) = run::validated(&path, loaded.clone(), scenario.clone(), &run_opts, &crate::progress::Silent)?;
            let body = snapshot::snapshot_text(&built).map_err(|message| Error::Report { message })?;
            let snapshot_name = format!("{name}__{scenario_name}");
            let file = folder.join(format!("{snapshot_name}.snap"));
            let contents = format!(
                "---\nsource: {source_line}\ndescription: {}\n---\n{body}",
                serde_json::to_string(&snapshot::description(&built)).unwrap_or_default()
            );
            let outcome = record(&file, &contents, &body, accept)?;
            entries.push(Entry {
                name: snapshot_name,
                file,
                verdict: report::verdict_line(&built.verdict),
                outcome,
            });
        }
    }
    let written: std::collections::BTreeSet<&Path> = entries.iter().map(|e| e.file.as_path()).collect();
    let mut orphans: Vec<PathBuf> = std::fs::read_dir(&folder)
        .map_err(|source| Error::Write {
            path: folder.clone(),
            source,
        })?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "snap") && !written.contains(p.as_path()))
        .collect();
    orphans.sort();
    if accept {
        for orphan in &orphans {
            std::fs::remove_file(orphan).map_err(|source| Error::Write {
                path: orphan.clone(),
                source,
            })?;
        }
    }
    Ok(SuiteResult {
        entries,
        orphans,
        accepted: accept,
    })
}

fn stem(path: &Path) -> String {
    path.file_stem().map_or_else(String::new, |s| s.to_string_lossy().into_owned())
}

/// The body of a snapshot file: what follows insta's `---` header.
fn body_of(text: &str) -> &str {
    text.strip_prefix("---\n")
        .and_then(|rest| rest.find("\n---\n").map(|end| &rest[end + 5..]))
        .unwrap_or(text)
}

/// The `key: value` lines of a snapshot's `summary:` block, quotes removed.
fn summary_lines(body: &str) -> Vec<(&str, &str)> {
    body.lines()
        .skip_while(|line| *line != "summary:")
        .skip(1)
        .take_while(|line| line.starts_with("  "))
        .filter_map(|line| line.trim().split_once(": "))
        .map(|(key, value)| (key, value.trim_matches('"')))
        .collect()
}

/// `key: old -> new` for each summary line that differs between two snapshot bodies.
fn summary_changes(old: &str, new: &str) -> Vec<String> {
    let before = summary_lines(old);
    summary_lines(new)
        .into_iter()
        .filter_map(|(key, value)| {
            let was = before.iter().find(|(k, _)| *k == key).map(|(_, v)| *v);
            (was != Some(value)).then(|| format!("{key}: {} -> {value}", was.unwrap_or("(none)")))
        })
        .collect()
}

/// Compares with the snapshot at `file`; writes `.snap.new` (insta's pending file, for `cargo
/// insta review`) when it differs, or the `.snap` itself with `accept`.
fn record(file: &Path, contents: &str, body: &str, accept: bool) -> Result<Outcome, Error> {
    let pending = file.with_extension("snap.new");
    let write = |path: &Path| pipeline::write_output(path, contents);
    let outcome = match std::fs::read_to_string(file) {
        Ok(old) if body_of(&old) == body => Outcome::Same,
        Ok(old) => Outcome::Changed {
            diff: similar::TextDiff::from_lines(body_of(&old), body)
                .unified_diff()
                .context_radius(2)
                .header(&file.display().to_string(), "this run")
                .to_string(),
            summary: summary_changes(body_of(&old), body),
        },
        Err(_) => Outcome::New,
    };
    match (&outcome, accept) {
        (Outcome::Same, _) => {}
        (_, true) => write(file)?,
        (_, false) => write(&pending)?,
    }
    if outcome == Outcome::Same || accept {
        let _ = std::fs::remove_file(&pending);
    }
    Ok(outcome)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_changed_summary_says_old_and_new() {
        let old = "summary:\n  verdict: \"FAIL: 3 goals unreachable (proven)\"\n  goals: \"8 (reached 5, unreachable 3)\"\n  engines: \"x\"\nreport:\n  a: 1\n";
        let new = "summary:\n  verdict: \"PASS\"\n  goals: \"8 (reached 8)\"\n  engines: \"x\"\nreport:\n  a: 2\n";
        assert_eq!(
            summary_changes(old, new),
            [
                "verdict: FAIL: 3 goals unreachable (proven) -> PASS",
                "goals: 8 (reached 5, unreachable 3) -> 8 (reached 8)"
            ]
        );
        assert!(summary_changes(old, old).is_empty());
    }

    #[test]
    fn body_follows_the_header() {
        assert_eq!(body_of("---\nsource: x\ndescription: \"y\"\n---\nsummary:\n"), "summary:\n");
        assert_eq!(body_of("no header"), "no header");
    }
}
