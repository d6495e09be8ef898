//! Proofs that a goal cannot be reached by any configuration, whatever IK does: the facts that
//! turn an `unreachable` goal from "not found from K starts" into "proven".
//!
//! Three proofs, each from the model and the world alone:
//! - beyond reach: every revolute joint turns the arm about an axis through its own origin, so no
//!   point of the tool frame gets further from joint 1's origin than the sum of the joint
//!   offsets after it, the prismatic travels and the tool offset. A goal further than that plus
//!   the 1 mm tolerance is out of reach;
//! - the last joints beyond reach: a `pose` goal fixes where the last joint's origin is (and
//!   puts the one before on a circle about the last axis; a `z_symmetric` goal puts the last
//!   joint's origin on a circle about tool z), each within 1 mm plus its lever times 1 degree.
//!   Further from joint 1's origin than the offsets up to that joint reach, the goal is out of
//!   reach: the tool offset no longer counts, nor does the last offset for the circle;
//! - inside an obstacle: when the tool point lies on the last link's geometry (a DH tube ends at
//!   the tool frame), a goal more than 1 mm inside a checked obstacle or below the floor puts
//!   that link into it at every configuration that reaches the goal within 1 mm.

use super::{REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use crate::collide::{Body, CollisionWorld};
use crate::model::{JointKind, Model};
use crate::scenario::{Goal, Tolerance};
use nalgebra::{Isometry3, Point3, Translation3, Vector3};

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
    if let Some(proof) = tool_beyond_reach(model, goal, &origin) {
        return Some(proof);
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

/// Why no configuration of `model` (as placed) reaches `goal` within the tolerance, obstacles
/// aside, when the reach proofs show it.
pub fn beyond_reach(model: &Model, goal: &Goal) -> Option<String> {
    let first = model.joints.first()?;
    let origin = (model.world_from_base * first.parent_from_joint).translation.vector;
    tool_beyond_reach(model, goal, &origin).or_else(|| last_joints_proof(model, goal, &origin))
}

/// The beyond-reach proof of the tool point.
fn tool_beyond_reach(model: &Model, goal: &Goal, origin: &Vector3<f64>) -> Option<String> {
    let reach = reach_bound(model);
    let away = (goal.position - origin).norm();
    (away - reach >= REACHED_POSITION_M).then(|| {
        format!(
            "the goal is {away:.3} m from joint 1's origin; no tool position is further than {reach:.3} m (the joint offsets after joint 1, the tool offset and any prismatic travel)"
        )
    })
}

/// The last-joints proof (see the module doc), for a revolute arm of two joints or more: the
/// pipeline's fallback where IK's own methods prove nothing (theirs say more where they do).
pub fn last_joints_beyond_reach(model: &Model, goal: &Goal) -> Option<String> {
    let first = model.joints.first()?;
    let origin = (model.world_from_base * first.parent_from_joint).translation.vector;
    last_joints_proof(model, goal, &origin)
}

/// The distance from `point` to the nearest point of the circle about the line through
/// `center` along unit `normal`, of `radius`.
fn to_circle(point: &Vector3<f64>, center: &Vector3<f64>, normal: &Vector3<f64>, radius: f64) -> f64 {
    let d = point - center;
    let along = normal.dot(&d);
    let across = (d - normal * along).norm();
    along.hypot(across - radius)
}

fn last_joints_proof(model: &Model, goal: &Goal, origin: &Vector3<f64>) -> Option<String> {
    let n = model.dof();
    let revolute = model.joints.iter().all(|j| j.kind != JointKind::Prismatic);
    if n < 2 || !revolute || goal.tolerance == Tolerance::Position {
        return None;
    }
    let offsets: Vec<f64> = model.joints.iter().map(|j| j.parent_from_joint.translation.vector.norm()).collect();
    let pose = Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
    // The last joint's origin in tool coordinates: the last link's origin.
    let tool_from_last = model.last_from_tool.inverse();
    let last_in_tool = tool_from_last.translation.vector;
    let reach: f64 = offsets[1..].iter().sum();
    let (nearest, lever, what) = match goal.tolerance {
        Tolerance::Pose => (
            ((pose * Point3::from(last_in_tool)).coords - origin).norm(),
            last_in_tool.norm(),
            "is",
        ),
        _ => {
            // Any turn about tool z: a circle about the goal's z axis.
            let z = goal.rotation * Vector3::z();
            let center = goal.position + z * last_in_tool.z;
            (
                to_circle(origin, &center, &z, last_in_tool.xy().norm()),
                last_in_tool.norm(),
                "comes no closer than",
            )
        }
    };
    let slack = REACHED_POSITION_M + lever * REACHED_ORIENTATION_RAD;
    if nearest - reach >= slack {
        return Some(format!(
            "with the tool within 1 mm and 1 deg of the goal, joint {n}'s origin {what} {nearest:.3} m from joint 1's origin (to within {:.1} mm); the joint offsets up to it reach {reach:.3} m",
            slack * 1e3
        ));
    }
    if goal.tolerance != Tolerance::Pose || n < 3 {
        return None;
    }
    // The origin of joint n - 1 in the last link's frame turns about joint n's axis.
    let last = &model.joints[n - 1];
    let before_in_last = -(last.parent_from_joint.rotation.inverse() * last.parent_from_joint.translation.vector);
    let axis = last.axis.into_inner();
    let center = axis * axis.dot(&before_in_last);
    let radius = (before_in_last - center).norm();
    let last_to_world = pose * tool_from_last;
    let center_world = (last_to_world * Point3::from(center)).coords;
    let normal_world = last_to_world.rotation * axis;
    let nearest = to_circle(origin, &center_world, &normal_world, radius);
    let lever = (tool_from_last * Point3::from(center)).coords.norm() + radius;
    let slack = REACHED_POSITION_M + lever * REACHED_ORIENTATION_RAD;
    let reach: f64 = offsets[1..n - 1].iter().sum();
    (nearest - reach >= slack).then(|| {
        format!(
            "with the tool within 1 mm and 1 deg of the goal, joint {}'s origin is on a circle about joint {n}'s axis that comes no closer than {nearest:.3} m to joint 1's origin (to within {:.1} mm); the joint offsets up to it reach {reach:.3} m",
            n - 1,
            slack * 1e3
        )
    })
}
