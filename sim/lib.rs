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
//! - MJCF input: a serial chain of hinge and slide joints only; geoms of type sphere, capsule
//!   (as a cylinder plus two spheres), cylinder, box and mesh are read.

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
