//! What a sweep runs: design arguments (files, folders, globs, catalogs) resolved to an ordered,
//! de-duplicated list of designs, and scenario arguments resolved to loaded scenarios.

use super::SweepError;
use crate::design::catalog::{Preset, SlotOption};
use crate::design::Design;
use crate::pipeline::{self, LoadOptions, Loaded};
use crate::scenario::Scenario;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Slots of a catalog robot: one connection slot after each of its six joints.
pub const CATALOG_SLOTS: usize = 6;

/// The built-in design sets a sweep can name instead of files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Catalog {
    /// Every 6-slot robot of the reference module catalog: 5^6 = 15 625 designs (the paper's
    /// brute force).
    Modular6,
    /// The industrial presets of the paper's Table 1 (UR15, UR20, ABB IRB 2600).
    Table1,
    /// Every industrial preset.
    Presets,
}

impl Catalog {
    /// The name used on the command line and in `sweep.json`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Modular6 => "modular6",
            Self::Table1 => "table1",
            Self::Presets => "presets",
        }
    }

    /// The catalog called `name`.
    pub fn named(name: &str) -> Option<Self> {
        [Self::Modular6, Self::Table1, Self::Presets].into_iter().find(|c| c.name() == name)
    }

    fn entries(self) -> Vec<DesignEntry> {
        match self {
            Self::Modular6 => (0..SlotOption::ALL.len().pow(CATALOG_SLOTS as u32)).map(modular6).collect(),
            Self::Table1 => [Preset::Ur15, Preset::Ur20, Preset::AbbIrb2600].into_iter().map(preset).collect(),
            Self::Presets => Preset::ALL.into_iter().map(preset).collect(),
        }
    }
}

/// The `index`-th 6-slot robot, slot 1 the most significant digit in base 5 (catalog order).
pub fn modular6_slots(index: usize) -> [SlotOption; CATALOG_SLOTS] {
    let base = SlotOption::ALL.len();
    let mut slots = [SlotOption::Direct; CATALOG_SLOTS];
    let mut rest = index;
    for slot in slots.iter_mut().rev() {
        *slot = SlotOption::ALL[rest % base];
        rest /= base;
    }
    slots
}

fn modular6(index: usize) -> DesignEntry {
    catalog_entry(&modular6_slots(index))
}

/// The catalog robot of `slots`, with its id (`modular6/D-Ls-...` for six slots).
pub fn catalog_entry(slots: &[SlotOption]) -> DesignEntry {
    DesignEntry {
        id: crate::design::catalog::modular_id(slots),
        source: DesignSource::Modular(slots.to_vec()),
        sha256: None,
    }
}

fn preset(preset: Preset) -> DesignEntry {
    DesignEntry {
        id: crate::design::catalog::preset_id(preset),
        source: DesignSource::Preset(preset),
        sha256: None,
    }
}

/// One design of a sweep.
#[derive(Debug, Clone)]
pub struct DesignEntry {
    /// Unique id: the file path as resolved, or `modular6/D-Ls-...`, `preset/UR20`.
    pub id: String,
    /// Where the design comes from.
    pub source: DesignSource,
    /// Files: SHA-256 of the file's bytes and of the model read from it.
    pub sha256: Option<String>,
}

/// How a sweep's design is built.
#[derive(Debug, Clone)]
pub enum DesignSource {
    /// A design, URDF or MJCF file, loaded once when the sweep starts.
    File(Arc<Loaded>),
    /// A modular robot of the reference catalog, built when its pairs run.
    Modular(Vec<SlotOption>),
    /// An industrial preset, built when its pairs run.
    Preset(Preset),
    /// A serial assembly of a Timor module set (its module order), built when its pairs run.
    Timor(Arc<crate::model::TimorSet>, Vec<String>),
}

impl DesignEntry {
    /// The loaded design (built for catalog entries, shared for files).
    pub fn load(&self) -> Loaded {
        match &self.source {
            DesignSource::File(loaded) => (**loaded).clone(),
            DesignSource::Modular(slots) => from_design(Design::modular(&self.id, slots)),
            DesignSource::Preset(preset) => from_design(Design::preset(&self.id, *preset)),
            DesignSource::Timor(set, order) => Loaded {
                // Every listed order was assembled once when the sweep resolved it.
                model: set
                    .assemble(order, Path::new(&self.id))
                    .unwrap_or_else(|e| unreachable!("{}: assembled when listed: {e}", self.id)),
                design: None,
            },
        }
    }
}

fn from_design(design: Design) -> Loaded {
    Loaded {
        model: crate::model::from_design(&design),
        design: Some(design),
    }
}

/// Most modules of an assembly `timor:SET` lists, fewer where more would list over
/// [`crate::model::MAX_ASSEMBLIES`] (`timor:SET@N` for another count).
pub const DEFAULT_TIMOR_MODULES: usize = 8;

/// Design files a sweep reads from a folder.
const DESIGN_EXTENSIONS: [&str; 4] = ["json", "urdf", "xml", "mjcf"];

/// Resolves design arguments in order: `catalog:NAME`, a folder (its design files, sorted, not
/// recursive), a glob (sorted matches) or a file. The same design twice counts once, at its first
/// place.
///
/// # Errors
/// [`SweepError::Designs`] for an unknown catalog, a glob matching nothing or a bad pattern, and
/// the load error of any design file (naming the file and the field).
pub fn resolve_designs(arguments: &[String], load: &LoadOptions) -> Result<Vec<DesignEntry>, SweepError> {
    let mut entries: Vec<DesignEntry> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let mut push = |entry: DesignEntry, entries: &mut Vec<DesignEntry>| {
        if seen.insert(entry.id.clone()) {
            entries.push(entry);
        }
    };
    for argument in arguments {
        // A Timor module set as a design space: `timor:SET` (up to 8 modules) or `timor:SET@N`.
        if let Some(rest) = argument.strip_prefix(crate::model::TIMOR_ID_PREFIX).filter(|r| !r.contains(',')) {
            let designs_error = |message: String| SweepError::Designs {
                argument: argument.clone(),
                message,
            };
            let (name, modules, fit) = match rest.rsplit_once('@') {
                Some((name, n)) => (
                    name,
                    n.parse::<usize>()
                        .ok()
                        .filter(|n| (2..=16).contains(n))
                        .ok_or_else(|| designs_error(format!("`@{n}`: expected the most modules an assembly has, 2 to 16")))?,
                    false,
                ),
                None => (rest, DEFAULT_TIMOR_MODULES, true),
            };
            let set = Arc::new(crate::model::TimorSet::load(name).map_err(|e| SweepError::Load(Box::new(e.into())))?);
            let (orders, modules) = set.assemblies(modules, fit).map_err(designs_error)?;
            if orders.is_empty() {
                return Err(designs_error(format!(
                    "module set {} has no serial assembly of up to {modules} modules that is a robot",
                    set.path().display()
                )));
            }
            for order in orders {
                let id = set.id(&order);
                push(
                    DesignEntry {
                        id,
                        source: DesignSource::Timor(set.clone(), order),
                        sha256: None,
                    },
                    &mut entries,
                );
            }
            continue;
        }
        if let Some(name) = argument.strip_prefix("catalog:") {
            let catalog = Catalog::named(name).ok_or_else(|| SweepError::Designs {
                argument: argument.clone(),
                message: "unknown catalog; expected catalog:modular6, catalog:table1 or catalog:presets".into(),
            })?;
            for entry in catalog.entries() {
                push(entry, &mut entries);
            }
            continue;
        }
        // One Timor assembly by its id (a file of that name wins).
        if !Path::new(argument).exists() {
            if let Some((name, order)) = crate::model::parse_timor_id(argument).map_err(|message| SweepError::Designs {
                argument: argument.clone(),
                message,
            })? {
                let set = Arc::new(crate::model::TimorSet::load(&name).map_err(|e| SweepError::Load(Box::new(e.into())))?);
                set.assemble(&order, Path::new(argument))
                    .map_err(|e| SweepError::Load(Box::new(e.into())))?;
                push(
                    DesignEntry {
                        id: set.id(&order),
                        source: DesignSource::Timor(set, order),
                        sha256: None,
                    },
                    &mut entries,
                );
                continue;
            }
        }
        // One catalog robot by its id, as sweeps and the GA print them (a file of that name wins).
        if !Path::new(argument).exists() {
            let id = crate::design::catalog::parse_id(argument).map_err(|message| SweepError::Designs {
                argument: argument.clone(),
                message,
            })?;
            match id {
                Some(crate::design::catalog::CatalogId::Modular(slots)) => {
                    push(catalog_entry(&slots), &mut entries);
                    continue;
                }
                Some(crate::design::catalog::CatalogId::Preset(p)) => {
                    push(preset(p), &mut entries);
                    continue;
                }
                None => {}
            }
        }
        for path in expand(argument, &DESIGN_EXTENSIONS, "design")? {
            let loaded = pipeline::load(&path, load).map_err(|e| SweepError::Load(Box::new(e)))?;
            let bytes = crate::files::read_bytes(&path, crate::limits::MAX_TEXT_BYTES).map_err(|source| SweepError::Read {
                path: path.clone(),
                source,
            })?;
            // The model's text covers what the file names (meshes, included files) too.
            let mut identity = bytes;
            identity.extend_from_slice(format!("{:?}", loaded.model).as_bytes());
            push(
                DesignEntry {
                    id: path_id(&path),
                    source: DesignSource::File(Arc::new(loaded)),
                    sha256: Some(super::store::sha256_hex(&identity)),
                },
                &mut entries,
            );
        }
    }
    if entries.is_empty() {
        return Err(SweepError::Designs {
            argument: arguments.join(" "),
            message: "no designs: give design files, folders, globs or catalog:modular6".into(),
        });
    }
    Ok(entries)
}

/// One scenario of a sweep.
#[derive(Debug, Clone)]
pub struct ScenarioEntry {
    /// Unique id: the file path as resolved.
    pub id: String,
    /// The loaded scenario.
    pub scenario: Scenario,
    /// SHA-256 of the file's bytes: a resumed or merged sweep must have read the same tasks.
    pub sha256: String,
}

/// Resolves scenario arguments (files, folders of `.json`, globs), sorted within each argument,
/// duplicates once.
///
/// # Errors
/// [`SweepError::Scenarios`] for a glob matching nothing, and any scenario's load error.
pub fn resolve_scenarios(arguments: &[String]) -> Result<Vec<ScenarioEntry>, SweepError> {
    let mut entries: Vec<ScenarioEntry> = Vec::new();
    for argument in arguments {
        for path in expand(argument, &["json"], "scenario")? {
            let id = path_id(&path);
            if entries.iter().any(|e| e.id == id) {
                continue;
            }
            let bytes = crate::files::read_bytes(&path, crate::limits::MAX_TEXT_BYTES).map_err(|source| SweepError::Read {
                path: path.clone(),
                source,
            })?;
            // Parsed from the bytes hashed, so the hash is of what was run.
            let scenario = crate::scenario::parse(&String::from_utf8_lossy(&bytes), &path)
                .map_err(|e| SweepError::Load(Box::new(crate::error::Error::from(e))))?;
            entries.push(ScenarioEntry {
                id,
                scenario,
                sha256: super::store::sha256_hex(&bytes),
            });
        }
    }
    if entries.is_empty() {
        return Err(SweepError::Scenarios {
            argument: arguments.join(" "),
            message: "no scenarios: give --scenarios with files, folders or globs".into(),
        });
    }
    Ok(entries)
}

/// A file's id in a sweep: its path as given, spelled one way (no `.` components; a path under
/// the current folder relative to it), so `./d.json`, `d.json` and `$PWD/d.json` are one design
/// for resume, merge and the list's duplicates. `..` stays (lexically it may cross a link).
fn path_id(path: &Path) -> String {
    let relative = std::env::current_dir()
        .ok()
        .and_then(|here| path.strip_prefix(here).ok().map(Path::to_path_buf))
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or_else(|| path.to_path_buf());
    let id: PathBuf = relative
        .components()
        .filter(|c| !matches!(c, std::path::Component::CurDir))
        .collect();
    id.to_string_lossy().into_owned()
}

/// The files an argument names: a folder's files with one of `extensions` (sorted), a glob's
/// matches (sorted), or the path itself.
fn expand(argument: &str, extensions: &[&str], what: &str) -> Result<Vec<PathBuf>, SweepError> {
    let path = Path::new(argument);
    let error = |message: String| match what {
        "scenario" => SweepError::Scenarios {
            argument: argument.to_string(),
            message,
        },
        _ => SweepError::Designs {
            argument: argument.to_string(),
            message,
        },
    };
    if path.is_dir() {
        let read = std::fs::read_dir(path).map_err(|e| error(format!("cannot list the folder: {e}")))?;
        let mut files: Vec<PathBuf> = read
            .filter_map(Result::ok)
            .map(|entry| entry.path())
            .filter(|p| p.is_file())
            .filter(|p| {
                p.extension()
                    .and_then(|e| e.to_str())
                    .is_some_and(|e| extensions.contains(&e.to_ascii_lowercase().as_str()))
            })
            .collect();
        files.sort();
        if files.is_empty() {
            return Err(error(format!("the folder holds no {what} files (.{})", extensions.join(", ."))));
        }
        return Ok(files);
    }
    if argument.contains(['*', '?', '[']) {
        let matches = glob::glob(argument).map_err(|e| error(format!("bad pattern: {e}")))?;
        let mut files: Vec<PathBuf> = matches.filter_map(Result::ok).filter(|p| p.is_file()).collect();
        files.sort();
        if files.is_empty() {
            return Err(error("the pattern matches no file".into()));
        }
        return Ok(files);
    }
    Ok(vec![path.to_path_buf()])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catalog_order_is_base_five_with_slot_one_most_significant() {
        assert_eq!(modular6_slots(0), [SlotOption::Direct; 6]);
        assert_eq!(modular6_slots(1)[5], SlotOption::IShort);
        assert_eq!(modular6_slots(5)[4], SlotOption::IShort);
        assert_eq!(modular6_slots(15_624), [SlotOption::LLong; 6]);
        let entries = Catalog::Modular6.entries();
        assert_eq!(entries.len(), 15_625);
        let mut ids: Vec<&str> = entries.iter().map(|e| e.id.as_str()).collect();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), 15_625, "catalog ids are unique");
    }

    #[test]
    fn one_file_spelled_three_ways_has_one_id() {
        let here = std::env::current_dir().expect("current folder");
        let absolute = here.join("designs").join("ur5e.json");
        for spelling in [Path::new("designs/ur5e.json"), Path::new("./designs/./ur5e.json"), &absolute] {
            assert_eq!(path_id(spelling), "designs/ur5e.json", "{}", spelling.display());
        }
        assert_eq!(path_id(Path::new("/elsewhere/./d.json")), "/elsewhere/d.json");
        assert_eq!(path_id(Path::new("../d.json")), "../d.json");
    }

    #[test]
    fn a_catalog_robot_is_the_modular_design_of_its_slots() {
        let entry = modular6(3_000);
        let loaded = entry.load();
        let design = loaded.design.expect("catalog entries are designs");
        assert_eq!(design.modules.as_deref(), Some(&modular6_slots(3_000)[..]));
        assert_eq!(loaded.model.dof(), 6);
    }
}
