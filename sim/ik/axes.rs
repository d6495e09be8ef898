//! The turning axes' proof: an arm whose revolute joints turn about at most two directions
//! cannot reach every orientation.
//!
//! Consecutive revolute joints with parallel axes (prismatic joints between them change no
//! direction) turn the tool about one direction: their rotations add up. Where all of an arm's
//! revolute joints form at most two such groups, its orientation is `C0 Rot(a, s) C1 Rot(b, t) C2`:
//! the first group's axis is fixed in the world, the last group's is fixed in the tool frame, and
//! the angle between the two never changes (`Rot(a, s)` keeps `a`). A goal whose orientation puts
//! them at another angle, by more than the orientation tolerance can move a direction fixed in
//! the tool, is out of reach whatever the position, the joint limits and the obstacles. Four or
//! more parallel axes in a row and two triples (modular `Ls-Ls-D-Ls-Ls-D`) are such arms, and so
//! is every SCARA; their pose goals have no isolated solutions, so the all-solutions methods do
//! not apply and this is the proof that decides them.

use super::{angle_between, REACHED_ORIENTATION_RAD};
use crate::model::{JointKind, Model};
use crate::scenario::{Goal, Tolerance};
use nalgebra::{Rotation3, Vector3};
use std::f64::consts::PI;

/// Largest sine of the angle between two axes counted as parallel: the catalog's and the DH
/// designs' are exact, a URDF's within its digits.
const PARALLEL: f64 = 1e-9;
/// Taken off the gap before it counts (rad): covers the axes' rounding many times over.
const ROUNDING_RAD: f64 = 1e-6;

/// Why no orientation within the goal's tolerance is one the arm can take, when its revolute
/// joints turn about at most two directions (see the module doc).
pub fn turning_axes_out_of_reach(model: &Model, goal: &Goal) -> Option<String> {
    if goal.tolerance == Tolerance::Position || !goal.rotation.coords.iter().all(|x| x.is_finite()) {
        return None;
    }
    let groups = parallel_groups(model);
    let (first, last) = match groups.as_slice() {
        [only] => (only, only),
        [first, last] => (first, last),
        _ => return None,
    };
    let mut ws = model.workspace();
    model.forward(&vec![0.0; model.dof()], &mut ws);
    let world_axis = |joint: usize| ws.link_in_world[joint + 1].rotation * model.joints[joint].axis.into_inner();
    // The first group's axis is fixed in the world; the last group's, fixed in the tool frame.
    let fixed = world_axis(first[0]);
    let last_axis = world_axis(last[last.len() - 1]);
    let in_tool = ws.tool_in_world.rotation.inverse() * last_axis;
    let held = angle_between(&fixed, &last_axis);
    let slack = REACHED_ORIENTATION_RAD;
    let (low, high) = if goal.tolerance == Tolerance::Pose {
        let at_goal = angle_between(&fixed, &(goal.rotation * in_tool));
        (at_goal - slack, at_goal + slack)
    } else {
        // Any turn about tool z, tool z within the tolerance of the goal's: the axis keeps its
        // angle to tool z, and tool z's angle to the fixed axis moves by the tolerance at most.
        let to_goal_z = angle_between(&fixed, &(goal.rotation * Vector3::z()));
        let to_tool_z = angle_between(&Vector3::z(), &in_tool);
        (
            (to_goal_z - to_tool_z).abs() - slack,
            PI - (PI - to_goal_z - to_tool_z).abs() + slack,
        )
    };
    if held >= low - ROUNDING_RAD && held <= high + ROUNDING_RAD {
        return None;
    }
    let (low, high) = (low.max(0.0).to_degrees(), high.min(PI).to_degrees());
    let within = match goal.tolerance {
        Tolerance::Pose => "within 1 deg of the goal's orientation",
        _ => "with tool z within 1 deg of the goal's, turned about it at will",
    };
    Some(if groups.len() == 1 {
        format!(
            "{} about one direction, which the tool carries along ({:.1} deg from it in the tool frame, whatever the configuration); {within} that direction would be {low:.1} to {high:.1} deg off",
            turn(first),
            held.to_degrees()
        )
    } else {
        format!(
            "{} about one direction and {} about another, {:.1} deg from the first whatever the configuration; {within} the two would be {low:.1} to {high:.1} deg apart",
            turn(first),
            joints(last),
            held.to_degrees()
        )
    })
}

/// The revolute joints in runs whose axes stay parallel (see the module doc), by index.
pub(super) fn parallel_groups(model: &Model) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    // The fixed rotation from the last revolute joint's moving frame to the current joint's.
    let mut between = Rotation3::identity();
    let mut previous: Option<usize> = None;
    for (index, joint) in model.joints.iter().enumerate() {
        if previous.is_some() {
            between *= joint.parent_from_joint.rotation.to_rotation_matrix();
        }
        if joint.kind == JointKind::Prismatic {
            continue;
        }
        let parallel = previous.is_some_and(|before| {
            let here = between * joint.axis.into_inner();
            model.joints[before].axis.cross(&here).norm() <= PARALLEL
        });
        match groups.last_mut() {
            Some(group) if parallel => group.push(index),
            _ => groups.push(vec![index]),
        }
        previous = Some(index);
        between = Rotation3::identity();
    }
    groups
}

/// "joint 3 turns", "joints 1 to 3 turn".
pub(super) fn turn(group: &[usize]) -> String {
    let verb = if group.len() == 1 { "turns" } else { "turn" };
    format!("{} {verb}", joints(group))
}

/// "joint 3", "joints 1 to 3", "joints 1, 2 and 4" (one-based).
pub(super) fn joints(group: &[usize]) -> String {
    match group {
        [only] => format!("joint {}", only + 1),
        _ if group.len() > 2 && group.windows(2).all(|w| w[1] == w[0] + 1) => {
            format!("joints {} to {}", group[0] + 1, group[group.len() - 1] + 1)
        }
        [init @ .., last] => {
            let listed: Vec<String> = init.iter().map(|j| (j + 1).to_string()).collect();
            format!("joints {} and {}", listed.join(", "), last + 1)
        }
        [] => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joints_are_named_as_runs_or_lists() {
        assert_eq!(joints(&[2]), "joint 3");
        assert_eq!(joints(&[0, 1, 2]), "joints 1 to 3");
        assert_eq!(joints(&[0, 1, 3]), "joints 1, 2 and 4");
        assert_eq!(joints(&[4, 5]), "joints 5 and 6");
    }
}
