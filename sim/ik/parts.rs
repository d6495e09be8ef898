//! A pose beyond reach whose out-of-reach proof over the whole tolerance falls short, proven
//! part by part.
//!
//! The closed form's and the spherical wrist's proofs bound where the wrist centre can be for
//! any pose within 1 mm and 1 degree of the goal: a ball of `1 mm + L * 1 deg` (`L` the centre's
//! lever from the tool) about where the goal needs it, or a cap of the sphere about the tool.
//! A pose just beyond reach (the wrist centre a millimetre or two outside the arm's shell) has
//! its reachable neighbours closer than that slack, and the proof fails though no pose within
//! the tolerance is reachable. Here the tolerance (position offsets within 1 mm, rotation
//! offsets within 1 degree: across goal z for a `z_symmetric` goal, whose turn about z the
//! caller's self-motion covers) is cut into boxes of offsets, each proven by the same method
//! at its centre pose with the radii of the ball that covers the box: the position part's
//! half-widths' norm, and the rotation part's (two rotations whose rotation vectors differ by
//! `v` differ by at most `|v|`, the exponential map contracting on the rotation group). A box
//! that fails is halved across the offset that widens its slack most, down to a thirty-second
//! of the tolerance; boxes that miss the tolerance need nothing, and one straddling its edge is
//! shrunk to the bounding box of what of it lies within ([`super::cells::clipped_to_tolerance`]).
//! Every box proven: out of reach.
//! A small box whose centre pose has solutions (ignoring the limits, as the proofs do) ends
//! the cut: the tolerance holds reachable poses and no cut can prove it.
//!
//! The proofs are the methods' own: the wrist centre's bound is rigorous; the closed form's
//! elbow certificate is first order, doubled (as over the whole tolerance, and with more room
//! over a part: its remainder shrinks as the square of the radius, the doubling as the radius).
//!
//! Used by the self-motion sweep of a UR-type arm's free turn ([`super::selfmotion`]), where
//! a sample without solutions stays unproven at the finest step, and for a UR-type arm's pose
//! goal with no solution that the searches leave open; the closed form's proof costs about a
//! microsecond a part.
//! The spherical wrist's bound (a search over joints 2 and 3) costs a thousand times that and
//! is not cut.

use super::search::Radii;
use super::{REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use crate::scenario::{Goal, Tolerance};

/// Boxes proven or split at most per goal (its self-motion's samples share them): about a
/// second of the closed form's proofs where none succeeds.
pub(super) const PARTS_PER_GOAL: usize = 100_000;
/// The half-width below which a box's centre pose is solved: solutions there mean the
/// tolerance holds reachable poses, and no cut will prove it.
const SOLVED_BELOW: f64 = 1.0 / 8.0;
/// The smallest half-width of a box, in units of the tolerance.
const SMALLEST_HALF: f64 = 1.0 / 32.0;
/// Metres of wrist-centre motion per radian of the tool's rotation that the split assumes
/// when weighing a rotation offset against a position one: which offset is halved, never what
/// is proven. Measured on modular-elbow's workspace goal 69 (61 samples of its free turn cut):
/// 0.3 m needs 1 607 596 parts, 0.1 m 187 055, 0.03 m 77 663, 0.01 m 46 163, 0.001 m 203 379.
pub(super) const LEVER_M: f64 = 0.03;

/// One part's poses, as a proof sees them: the ball about its centre pose that holds them, and
/// its box of offsets about that pose, position along the world axes (m), then rotation (rad)
/// about the goal's own axes where `local` (a `z_symmetric` goal's), else the world's.
#[derive(Debug, Clone, Copy)]
pub(super) struct Extent {
    pub radii: Radii,
    pub half: [f64; 6],
    pub local: bool,
}

/// A box of pose offsets in units of the tolerance: position (mm, world axes), then rotation
/// (degrees, world axes; a `z_symmetric` goal's along goal x and y, the last one 0).
#[derive(Debug, Clone, Copy)]
struct Part {
    centre: [f64; 6],
    half: [f64; 6],
}

impl Part {
    fn norm(values: &[f64]) -> f64 {
        values.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// Whether the centre's pose is within the tolerance.
    fn is_within(&self) -> bool {
        Self::norm(&self.centre[..3]) <= 1.0 && Self::norm(&self.centre[3..]) <= 1.0
    }

    /// The ball about the centre's pose that holds every pose of the box.
    fn radii(&self) -> Radii {
        Radii {
            position_m: Self::norm(&self.half[..3]) * REACHED_POSITION_M,
            orientation_rad: Self::norm(&self.half[3..]) * REACHED_ORIENTATION_RAD,
        }
    }

    /// The part's extent about its centre pose.
    fn extent(&self, tolerance: Tolerance) -> Extent {
        Extent {
            radii: self.radii(),
            half: std::array::from_fn(|k| self.half[k] * if k < 3 { REACHED_POSITION_M } else { REACHED_ORIENTATION_RAD }),
            local: tolerance == Tolerance::ZSymmetric,
        }
    }

    /// Whether offset `k` may still be halved.
    fn halvable(&self, k: usize) -> bool {
        self.half[k] / 2.0 >= SMALLEST_HALF
    }

    /// The offset to halve: the one whose half-width adds most to the slack, a rotation's
    /// weighed as `lever` (m per rad) times it; `None` when every one is at its smallest.
    fn widest(&self, lever: f64) -> Option<usize> {
        let weight = |k: usize| {
            if k < 3 {
                self.half[k] * REACHED_POSITION_M
            } else {
                self.half[k] * REACHED_ORIENTATION_RAD * lever
            }
        };
        (0..6)
            .filter(|&k| self.halvable(k))
            .max_by(|&a, &b| weight(a).total_cmp(&weight(b)).then(b.cmp(&a)))
    }

    fn halves(&self, k: usize) -> [Part; 2] {
        let mut low = *self;
        low.half[k] /= 2.0;
        let mut high = low;
        low.centre[k] -= low.half[k];
        high.centre[k] += low.half[k];
        [low, high]
    }
}

/// Why no pose within `goal`'s tolerance is reachable, when `prove` (a method's proof for the
/// poses of a part about its centre pose) proves it of every part of the tolerance; `None`
/// when a part stays unproven at the smallest size, `solvable` (whether a goal's pose has
/// solutions) finds a small part's centre reachable, or `budget` (boxes, taken as used) runs
/// out. A failing proof may name the offset to halve (the one that moved it most); else
/// `lever` (m per rad) weighs a rotation offset against a position one (the proof's own slack:
/// [`LEVER_M`] for a wrist centre's).
pub(super) fn out_of_reach_by_parts(
    goal: &Goal,
    budget: &mut usize,
    lever: f64,
    prove: impl Fn(&Goal, &Extent) -> Result<String, Option<usize>>,
    solvable: impl Fn(&Goal) -> bool,
) -> Option<String> {
    let rotations = if goal.tolerance == Tolerance::ZSymmetric { 2 } else { 3 };
    let mut whole = Part {
        centre: [0.0; 6],
        half: [1.0; 6],
    };
    whole.half[3 + rotations..].fill(0.0);
    let mut stack = vec![whole];
    let mut proven = 0;
    let mut first: Option<String> = None;
    while let Some(mut part) = stack.pop() {
        let Some((centre, half)) = super::cells::clipped_to_tolerance(&part.centre, &part.half) else {
            continue;
        };
        (part.centre, part.half) = (centre, half);
        *budget = budget.checked_sub(1)?;
        let centre = super::cells::offset_goal(goal, &part.centre);
        match prove(&centre, &part.extent(goal.tolerance)) {
            Ok(proof) => {
                proven += 1;
                first.get_or_insert(proof);
            }
            Err(hint) => {
                let small = part.half.iter().all(|h| *h <= SOLVED_BELOW);
                if small && part.is_within() && solvable(&centre) {
                    return None;
                }
                let halve = hint.filter(|&k| part.halvable(k)).or_else(|| part.widest(lever))?;
                stack.extend(part.halves(halve));
            }
        }
    }
    Some(format!(
        "the goal's tolerance cut into {proven} parts, each out of reach (the first: {})",
        first?
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{UnitQuaternion, Vector3};

    fn goal(tolerance: Tolerance) -> Goal {
        Goal {
            name: "g".into(),
            position: Vector3::new(0.4, -0.2, 0.3),
            rotation: UnitQuaternion::from_euler_angles(0.2, 0.9, -1.3),
            tolerance,
            task: None,
        }
    }

    /// Every pose within the tolerance lies within the radii of some part that a proof was
    /// asked about and gave: a "proof" that holds only away from one pose (inside the
    /// tolerance) is never accepted, one that holds away from a pose just outside is.
    #[test]
    fn parts_cover_the_tolerance_and_a_pose_inside_is_never_proven() {
        for tolerance in [Tolerance::Pose, Tolerance::ZSymmetric] {
            let goal = goal(tolerance);
            let inside = goal.position + Vector3::new(0.6, -0.5, 0.3) * REACHED_POSITION_M;
            let outside = goal.position + Vector3::new(2.0, -1.2, 0.9) * REACHED_POSITION_M;
            let far_from = |point: Vector3<f64>| {
                // The shape of the real proofs' slack: the position's radius and a lever's share
                // of the rotation's.
                move |part: &Goal, extent: &Extent| {
                    let slack = extent.radii.position_m + LEVER_M * extent.radii.orientation_rad;
                    ((part.position - point).norm() > slack).then(|| "away".to_string()).ok_or(None)
                }
            };
            let never = |_: &Goal| false;
            let mut budget = PARTS_PER_GOAL;
            assert!(
                out_of_reach_by_parts(&goal, &mut budget, LEVER_M, far_from(inside), never).is_none(),
                "{tolerance:?}"
            );
            let mut budget = PARTS_PER_GOAL;
            let proof = out_of_reach_by_parts(&goal, &mut budget, LEVER_M, far_from(outside), never);
            assert!(proof.is_some(), "{tolerance:?}");
        }
    }
}
