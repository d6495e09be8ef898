//! A colliding exact solution whose one certificate is too coarse for the whole tolerance is
//! judged part by part: the tolerance (the position within 1 mm and the rotation within 1
//! degree of the goal's, as offsets in a cube of side 2 in those units, in the goal's
//! constrained rows: a `z_symmetric` goal's turn about its z is free) is cut into boxes, each
//! solved exactly at its centre pose from its parent's configuration and certified over its own
//! extent alone; a box straddling the tolerance's edge is first shrunk to the bounding box of
//! what of it lies within (the poses beyond need no certificate). A box is settled when its
//! configuration stays colliding, or outside a joint's limits, throughout it; one that is not
//! is halved across the offset that moves the pair most there (its distance gradient times the
//! box's extent), down to 1/64 of the tolerance in each (1/16 for a sweep's cheap search
//! budget). A free configuration within the limits at a centre well inside the tolerance
//! reaches the goal. Same order of rigour as the one certificate (first order, doubled):
//! docs/ik.md.

use super::certify::{limit_gap, Region, LINEAR_REACH_RAD};
use super::search::FIRST_ORDER_BUDGET;
use super::{joint_difference, Ik, IkSolution, EXACT, REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use crate::scenario::{Goal, Tolerance};
use nalgebra::{UnitQuaternion, Vector3, Vector6};
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::rc::Rc;

/// Boxes solved and measured at most per solution.
const CELL_BUDGET: usize = 4096;
/// Boxes solved and measured at most per goal: a self-motion's samples may each need cutting,
/// and a goal that is left open anyway should not cost seconds.
pub(super) const PARTS_PER_GOAL: usize = 8192;
/// Cells searched for a free configuration once one has failed for good.
const AFTER_FAILURE: usize = 256;
/// The smallest half-width of a box is the tolerance's divided by this: a thorough run's (a
/// joint-space search budget from [`FIRST_ORDER_BUDGET`] boxes, validation's) and a cheap
/// one's (a sweep's). Measured on eight shipped 6-joint designs on 36 cluttered tasks of
/// another seed (2 304 goals), with boxes clipped to the tolerance: a sweep's 200 search boxes
/// left 31 goals undecided at 1/16 (0.49 s), 30 at 1/32 (0.55 s), 28 at 1/64 (0.70 s);
/// validation's 200 000 left 16, 15 and 13.
const SMALLEST_PART: [u32; 2] = [16, 64];
/// How far into the tolerance (a part of it) a cell's centre may lie for its free
/// configuration to reach the goal: the error must stay within it after rounding.
const WITNESS: f64 = 0.9;

/// What cutting the tolerance found.
pub(super) enum Cells {
    /// Every box within the tolerance collides or is outside the limits throughout: the pair
    /// at the solution, with how many boxes it took.
    Settled(String),
    /// A free configuration within the limits and the tolerance.
    Free(IkSolution),
    /// Why neither.
    Open(String),
    /// Not cut: a `position` goal, or a solution near a singularity (no `dq` over the whole
    /// tolerance), where the centres' solutions leave the branch.
    Untried,
}

/// A box of pose offsets in units of the tolerance: position (mm), then rotation (degrees),
/// in the goal's constrained rows (world axes for a pose goal; a `z_symmetric` goal's turns
/// about its x and y, the last offset 0).
struct Cell {
    centre: [f64; 6],
    half: [f64; 6],
    /// The configuration its parent's centre reached (shared by both halves).
    start: Rc<Vec<f64>>,
    /// How far each joint may move over the parent (its neighbourhood): a centre's
    /// configuration further from `start` is on another branch.
    within: Rc<Vec<f64>>,
}

/// Metres or radians per unit of offset `k`.
fn unit(k: usize) -> f64 {
    if k < 3 {
        REACHED_POSITION_M
    } else {
        REACHED_ORIENTATION_RAD
    }
}

/// The smallest box holding the part of the box `centre` +- `half` (units of the tolerance, as
/// [`Cell`]'s) within the tolerance: per part, the bounding box of the box's intersection with
/// the unit ball (along each offset, as far as the ball reaches with the other two offsets at
/// their smallest magnitude in the box); `None` when they do not meet. A box straddling the
/// tolerance's edge is certified over what of it the tolerance holds, about a centre within
/// it, not over the poses beyond.
pub(super) fn clipped_to_tolerance(centre: &[f64; 6], half: &[f64; 6]) -> Option<([f64; 6], [f64; 6])> {
    let (mut low, mut high): ([f64; 6], [f64; 6]) = (
        std::array::from_fn(|k| centre[k] - half[k]),
        std::array::from_fn(|k| centre[k] + half[k]),
    );
    for first in [0, 3] {
        let least: [f64; 3] = std::array::from_fn(|i| {
            let k = first + i;
            if low[k] <= 0.0 && high[k] >= 0.0 {
                0.0
            } else {
                low[k].abs().min(high[k].abs())
            }
        });
        let total: f64 = least.iter().map(|m| m * m).sum();
        if total > 1.0 {
            return None;
        }
        for (i, own) in least.iter().enumerate() {
            let reach = (1.0 - (total - own * own)).max(0.0).sqrt();
            let k = first + i;
            low[k] = low[k].max(-reach);
            high[k] = high[k].min(reach);
            if low[k] > high[k] {
                return None;
            }
        }
    }
    // Offsets the clip leaves alone keep their bits: a box the tolerance holds is unchanged.
    let (mut centre, mut half) = (*centre, *half);
    for k in 0..6 {
        if low[k] > centre[k] - half[k] || high[k] < centre[k] + half[k] {
            centre[k] = 0.5 * (low[k] + high[k]);
            half[k] = 0.5 * (high[k] - low[k]);
        }
    }
    Some((centre, half))
}

/// `goal` moved by the offsets `centre` (units of the tolerance, as [`Cell`]'s: a
/// `z_symmetric` goal's rotation offsets about its own x and y).
pub(super) fn offset_goal(goal: &Goal, centre: &[f64; 6]) -> Goal {
    let part = |first: usize| Vector3::new(centre[first], centre[first + 1], centre[first + 2]);
    let turn = part(3) * REACHED_ORIENTATION_RAD;
    let turn = match goal.tolerance {
        Tolerance::ZSymmetric => goal.rotation * turn,
        _ => turn,
    };
    Goal {
        position: goal.position + part(0) * REACHED_POSITION_M,
        rotation: UnitQuaternion::from_scaled_axis(turn) * goal.rotation,
        ..goal.clone()
    }
}

impl Cell {
    /// The position part (`0`) or the rotation part (`3`) of the centre.
    fn part(&self, first: usize) -> Vector3<f64> {
        Vector3::new(self.centre[first], self.centre[first + 1], self.centre[first + 2])
    }

    /// Whether the centre is far enough inside the tolerance to stand for the goal.
    fn is_witness(&self) -> bool {
        self.part(0).norm() <= WITNESS && self.part(3).norm() <= WITNESS
    }

    /// The poses of the box, about its centre.
    fn region(&self) -> Region {
        Region::Box(std::array::from_fn(|k| self.half[k] * unit(k)))
    }

    /// The centre as a goal.
    fn goal(&self, goal: &Goal) -> Goal {
        offset_goal(goal, &self.centre)
    }

    /// The offset to halve across: the one the pair's distance `gradient` (task space) changes
    /// most over, else the widest; `None` when every offset is at its smallest.
    fn widest(&self, gradient: Option<&Vector6<f64>>, smallest_half: f64) -> Option<usize> {
        let weight = |k: usize| gradient.map_or(self.half[k], |h| h[k].abs() * unit(k) * self.half[k]);
        (0..6)
            .filter(|&k| self.half[k] / 2.0 >= smallest_half)
            .max_by(|&a, &b| weight(a).total_cmp(&weight(b)).then(b.cmp(&a)))
    }

    fn describe(&self) -> String {
        format!(
            "({:.2}, {:.2}, {:.2}) mm and ({:.2}, {:.2}, {:.2}) deg off the goal",
            self.centre[0], self.centre[1], self.centre[2], self.centre[3], self.centre[4], self.centre[5]
        )
    }
}

/// A box waiting, by how far its pair's distance is expected to be at its centre: the boxes
/// most likely free first, so a free configuration is found early; ties in the order made.
struct Queued {
    expected: f64,
    order: u64,
    cell: Cell,
}

impl PartialEq for Queued {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Queued {}

impl PartialOrd for Queued {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Queued {
    fn cmp(&self, other: &Self) -> Ordering {
        self.expected.total_cmp(&other.expected).then_with(|| other.order.cmp(&self.order))
    }
}

/// The boxes waiting.
#[derive(Default)]
struct Queue {
    heap: BinaryHeap<Queued>,
    made: u64,
}

impl Queue {
    /// The two halves of `cell` across offset `k`; its centre reached `reached` with the pair
    /// at `clearance` and its task-space `gradient` there; `within` as in [`Cell::within`].
    fn halve(&mut self, cell: &Cell, k: usize, reached: Vec<f64>, within: Vec<f64>, clearance: f64, gradient: Option<&Vector6<f64>>) {
        let (start, within) = (Rc::new(reached), Rc::new(within));
        let quarter = cell.half[k] / 2.0;
        for side in [-1.0, 1.0] {
            let mut half = Cell {
                centre: cell.centre,
                half: cell.half,
                start: Rc::clone(&start),
                within: Rc::clone(&within),
            };
            half.centre[k] += side * quarter;
            half.half[k] = quarter;
            let growth = gradient.map_or(0.0, |h| h[k] * side * quarter * unit(k));
            self.made += 1;
            self.heap.push(Queued {
                expected: clearance + growth,
                order: self.made,
                cell: half,
            });
        }
    }
}

/// The first box left unsettled for good, and the boxes to evaluate.
struct Unsettled {
    failure: Option<String>,
    budget: usize,
}

impl Unsettled {
    /// A box unsettled for good leaves the goal open; the others are still searched for a
    /// free configuration, briefly.
    fn give_up(&mut self, evaluated: usize, why: String) {
        if self.failure.is_none() {
            self.budget = self.budget.min(evaluated + AFTER_FAILURE);
            self.failure = Some(why);
        }
    }
}

impl Ik<'_> {
    /// Cuts the tolerance of `pose` or `z_symmetric` goal `goal` about its exact solution `q`
    /// into boxes (module doc); `judged` is the goal a free configuration is judged against (a
    /// sample of a `z_symmetric` goal's self-motion is a pose goal, the goal itself looser),
    /// `turn` as in [`Self::collision_certificate`].
    pub(super) fn cut_tolerance(&mut self, goal: &Goal, judged: &Goal, q: &[f64], margin: f64, turn: f64) -> Cells {
        let free_turn = match goal.tolerance {
            Tolerance::Pose => 1.0,
            Tolerance::ZSymmetric => 0.0,
            Tolerance::Position => return Cells::Untried,
        };
        let measured = self.checker.as_mut().and_then(|checker| {
            let clearance = checker.clearance(q, true).exact_m;
            checker.closest_pair().map(|pair| (pair, clearance))
        });
        let Some((pair, clearance)) = measured else {
            return Cells::Open("a solution's collision was not measured".into());
        };
        let at_solution = format!("{} {:.1} mm", pair.name, clearance * 1e3);
        let Some(within) = self.neighbourhood_within(goal, q, turn, Region::WHOLE) else {
            return Cells::Untried;
        };
        let whole = Cell {
            centre: [0.0; 6],
            half: [1.0, 1.0, 1.0, 1.0, 1.0, free_turn],
            start: Rc::new(Vec::new()),
            within: Rc::new(Vec::new()),
        };
        let gradient = self.distance_gradient(goal, q, &pair).map(|(h, _)| h);
        let mut queue = Queue::default();
        let smallest_part = SMALLEST_PART[usize::from(self.opts.search_boxes >= FIRST_ORDER_BUDGET)];
        let smallest_half = 1.0 / f64::from(smallest_part);
        if let Some(k) = whole.widest(gradient.as_ref(), smallest_half) {
            queue.halve(&whole, k, q.to_vec(), within, clearance, gradient.as_ref());
        }
        let mut settled = 0usize;
        let mut evaluated = 0usize;
        if self.parts_left == 0 {
            return Cells::Open(format!("the goal's {} parts to cut are spent", self.cell_parts));
        }
        let mut open = Unsettled {
            failure: None,
            budget: CELL_BUDGET.min(self.parts_left),
        };
        while let Some(Queued { mut cell, .. }) = queue.heap.pop() {
            let Some((centre, half)) = clipped_to_tolerance(&cell.centre, &cell.half) else {
                continue;
            };
            (cell.centre, cell.half) = (centre, half);
            if evaluated == open.budget {
                return Cells::Open(open.failure.unwrap_or_else(|| {
                    format!("{settled} parts of the goal's tolerance are proven, but more than {evaluated} were needed")
                }));
            }
            evaluated += 1;
            self.parts_left -= 1;
            let target = cell.goal(goal);
            let mut reached = cell.start.to_vec();
            let (_, size, _) = self.polish(&target, &mut reached);
            if size > EXACT {
                open.give_up(
                    evaluated,
                    format!("the pose {} has no verified solution on this branch", cell.describe()),
                );
                continue;
            }
            // A free configuration of another branch still reaches the goal; it proves nothing
            // about this one.
            let jumped = (self
                .model
                .joints
                .iter()
                .zip(&reached)
                .zip(cell.start.iter())
                .zip(cell.within.iter()))
            .any(|(((joint, a), b), within)| joint_difference(joint, *a, *b).abs() > *within);
            let region = cell.region();
            let reach = self.neighbourhood_within(&target, &reached, turn, region);
            let joints = &self.model.joints;
            if let Some(reach) = &reach {
                if !jumped
                    && joints
                        .iter()
                        .zip(&reached)
                        .zip(reach)
                        .any(|((joint, value), r)| limit_gap(joint, *value) > *r)
                {
                    settled += 1;
                    continue;
                }
            }
            let within_limits = joints.iter().zip(&reached).all(|(joint, value)| limit_gap(joint, *value) <= 0.0);
            let Some(checker) = self.checker.as_mut() else {
                return Cells::Open("a solution's collision was not measured".into());
            };
            let clearance = checker.clearance(&reached, true).exact_m;
            let pair = checker.closest_pair();
            if within_limits && clearance > margin && cell.is_witness() {
                let mut shifted = reached.clone();
                if self.shift_into_limits(&mut shifted, Some(q)) {
                    let solution = self.judge(judged, shifted, None, margin);
                    if solution.reached {
                        return Cells::Free(solution);
                    }
                }
            }
            if jumped {
                open.give_up(
                    evaluated,
                    format!("the pose {} has no verified solution on this branch", cell.describe()),
                );
                continue;
            }
            // The gradient serves the bound and the choice of the offset to halve alike.
            let gradient = pair.as_ref().and_then(|pair| self.distance_gradient(&target, &reached, pair));
            let motion = match (&reach, &pair) {
                (Some(reach), Some(pair)) => self.pair_motion(pair, turn, region, Some(reach), gradient.as_ref()),
                _ => None,
            };
            if motion.is_some_and(|motion| clearance + motion <= margin) {
                settled += 1;
                continue;
            }
            let gradient = gradient.map(|(h, _)| h);
            let Some(k) = cell.widest(gradient.as_ref(), smallest_half) else {
                let name = pair.map_or_else(|| "no pair".to_string(), |p| p.name);
                open.give_up(
                    evaluated,
                    match motion {
                        Some(motion) => format!(
                            "at the pose {} {name} are at {:.1} mm, within the {:.1} mm a 1/{smallest_part} part of the tolerance can move them",
                            cell.describe(),
                            clearance * 1e3,
                            motion * 1e3
                        ),
                        None => format!(
                            "the pose {} is near a singularity, with {name} at {:.1} mm",
                            cell.describe(),
                            clearance * 1e3
                        ),
                    },
                );
                continue;
            };
            let within = reach.unwrap_or_else(|| vec![LINEAR_REACH_RAD; reached.len()]);
            queue.halve(&cell, k, reached, within, clearance, gradient.as_ref());
        }
        if let Some(failure) = open.failure {
            return Cells::Open(failure);
        }
        Cells::Settled(format!("{at_solution}, throughout {settled} parts of the tolerance"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Whether some offset of the box `centre` +- `half` (units of the tolerance, as [`Cell`]'s) is
    /// within the tolerance: both parts' nearest points within the unit ball.
    fn touches_tolerance(centre: &[f64; 6], half: &[f64; 6]) -> bool {
        [0, 3].into_iter().all(|first| {
            let nearest = Vector3::from_fn(|k, _| (centre[first + k].abs() - half[first + k]).max(0.0));
            nearest.norm() <= 1.0
        })
    }

    /// Every offset of a box within the tolerance lies in its clipped box, and the clipped box
    /// lies in the box; a box the tolerance holds is its own clip, one it misses has none.
    #[test]
    fn a_clipped_box_holds_what_the_tolerance_holds_of_it() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(64);
        let mut clipped_some = 0;
        for _ in 0..2000 {
            let centre: [f64; 6] = std::array::from_fn(|_| rng.random_range(-1.3..1.3));
            let half: [f64; 6] = std::array::from_fn(|_| rng.random_range(0.0..0.4));
            let clip = clipped_to_tolerance(&centre, &half);
            assert_eq!(clip.is_some(), touches_tolerance(&centre, &half), "{centre:?} +- {half:?}");
            let Some((c, h)) = clip else { continue };
            if h != half {
                clipped_some += 1;
            }
            for k in 0..6 {
                assert!(c[k] - h[k] >= centre[k] - half[k] - 1e-12 && c[k] + h[k] <= centre[k] + half[k] + 1e-12);
            }
            for _ in 0..200 {
                let point: [f64; 6] = std::array::from_fn(|k| centre[k] + half[k] * rng.random_range(-1.0..=1.0));
                let norm = |first: usize| point[first..first + 3].iter().map(|x| x * x).sum::<f64>().sqrt();
                if norm(0) <= 1.0 && norm(3) <= 1.0 {
                    assert!(
                        (0..6).all(|k| (point[k] - c[k]).abs() <= h[k] + 1e-12),
                        "{point:?} within the tolerance, outside the clip {c:?} +- {h:?}"
                    );
                }
            }
        }
        assert!(clipped_some > 100, "{clipped_some} boxes clipped");
        let inside = ([0.1, -0.2, 0.1, 0.0, 0.3, -0.1], [0.1; 6]);
        assert_eq!(clipped_to_tolerance(&inside.0, &inside.1), Some(inside));
        assert_eq!(clipped_to_tolerance(&[1.5, 0.0, 0.0, 0.0, 0.0, 0.0], &[0.2; 6]), None);
    }
}
