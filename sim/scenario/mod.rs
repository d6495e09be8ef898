//! Consumes scenario JSON files (`scenarios/**/*.json`) or generator parameters.
//! Produces a validated [`Scenario`]: obstacles with exact shapes, goals in course order with
//! their tolerance modes, the robot base pose, an optional floor. Fails with [`ScenarioError`].

mod file;
pub mod generate;
mod write;

pub use file::{load, parse, ORIENTATION_TOLERANCE};
pub use write::{save, to_json};

use crate::model::Shape;
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use serde::Serialize;
use std::path::PathBuf;

/// A world a design must work in.
#[derive(Debug, Clone, Serialize)]
pub struct Scenario {
    /// Scenario name (file field `name`, else the file stem).
    pub name: String,
    /// Pose of the robot base in the world (default identity).
    pub world_from_base: Isometry3<f64>,
    /// The floor, a half-space below `z = height` in the world, if any.
    pub floor: Option<Floor>,
    /// Obstacles with exact shapes.
    pub obstacles: Vec<Obstacle>,
    /// Goals in course order.
    pub goals: Vec<Goal>,
    /// Joint configuration to start from, if the scenario gives one (rad or m).
    pub home: Option<Vec<f64>>,
    /// How the file was made, so a generated file can be regenerated.
    pub provenance: Option<Provenance>,
}

/// The floor plane.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Floor {
    /// Height of the floor surface in the world (m); everything below is solid.
    pub height: f64,
}

/// One obstacle.
#[derive(Debug, Clone, Serialize)]
pub struct Obstacle {
    /// Name (given, or `obstacle <index>`).
    pub name: String,
    /// Pose of the shape frame in the world.
    pub world_from_shape: Isometry3<f64>,
    /// Exact shape in its own frame (sphere, capsule, box, cylinder along z, or mesh).
    pub shape: Shape,
}

/// How a goal's orientation is judged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Tolerance {
    /// Full pose: position and orientation.
    Pose,
    /// Position and the tool z axis; any rotation about tool z is accepted.
    ZSymmetric,
    /// Position only.
    Position,
}

impl Tolerance {
    /// The name used in files and messages: `pose`, `z_symmetric` or `position`.
    pub fn name(self) -> &'static str {
        match self {
            Tolerance::Pose => "pose",
            Tolerance::ZSymmetric => "z_symmetric",
            Tolerance::Position => "position",
        }
    }
}

/// One target pose of the tool frame, in the world.
#[derive(Debug, Clone, Serialize)]
pub struct Goal {
    /// Name (given, or `goal <index>`).
    pub name: String,
    /// Target tool position in the world (m).
    pub position: Vector3<f64>,
    /// Target tool orientation in the world.
    pub rotation: UnitQuaternion<f64>,
    /// How the orientation is judged.
    pub tolerance: Tolerance,
}

/// Who made a scenario and how to make it again.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Provenance {
    /// Generator name (`cluttered`, `workspace`, `course`, or a tool of the user's).
    pub generator: String,
    /// Seed of the generator's random number generator.
    pub seed: u64,
    /// Every other parameter, as given to the generator.
    #[serde(default)]
    pub parameters: std::collections::BTreeMap<String, serde_json::Value>,
}

/// Why a scenario could not be used.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("cannot read scenario {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// Malformed JSON or a schema mismatch (serde's message has the line and column).
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong, with line and column.
        message: String,
    },
    /// A field has a value outside what it allows.
    #[error("{path}: {field}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The field (`goals[3].quaternion`, `obstacles[1].radius`).
        field: String,
        /// The value and what was expected.
        message: String,
    },
    /// A mesh obstacle's file is missing or unreadable.
    #[error("{path}: {field}: mesh file {mesh}: {message}")]
    Mesh {
        /// The scenario file.
        path: PathBuf,
        /// The field (`obstacles[2].file`).
        field: String,
        /// The mesh file looked for.
        mesh: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A generator was given a parameter outside its range.
    #[error("{generator} generator: {parameter} {message}")]
    Parameter {
        /// The generator (`cluttered`, `workspace`, `course`).
        generator: String,
        /// The parameter (`scale`, `count`).
        parameter: String,
        /// The value and what was expected.
        message: String,
    },
    /// A generated file could not be written.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
}
