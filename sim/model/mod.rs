//! Consumes a validated [`Design`](crate::design::Design), a URDF file or an MJCF file.
//! Produces a [`Model`]: a serial chain of movable joints with exact collision geometry and
//! inertia per link, plus forward kinematics and the geometric Jacobian. Fails with [`ModelError`].

mod arm;
mod chain;
mod dynamics;
mod from_design;
mod from_mjcf;
mod from_urdf;
mod geometry;
mod inertia;
mod kinematics;
mod mesh;
mod names;
pub(crate) mod timor;
mod trig;
mod urdf_xml;

pub use from_design::from_design;
pub use from_mjcf::{from_mjcf, from_mjcf_to, TOOL_SITE};
pub use from_urdf::{from_urdf, from_urdf_str, UrdfOptions, PACKAGE_PATH_ENV};
pub use geometry::{Collider, Shape};
pub use timor::{
    from_timor, from_timor_text, load_module_set, parse_timor_id, pose_rows, timor_kind, ModuleSetSummary, TimorKind, TimorSet,
    MAX_ASSEMBLIES, SHIPPED_SETS, TIMOR_ID_PREFIX,
};

pub use inertia::Inertial;
pub use kinematics::KinematicsWorkspace;
pub use mesh::{load_mesh, load_mesh_bytes, package_paths_from_env, resolve_mesh_uri, TriMesh};
pub use trig::sin_cos;

use nalgebra::{Isometry3, Unit, Vector3};
use serde::Serialize;
use std::path::PathBuf;

/// One robot, as every later stage sees it.
///
/// `links[0]` is the fixed base; `links[i + 1]` is moved by `joints[i]`. Link frames follow the
/// URDF convention: the frame of link `i + 1` is `frame(links[i]) * joints[i].parent_from_joint *
/// motion(q_i)`, so at `q = 0` a link frame coincides with its joint frame.
#[derive(Debug, Clone, Serialize)]
pub struct Model {
    /// Robot name (design name or URDF `<robot name>`).
    pub name: String,
    /// Where the model came from.
    pub source: ModelSource,
    /// Pose of the base link in the world.
    pub world_from_base: Isometry3<f64>,
    /// Movable joints in chain order, base to tip.
    pub joints: Vec<Joint>,
    /// `joints.len() + 1` links: the base, then one per joint.
    pub links: Vec<Link>,
    /// The tool frame relative to the last link frame.
    pub last_from_tool: Isometry3<f64>,
    /// Suspicious but usable input found while building the model.
    pub diagnostics: Vec<Diagnostic>,
}

/// Where a [`Model`] came from.
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ModelSource {
    /// A design JSON (free, economic, modular or preset).
    Design {
        /// Design mode as written in the file.
        mode: String,
        /// What the reader chose, each a sentence: the economic values read as a named value of
        /// their set (float32 rounding, see [`crate::design::SnappedValue`]).
        #[serde(skip_serializing_if = "Vec::is_empty")]
        choices: Vec<String>,
    },
    /// A URDF file.
    Urdf {
        /// The file read.
        path: PathBuf,
        /// Root link of the chain.
        base_link: String,
        /// Tip link of the chain.
        tip_link: String,
        /// Defaults the reader chose, each a sentence saying what and why (the default tip, the
        /// joints left out of the arm as gripper joints); empty when `--tip` was given.
        #[serde(skip_serializing_if = "Vec::is_empty")]
        choices: Vec<String>,
    },
    /// An MJCF file, loaded by MuJoCo.
    Mjcf {
        /// The file read.
        path: PathBuf,
        /// Body the chain hangs from (`world` when the first moving body is in `<worldbody>`).
        base_body: String,
        /// Last body of the chain (the last one carrying an arm joint).
        tip_body: String,
        /// Defaults the reader chose, each a sentence saying what and why (the tool frame, the
        /// joints left out of the arm as gripper joints).
        #[serde(skip_serializing_if = "Vec::is_empty")]
        choices: Vec<String>,
    },
    /// A Timor assembly of modules from a Timor module set.
    Timor {
        /// The assembly file read.
        path: PathBuf,
        /// The module set (`modules.json`) its modules come from.
        module_set: PathBuf,
        /// Module IDs from the base on (`moduleOrder`).
        modules: Vec<String>,
        /// The free connector that is the tool frame (`module.connector`).
        tool: String,
        /// Defaults the reader chose, each a sentence.
        #[serde(skip_serializing_if = "Vec::is_empty")]
        choices: Vec<String>,
    },
}

/// Kind of a movable joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKind {
    /// Rotation about the axis, with limits.
    Revolute,
    /// Rotation about the axis without limits.
    Continuous,
    /// Translation along the axis, with limits.
    Prismatic,
}

/// A movable joint of the chain.
#[derive(Debug, Clone, Serialize)]
pub struct Joint {
    /// Joint name.
    pub name: String,
    /// Revolute, continuous or prismatic.
    pub kind: JointKind,
    /// Joint frame in the parent link frame at `q = 0`.
    pub parent_from_joint: Isometry3<f64>,
    /// Unit axis in the joint frame.
    pub axis: Unit<Vector3<f64>>,
    /// Lower and upper position limit (rad or m); `None` for continuous joints.
    pub limits: Option<[f64; 2]>,
    /// Maximum speed (rad/s or m/s), if known.
    pub max_velocity: Option<f64>,
    /// Rated torque or force (N m or N), if known.
    pub max_effort: Option<f64>,
}

/// A rigid body of the chain with everything attached to it.
#[derive(Debug, Clone, Serialize)]
pub struct Link {
    /// Link name (for URDF: the chain link; links folded into it are listed in `merged`).
    pub name: String,
    /// Names of links rigidly attached to this one and merged into it (fixed joints, off-chain
    /// links held at their joints' zero position).
    pub merged: Vec<String>,
    /// Exact collision geometry in the link frame.
    pub colliders: Vec<Collider>,
    /// Mass properties in the link frame; `None` only for the fixed base.
    pub inertial: Option<Inertial>,
    /// Axis segments of the paper's capsule approximation of this link, in the link frame
    /// (a zero-length segment is a sphere). Radius: [`PAPER_CAPSULE_RADIUS_M`].
    pub segments: Vec<Segment>,
}

/// Radius of the capsules of the paper's approximate link model (m).
pub const PAPER_CAPSULE_RADIUS_M: f64 = 0.06;

/// A line segment in a link frame (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Segment {
    /// One end.
    pub start: Vector3<f64>,
    /// The other end.
    pub end: Vector3<f64>,
}

/// The paper's capsule approximation of a robot read from a file (URDF, MJCF), which has no DH
/// rows: each moving link's bone runs from its origin to the next joint (the tool frame for the
/// last link); a link whose next joint sits at its origin gets none.
pub(crate) fn add_bones(links: &mut [Link], joints: &[Joint], last_from_tool: &Isometry3<f64>) {
    for (i, link) in links.iter_mut().enumerate().skip(1) {
        let next = joints
            .get(i)
            .map(|j| j.parent_from_joint.translation.vector)
            .unwrap_or(last_from_tool.translation.vector);
        if next.norm() > 1e-9 {
            link.segments.push(Segment {
                start: Vector3::zeros(),
                end: next,
            });
        }
    }
}

/// A warning about usable but suspicious input.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnostic {
    /// File the warning is about.
    pub path: PathBuf,
    /// Element or field (e.g. `joint panda_joint1 <limit>`).
    pub element: String,
    /// What is suspicious and what was assumed.
    pub message: String,
}

impl std::fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "warning: {}: {}: {}", self.path.display(), self.element, self.message)
    }
}

/// Why a model could not be built.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// urdf-rs rejected the XML.
    #[error("{path}: not a valid URDF: {message}")]
    UrdfParse {
        /// The file.
        path: PathBuf,
        /// What urdf-rs said.
        message: String,
    },
    /// A link named on the command line or in a joint does not exist.
    #[error("{path}: {context}: no link named `{link}` (links: {known})")]
    UnknownLink {
        /// The file.
        path: PathBuf,
        /// Where the name came from.
        context: String,
        /// The missing name.
        link: String,
        /// Every link the file has.
        known: String,
    },
    /// The URDF is not a tree.
    #[error("{path}: {message}")]
    NotATree {
        /// The file.
        path: PathBuf,
        /// Which link breaks the tree property.
        message: String,
    },
    /// Several chains are equally long and no `--tip` was given.
    #[error(
        "{path}: the longest chains of movable joints from `{base}` tie at {length} joints, ending at {candidates}; choose one with --tip"
    )]
    AmbiguousTip {
        /// The file.
        path: PathBuf,
        /// Base link.
        base: String,
        /// Number of movable joints on each candidate chain.
        length: usize,
        /// The candidate tip links.
        candidates: String,
    },
    /// The chosen tip is not below the chosen base.
    #[error("{path}: link `{tip}` is not below base link `{base}`")]
    TipNotBelowBase {
        /// The file.
        path: PathBuf,
        /// Base link.
        base: String,
        /// Tip link.
        tip: String,
    },
    /// A joint type the serial model cannot represent sits on the chain.
    #[error("{path}: joint `{joint}` on the chain from `{base}` to `{tip}` is {kind}; only revolute, continuous, prismatic and fixed joints can be on the chain")]
    UnsupportedJoint {
        /// The file.
        path: PathBuf,
        /// Joint name.
        joint: String,
        /// Its kind (`floating`, `planar`, `mimic`).
        kind: String,
        /// Base link.
        base: String,
        /// Tip link.
        tip: String,
    },
    /// The chain has no movable joint.
    #[error("{path}: the chain from `{base}` to `{tip}` has no movable joint")]
    NoMovableJoint {
        /// The file.
        path: PathBuf,
        /// Base link.
        base: String,
        /// Tip link.
        tip: String,
    },
    /// A number is NaN, infinite or out of its range.
    #[error("{path}: {element}: {message}")]
    InvalidValue {
        /// The file.
        path: PathBuf,
        /// Element and attribute.
        element: String,
        /// The value and what was expected.
        message: String,
    },
    /// A mesh file could not be found.
    #[error("{path}: link `{link}`: mesh `{uri}` not found; searched {searched}; {hint}")]
    MissingMesh {
        /// The URDF.
        path: PathBuf,
        /// Link holding the mesh.
        link: String,
        /// The URI as written.
        uri: String,
        /// Every place searched.
        searched: String,
        /// What to do about it.
        hint: String,
    },
    /// A mesh file exists but could not be read.
    #[error("{path}: link `{link}`: cannot load mesh {mesh}: {message}")]
    BadMesh {
        /// The URDF.
        path: PathBuf,
        /// Link holding the mesh.
        link: String,
        /// The mesh file.
        mesh: PathBuf,
        /// What the loader said.
        message: String,
    },
    /// MuJoCo could not load an MJCF file.
    #[error("{path}: MuJoCo cannot load the MJCF: {message}")]
    MjcfLoad {
        /// The file.
        path: PathBuf,
        /// MuJoCo's message (it names the element and line where it can).
        message: String,
    },
    /// An MJCF element the serial model cannot represent.
    #[error("{path}: {element}: {problem}")]
    UnsupportedMjcf {
        /// The file.
        path: PathBuf,
        /// Body, joint, geom or site, by name.
        element: String,
        /// What is wrong and what is expected.
        problem: String,
    },
    /// A moving link has no usable mass (and `--strict` or no fallback applies).
    #[error("{path}: link `{link}` is moved by joint `{joint}` but {problem}")]
    BadInertia {
        /// The file.
        path: PathBuf,
        /// Link name.
        link: String,
        /// The joint moving it.
        joint: String,
        /// What is wrong.
        problem: String,
    },
}

impl ModelSource {
    /// What the reader chose (see the `choices` fields).
    pub fn choices(&self) -> &[String] {
        match self {
            ModelSource::Design { choices, .. }
            | ModelSource::Urdf { choices, .. }
            | ModelSource::Mjcf { choices, .. }
            | ModelSource::Timor { choices, .. } => choices,
        }
    }

    /// The file the model was read from; `None` for a design (its path is not kept).
    pub fn path(&self) -> Option<&std::path::Path> {
        match self {
            ModelSource::Design { .. } => None,
            ModelSource::Urdf { path, .. } | ModelSource::Mjcf { path, .. } | ModelSource::Timor { path, .. } => Some(path),
        }
    }
}

impl Model {
    /// Number of movable joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The first moving link without mass properties (a URDF without `<inertial>`), with the
    /// joint that moves it: the engines, the torque check and an MJCF export need them.
    pub fn massless_link(&self) -> Option<(&Joint, &Link)> {
        self.joints.iter().zip(&self.links[1..]).find(|(_, link)| link.inertial.is_none())
    }

    /// The same robot mounted at `world_from_mount` (a scenario's base pose): the design's own
    /// base pose is then relative to the mount.
    pub fn placed(&self, world_from_mount: &Isometry3<f64>) -> Model {
        Model {
            world_from_base: world_from_mount * self.world_from_base,
            ..self.clone()
        }
    }

    /// Link pairs `(i, i + 1)` joined by one joint: the pairs self-collision leaves out.
    pub fn adjacent_link_pairs(&self) -> Vec<(usize, usize)> {
        (0..self.joints.len()).map(|i| (i, i + 1)).collect()
    }
}
