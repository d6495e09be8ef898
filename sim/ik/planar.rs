//! The planar run's proof: an arm with one run of parallel axes and single joints elsewhere
//! reaches a pose only where three conditions on a few numbers hold together.
//!
//! Joints turning about parallel axes (see `ik::axes`) move within planes across their
//! axis: rotations about it and offsets carried by them keep every offset's component along it,
//! and the run's last axis stays within the reach of its links (the offsets across the axis
//! between consecutive ones) from its first. With every other revolute joint alone in its
//! direction, the tool's orientation depends on the run's (signed) sum of angles and the other
//! joints' angles alone, and so do, for a tool pose, where the run's first joint is (the joints
//! before it) and where its last joint must be (the pose, less the joints after it). So a pose is
//! reached only at sums and angles where the orientation is the pose's, the last joint's origin
//! is at the run's offset along the axis from the first joint's, and across the axis within the
//! run's reach. A run of four parallel axes in a 6R arm (modular `D-Ls-Ls-Ls-D-D`) has three
//! numbers for four conditions, and most poses have no solution; a run of three decides the
//! poses just out of reach that the closed form only finds without solution.
//!
//! A `pose` goal is searched first without the run's sum: the run turns the tool about its axis
//! alone, so the orientation is reachable exactly where the axis as the joints before the run
//! turn it agrees with the axis as the goal turns the tool (the joints after the run fix it in
//! the tool frame), and the last joint's origin is where the goal's pose less the joints after
//! the run puts it, off by the tolerance (1 mm, and 1 degree times its distance from the tool).
//! One number fewer; where that fails, the search with the sum (the orientation exact, so the
//! origin is off by the tool's position error alone, 1 mm) is tighter near the boundary. A
//! `z_symmetric` goal is searched with the sum, tool z within 1 degree.
//!
//! A branch-and-bound over the numbers proves that none meets the conditions within the goal's
//! tolerance: each box is dropped by a condition's distance at its centre less how far the box
//! can change it (the sum of its half-widths for the orientation; levers, the offsets between
//! the joints, for the positions; the distance across the axis changes by at most the offset's
//! length times the axis's turn, `|d x a| - |d x b| <= |d| |a - b|`) and less the tolerance.
//! Joint limits are left out (wider: still sound), except a single joint's narrower than a turn.

use super::axes::{joints, parallel_groups};
use super::{REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use crate::model::{JointKind, Model};
use crate::scenario::{Goal, Tolerance};
use nalgebra::Vector3;
use std::f64::consts::PI;

/// Boxes the search may split before it gives up (each one forward kinematics), with three
/// numbers or fewer (tried before IK's other searches, after the aim at the tolerance): a run of
/// four parallel axes in a 6R arm takes about a thousand. Four numbers (a run of three, or two in
/// a 5R arm) take 25 000 to 300 000 for goals well out of reach: IK tries them last, with a
/// validation's joint-space budget, never a sweep's.
pub const PLANAR_BOXES: usize = 20_000;
/// Most numbers searched over (the run's sum and the single joints' angles).
const DIMENSIONS: usize = 4;
/// Half-width below which a box is not split: a pose this close is not out of reach.
const SMALLEST: f64 = 1e-9;

/// One number searched over: the joint that carries it, its range, and how far turning it moves
/// the run's first joint's origin and, in the tool frame, its last joint's origin (per radian).
struct Dimension {
    joint: usize,
    range: [f64; 2],
    moves_first: f64,
    moves_last: f64,
    /// Whether the joint comes before the run (turning it tilts the run's axis).
    before: bool,
}

/// The run and what the search needs of it.
struct Run {
    first: usize,
    last: usize,
    /// Its offset along the axis, last origin from first.
    along: f64,
    /// Least and most distance across the axis between its first and last axes.
    across: [f64; 2],
}

/// Why no configuration of `model` reaches `goal` within the tolerance, when the arm has one run
/// of parallel axes and single joints elsewhere, and a search over at most `most` numbers (four
/// at most) proves it within `budget` boxes (see the module doc). A `pose` goal is
/// searched first without the run's sum (the axis's direction stands in for the orientation),
/// then with it (the orientation exact, the tolerance 1 mm: tighter near the boundary).
pub fn planar_group_out_of_reach(model: &Model, goal: &Goal, most: usize, budget: usize) -> Option<String> {
    let finite = goal.position.iter().chain(goal.rotation.coords.iter()).all(|x| x.is_finite());
    if !finite {
        return None;
    }
    let (groups, run_index) = applies(model, goal.tolerance)?;
    let run = run_of(model, &groups[run_index]);
    for reduced in [true, false] {
        let numbers = groups.len() - usize::from(reduced);
        if (reduced && goal.tolerance != Tolerance::Pose) || numbers > most.min(DIMENSIONS) {
            continue;
        }
        if let Some(boxes) = search(model, goal, &groups, run_index, &run, reduced, budget) {
            return Some(proof(&groups, run_index, &run, reduced, goal.tolerance, boxes));
        }
    }
    None
}

/// The branch-and-bound (see the module doc): the boxes it took to drop them all, or `None` when
/// a box's centre meets every condition, or the budget runs out.
fn search(model: &Model, goal: &Goal, groups: &[Vec<usize>], run_index: usize, run: &Run, reduced: bool, budget: usize) -> Option<usize> {
    let offsets: Vec<f64> = model.joints.iter().map(|j| j.parent_from_joint.translation.vector.norm()).collect();
    // The largest distance between the origins of joints `a` and `b` (a <= b).
    let apart = |a: usize, b: usize| offsets[a + 1..=b].iter().sum::<f64>();
    let dimensions: Vec<Dimension> = groups
        .iter()
        .enumerate()
        .filter(|(k, _)| !reduced || *k != run_index)
        .map(|(_, group)| {
            let joint = group[0];
            let limits = model.joints[joint].limits.filter(|[lo, hi]| group.len() == 1 && hi - lo < 2.0 * PI);
            Dimension {
                joint,
                range: limits.unwrap_or([-PI, PI]),
                moves_first: if joint < run.first { apart(joint, run.first) } else { 0.0 },
                moves_last: if joint > run.last { apart(run.last, joint) } else { 0.0 },
                before: joint < run.first,
            }
        })
        .collect();
    let axis = model.joints[run.first].axis.into_inner();
    let goal_z = goal.rotation * Vector3::z();
    let mut ws = model.workspace();
    let mut q = vec![0.0; model.dof()];
    model.forward(&q, &mut ws);
    let mut stack: Vec<([f64; DIMENSIONS], [f64; DIMENSIONS])> = vec![(
        std::array::from_fn(|k| dimensions.get(k).map_or(0.0, |d| 0.5 * (d.range[0] + d.range[1]))),
        std::array::from_fn(|k| dimensions.get(k).map_or(0.0, |d| 0.5 * (d.range[1] - d.range[0]))),
    )];
    let mut boxes = 0;
    while let Some((centre, half)) = stack.pop() {
        boxes += 1;
        if boxes > budget {
            return None;
        }
        // Depth first, the next box mostly differs from the last in one angle: the links
        // before the first joint whose angle changed stay as they are.
        let mut changed = model.dof();
        for (d, s) in dimensions.iter().zip(&centre) {
            if q[d.joint].to_bits() != s.to_bits() {
                q[d.joint] = *s;
                changed = changed.min(d.joint);
            }
        }
        model.forward_from(&q, &mut ws, changed);
        let sum = |pick: &dyn Fn(&Dimension) -> f64| dimensions.iter().zip(&half).map(|(d, h)| pick(d) * h).sum::<f64>();
        let tilted = sum(&|d| f64::from(u8::from(d.before)));
        let turn = sum(&|_| 1.0);
        let rotation = ws.tool_in_world.rotation;
        let direction = ws.link_in_world[run.first + 1].rotation * axis;
        let first = ws.link_in_world[run.first + 1].translation.vector;
        let from_tool = ws.link_in_world[run.last + 1].translation.vector - ws.tool_in_world.translation.vector;
        let in_tool = sum(&|d| d.moves_last);
        let lever = from_tool.norm() + in_tool;
        let (off_orientation, last, moved, tolerance) = if reduced {
            // The run's axis as the joints before it turn it, and as the goal turns the tool
            // (fixed in the tool frame by the joints after it): the run's sum turns about it
            // alone, so the two agree within the tolerance. Where the last joint's origin must
            // be: the goal's pose less the joints after the run, off by the tolerance (1 mm,
            // and 1 degree times its distance from the tool).
            let in_tool_frame = rotation.inverse() * direction;
            let off = super::angle_between(&direction, &(goal.rotation * in_tool_frame));
            let last = goal.position + goal.rotation * (rotation.inverse() * from_tool);
            (
                off,
                last,
                sum(&|d| d.moves_first) + in_tool,
                REACHED_POSITION_M + REACHED_ORIENTATION_RAD * lever,
            )
        } else {
            // The numbers fix the orientation: the last joint's origin is where the tool at the
            // goal's position, turned as the arm turns it, puts it (off by 1 mm).
            let off = match goal.tolerance {
                Tolerance::Pose => goal.rotation.angle_to(&rotation),
                _ => super::angle_between(&goal_z, &(rotation * Vector3::z())),
            };
            let last = goal.position + from_tool;
            (off, last, sum(&|d| d.moves_first) + in_tool + turn * lever, REACHED_POSITION_M)
        };
        if off_orientation - turn >= REACHED_ORIENTATION_RAD {
            continue;
        }
        let d = last - first;
        let along = direction.dot(&d);
        let across = (d - direction * along).norm();
        let reach = d.norm() + moved;
        let along_change = tilted * reach + moved;
        let across_change = tilted * reach + moved;
        let along_off = (along - run.along).abs() - along_change - tolerance;
        let across_off = (across - across_change - tolerance - run.across[1]).max(run.across[0] - across - across_change - tolerance);
        if along_off > 0.0 || across_off > 0.0 {
            continue;
        }
        let exact = (along - run.along).abs() <= REACHED_POSITION_M && across >= run.across[0] && across <= run.across[1];
        if off_orientation < REACHED_ORIENTATION_RAD && exact {
            // A centre that meets them all: nothing to prove.
            return None;
        }
        let weight = |k: usize| {
            let dim = &dimensions[k];
            half[k] * (1.0 + lever + dim.moves_first + dim.moves_last + reach * f64::from(u8::from(dim.before)))
        };
        let Some(widest) = (0..dimensions.len()).max_by(|&a, &b| weight(a).total_cmp(&weight(b))) else {
            // Nothing to search over (a run and no other joint): the centre was the whole.
            return None;
        };
        if half[widest] < SMALLEST {
            return None;
        }
        for side in [-0.5, 0.5] {
            let (mut c, mut h) = (centre, half);
            h[widest] *= 0.5;
            c[widest] += side * half[widest];
            stack.push((c, h));
        }
    }
    Some(boxes)
}

/// The proof's words for a search of `boxes` boxes.
fn proof(groups: &[Vec<usize>], run_index: usize, run: &Run, reduced: bool, tolerance: Tolerance, boxes: usize) -> String {
    let others: Vec<usize> = groups
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != run_index)
        .flat_map(|(_, g)| g.iter().copied())
        .collect();
    let noun = if others.len() == 1 { "angle" } else { "angles" };
    let last = run.last + 1;
    let found = if reduced {
        let angles = if others.is_empty() {
            "nothing".to_string()
        } else {
            format!("the {noun} of {}", joints(&others))
        };
        format!(
            "a search of {boxes} boxes over {angles} finds none that turns their axis within 1 deg of where the goal's orientation puts it and brings joint {last}'s origin within the tolerance of both"
        )
    } else {
        let angles = if others.is_empty() {
            "their sum".to_string()
        } else {
            format!("their sum and the {noun} of {}", joints(&others))
        };
        let orientation = match tolerance {
            Tolerance::Pose => "the orientation",
            _ => "tool z",
        };
        format!("a search of {boxes} boxes over {angles} finds none with {orientation} within 1 deg of the goal's that puts joint {last}'s origin within the tolerance of both")
    };
    format!(
        "{} turn about parallel axes, whose offsets along them add up to {:.3} m and across them reach {:.3} to {:.3} m from joint {}'s axis to joint {last}'s; {found}",
        joints(&groups[run_index]),
        run.along,
        run.across[0],
        run.across[1],
        run.first + 1,
    )
}

/// How many numbers the planar run's search goes over for `model` on goals of `tolerance` (the
/// single joints' angles, and the run's sum unless the goal is a pose), when it applies: one run
/// of parallel axes, single joints elsewhere, no prismatic joint, a `pose` or `z_symmetric` goal,
/// at most four numbers.
pub fn planar_numbers(model: &Model, tolerance: Tolerance) -> Option<usize> {
    let (groups, _) = applies(model, tolerance)?;
    let numbers = groups.len() - usize::from(tolerance == Tolerance::Pose);
    (numbers <= DIMENSIONS).then_some(numbers)
}

/// The arm's groups of parallel axes and the index of its one run of two joints or more, when
/// the planar run's proof applies to it on goals of `tolerance` (no prismatic joint, exactly
/// one run, a `pose` or `z_symmetric` goal).
fn applies(model: &Model, tolerance: Tolerance) -> Option<(Vec<Vec<usize>>, usize)> {
    if tolerance == Tolerance::Position || model.joints.iter().any(|j| j.kind == JointKind::Prismatic) {
        return None;
    }
    let groups = parallel_groups(model);
    let runs: Vec<usize> = (0..groups.len()).filter(|&k| groups[k].len() >= 2).collect();
    let [run] = runs.as_slice() else { return None };
    let run = *run;
    Some((groups, run))
}

/// The run of joints `group` (consecutive, parallel axes): its offsets along and across the axis.
fn run_of(model: &Model, group: &[usize]) -> Run {
    let mut ws = model.workspace();
    model.forward(&vec![0.0; model.dof()], &mut ws);
    let (first, last) = (group[0], group[group.len() - 1]);
    let direction = ws.link_in_world[first + 1].rotation * model.joints[first].axis.into_inner();
    let origin = |j: usize| ws.link_in_world[j + 1].translation.vector;
    let links: Vec<f64> = group
        .windows(2)
        .map(|w| {
            let step = origin(w[1]) - origin(w[0]);
            (step - direction * direction.dot(&step)).norm()
        })
        .collect();
    let total: f64 = links.iter().sum();
    let longest = links.iter().copied().fold(0.0, f64::max);
    Run {
        first,
        last,
        along: direction.dot(&(origin(last) - origin(first))),
        across: [(2.0 * longest - total).max(0.0), total],
    }
}
