//! # proving-ground
//!
//! Proves or disproves robot manipulator designs in simulation, independently of the design tool
//! that proposed them.
//!
//! ```text
//! design JSON ─┐
//! URDF ────────┼─> model::Model ──> export (URDF, MJCF) ──> MuJoCo / rapier
//! MJCF ────────┘     FK, Jacobian, exact geometry, inertia
//! ```
//!
//! Stages, one module each: [`design`] (design files, catalog, presets), [`model`] (the kinematic
//! model every later stage uses), [`export`] (URDF and MJCF writers), [`engine`] (MuJoCo as the
//! kinematic oracle), [`pipeline`] (runs the stages in order).
//!
//! ```no_run
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

pub mod collide;
pub mod design;
pub mod engine;
pub mod error;
pub mod export;
pub mod frames;
pub mod ik;
pub mod model;
pub mod pipeline;
pub mod plan;
pub mod report;
pub mod scenario;
