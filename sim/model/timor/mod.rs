//! Timor (timor-python, TU Munich) module sets and assemblies -> Model.
//!
//! A module set is `modules.json` ([`set`]); a robot is an assembly of its modules, written as
//! Timor writes one in a solution: `moduleSet` (a module set file, a folder holding
//! `modules.json`, or the name of a set shipped in `designs/timor/`), `moduleOrder`, and
//! optionally `moduleConnection`, `baseConnection` and `basePose` ([`assembly`]). Other keys of
//! a Timor solution (`taskID`, `trajectory`, `cost`, ...) are named in a warning and not read.

mod assembly;
pub(crate) mod json;
pub(crate) mod mesh;
pub(crate) mod set;
mod space;

pub use space::{parse_timor_id, TimorSet, MAX_ASSEMBLIES, TIMOR_ID_PREFIX};

use super::{Diagnostic, Model, ModelError};
use json::{Id, Matrix4Rows, OneOrMany};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What a JSON file written by Timor holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimorKind {
    /// A module set (`{"modules": [...]}`).
    ModuleSet,
    /// An assembly (`{"moduleSet": ..., "moduleOrder": [...]}`).
    Assembly,
}

/// Folder of the module sets shipped with proving-ground (Timor's samples, MIT licence).
pub const SHIPPED_SETS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/designs/timor");

/// Whether `text` is a Timor module set or assembly, by its top-level keys; `None` for anything
/// else (a design, broken JSON).
pub fn timor_kind(text: &str) -> Option<TimorKind> {
    let value: serde_json::Value = serde_json::from_str(&json::quote_non_finite(text)).ok()?;
    let object = value.as_object()?;
    if object.contains_key("moduleOrder") {
        Some(TimorKind::Assembly)
    } else if object.get("modules").is_some_and(serde_json::Value::is_array) && !object.contains_key("mode") {
        Some(TimorKind::ModuleSet)
    } else {
        None
    }
}

/// An assembly file as Timor writes it.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
struct AssemblyFile {
    /// Not Timor's: the robot's name (default: the file name).
    #[serde(default)]
    name: Option<String>,
    /// Not Timor's: what the file is (a sweep's rank), not read.
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<String>,
    module_set: String,
    module_order: Vec<Id>,
    #[serde(default)]
    module_connection: Option<Vec<(usize, Id, usize, Id)>>,
    #[serde(default)]
    base_connection: Option<Vec<Vec<serde_json::Value>>>,
    #[serde(default)]
    base_pose: Option<OneOrMany<Matrix4Rows>>,
    #[serde(flatten)]
    other: BTreeMap<String, serde::de::IgnoredAny>,
}

fn parse_error(path: &Path, error: &serde_json::Error) -> ModelError {
    ModelError::InvalidValue {
        path: path.to_path_buf(),
        element: format!("line {}", error.line()),
        message: format!("{error}"),
    }
}

fn problem(path: &Path, (element, message): (String, String)) -> ModelError {
    ModelError::InvalidValue {
        path: path.to_path_buf(),
        element,
        message,
    }
}

fn read(path: &Path) -> Result<String, ModelError> {
    crate::files::read_text(path, crate::limits::MAX_TEXT_BYTES).map_err(|source| ModelError::Read {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads a Timor module set (`modules.json`).
///
/// # Errors
/// [`ModelError`] naming the file and the module, body, joint or connector: malformed JSON,
/// unknown keys (Timor refuses them too), a pose that is not rigid, missing mesh files.
pub fn load_module_set(path: &Path) -> Result<ModuleSetSummary, ModelError> {
    let set = read_set(path)?;
    Ok(ModuleSetSummary {
        modules: set
            .modules
            .iter()
            .map(|m| (m.id.clone(), m.name.clone().unwrap_or_default()))
            .collect(),
        bases: set
            .modules
            .iter()
            .filter(|m| m.connectors.iter().any(|c| c.kind == "base"))
            .map(|m| m.id.clone())
            .collect(),
    })
}

/// What a module set holds, for messages: each module's ID and name.
#[derive(Debug, Clone, PartialEq)]
pub struct ModuleSetSummary {
    /// (ID, name) per module, in file order.
    pub modules: Vec<(String, String)>,
    /// IDs of the modules with a connector of type `base`: those a module order starts with.
    pub bases: Vec<String>,
}

fn read_set(path: &Path) -> Result<set::ModuleSet, ModelError> {
    parse_set(&read(path)?, path)
}

fn parse_set(text: &str, path: &Path) -> Result<set::ModuleSet, ModelError> {
    let file: set::SetFile = serde_json::from_str(&json::quote_non_finite(text)).map_err(|e| parse_error(path, &e))?;
    set::check(file, path).map_err(|p| problem(path, p))
}

/// Reads a module set and an assembly of it from text, `path` naming both in messages (mesh
/// files are relative to its folder; the assembly's `moduleSet` is not looked up): what the
/// fuzzer drives.
///
/// # Errors
/// As [`from_timor`].
pub fn from_timor_text(set_text: &str, assembly_text: &str, path: &Path) -> Result<Model, ModelError> {
    let set = parse_set(set_text, path)?;
    let file: AssemblyFile = serde_json::from_str(&json::quote_non_finite(assembly_text)).map_err(|e| parse_error(path, &e))?;
    build(file, &set, path)
}

/// The module set an assembly names: a file or folder relative to the assembly, else a shipped
/// set of that name.
fn find_set(name: &str, assembly: &Path) -> Result<PathBuf, ModelError> {
    find_set_in(name, assembly.parent().unwrap_or(Path::new(".")), assembly)
}

/// [`find_set`] relative to `dir`; `label` names the asker in messages.
fn find_set_in(name: &str, dir: &Path, label: &Path) -> Result<PathBuf, ModelError> {
    let shipped = Path::new(SHIPPED_SETS).join(name);
    let mut searched = Vec::new();
    for root in [dir.join(name), shipped] {
        for candidate in [root.join("modules.json"), root.clone()] {
            if candidate.is_file() {
                return Ok(candidate);
            }
            let shown = candidate.display().to_string();
            if !searched.contains(&shown) {
                searched.push(shown);
            }
        }
    }
    let shipped: Vec<String> = std::fs::read_dir(SHIPPED_SETS)
        .map(|entries| {
            let mut names: Vec<String> = entries
                .filter_map(Result::ok)
                .filter(|e| e.path().join("modules.json").is_file())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect();
            names.sort();
            names
        })
        .unwrap_or_default();
    Err(ModelError::InvalidValue {
        path: label.to_path_buf(),
        element: "moduleSet".into(),
        message: format!(
            "`{name}` is no module set file, no folder holding modules.json and no shipped set (shipped: {}); searched {}",
            shipped.join(", "),
            searched.join(", ")
        ),
    })
}

/// Reads a Timor assembly into a model.
///
/// # Errors
/// [`ModelError`] naming the file and the key (`moduleOrder[3]`, `moduleConnection[1]`) or the
/// module set's element: modules that do not mate, an order that mates in several ways, a
/// closed loop or a branching chain of joints, no tool connector, bad mass properties.
pub fn from_timor(path: &Path) -> Result<Model, ModelError> {
    let text = read(path)?;
    let file: AssemblyFile = serde_json::from_str(&json::quote_non_finite(&text)).map_err(|e| parse_error(path, &e))?;
    let set_path = find_set(&file.module_set, path)?;
    let set = read_set(&set_path)?;
    build(file, &set, path)
}

/// The model of the assembly `file` of `set`; `path` names the assembly in messages.
fn build(file: AssemblyFile, set: &set::ModuleSet, path: &Path) -> Result<Model, ModelError> {
    let order: Vec<String> = file.module_order.iter().map(|id| id.0.clone()).collect();
    let instances = assembly::instances(set, &order).map_err(|p| problem(path, p))?;
    let base = match &file.base_connection {
        None => None,
        Some(list) => match list.as_slice() {
            [] => None,
            [one] => {
                let index = one
                    .first()
                    .and_then(serde_json::Value::as_u64)
                    .and_then(|v| usize::try_from(v).ok());
                let connector = one
                    .get(1)
                    .and_then(|v| v.as_str().map(str::to_string).or_else(|| v.as_u64().map(|n| n.to_string())));
                match (index, connector) {
                    (Some(i), Some(c)) => Some((i, c)),
                    _ => {
                        return Err(problem(
                            path,
                            (
                                "baseConnection[0]".into(),
                                format!(
                                    "{}; expected [module index, connector ID, 0]",
                                    serde_json::Value::Array(one.clone())
                                ),
                            ),
                        ))
                    }
                }
            }
            _ => {
                return Err(problem(
                    path,
                    (
                        "baseConnection".into(),
                        format!("holds {} base connections; a robot has one", list.len()),
                    ),
                ))
            }
        },
    };
    let built = match &file.module_connection {
        None if base.is_none() => assembly::Assembly::serial(instances),
        None => assembly::Assembly::connected(instances, &[], base),
        Some(connections) => {
            let connections: Vec<(usize, String, usize, String)> = connections
                .iter()
                .map(|(a, ca, b, cb)| (*a, ca.0.clone(), *b, cb.0.clone()))
                .collect();
            assembly::Assembly::connected(instances, &connections, base)
        }
    }
    .map_err(|p| problem(path, p))?;
    let world_from_pose = match file.base_pose.map(OneOrMany::into_vec).as_deref() {
        None | Some([]) => nalgebra::Isometry3::identity(),
        Some([one]) => json::isometry(one).map_err(|m| problem(path, ("basePose".into(), m)))?,
        Some(more) => {
            return Err(problem(
                path,
                ("basePose".into(), format!("holds {} poses; a robot has one base", more.len())),
            ))
        }
    };
    let mut diagnostics = Vec::new();
    if !file.other.is_empty() {
        diagnostics.push(Diagnostic {
            path: path.to_path_buf(),
            element: "the assembly".into(),
            message: format!(
                "{} not read (an assembly is moduleSet, moduleOrder, moduleConnection, baseConnection, basePose)",
                file.other.keys().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ")
            ),
        });
    }
    let name = file.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map_or("timor-assembly".into(), |s| s.to_string_lossy().into_owned())
    });
    assembly::model(&built, &set.path, path, name, world_from_pose, diagnostics)
}

/// The 4x4 rows Timor writes for a pose (for writing assemblies and tasks back).
pub fn pose_rows(pose: &nalgebra::Isometry3<f64>) -> [[f64; 4]; 4] {
    json::rows(pose)
}
