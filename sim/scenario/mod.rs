//! Consumes scenario JSON files (`scenarios/**/*.json`) or generator parameters.
//! Produces a validated [`Scenario`]: obstacles with exact shapes, goals in course order with
//! their tolerance modes, the robot base pose, an optional floor. Fails with [`ScenarioError`].

mod file;
pub mod generate;
mod timor;
mod write;

pub use file::{load, parse, ORIENTATION_TOLERANCE};
pub use timor::{is_timor_task, load_timor_task, parse_timor_task, save_timor_task, to_timor_task};
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
    /// What reading the file left unchecked, a sentence each (a Timor task's `follow` goals);
    /// said as warnings with the report.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
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
    /// The goal's own tolerance, where its source (a Timor task) gives one other than the
    /// harness's 1 mm and 1 degree; `None` for the harness's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub task: Option<TaskTolerance>,
}

/// A goal's own tolerance, as balls around the goal the harness can reason with: IK proves and
/// reaches within 1 mm and 1 degree, which decides the task's goal only where the task's region
/// lies inside that (a proof of unreachability carries over) and the configuration found lies
/// inside the task's region (a reached goal carries over).
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskTolerance {
    /// The tolerance as the task writes it: Timor's projections with their intervals.
    pub parts: Vec<TolerancePart>,
    /// Largest position error (m) every pose with that error or less is within the task's
    /// tolerance (the radius of the ball inside its position region).
    pub inner_m: f64,
    /// Largest orientation error (rad) likewise; infinite when the task leaves orientation free.
    pub inner_rad: f64,
    /// Smallest position error (m) beyond which no pose is within the task's tolerance (the
    /// radius of the ball around its position region); infinite when unbounded.
    pub outer_m: f64,
    /// Smallest orientation error (rad) likewise; infinite when orientation is free.
    pub outer_rad: f64,
}

/// One bounded coordinate of a Timor tolerance (`r_sph` in `[0, 0.01]`, about the nominal frame).
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TolerancePart {
    /// Timor's projection name (`x`, `r_sph`, `Theta_R`, `N_z`, ...).
    pub projection: String,
    /// Lower and upper bound (m or rad).
    pub interval: [f64; 2],
    /// The frame whose axes it is measured along (`nominal` or `world`).
    pub frame: String,
}

impl std::fmt::Display for TolerancePart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} [{}, {}]", self.projection, self.interval[0], self.interval[1])?;
        if self.frame != "nominal" {
            write!(f, " in {}", self.frame)?;
        }
        Ok(())
    }
}

impl std::fmt::Display for TaskTolerance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&parts_text(&self.parts))
    }
}

/// Tolerance parts as a task writes them, comma-separated (`r_sph [0, 0.01], Theta_R [0, 0.1]`).
pub(crate) fn parts_text(parts: &[TolerancePart]) -> String {
    parts.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")
}

impl TaskTolerance {
    /// Why a proof of unreachability within the harness's tolerance does not decide the task's
    /// goal, if it does not: the task accepts poses further away.
    pub fn proof_gap(&self, harness_m: f64, harness_rad: f64, orientation_judged: bool) -> Option<String> {
        let wider = self.outer_m > harness_m || (orientation_judged && self.outer_rad > harness_rad);
        wider.then(|| {
            format!(
                "unreachable within {:.0} mm and {:.0} deg, but the task's tolerance ({}) accepts poses up to {} and {} away, which the harness does not check",
                harness_m * 1e3,
                harness_rad.to_degrees(),
                self,
                distance(self.outer_m),
                angle(self.outer_rad),
            )
        })
    }

    /// Whether a configuration this far from the goal is within the task's tolerance.
    pub fn accepts(&self, position_m: f64, orientation_rad: f64, orientation_judged: bool) -> bool {
        position_m <= self.inner_m && (!orientation_judged || orientation_rad <= self.inner_rad)
    }
}

fn distance(m: f64) -> String {
    if m.is_finite() {
        format!("{:.1} mm", m * 1e3)
    } else {
        "any distance".into()
    }
}

fn angle(rad: f64) -> String {
    if rad.is_finite() {
        format!("{:.2} deg", rad.to_degrees())
    } else {
        "any angle".into()
    }
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
