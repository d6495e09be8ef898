//! # proving-ground
//!
//! Proves or disproves robot manipulator designs in simulation, independently of the design tool
//! that proposed them.
//!
//! ```text
//! design JSON ─┐                                                    ┌─> rapier (dynamic, replay)
//! URDF ────────┼─> model::Model ─> collide + ik ─> plan ─> engine ──┤
//! MJCF ────────┘   FK, Jacobian,   exact distances, trajectory,     └─> MuJoCo (dynamic, replay,
//!                  geometry,       every IK solution certified segments,    static load)
//!                  inertia   scenario ──┘          timing           └────────> report: findings,
//!                                                                               verdict
//! ```
//!
//! Stages, one module each: [`design`] (design files, catalog, presets), [`model`] (the kinematic
//! model every later stage uses), [`export`] (URDF and MJCF writers), [`scenario`] (courses and
//! their generators), [`collide`] (exact and approximate distances), [`ik`] (every collision-free
//! solution of a goal), [`plan`] (the trajectory, certified continuous checking, timing),
//! [`engine`] (rapier and MuJoCo runs, the static load, MuJoCo as kinematic oracle), [`report`]
//! (findings and the verdict), [`render`] (pictures and the HTML report). Below them
//! [`mujoco`] loads the MuJoCo library at first use and checks its version. Above them
//! [`pipeline`] runs the stages in order ([`pipeline::validate`]); [`run`] is one validation run
//! as `validate-design` does it ([`validate`]: the robot file, SRDF, strict checks, tolerance
//! override, exports, MuJoCo's kinematics check, the validation and its report), the entry
//! point every front end calls; experiments ([`sweep`], [`optimize`], [`suite`]) build on both.
//!
//! ```no_run
//! let opts = proving_ground::Options {
//!     scenario: Some("scenarios/cluttered/task-07.json".into()),
//!     ..Default::default()
//! };
//! let run = proving_ground::validate("designs/ur5e.json".as_ref(), &opts, &proving_ground::progress::Silent)?;
//! println!("{:?}", run.outcome());
//! let model = proving_ground::pipeline::load_model(
//!     std::path::Path::new("designs/paper-real-world.json"),
//!     &proving_ground::pipeline::LoadOptions::default(),
//! )?;
//! let tool = model.tool_pose(&vec![0.0; model.dof()]);
//! println!("{} joints, tool at {:?}", model.dof(), tool.translation);
//! # Ok::<(), proving_ground::error::Error>(())
//! ```
//!
//! ## Known limitations
//! - URDF: `<visual>`, `<transmission>`, `<gazebo>`, `<safety_controller>`, `<calibration>` and
//!   `<dynamics>` are ignored; links off the chain are held at their joints' zero position.
//! - MJCF input (loaded by MuJoCo): a serial chain of hinge and slide joints only (one joint per
//!   body; free and ball joints, branching moving bodies, slide joints without `range` and a
//!   joint `ref` other than 0 are errors). Jointless bodies are merged into the link above them.
//!   Sphere, capsule, cylinder, box and mesh geoms are read exactly (meshes as MuJoCo's f32 copy);
//!   an ellipsoid becomes its enclosing sphere (a warning); visual geoms (`contype` and
//!   `conaffinity` 0) are skipped; planes and height fields are ignored on the base and errors
//!   elsewhere. No velocity limits; ratings come from `actuatorfrcrange` or actuator
//!   `forcerange`. The tool frame is the site `tool`, else the last moving body's frame.
//! - Trajectories join the goals by straight joint-space segments, else a certified RRT-Connect
//!   detour within a sample budget; a goal it does not join in the budget is `no_path`
//!   (undecided), not a failure.
//! - rapier runs in f32 and its narrow phase on cylinders can be off by up to 1.25 cm: its
//!   contacts are re-measured in exact geometry before they count. rapier 0.36 does not report a
//!   multibody's motor impulses: its effort is the control law on the state after each step.

pub mod collide;
pub mod convex;
pub mod design;
pub mod engine;
pub mod error;
pub mod export;
pub mod files;
pub mod frames;
pub mod ik;
pub mod json;
pub mod limits;
pub mod model;
pub mod mujoco;
pub mod optimize;
pub mod pipeline;
pub mod plan;
pub mod progress;
pub mod render;
pub mod report;
pub mod run;
pub mod scenario;
pub mod srdf;
pub mod suite;
pub mod sweep;
pub mod workflow;
pub mod xml;

pub use run::{validate, Options, Run};

/// The README's Rust examples, compiled as doc tests so they cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeExamples;
