//! Proofs that a goal cannot be reached by any configuration, whatever IK does: the facts that
//! turn an `unreachable` goal from "not found from K starts" into "proven".
//!
//! Two proofs, each from the model and the world alone:
//! - beyond reach: every revolute joint turns the arm about an axis through its own origin, so no
//!   point of the tool frame gets further from joint 1's origin than the sum of the joint
//!   offsets after it, the prismatic travels and the tool offset. A goal further than that plus
//!   the 1 mm tolerance is out of reach;
//! - inside an obstacle: when the tool point lies on the last link's geometry (a DH tube ends at
//!   the tool frame), a goal more than 1 mm inside a checked obstacle or below the floor puts
//!   that link into it at every configuration that reaches the goal within 1 mm.

use super::REACHED_POSITION_M;
use crate::collide::{Body, CollisionWorld};
use crate::model::{JointKind, Model};
use crate::scenario::Goal;

/// A tool point this close to the last link's geometry counts as on it (m).
const ON_GEOMETRY_M: f64 = 1e-9;

/// Farthest the tool frame's origin can be from joint 1's origin (m).
pub fn reach_bound(model: &Model) -> f64 {
    let offsets: f64 = model
        .joints
        .iter()
        .skip(1)
        .map(|j| j.parent_from_joint.translation.vector.norm())
        .sum();
    let travel: f64 = model
        .joints
        .iter()
        .filter(|j| j.kind == JointKind::Prismatic)
        .map(|j| j.limits.map_or(f64::INFINITY, |[lo, hi]| lo.abs().max(hi.abs())))
        .sum();
    offsets + travel + model.last_from_tool.translation.vector.norm()
}

/// Why no configuration of `model` (placed as `world` was built) can reach `goal` collision-free,
/// when one of the proofs applies; `None` when none does (the goal may still be unreachable).
pub fn unreachable_proof(model: &Model, world: &CollisionWorld, goal: &Goal) -> Option<String> {
    let first = model.joints.first()?;
    let origin = (model.world_from_base * first.parent_from_joint).translation.vector;
    let reach = reach_bound(model);
    let away = (goal.position - origin).norm();
    if away - reach >= REACHED_POSITION_M {
        return Some(format!(
            "the goal is {away:.3} m from joint 1's origin; no tool position is further than {reach:.3} m (the joint offsets after joint 1, the tool offset and any prismatic travel)"
        ));
    }
    let last = model.links.len() - 1;
    let tool_in_link = model.last_from_tool.translation.vector;
    if world.point_to_link(last, &tool_in_link)? > ON_GEOMETRY_M {
        return None;
    }
    let (body, depth) = world
        .point_depths(&goal.position)
        .into_iter()
        .filter(|(body, depth)| *depth <= -REACHED_POSITION_M && world.checks(last, *body))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let what = match body {
        Body::Floor => "below the floor".to_string(),
        _ => format!("inside {}", world.body_name(body)),
    };
    Some(format!(
        "the goal lies {:.1} mm {what}, and the tool point is on link `{}`: every configuration within 1 mm of the goal puts that link into it",
        -depth * 1e3,
        model.links[last].name
    ))
}
