//! What MuJoCo does not check for us. Before it loads a file: every file the MJCF reads (the
//! file, its `<include>`s, mesh, texture, height-field and skin files) is a regular file within
//! the size limits and UTF-8 XML within the XML limits (MuJoCo would block on a FIFO, read a
//! device forever, and hand back names that are not UTF-8), and each is remembered as an input so
//! no output replaces it. After it compiled the model: every number is finite and every range is
//! ordered (MuJoCo compiles NaN positions and reversed ranges without a word).

use super::{ModelError, Reader};
use crate::{files, limits};
use mujoco_rs::prelude::*;
use std::path::{Path, PathBuf};

/// Attributes that name a file MuJoCo reads (besides `<include file>`).
const FILE_ATTRIBUTES: &[&str] = &["file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"];

/// Checks the MJCF at `path` and everything it reads, and remembers each as an input.
///
/// # Errors
/// [`ModelError::Read`] for a file that is missing, not regular, too large or not UTF-8;
/// [`ModelError::UnsupportedMjcf`] for malformed XML or XML past the limits, naming the line.
pub(super) fn before_load(path: &Path) -> Result<(), ModelError> {
    let dir = path.parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    // Texts of the file and its includes, in the order found; MuJoCo resolves an include
    // relative to the main file's folder.
    let mut texts: Vec<(PathBuf, String)> = vec![(path.to_path_buf(), read(path, limits::MAX_TEXT_BYTES)?)];
    let mut next = 0;
    while next < texts.len() {
        let (file, text) = (texts[next].0.clone(), texts[next].1.clone());
        next += 1;
        let doc = xml(&file, &text)?;
        for node in doc.descendants().filter(|n| n.has_tag_name("include")) {
            let Some(name) = node.attribute("file") else { continue };
            // MuJoCo 3.17 resolves an include against the including file's folder.
            let here = file.parent().map_or_else(|| dir.clone(), Path::to_path_buf);
            let included = here.join(name);
            if texts.iter().any(|(seen, _)| seen == &included) || !included.exists() {
                // A cycle or a missing file: MuJoCo reports both with its own message.
                continue;
            }
            if texts.len() > limits::MAX_MJCF_INCLUDES {
                return Err(unsupported(
                    &file,
                    &doc,
                    node,
                    format!("more than {} included files (the limit)", limits::MAX_MJCF_INCLUDES),
                ));
            }
            let included_text = read(&included, limits::MAX_TEXT_BYTES)?;
            texts.push((included, included_text));
        }
    }
    let docs = texts
        .iter()
        .map(|(file, text)| Ok((file, xml(file, text)?)))
        .collect::<Result<Vec<_>, ModelError>>()?;
    // Asset folders may be set in any of the files.
    let mut folders = vec![dir.clone()];
    for (_, doc) in &docs {
        for node in doc.descendants().filter(|n| n.has_tag_name("compiler")) {
            for attribute in ["meshdir", "texturedir", "assetdir"] {
                if let Some(sub) = node.attribute(attribute) {
                    folders.push(dir.join(sub));
                }
            }
        }
    }
    for (file, doc) in &docs {
        for node in doc.descendants().filter(|n| n.is_element() && !n.has_tag_name("include")) {
            check_numbers(file, doc, node)?;
            for attribute in FILE_ATTRIBUTES {
                let Some(name) = node.attribute(*attribute) else { continue };
                let here = file.parent().map_or_else(|| dir.clone(), Path::to_path_buf);
                let candidates: Vec<PathBuf> = folders.iter().chain([&here]).map(|folder| folder.join(name)).collect();
                if !candidates.iter().any(|c| std::fs::symlink_metadata(c).is_ok()) {
                    let searched: Vec<String> = candidates.iter().map(|c| c.display().to_string()).collect();
                    return Err(unsupported(
                        file,
                        doc,
                        node,
                        format!("{attribute}=\"{name}\": not found; searched {}", searched.join(", ")),
                    ));
                }
                for candidate in candidates {
                    if std::fs::symlink_metadata(&candidate).is_err() {
                        continue;
                    }
                    files::check_regular(&candidate, limits::MAX_MESH_BYTES)
                        .map_err(|e| unsupported(file, doc, node, format!("{attribute}=\"{name}\": {}: {e}", candidate.display())))?;
                    files::record_input(&candidate);
                }
            }
        }
    }
    Ok(())
}

/// Attributes holding lengths, checked before MuJoCo compiles them: MuJoCo turns a NaN, an
/// infinite or a huge size into a complaint about mass on another line.
const LENGTH_ATTRIBUTES: [&str; 3] = ["pos", "size", "fromto"];
/// Attributes holding other numbers: finite, within +-1e9.
const NUMBER_ATTRIBUTES: [&str; 7] = ["quat", "euler", "axis", "range", "mass", "diaginertia", "fullinertia"];

fn check_numbers(file: &Path, doc: &roxmltree::Document, node: roxmltree::Node) -> Result<(), ModelError> {
    for (attributes, bound) in [(&LENGTH_ATTRIBUTES[..], limits::MAX_LENGTH_M), (&NUMBER_ATTRIBUTES[..], 1e9)] {
        for attribute in attributes {
            let Some(text) = node.attribute(*attribute) else { continue };
            for word in text.split_whitespace() {
                let problem = match word.parse::<f64>() {
                    Err(_) => format!("`{word}` is not a number"),
                    Ok(v) if !v.is_finite() => format!("`{word}` is not a finite number"),
                    Ok(v) if v.abs() > bound => format!("`{word}`: expected at most {bound} in absolute value"),
                    Ok(_) => continue,
                };
                return Err(unsupported(file, doc, node, format!("{attribute}=\"{text}\": {problem}")));
            }
        }
    }
    Ok(())
}

fn read(path: &Path, limit: u64) -> Result<String, ModelError> {
    files::read_text(path, limit).map_err(|source| ModelError::Read {
        path: path.to_path_buf(),
        source,
    })
}

fn xml<'a>(path: &Path, text: &'a str) -> Result<roxmltree::Document<'a>, ModelError> {
    limits::parse_xml(text).map_err(|problem| ModelError::UnsupportedMjcf {
        path: path.to_path_buf(),
        element: "the XML".into(),
        problem,
    })
}

fn unsupported(path: &Path, doc: &roxmltree::Document, node: roxmltree::Node, problem: String) -> ModelError {
    ModelError::UnsupportedMjcf {
        path: path.to_path_buf(),
        element: match node.attribute("name") {
            Some(name) => format!(
                "<{} name=\"{name}\"> (line {})",
                node.tag_name().name(),
                doc.text_pos_at(node.range().start).row
            ),
            None => format!("<{}> (line {})", node.tag_name().name(), doc.text_pos_at(node.range().start).row),
        },
        problem,
    }
}

impl Reader<'_> {
    /// Every number of the compiled model that the model reads is finite and within the limits,
    /// every limited joint's range is ordered, and the chain is within the joint limit.
    pub(super) fn check_numbers(&self) -> Result<(), ModelError> {
        let mj = self.mj;
        let joints = mj.ffi().njnt as usize;
        if joints > limits::MAX_JOINTS {
            return Err(self.unsupported(
                "<worldbody>".into(),
                format!("has {joints} joints; the limit is {}", limits::MAX_JOINTS),
            ));
        }
        let bad = |values: &[f64], bound: f64| values.iter().any(|v| !v.is_finite() || v.abs() > bound);
        let length = limits::MAX_LENGTH_M;
        for body in 0..mj.ffi().nbody as usize {
            let checks: [(&str, &[f64], f64); 6] = [
                ("pos", &mj.body_pos()[body], length),
                ("quat", &mj.body_quat()[body], 2.0),
                ("inertial pos", &mj.body_ipos()[body], length),
                ("inertial quat", &mj.body_iquat()[body], 2.0),
                ("mass", std::slice::from_ref(&mj.body_mass()[body]), 1e9),
                ("inertia", &mj.body_inertia()[body], 1e9),
            ];
            if let Some((what, values, _)) = checks.iter().find(|(_, values, bound)| bad(values, *bound)) {
                return Err(self.unsupported(
                    self.body(body),
                    format!("{what} {values:?}: expected finite numbers within the limits"),
                ));
            }
        }
        for joint in 0..joints {
            let checks: [(&str, &[f64], f64); 3] = [
                ("pos", &mj.jnt_pos()[joint], length),
                ("axis", &mj.jnt_axis()[joint], 1e9),
                ("range", &mj.jnt_range()[joint], limits::MAX_JOINT_LIMIT),
            ];
            if let Some((what, values, _)) = checks.iter().find(|(_, values, bound)| bad(values, *bound)) {
                return Err(self.unsupported(
                    self.joint_element(joint),
                    format!(
                        "{what} {values:?}: expected finite numbers within the limits (range within +-{})",
                        limits::MAX_JOINT_LIMIT
                    ),
                ));
            }
            let [lower, upper] = mj.jnt_range()[joint];
            if lower > upper {
                return Err(self.unsupported(
                    self.joint_element(joint),
                    format!("range [{lower}, {upper}] is reversed: expected lower <= upper"),
                ));
            }
        }
        for geom in 0..mj.ffi().ngeom as usize {
            let checks: [(&str, &[f64], f64); 3] = [
                ("size", &mj.geom_size()[geom], length),
                ("pos", &mj.geom_pos()[geom], length),
                ("quat", &mj.geom_quat()[geom], 2.0),
            ];
            if let Some((what, values, _)) = checks.iter().find(|(_, values, bound)| bad(values, *bound)) {
                return Err(self.unsupported(
                    format!("geom `{}`", self.name(MjtObjBase::mjOBJ_GEOM, geom)),
                    format!("{what} {values:?}: expected finite numbers within the limits"),
                ));
            }
        }
        for site in 0..mj.ffi().nsite as usize {
            if bad(&mj.site_pos()[site], length) || bad(&mj.site_quat()[site], 2.0) {
                return Err(self.unsupported(
                    format!("site `{}`", self.name(MjtObjBase::mjOBJ_SITE, site)),
                    "pos or quat: expected finite numbers within the limits".into(),
                ));
            }
        }
        for mesh in 0..mj.ffi().nmesh as usize {
            let faces = mj.mesh_facenum()[mesh] as usize;
            if faces > limits::MAX_MESH_TRIANGLES {
                return Err(self.unsupported(
                    format!("mesh `{}`", self.name(MjtObjBase::mjOBJ_MESH, mesh)),
                    format!(
                        "{faces} triangles; the limit is {} per mesh (use a simplified collision mesh)",
                        limits::MAX_MESH_TRIANGLES
                    ),
                ));
            }
        }
        if mj.mesh_vert().iter().flatten().any(|v| !v.is_finite()) {
            return Err(self.unsupported("<asset>".into(), "a mesh vertex is not finite".into()));
        }
        Ok(())
    }
}
