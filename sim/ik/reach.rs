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
//!   Joint 1's origin is fixed and joint 2's turns on a circle about joint 1's axis. Further
//!   apart than the joint offsets between the two reach, the goal is out of reach: the tool
//!   offset no longer counts, nor do the offsets outside the pair (circle to circle, a lower
//!   bound from 64 samples less the arc between them);
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
    tool_beyond_reach(model, goal, &origin)
        .or_else(|| last_joints_beyond_reach(model, goal))
        .or_else(|| super::axes::turning_axes_out_of_reach(model, goal))
}

/// The beyond-reach proof of the tool point for a goal whose own (task) tolerance is wider than
/// the harness's: the goal lies further beyond reach than that tolerance accepts.
pub fn task_beyond_reach(model: &Model, goal: &Goal) -> Option<String> {
    let task = goal.task.as_ref()?;
    let first = model.joints.first()?;
    let origin = (model.world_from_base * first.parent_from_joint).translation.vector;
    let reach = reach_bound(model);
    let away = (goal.position - origin).norm();
    (away - reach >= task.outer_m).then(|| {
        format!(
            "the goal is {away:.3} m from joint 1's origin; no tool position is further than {reach:.3} m, {:.1} mm short, beyond what the task's tolerance ({task}) accepts",
            (away - reach) * 1e3
        )
    })
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

/// A circle (a point where `radius` is 0): where a joint's origin can be as one joint turns.
#[derive(Debug, Clone, Copy)]
struct Circle {
    center: Vector3<f64>,
    normal: Vector3<f64>,
    radius: f64,
}

/// Samples along a circle when bounding its distance from another.
const CIRCLE_SAMPLES: usize = 64;

impl Circle {
    fn point(center: Vector3<f64>) -> Circle {
        Circle {
            center,
            normal: Vector3::z(),
            radius: 0.0,
        }
    }

    /// `point` turned about the line through `on` along unit `axis`.
    fn turning(point: &Vector3<f64>, on: &Vector3<f64>, axis: &Vector3<f64>) -> Circle {
        let center = on + axis * axis.dot(&(point - on));
        Circle {
            center,
            normal: *axis,
            radius: (point - center).norm(),
        }
    }

    /// The distance from `point` to the nearest point of the circle.
    fn distance_to(&self, point: &Vector3<f64>) -> f64 {
        let d = point - self.center;
        let along = self.normal.dot(&d);
        let across = (d - self.normal * along).norm();
        along.hypot(across - self.radius)
    }

    /// A lower bound on the distance between the two circles: `other`'s distance from samples
    /// of this one, less the arc to the nearest sample (moving along an arc changes a distance
    /// by no more than its length).
    fn lower_distance(&self, other: &Circle) -> f64 {
        if self.radius == 0.0 {
            return other.distance_to(&self.center);
        }
        if other.radius == 0.0 {
            return self.distance_to(&other.center);
        }
        let helper = if self.normal.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        let e1 = self.normal.cross(&helper).normalize();
        let e2 = self.normal.cross(&e1);
        let nearest = (0..CIRCLE_SAMPLES)
            .map(|k| {
                let angle = 2.0 * std::f64::consts::PI * k as f64 / CIRCLE_SAMPLES as f64;
                let point = self.center + (e1 * angle.cos() + e2 * angle.sin()) * self.radius;
                other.distance_to(&point)
            })
            .fold(f64::INFINITY, f64::min);
        nearest - self.radius * std::f64::consts::PI / CIRCLE_SAMPLES as f64
    }
}

/// Where a `pose` or `z_symmetric` goal puts the last joints' origins (see the module doc):
/// `(joint index, where, slack, words)`, the slack 1 mm plus the lever times 1 degree.
fn tool_side(model: &Model, goal: &Goal) -> Vec<(usize, Circle, f64, String)> {
    let n = model.dof();
    let pose = Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
    // The last joint's origin in tool coordinates: the last link's origin.
    let tool_from_last = model.last_from_tool.inverse();
    let last_in_tool = tool_from_last.translation.vector;
    let slack = |lever: f64| REACHED_POSITION_M + lever * REACHED_ORIENTATION_RAD;
    let mut out = Vec::with_capacity(2);
    if goal.tolerance == Tolerance::ZSymmetric {
        // Any turn about tool z: a circle about the goal's z axis.
        let z = goal.rotation * Vector3::z();
        let at = (pose * Point3::from(last_in_tool)).coords;
        out.push((
            n - 1,
            Circle::turning(&at, &goal.position, &z),
            slack(last_in_tool.norm()),
            format!("joint {n}'s origin, on a circle about tool z,"),
        ));
        return out;
    }
    out.push((
        n - 1,
        Circle::point((pose * Point3::from(last_in_tool)).coords),
        slack(last_in_tool.norm()),
        format!("joint {n}'s origin"),
    ));
    if n >= 3 {
        // The origin of joint n - 1 in the last link's frame turns about joint n's axis.
        let last = &model.joints[n - 1];
        let before_in_last = -(last.parent_from_joint.rotation.inverse() * last.parent_from_joint.translation.vector);
        let axis = last.axis.into_inner();
        let local = Circle::turning(&before_in_last, &Vector3::zeros(), &axis);
        let last_to_world = pose * tool_from_last;
        let lever = (tool_from_last * Point3::from(local.center)).coords.norm() + local.radius;
        out.push((
            n - 2,
            Circle {
                center: (last_to_world * Point3::from(local.center)).coords,
                normal: last_to_world.rotation * axis,
                radius: local.radius,
            },
            slack(lever),
            format!("joint {}'s origin, on a circle about joint {n}'s axis,", n - 1),
        ));
    }
    out
}

/// Where the first joints' origins are whatever the configuration: joint 1's (fixed) and
/// joint 2's (on a circle about joint 1's axis), as `(joint index, where, words)`.
fn base_side(model: &Model) -> Vec<(usize, Circle, &'static str)> {
    let mut ws = model.workspace();
    model.forward(&vec![0.0; model.dof()], &mut ws);
    let first = ws.link_in_world[1];
    let origin = first.translation.vector;
    let axis = (first.rotation * model.joints[0].axis.into_inner()).normalize();
    let mut out = vec![(0, Circle::point(origin), "joint 1's origin")];
    if model.dof() >= 3 {
        out.push((
            1,
            Circle::turning(&ws.link_in_world[2].translation.vector, &origin, &axis),
            "joint 2's origin (on a circle about joint 1's axis)",
        ));
    }
    out
}

/// The last-joints proof (see the module doc), for a revolute arm of two joints or more: each
/// place the goal puts a last joint's origin against each place of a first joint's origin, the
/// offsets between them the most they can be apart. The pipeline's fallback where IK's own
/// methods prove nothing (theirs say more where they do).
pub fn last_joints_beyond_reach(model: &Model, goal: &Goal) -> Option<String> {
    let n = model.dof();
    let revolute = model.joints.iter().all(|j| j.kind != JointKind::Prismatic);
    if n < 2 || !revolute || goal.tolerance == Tolerance::Position {
        return None;
    }
    let offsets: Vec<f64> = model.joints.iter().map(|j| j.parent_from_joint.translation.vector.norm()).collect();
    let bases = base_side(model);
    for (k, far, slack, far_words) in tool_side(model, goal) {
        for (i, near, near_words) in &bases {
            if *i >= k {
                continue;
            }
            let reach: f64 = offsets[i + 1..=k].iter().sum();
            let apart = far.lower_distance(near);
            if apart - reach >= slack {
                return Some(format!(
                    "with the tool within 1 mm and 1 deg of the goal, {far_words} is at least {apart:.3} m from {near_words} (to within {:.1} mm); the joint offsets between them reach {reach:.3} m",
                    slack * 1e3
                ));
            }
        }
    }
    None
}
