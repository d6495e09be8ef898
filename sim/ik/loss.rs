//! The paper's objective at a configuration: `w_d d(g, q) + w_col c_col(q)` per goal, with the
//! pose distance `d = ||p_g - p|| + w_r * rotational distance` and the collision cost summed over
//! every checked pair of the paper's capsule model within the threshold (see [`super::refine`]).
//! The rotational distance is the angle `arccos((tr(R_g^T R) - 1) / 2)` (rad) for `pose`, the
//! paper's loss form `(1 - z^T R_g^T R z) / 2` for `z_symmetric`, and 0 for `position`.

use super::refine::{COLLISION_THRESHOLD_M, COLLISION_WEIGHT};
use crate::collide::{approximate_distances, CollisionWorld, Distances, QueryOptions};
use crate::model::Model;
use crate::scenario::{Goal, Tolerance};
use nalgebra::Vector3;
use serde::Serialize;

/// The paper's weight of the pose distance (Table A: `w_d = 5`).
pub const DISTANCE_WEIGHT: f64 = 5.0;
/// The paper's weight of the rotational distance inside `d` (Table A: `w_r = 0.5`, applied to
/// the angle in radians).
pub const ROTATION_WEIGHT: f64 = 0.5;
/// The paper's weight of the hardware cost (Table A: `w_c = 0.1`).
pub const HARDWARE_WEIGHT: f64 = 0.1;

/// The paper's loss terms of one goal at one configuration, unweighted.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LossTerms {
    /// Pose distance `d` (m, with the rotation weighted by `w_r`).
    pub distance: f64,
    /// Collision cost `c_col`: the summed pair losses of the capsule model.
    pub collision: f64,
}

impl LossTerms {
    /// `w_d d + w_col c_col`.
    pub fn weighted(&self) -> f64 {
        DISTANCE_WEIGHT * self.distance + COLLISION_WEIGHT * self.collision
    }
}

/// The loss terms of `goal` at `q` in `world` (built for `model`).
pub fn paper_loss_terms(model: &Model, world: &CollisionWorld, goal: &Goal, q: &[f64]) -> LossTerms {
    let mut ws = model.workspace();
    model.forward(q, &mut ws);
    let tool = ws.tool_in_world;
    let position = (goal.position - tool.translation.vector).norm();
    let rotation = match goal.tolerance {
        Tolerance::Pose => goal.rotation.angle_to(&tool.rotation),
        Tolerance::ZSymmetric => (1.0 - (goal.rotation * Vector3::z()).dot(&(tool.rotation * Vector3::z()))) / 2.0,
        Tolerance::Position => 0.0,
    };
    let mut out = Distances::new();
    let query = QueryOptions {
        margin: COLLISION_THRESHOLD_M,
        hulls: false,
        exact_depth: true,
        mesh_hulls: false,
    };
    approximate_distances(world, &ws.link_in_world, &query, &mut out);
    let scale = 1.0 / (1.0 - (-1.0f64).exp());
    let collision = out
        .within_margin
        .iter()
        .filter(|pair| pair.distance <= COLLISION_THRESHOLD_M)
        .map(|pair| scale * ((-pair.distance / COLLISION_THRESHOLD_M).exp() - (-1.0f64).exp()))
        .sum();
    LossTerms {
        distance: position + ROTATION_WEIGHT * rotation,
        collision,
    }
}
