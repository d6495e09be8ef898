//! Consumes an SRDF file (MoveIt's semantic robot description) and a [`Model`] read from the
//! URDF it belongs to. Produces the self-collision pairs its `<disable_collisions>` elements
//! leave out, as [`ExcludedPair`]s with the SRDF's reason, for
//! [`ValidateOptions::excluded_pairs`](crate::pipeline::ValidateOptions). Nothing else of the
//! SRDF is read.
//!
//! The SRDF names URDF links; the model merges links joined by fixed joints (and the parts
//! gripper joints move) into one model link. A model pair is left out only when every pair of
//! URDF links with collision geometry it stands for is disabled: leaving it out on one disabled
//! part would stop checking the others. A disabled pair inside one model link says nothing the
//! model does not already do (one rigid body never collides with itself).

use crate::collide::ExcludedPair;
use crate::model::Model;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// An SRDF file is unusable, or names a link the model does not have.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {element}: {message}")]
pub struct SrdfError {
    /// The SRDF file.
    pub path: PathBuf,
    /// The element and its line (or `the file`, `the XML`).
    pub element: String,
    /// What is wrong and what was expected.
    pub message: String,
}

/// The self pairs an SRDF disables, on a model.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SrdfExclusions {
    /// The SRDF file.
    pub path: PathBuf,
    /// Model link pairs left out, each with the SRDF reasons of the URDF link pairs it covers.
    pub pairs: Vec<ExcludedPair>,
    /// What was not applied, and why (pairs inside one model link, model pairs only partly
    /// disabled), one sentence each.
    pub notes: Vec<String>,
}

impl SrdfExclusions {
    /// The pairs and notes as text: a heading, then one line each.
    pub fn describe(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "collision pairs disabled by {} ({} model link pairs left out):",
            self.path.display(),
            self.pairs.len()
        );
        for pair in &self.pairs {
            let _ = writeln!(out, "  {} - {}: {}", pair.a, pair.b, pair.reason);
        }
        for note in &self.notes {
            let _ = writeln!(out, "  not applied: {note}");
        }
        out
    }
}

/// One `<disable_collisions>`.
struct Disabled {
    a: String,
    b: String,
    reason: String,
    line: u32,
}

/// Reads the `<disable_collisions>` of the SRDF at `path` and maps them onto `model`'s links.
///
/// # Errors
/// [`SrdfError`] naming the file, and the element and line: an unreadable file, malformed XML,
/// a root other than `<robot>`, a `<disable_collisions>` without `link1` or `link2`, or a link
/// name neither the model nor the URDF it was read from has. A link of the URDF outside the
/// model's chain (`--base`, `--tip`) leaves its pairs out of nothing: a note says so.
pub fn exclusions(path: &Path, model: &Model) -> Result<SrdfExclusions, SrdfError> {
    let error = |element: String, message: String| SrdfError {
        path: path.to_path_buf(),
        element,
        message,
    };
    let text = crate::files::read_text(path, crate::limits::MAX_TEXT_BYTES)
        .map_err(|e| error("the file".into(), format!("cannot read it: {e}")))?;
    let doc = crate::limits::parse_xml(&text).map_err(|message| error("the XML".into(), message))?;
    let root = doc.root_element();
    let line = |node: roxmltree::Node| doc.text_pos_at(node.range().start).row;
    if root.tag_name().name() != "robot" {
        return Err(error(
            format!("<{}> (line {})", root.tag_name().name(), line(root)),
            "expected <robot> as the root element of an SRDF".into(),
        ));
    }
    let mut disabled = Vec::new();
    for node in root.children().filter(|n| n.has_tag_name("disable_collisions")) {
        let element = format!("<disable_collisions> (line {})", line(node));
        let link = |attribute: &str| {
            node.attribute(attribute)
                .filter(|name| !name.is_empty())
                .map(str::to_string)
                .ok_or_else(|| error(element.clone(), format!("has no {attribute} attribute")))
        };
        disabled.push(Disabled {
            a: link("link1")?,
            b: link("link2")?,
            reason: node.attribute("reason").unwrap_or("no reason given").to_string(),
            line: line(node),
        });
    }

    // The model link each URDF link is part of, and the URDF links with collision geometry of
    // each model link.
    let mut owner: BTreeMap<&str, usize> = BTreeMap::new();
    for (index, link) in model.links.iter().enumerate() {
        for name in std::iter::once(&link.name).chain(&link.merged) {
            owner.insert(name.as_str(), index);
        }
    }
    let parts = colliding_parts(model);
    let known = || model.links.iter().map(|l| format!("`{}`", l.name)).collect::<Vec<_>>().join(", ");
    let file = path
        .file_name()
        .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());

    let outside = urdf_links(model);
    let mut covered: BTreeMap<(usize, usize), Vec<&Disabled>> = BTreeMap::new();
    let mut disabled_names: BTreeSet<(&str, &str)> = BTreeSet::new();
    let mut notes = Vec::new();
    for entry in &disabled {
        let missing = [&entry.a, &entry.b].into_iter().find(|name| !owner.contains_key(name.as_str()));
        if let Some(name) = missing {
            if !outside.contains(name.as_str()) {
                return Err(error(
                    format!(
                        "<disable_collisions link1=\"{}\" link2=\"{}\"> (line {})",
                        entry.a, entry.b, entry.line
                    ),
                    format!(
                        "no link named `{name}` in the model of {} (model links: {}, and the links merged into them){}",
                        model.name,
                        known(),
                        if outside.is_empty() { "" } else { ", nor in its URDF" }
                    ),
                ));
            }
            // A whole robot's SRDF names every link of the URDF; an arm chosen with --base or
            // --tip has only some of them, and a pair with one outside is never checked.
            notes.push(format!(
                "{} - {} (line {}): `{name}` is in the URDF but not in the arm checked, so the pair is never checked",
                entry.a, entry.b, entry.line
            ));
            continue;
        }
        let (i, j) = (owner[entry.a.as_str()], owner[entry.b.as_str()]);
        if i == j {
            notes.push(format!(
                "{} - {} (line {}): both are part of model link `{}`, one rigid body",
                entry.a, entry.b, entry.line, model.links[i].name
            ));
            continue;
        }
        disabled_names.insert((entry.a.as_str(), entry.b.as_str()));
        disabled_names.insert((entry.b.as_str(), entry.a.as_str()));
        covered.entry((i.min(j), i.max(j))).or_default().push(entry);
    }

    let mut pairs = Vec::new();
    for ((i, j), entries) in covered {
        let still_checked: Vec<String> = parts[i]
            .iter()
            .flat_map(|a| parts[j].iter().map(move |b| (a.as_str(), b.as_str())))
            .filter(|pair| !disabled_names.contains(pair))
            .map(|(a, b)| format!("{a} - {b}"))
            .collect();
        let (a, b) = (&model.links[i].name, &model.links[j].name);
        if !still_checked.is_empty() {
            notes.push(format!(
                "{a} - {b}: the SRDF disables only some of the link pairs they stand for; {} still checked, so the pair is checked",
                still_checked.join(", ")
            ));
            continue;
        }
        let reasons: Vec<String> = entries
            .iter()
            .map(|e| format!("{} - {} \"{}\" (line {})", e.a, e.b, e.reason, e.line))
            .collect();
        pairs.push(ExcludedPair::new(
            a.clone(),
            b.clone(),
            format!("disabled in SRDF {file}: {}", reasons.join(", ")),
        ));
    }
    Ok(SrdfExclusions {
        path: path.to_path_buf(),
        pairs,
        notes,
    })
}

/// The link names of the URDF `model` was read from (none for other sources, or when the file
/// cannot be read again): what an SRDF may name outside the model's chain.
fn urdf_links(model: &Model) -> BTreeSet<String> {
    let crate::model::ModelSource::Urdf { path, .. } = &model.source else {
        return BTreeSet::new();
    };
    let Ok(text) = crate::files::read_text(path, crate::limits::MAX_TEXT_BYTES) else {
        return BTreeSet::new();
    };
    let Ok(doc) = crate::limits::parse_xml(&text) else {
        return BTreeSet::new();
    };
    doc.root_element()
        .children()
        .filter(|node| node.has_tag_name("link"))
        .filter_map(|node| node.attribute("name"))
        .map(str::to_string)
        .collect()
}

/// Per model link, the URDF links with collision geometry it is made of (a collider's label
/// starts with its URDF link's name and `/`); a link with no collider stands for itself.
fn colliding_parts(model: &Model) -> Vec<BTreeSet<String>> {
    model
        .links
        .iter()
        .map(|link| {
            let names: Vec<&String> = std::iter::once(&link.name).chain(&link.merged).collect();
            let mut parts: BTreeSet<String> = link
                .colliders
                .iter()
                .filter_map(|collider| {
                    names
                        .iter()
                        .filter(|name| collider.label.starts_with(&format!("{name}/")))
                        .max_by_key(|name| name.len())
                        .map(|name| (*name).clone())
                })
                .collect();
            if parts.is_empty() {
                parts.insert(link.name.clone());
            }
            parts
        })
        .collect()
}
