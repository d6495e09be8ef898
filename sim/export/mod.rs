//! Consumes a [`Model`] (and for [`scene_mjcf`] a scenario).
//! Produces URDF text ([`to_urdf`], through urdf-rs) and MJCF text ([`to_mjcf`], written directly;
//! [`scene_mjcf`], the robot in its scenario).
//! Fails with [`ExportError`]: names that would clash, unreferenceable meshes, massless moving links.

mod mjcf;
mod scene;
mod urdf;

pub use mjcf::{to_mjcf, MjcfOptions};
pub use scene::scene_mjcf;
pub use urdf::{to_urdf, written_meshes, UrdfExportOptions};

use crate::model::Model;
use std::collections::HashSet;
use std::path::PathBuf;

/// Why a model could not be exported.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// A mesh collider whose file cannot be named in the output (no file, or a path that is not
    /// UTF-8).
    #[error("robot `{robot}`: link `{link}`: collider {collider} (`{label}`): mesh file `{}` cannot be referenced: {problem}", .file.display())]
    MeshPath {
        /// Robot name.
        robot: String,
        /// Link holding the mesh.
        link: String,
        /// Index of the collider in the link.
        collider: usize,
        /// The collider's label.
        label: String,
        /// The mesh file as recorded in the model.
        file: PathBuf,
        /// What is wrong with it.
        problem: &'static str,
    },
    /// A link moved by a joint has no mass properties; MuJoCo would give its body zero mass.
    #[error("robot `{robot}`: link `{link}` is moved by joint `{joint}` but has no inertial; its mass would be 0")]
    MissingInertial {
        /// Robot name.
        robot: String,
        /// Link name.
        link: String,
        /// The joint moving it.
        joint: String,
    },
    /// Two elements of one kind would get the same name (model names clashing with each other or
    /// with the names the exporter adds: `world`, `tool`, `world_to_<base>`, `<last>_to_tool`).
    #[error("robot `{robot}`: {format}: {kind} name `{name}` would be used twice")]
    DuplicateName {
        /// Robot name.
        robot: String,
        /// `URDF` or `MJCF`.
        format: &'static str,
        /// `link`, `joint` or `body`.
        kind: &'static str,
        /// The clashing name.
        name: String,
    },
    /// A per-joint gain vector in [`MjcfOptions`] has the wrong length.
    #[error("robot `{robot}`: MjcfOptions::{gain} has {given} values but the model has {joints} joints")]
    GainCount {
        /// Robot name.
        robot: String,
        /// `kp`, `kv` or `keyframe` (a key's configuration).
        gain: &'static str,
        /// Number of values given.
        given: usize,
        /// Number of joints.
        joints: usize,
    },
    /// The model is not a serial chain (`links.len()` must be `joints.len() + 1`).
    #[error("robot `{robot}`: {links} links for {joints} joints; a serial chain has one link more than joints")]
    ChainShape {
        /// Robot name.
        robot: String,
        /// Number of links.
        links: usize,
        /// Number of joints.
        joints: usize,
    },
}

/// Checks the serial-chain invariant every writer indexes by.
/// Space-separated numbers, each at full precision (the shortest text that reads back to the
/// same bits), as URDF and MJCF attributes hold them: tiny and huge magnitudes in exponent form,
/// since Rust's plain form writes every zero (a mesh vertex of 2e-35 m, as the ROBOTIS Open
/// Manipulator's STLs hold, took 55 characters) and MuJoCo refuses such a number ("number is
/// too large").
fn numbers(values: impl IntoIterator<Item = f64>) -> String {
    values.into_iter().map(number).collect::<Vec<_>>().join(" ")
}

/// One number as [`numbers`] writes it.
fn number(value: f64) -> String {
    let magnitude = value.abs();
    if value != 0.0 && !(1e-4..1e15).contains(&magnitude) {
        format!("{value:e}")
    } else {
        value.to_string()
    }
}

fn check_chain(model: &Model) -> Result<(), ExportError> {
    if model.links.len() == model.joints.len() + 1 {
        Ok(())
    } else {
        Err(ExportError::ChainShape {
            robot: model.name.clone(),
            links: model.links.len(),
            joints: model.joints.len(),
        })
    }
}

/// Fails on the first name that occurs twice.
fn check_unique<'a>(
    model: &Model,
    format: &'static str,
    kind: &'static str,
    names: impl IntoIterator<Item = &'a str>,
) -> Result<(), ExportError> {
    let mut seen = HashSet::new();
    for name in names {
        if !seen.insert(name) {
            return Err(ExportError::DuplicateName {
                robot: model.name.clone(),
                format,
                kind,
                name: name.to_string(),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    /// Tiny and huge magnitudes in exponent form, the rest plain; every one reads back to the
    /// same bits.
    #[test]
    fn numbers_are_short_and_exact() {
        for value in [
            2.0733839557543838e-35,
            -1e-300,
            5e-17,
            1.5e20,
            0.0,
            -0.0,
            0.25,
            1e-4,
            123456.789,
            f64::MIN_POSITIVE,
        ] {
            let text = super::number(value);
            assert!(text.len() <= 24, "{value}: {text}");
            assert_eq!(text.parse::<f64>().map(f64::to_bits), Ok(value.to_bits()), "{text}");
        }
        assert_eq!(super::number(2.5e-35), "2.5e-35");
        assert_eq!(super::number(0.001), "0.001");
    }
}
