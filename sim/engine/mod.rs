//! Consumes exported models (MJCF, URDF text) and joint configurations.
//! Produces what the engines compute: today MuJoCo's kinematics, Jacobians and geom distances,
//! the independent oracles for our own. Fails with [`EngineError`] when an engine refuses a model.

mod confirm;
mod crosscheck;
mod engines;
mod gains;
mod inputs;
mod load;
mod mujoco;
mod mujoco_run;
mod rapier;
mod run;

pub use confirm::{confirm_contacts, measure_reference};
pub use crosscheck::{check_kinematics, compare_kinematics, KinematicsAgreement, KinematicsCheck, ToolElement, KINEMATICS_AGREEMENT};
pub use engines::{find, Effort, Engine, Engines, Mujoco, Rapier, ENGINES};
pub use gains::{gains, GainOptions};
pub use load::{static_load, static_load_ours, JointLoad, StaticLoad};
pub use mujoco::{check_version, GeomDistance, MujocoGeomDistance, MujocoKinematics, MujocoSample, MUJOCO_VERSION};
pub use mujoco_run::{replay_mujoco, run_mujoco};
pub use rapier::{replay_rapier, run_rapier};
pub use run::{ContactInterval, ContactRecorder, EngineRun, Gains, GoalHold, RunOptions};

use std::path::PathBuf;

/// Why an engine could not run a model.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// MuJoCo refused the model.
    #[error("MuJoCo could not load {source_name}: {message}")]
    MujocoLoad {
        /// File path or a description of the in-memory text.
        source_name: String,
        /// MuJoCo's message.
        message: String,
    },
    /// The model lacks a named element.
    #[error("MuJoCo model {source_name} has no {kind} named `{name}`")]
    MissingElement {
        /// File path or a description of the in-memory text.
        source_name: String,
        /// `body`, `joint` or `site`.
        kind: &'static str,
        /// The name looked for.
        name: String,
    },
    /// MuJoCo cannot be used: not loaded, or not the pinned version.
    #[error(transparent)]
    Mujoco(#[from] crate::mujoco::MujocoError),
    /// The model could not be written as MJCF for an engine run.
    #[error("robot `{robot}`: cannot export the model for MuJoCo: {source}")]
    Export {
        /// Robot name.
        robot: String,
        /// The exporter's error.
        #[source]
        source: crate::export::ExportError,
    },
    /// A run's integration step is not a positive number of seconds.
    #[error("the integration step must be positive and finite, got {timestep_s} s")]
    InvalidTimestep {
        /// The step given (s).
        timestep_s: f64,
    },
    /// A configuration handed to an engine does not have one value per joint.
    #[error("robot `{robot}`: {context} {index} has {found} joint values, expected {expected}")]
    ConfigurationLength {
        /// Robot name.
        robot: String,
        /// What the configuration is (`sample`, `path waypoint`).
        context: &'static str,
        /// Its index.
        index: usize,
        /// Values given.
        found: usize,
        /// Joints of the robot.
        expected: usize,
    },
    /// The model is not one chain of links joined by its joints.
    #[error("robot `{robot}`: {links} links for {joints} joints, expected one more link than joints")]
    Chain {
        /// Robot name.
        robot: String,
        /// Links of the model.
        links: usize,
        /// Joints of the model.
        joints: usize,
    },
    /// The controller gains do not have one value per joint.
    #[error("robot `{robot}`: gains for {stiffness} and {damping} joints (stiffness, damping), the model has {expected}")]
    GainsLength {
        /// Robot name.
        robot: String,
        /// Stiffness values given.
        stiffness: usize,
        /// Damping values given.
        damping: usize,
        /// Joints of the model.
        expected: usize,
    },
    /// A dynamic run was given a path without a segment.
    #[error("robot `{robot}`: the path to follow has no segment")]
    EmptyPath {
        /// Robot name.
        robot: String,
    },
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// rapier could not be given the model or the run's inputs.
    #[error("rapier cannot run `{model}`: {message}")]
    Rapier {
        /// Model name.
        model: String,
        /// What is wrong, naming the joint, link, collider or value.
        message: String,
    },
}
