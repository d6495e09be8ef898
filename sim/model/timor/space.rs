//! A Timor module set as a design space: its serial assemblies by module order, named by ids
//! (`timor:SET/M1,M2,...`) that are robots wherever a robot is taken, and enumerated for sweeps.

use super::assembly::{self, Assembly};
use super::set::ModuleSet;
use crate::model::{Model, ModelError};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The prefix of a Timor assembly id.
pub const TIMOR_ID_PREFIX: &str = "timor:";

/// Most assemblies one enumeration lists: beyond, a smaller module count is asked for.
pub const MAX_ASSEMBLIES: usize = 100_000;

/// A module set read once, shared by every assembly of a sweep.
#[derive(Debug, Clone)]
pub struct TimorSet {
    /// The set as named (a shipped set's name, or the path given).
    pub name: String,
    set: Arc<ModuleSet>,
}

impl TimorSet {
    /// Reads the module set `name` names: a `modules.json`, a folder holding one, or a shipped
    /// set (relative paths from the current folder).
    ///
    /// # Errors
    /// [`ModelError`] naming the set and what is wrong in it.
    pub fn load(name: &str) -> Result<TimorSet, ModelError> {
        let label = PathBuf::from(format!("{TIMOR_ID_PREFIX}{name}"));
        let path = super::find_set_in(name, Path::new("."), &label)?;
        Ok(TimorSet {
            name: name.to_string(),
            set: Arc::new(super::read_set(&path)?),
        })
    }

    /// The `modules.json` read.
    pub fn path(&self) -> &Path {
        &self.set.path
    }

    /// The id of the assembly `order`.
    pub fn id(&self, order: &[String]) -> String {
        format!("{TIMOR_ID_PREFIX}{}/{}", self.name, order.join(","))
    }

    /// The model of the serial assembly `order` (Timor's `from_serial_modules`); `label` names
    /// it in messages.
    ///
    /// # Errors
    /// As [`super::from_timor`] for a file with this module order.
    pub fn assemble(&self, order: &[String], label: &Path) -> Result<Model, ModelError> {
        let problem = |p| super::problem(label, p);
        let instances = assembly::instances(&self.set, order).map_err(problem)?;
        let built = Assembly::serial(instances).map_err(problem)?;
        let name = order.join("-");
        assembly::model(&built, &self.set.path, label, name, nalgebra::Isometry3::identity(), Vec::new())
    }

    /// Every serial assembly of at most `max_modules` modules that is a robot: a base module
    /// first, each module mating the one before it in exactly one way, at least one moving joint,
    /// a tool connector; where the set has connectors of type `eef`, the tool is one of them (the
    /// robot ends in an end effector). Shorter assemblies first, then modules in file order: the
    /// same set gives the same list. With `fit`, the list stops at the most modules that keep it
    /// within [`MAX_ASSEMBLIES`]; the second value is the module count reached.
    ///
    /// # Errors
    /// Without `fit`, a message when more than [`MAX_ASSEMBLIES`] would be listed, naming the
    /// most modules that stay within it.
    pub fn assemblies(&self, max_modules: usize, fit: bool) -> Result<(Vec<Vec<String>>, usize), String> {
        let ids: Vec<String> = self.set.modules.iter().map(|m| m.id.clone()).collect();
        let names = |order: &[u16]| -> Vec<String> { order.iter().map(|&m| ids[usize::from(m)].clone()).collect() };
        let count = u16::try_from(ids.len()).unwrap_or(u16::MAX);
        let needs_eef = self.set.modules.iter().flat_map(|m| &m.connectors).any(|c| c.kind == "eef");
        let mut found: Vec<Vec<String>> = Vec::new();
        // The prefixes that assemble, as module indices: each level's candidates are made from
        // the last level's on the fly, so only what assembles is kept.
        let mut assembling: Vec<Vec<u16>> = Vec::new();
        for modules in 1..=max_modules {
            let candidates: Vec<Vec<u16>> = if modules == 1 {
                (0..count)
                    .filter(|&m| {
                        self.set.modules[usize::from(m)]
                            .connectors
                            .iter()
                            .filter(|c| c.kind == "base")
                            .count()
                            == 1
                    })
                    .map(|m| vec![m])
                    .collect()
            } else {
                Vec::new()
            };
            let extended = assembling.iter().flat_map(|prefix| {
                (0..count).map(move |m| {
                    let mut next = prefix.clone();
                    next.push(m);
                    next
                })
            });
            let mut robots = Vec::new();
            let mut next_assembling = Vec::new();
            let mut over = false;
            for order in candidates.into_iter().chain(extended) {
                let named = names(&order);
                // A prefix that does not assemble has no assembling extension either.
                let Some(robot) = self.judge(&named, needs_eef) else { continue };
                if robot {
                    robots.push(named);
                    if found.len() + robots.len() > MAX_ASSEMBLIES {
                        over = true;
                        break;
                    }
                }
                if modules < max_modules {
                    next_assembling.push(order);
                }
            }
            if over {
                if fit {
                    return Ok((found, modules - 1));
                }
                return Err(format!(
                    "more than {MAX_ASSEMBLIES} assemblies of up to {max_modules} modules; up to {} modules there are {} (timor:{}@{}), or leave out @N for the most that fit",
                    modules - 1,
                    found.len(),
                    self.name,
                    modules - 1
                ));
            }
            found.extend(robots);
            assembling = next_assembling;
        }
        Ok((found, max_modules))
    }

    /// Whether the serial assembly `order` assembles (`None` when not) and is a robot (ending in
    /// an `eef` tool where `needs_eef`).
    fn judge(&self, order: &[String], needs_eef: bool) -> Option<bool> {
        let instances = assembly::instances(&self.set, order).ok()?;
        let built = Assembly::serial(instances).ok()?;
        // Where the robot must end in an end effector, only an assembly whose last module has an
        // `eef` connector can be one: the model (meshes and all) is built only for those.
        let last = built.instances.last()?;
        if needs_eef && !last.module.connectors.iter().any(|c| c.kind == "eef") {
            return Some(false);
        }
        let label = Path::new(&self.name);
        let Ok(model) = assembly::model(
            &built,
            &self.set.path,
            label,
            String::new(),
            nalgebra::Isometry3::identity(),
            Vec::new(),
        ) else {
            return Some(false);
        };
        let crate::model::ModelSource::Timor { tool, .. } = &model.source else {
            return Some(false);
        };
        let tool_is_eef = || {
            built.instances.iter().any(|i| {
                i.module
                    .connectors
                    .iter()
                    .any(|c| c.kind == "eef" && format!("{}.{}", i.name, c.id) == *tool)
            })
        };
        Some(!needs_eef || tool_is_eef())
    }
}

/// A Timor assembly id's module set and module order (`timor:SET/M1,M2,...`); `None` when `text`
/// is no such id.
///
/// # Errors
/// A message when it starts like one but names no modules.
pub fn parse_timor_id(text: &str) -> Result<Option<(String, Vec<String>)>, String> {
    let Some(rest) = text.strip_prefix(TIMOR_ID_PREFIX) else {
        return Ok(None);
    };
    let Some((set, order)) = rest.rsplit_once('/') else {
        return Err(format!(
            "a Timor assembly id is {TIMOR_ID_PREFIX}SET/M1,M2,... (SET a modules.json, a folder or a shipped set; the module IDs from the base on); `{text}` names no modules"
        ));
    };
    let order: Vec<String> = order.split(',').map(str::trim).map(str::to_string).collect();
    if set.is_empty() || order.iter().any(String::is_empty) {
        return Err(format!("`{text}`: expected {TIMOR_ID_PREFIX}SET/M1,M2,... with no empty part"));
    }
    Ok(Some((set.to_string(), order)))
}

impl TimorSet {
    /// An assembly file for `order`, as Timor writes one (plus our `name` and `description`):
    /// the set by its shipped name, else by its absolute path, so the file reads anywhere.
    pub fn assembly_json(&self, order: &[String], description: &str) -> String {
        let shipped = Path::new(super::SHIPPED_SETS).join(&self.name);
        let set = if !self.name.contains('/') && shipped.exists() && !Path::new(&self.name).exists() {
            self.name.clone()
        } else {
            std::path::absolute(self.path())
                .unwrap_or_else(|_| self.path().to_path_buf())
                .to_string_lossy()
                .into_owned()
        };
        let file = serde_json::json!({
            "name": order.join("-"),
            "description": description,
            "moduleSet": set,
            "moduleOrder": order,
        });
        crate::json::to_text(&file).unwrap_or_default()
    }
}
