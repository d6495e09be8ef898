//! The top-level error: one variant per stage. An error means "could not evaluate"; a design
//! that fails its checks is not an error.

use std::path::PathBuf;

/// Anything that stops proving-ground from evaluating a design.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The design file is unusable.
    #[error(transparent)]
    Design(#[from] crate::design::DesignError),
    /// The robot model could not be built.
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
    /// The model could not be written as URDF or MJCF.
    #[error(transparent)]
    Export(#[from] crate::export::ExportError),
    /// The collision geometry could not be built.
    #[error(transparent)]
    Collide(#[from] crate::collide::CollideError),
    /// The scenario file is unusable, or a generated one could not be written.
    #[error(transparent)]
    Scenario(#[from] crate::scenario::ScenarioError),
    /// The scenario does not fit the robot (its home configuration).
    #[error(transparent)]
    Plan(#[from] crate::plan::PlanError),
    /// MuJoCo refused a model.
    #[error(transparent)]
    Engine(#[from] crate::engine::EngineError),
    /// A picture could not be made.
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    /// An input file type proving-ground does not read.
    #[error("{path}: {reason}")]
    UnknownInput {
        /// The file.
        path: PathBuf,
        /// What the input is, and what would be read.
        reason: String,
    },
    /// An output file could not be written.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A picture folder is a file, or holds a file of another kind under one of the names the
    /// pictures use.
    #[error("cannot write pictures into {path}: {message}")]
    PictureFolder {
        /// The folder.
        path: PathBuf,
        /// What is in the way.
        message: String,
    },
    /// An output file would overwrite an input.
    #[error("refusing to write {path}: this run read that file (the design, the scenario, a mesh, an included file, or a link to one)")]
    WouldOverwriteInput {
        /// The file.
        path: PathBuf,
    },
    /// A scenario obstacle has the name of a robot link.
    #[error("scenario {scenario}: `{field}` is `{name}`, the name of a link of {robot}; rename the obstacle")]
    NameClash {
        /// Scenario name.
        scenario: String,
        /// The obstacle's field.
        field: String,
        /// The name.
        name: String,
        /// The robot.
        robot: String,
    },
    /// A full validation of a robot with a moving link that has no mass (a URDF without
    /// `<inertial>`): its engines and torque check need one.
    #[error("{robot}: link `{link}` is moved by joint `{joint}` but has no <inertial>; its mass would be 0, and the engines and the torque check need it (--reach-only checks reach, IK and collisions without them)")]
    NoMass {
        /// The robot.
        robot: String,
        /// The link.
        link: String,
        /// The joint moving it.
        joint: String,
    },
    /// The caller stopped the run ([`crate::progress::Progress::stopped`]) before it finished.
    #[error("stopped before the run finished")]
    Stopped,
    /// The report could not be serialised (a bug: every field is plain data).
    #[error("cannot write the report as JSON: {message}")]
    Report {
        /// serde_json's message.
        message: String,
    },
    /// A run option has a value it does not allow (`options` of the library's callers).
    #[error("option `{name}`: {message}")]
    Option {
        /// The option, named as on the command line with `_` for `-` (`ik_seeds`).
        name: &'static str,
        /// The value and what was expected.
        message: String,
    },
    /// An SRDF file is unusable, or names a link the model does not have.
    #[error(transparent)]
    Srdf(#[from] crate::srdf::SrdfError),
    /// Warnings were found and `--strict` was given.
    #[error("{count} warning(s) and --strict was given:\n{list}")]
    Strict {
        /// Number of warnings.
        count: usize,
        /// The warnings, one per line.
        list: String,
    },
}
