//! Runs the stages in order; no domain logic of its own.

use crate::error::Error;
use crate::model::{self, Model, UrdfOptions};
use crate::{collide, design, export};
use std::path::{Path, PathBuf};

/// How to read the robot a run is about.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// URDF: first link of the chain (default: the root).
    pub base_link: Option<String>,
    /// URDF: last link of the chain (default: end of the longest chain of movable joints).
    pub tip_link: Option<String>,
    /// URDF: roots for `package://` URIs, searched before `ROS_PACKAGE_PATH`.
    pub package_paths: Vec<PathBuf>,
}

/// What kind of robot description a file is, from its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// Design JSON.
    Design,
    /// URDF.
    Urdf,
}

/// The kind of a robot description file.
///
/// # Errors
/// [`Error::UnknownInput`] for an extension other than `.json` or `.urdf`.
pub fn input_kind(path: &Path) -> Result<InputKind, Error> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("json") => Ok(InputKind::Design),
        Some("urdf") => Ok(InputKind::Urdf),
        _ => Err(Error::UnknownInput { path: path.to_path_buf() }),
    }
}

/// A loaded robot: the model, and the design when it came from one.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The model every stage uses.
    pub model: Model,
    /// The validated design, for design files.
    pub design: Option<design::Design>,
}

/// Reads a design JSON or a URDF into a model.
///
/// # Errors
/// The design or model stage's error, naming the file and the field or element.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Loaded, Error> {
    match input_kind(path)? {
        InputKind::Design => {
            let design = design::load(path)?;
            Ok(Loaded {
                model: model::from_design(&design),
                design: Some(design),
            })
        }
        InputKind::Urdf => {
            let urdf = UrdfOptions {
                base_link: opts.base_link.clone(),
                tip_link: opts.tip_link.clone(),
                package_paths: opts.package_paths.clone(),
            };
            Ok(Loaded {
                model: model::from_urdf(path, &urdf)?,
                design: None,
            })
        }
    }
}

/// Reads a design JSON or a URDF into a model.
///
/// # Errors
/// As [`load`].
pub fn load_model(path: &Path, opts: &LoadOptions) -> Result<Model, Error> {
    Ok(load(path, opts)?.model)
}

/// Reads and validates a scenario file.
///
/// # Errors
/// [`Error::Scenario`] naming the file and the field.
pub fn load_scenario(path: &Path) -> Result<crate::scenario::Scenario, Error> {
    Ok(crate::scenario::load(path)?)
}

/// Writes text to `path`, refusing to overwrite any of `inputs`.
///
/// # Errors
/// [`Error::WouldOverwriteInput`] or [`Error::Write`].
pub fn write_output(path: &Path, text: &str, inputs: &[&Path]) -> Result<(), Error> {
    let canonical = |p: &Path| p.canonicalize().ok();
    if let Some(target) = canonical(path) {
        if inputs.iter().any(|input| canonical(input).as_ref() == Some(&target)) {
            return Err(Error::WouldOverwriteInput { path: path.to_path_buf() });
        }
    }
    std::fs::write(path, text).map_err(|source| Error::Write {
        path: path.to_path_buf(),
        source,
    })
}

/// MJCF text for a model with default export options.
///
/// # Errors
/// [`Error::Export`].
pub fn mjcf_of(model: &Model) -> Result<String, Error> {
    Ok(export::to_mjcf(model, &export::MjcfOptions::default())?)
}

/// The exact collision world of a placed model in a scenario, with the model's structurally
/// overlapping self pairs excluded (each with its reason, see [`collide::structural_overlaps`])
/// plus `extra` exclusions (e.g. from an SRDF).
///
/// # Errors
/// [`Error::Collide`] when the geometry cannot be built or an exclusion names an unknown link.
pub fn collision_world(
    placed: &Model,
    scenario: &crate::scenario::Scenario,
    extra: &[collide::ExcludedPair],
) -> Result<collide::CollisionWorld, Error> {
    let mut excluded_pairs = collide::structural_overlaps(placed, &collide::StructuralOptions::default())?;
    excluded_pairs.extend_from_slice(extra);
    Ok(collide::world(placed, scenario, &collide::CollideOptions { excluded_pairs })?)
}
