//! Consumes exported models (MJCF, URDF text) and joint configurations.
//! Produces what the engines compute: today MuJoCo's kinematics, Jacobians and geom distances,
//! the independent oracles for our own. Fails with [`EngineError`] when an engine refuses a model.

mod crosscheck;
mod mujoco;
mod run;

pub use crosscheck::{compare_kinematics, KinematicsAgreement, ToolElement};
pub use mujoco::{check_version, GeomDistance, MujocoGeomDistance, MujocoKinematics, MujocoSample, MUJOCO_VERSION};
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
    /// The linked MuJoCo is not the version the project pins.
    #[error("linked MuJoCo is {found}, proving-ground was built and verified against {expected} (mujoco/PIN)")]
    Version {
        /// Version reported by the library.
        found: String,
        /// Version pinned.
        expected: &'static str,
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
}
