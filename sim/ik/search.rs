//! Joint-space branch and bound: proves that no configuration within the joint limits brings
//! the tool within a goal's tolerance, or finds one that does. It needs no closed form and no
//! particular geometry (any number of joints, redundant or not, singular or not), so it decides
//! what the all-solutions methods leave open: a pose with no exact solution whose tolerance may
//! still hold one, a self-motion sampled but not covered, an arm no method applies to.
//!
//! A box of joint values is discarded when the goal error at its centre exceeds the tolerance by
//! more than the tool can move within the box. The bound is rigorous, not first order: moving
//! the joints from the centre to any point of the box one at a time, last joint first, each
//! joint's axis stays where the centre puts it, and the tool point, already displaced by at most
//! `D` by the later joints, is at most `r + D` from that axis (`r` its distance at the centre),
//! so a turn by `h` moves it by at most `2 sin(h / 2) (r + D)`. Rotations compose the same way
//! (the angle of a product is at most the sum of the angles; a direction at angle `s` from an
//! axis moves by at most `h sin s`).
//!
//! A box these bounds keep is tried against first-order ones (`ik::separate`: the
//! residual's linear model over the box, in the direction the model misses the tolerance by
//! most), and, once small, split at the joint that keeps that test from discarding it:
//! splitting by the zeroth-order bound alone cut joints that move the tool's position while its
//! orientation was what could rule the box out (see `FIRST_ORDER_M`). A box shrunk to a point
//! on the tolerance's edge is left open after one local solve, never split further: splitting
//! it again only repeated it until the budget ran out.

use super::{goal_error, REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use crate::model::{JointKind, KinematicsWorkspace, Model};
use crate::scenario::{Goal, Tolerance};
use nalgebra::Vector3;
use std::f64::consts::{PI, TAU};

/// What the search established.
#[derive(Debug, Clone, PartialEq)]
pub enum Search {
    /// Every box was discarded: no configuration within the limits is within the tolerance
    /// (and free, where collisions count).
    Proven {
        /// Boxes visited.
        boxes: usize,
        /// Boxes discarded because every configuration in them collides.
        colliding: usize,
    },
    /// A configuration within the tolerance and the limits.
    Found {
        /// The configuration (a box centre, or where the local solve from one ended).
        q: Vec<f64>,
        /// Boxes visited.
        boxes: usize,
    },
    /// The budget ran out first.
    Open {
        /// Boxes visited: the budget.
        boxes: usize,
    },
}

/// Rounding of the goal error at a box centre (m and rad), far below any tolerance.
pub(super) const ROUNDING: f64 = 1e-9;

/// The tolerance a search proves against: the harness's 1 mm and 1 degree, or wider ones for a
/// sub-chain that stands in for the arm (`ik::reduce`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Radii {
    /// Position (m).
    pub position_m: f64,
    /// Orientation (rad): of the whole rotation (`pose`) or of the tool z axis (`z_symmetric`).
    pub orientation_rad: f64,
}

impl Radii {
    /// The harness's tolerance: [`REACHED_POSITION_M`] and [`REACHED_ORIENTATION_RAD`].
    pub const REACHED: Radii = Radii {
        position_m: REACHED_POSITION_M,
        orientation_rad: REACHED_ORIENTATION_RAD,
    };

    /// The radii in words: "1 mm and 1 degree" for the harness's own.
    pub(super) fn words(&self) -> String {
        if *self == Self::REACHED {
            "1 mm and 1 degree".to_string()
        } else {
            format!("{:.3} mm and {:.3} deg", self.position_m * 1e3, self.orientation_rad.to_degrees())
        }
    }

    /// Whether `error` is within these radii.
    pub(super) fn holds(&self, error: &super::GoalError) -> bool {
        error.position_m < self.position_m && error.orientation_rad < self.orientation_rad
    }
}

/// One box: the lower and upper joint values.
type JointBox = (Vec<f64>, Vec<f64>);

/// The joint ranges the search covers: the limits, a revolute joint's at most one turn (FK is
/// periodic), `[-pi, pi]` without limits; `None` when a prismatic joint has no limits or a
/// limit is not finite (nothing bounds the box).
pub(super) fn ranges(model: &Model) -> Option<JointBox> {
    let mut lower = Vec::with_capacity(model.dof());
    let mut upper = Vec::with_capacity(model.dof());
    for joint in &model.joints {
        let [low, high] = match (joint.kind, joint.limits) {
            (JointKind::Prismatic, None) => return None,
            (JointKind::Prismatic, Some(limits)) => limits,
            (_, None) => [-PI, PI],
            (_, Some([low, high])) => [low, high.min(low + TAU)],
        };
        if !(low.is_finite() && high.is_finite()) || high < low {
            return None;
        }
        lower.push(low);
        upper.push(high);
    }
    Some((lower, upper))
}

/// Tool motion bound (m) below which a box that is not ruled out is small enough for a local
/// solve from its centre to land in it: the proof's boxes around a reachable pose would
/// otherwise have to shrink to the tolerance itself before a centre falls within it.
const LOCAL_SOLVE_M: f64 = 0.05;

/// Tool motion (m and rad) within a box below which the box is a point: its centre stands
/// for all of it.
const POINT: f64 = 1e-9;

/// Tool motion bound (m) up to which a box is split where the first-order test is held back
/// most; larger boxes by the zeroth-order bound. Measured on the workspace task (100
/// `z_symmetric` goals, 200 000 boxes): the paper's real-world arm (5 joints) leaves 14 goals
/// open splitting by the zeroth-order bound alone, 3 by the first-order test alone, 4 with this
/// switch; the free 6-joint design (redundant there) 5 and 11 and 5.
const FIRST_ORDER_M: f64 = 0.2;

/// Budget (boxes) from which a search uses the separating test: a smaller one never splits
/// boxes down to where that test pays. The brute force's 200-box searches (60 375 undecided
/// goals on cluttered task 00) decided the same goals with and without it, 14 % slower with.
pub(super) const FIRST_ORDER_BUDGET: usize = 10_000;

/// Share of a box's tool motion bound below which a joint's split is not worth making.
const SPLIT_SHARE: f64 = 1e-6;

/// Jacobian evaluations of a local solve from a box centre.
pub(super) const LOCAL_ITERATIONS: usize = 20;

/// The local solve [`search`] wants: the numeric solver from `q` (kept within the limits), true
/// when it ends within the goal's tolerance.
pub(super) fn solve_locally<R: rand::Rng>(model: &Model, solver: &mut super::dls::Solver, goal: &Goal, q: &mut [f64], rng: &mut R) -> bool {
    solver.solve(goal, q, LOCAL_ITERATIONS, super::CONVERGED, rng);
    super::is_reached(&goal_error(goal, &model.tool_pose(q)))
}

/// What one box's bounds say.
enum Judged {
    /// Its centre is within the tolerance.
    Inside,
    /// No configuration in it is.
    RuledOut,
    /// Undecided: split this joint; the tool moves at most this far (m) within the box.
    Split(usize, f64),
}

/// Scratch space for judging boxes of one model against one goal.
struct Judge<'a> {
    model: &'a Model,
    goal: &'a Goal,
    radii: Radii,
    ws: KinematicsWorkspace,
    revolute: Vec<bool>,
    centre: Vec<f64>,
    half: Vec<f64>,
    // Per joint: how far the tool point and the constrained direction can move because of it
    // and the joints after it (the recursion's D and A).
    moves: Vec<f64>,
    turns: Vec<f64>,
    // Per joint: the second-order remainders of the box ([`remainders`]) and the first-order
    // test's terms ([`linear_rules_out`]); scratch, reused box after box.
    position_rest: Vec<f64>,
    axis_rest: Vec<f64>,
    rates: Vec<Rates>,
    separator: super::separate::Separator,
    /// Whether boxes face the separating test (see [`FIRST_ORDER_BUDGET`]).
    separating: bool,
    /// Judges of sub-chains that stand in for the arm ([`Helper`]): a box whose first joints
    /// one of them rules out is out.
    helpers: Vec<Judge<'a>>,
}

/// A sub-chain of the searched arm (its first joints) with a goal it must reach within `radii`
/// whenever the arm reaches its own (`ik::reduce`): its bounds, over the box's first
/// joints alone, rule boxes out long before the whole arm's do.
pub struct Helper<'a> {
    /// The sub-chain: the searched arm's first joints.
    pub model: &'a Model,
    /// Where its tool must be.
    pub goal: &'a Goal,
    /// Within what.
    pub radii: Radii,
}

impl<'a> Judge<'a> {
    fn new(model: &'a Model, goal: &'a Goal, radii: Radii) -> Self {
        let dof = model.dof();
        Self {
            model,
            goal,
            radii,
            ws: model.workspace(),
            revolute: model.joints.iter().map(|j| j.kind != JointKind::Prismatic).collect(),
            centre: vec![0.0; dof],
            half: vec![0.0; dof],
            moves: vec![0.0; dof + 1],
            turns: vec![0.0; dof + 1],
            position_rest: vec![0.0; dof],
            axis_rest: vec![0.0; dof],
            rates: vec![Rates::default(); dof],
            separator: super::separate::Separator::new(dof),
            separating: true,
            helpers: Vec::new(),
        }
    }

    /// Fills the centre, the half-widths, the Jacobian at the centre and the zeroth-order
    /// bounds of a box; returns the goal error at its centre.
    fn measure(&mut self, lower: &[f64], upper: &[f64]) -> super::GoalError {
        let (model, goal) = (self.model, self.goal);
        let dof = model.dof();
        for i in 0..dof {
            self.centre[i] = 0.5 * (lower[i] + upper[i]);
            self.half[i] = 0.5 * (upper[i] - lower[i]);
        }
        model.tool_jacobian(&self.centre, &mut self.ws);
        let tool = self.ws.tool_in_world;
        let error = goal_error(goal, &tool);
        let tool_z = tool.rotation * Vector3::z();
        let (half, moves, turns) = (&self.half, &mut self.moves, &mut self.turns);
        for j in (0..dof).rev() {
            let column = self.ws.jacobian.column(j);
            let (linear, axis) = (column.fixed_rows::<3>(0).norm(), Vector3::new(column[3], column[4], column[5]));
            let (after_move, after_turn) = (moves[j + 1], turns[j + 1]);
            if self.revolute[j] {
                let chord = 2.0 * (half[j].min(PI) / 2.0).sin();
                moves[j] = after_move + chord * (linear + after_move);
                let spin = match goal.tolerance {
                    Tolerance::Pose => half[j],
                    Tolerance::ZSymmetric => half[j] * (axis.cross(&tool_z).norm() + after_turn).min(1.0),
                    Tolerance::Position => 0.0,
                };
                turns[j] = (after_turn + spin).min(PI);
            } else {
                moves[j] = after_move + half[j];
                turns[j] = after_turn;
            }
        }
        error
    }

    fn judge(&mut self, lower: &[f64], upper: &[f64]) -> Judged {
        let goal = self.goal;
        let error = self.measure(lower, upper);
        if self.radii.holds(&error) {
            return Judged::Inside;
        }
        let (moves, turns) = (&self.moves, &self.turns);
        let position_gap = error.position_m - ROUNDING - self.radii.position_m;
        let orientation_gap = error.orientation_rad - ROUNDING - self.radii.orientation_rad;
        if moves[0] <= position_gap || turns[0] <= orientation_gap {
            return Judged::RuledOut;
        }
        for helper in &mut self.helpers {
            let joints = helper.model.dof();
            if matches!(helper.judge(&lower[..joints], &upper[..joints]), Judged::RuledOut) {
                return Judged::RuledOut;
            }
        }
        let bounds = Bounds {
            half: &self.half,
            revolute: &self.revolute,
            moves: &self.moves,
            turns: &self.turns,
        };
        remainders(&self.ws, &bounds, &mut self.position_rest, &mut self.axis_rest);
        let rests = (self.position_rest.as_slice(), self.axis_rest.as_slice());
        if linear_rules_out(goal, self.radii, &self.ws, &bounds, rests, &mut self.rates) {
            return Judged::RuledOut;
        }
        if !self.separating {
            return Judged::Split(self.coarse_split(position_gap, orientation_gap), self.moves[0]);
        }
        let separating = super::separate::BoxBounds {
            half: &self.half,
            revolute: &self.revolute,
            position_rest: &self.position_rest,
            axis_rest: &self.axis_rest,
        };
        let Some(split) = self.separator.rules_out(goal, self.radii, &self.ws, &separating) else {
            return Judged::RuledOut;
        };
        // A joint that moves the tool by next to nothing within the box (at a singularity of
        // the chain) gains nothing by its split, however the first-order test weighs it: split
        // that one forever and the box never shrinks.
        let moves_tool = |j: usize| {
            self.moves[j] - self.moves[j + 1] > SPLIT_SHARE * self.moves[0]
                || self.turns[j] - self.turns[j + 1] > SPLIT_SHARE * self.turns[0]
        };
        if self.moves[0] <= FIRST_ORDER_M && moves_tool(split) {
            return Judged::Split(split, self.moves[0]);
        }
        Judged::Split(self.coarse_split(position_gap, orientation_gap), self.moves[0])
    }

    /// The split of a box whose centre is within the tolerance but collides: the joint that
    /// moves the tool furthest within it.
    fn widest(&self) -> usize {
        let contribution = |j: usize| self.moves[j] - self.moves[j + 1];
        (0..self.model.dof()).fold(0, |best, j| if contribution(j) > contribution(best) { j } else { best })
    }

    /// The split of a large box, where the first-order model says little: the joint that
    /// contributes most to the zeroth-order bound nearer to discarding it.
    fn coarse_split(&self, position_gap: f64, orientation_gap: f64) -> usize {
        let by_orientation = self.goal.tolerance != Tolerance::Position
            && orientation_gap > 0.0
            && (position_gap <= 0.0 || self.turns[0] / orientation_gap < self.moves[0] / position_gap);
        let contribution = |j: usize| {
            if by_orientation {
                self.turns[j] - self.turns[j + 1]
            } else {
                self.moves[j] - self.moves[j + 1]
            }
        };
        (0..self.model.dof()).fold(0, |best, j| if contribution(j) > contribution(best) { j } else { best })
    }
}

/// Whether the bounds rule out every configuration in the box from `lower` to `upper` for
/// `goal`: the test [`search`] discards boxes by, for checks against configurations known to
/// be within the tolerance.
pub fn rules_out(model: &Model, goal: &Goal, lower: &[f64], upper: &[f64]) -> bool {
    matches!(Judge::new(model, goal, Radii::REACHED).judge(lower, upper), Judged::RuledOut)
}

/// What a box's configurations are against collisions (see [`Oracle::clear`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Clear {
    /// The centre is free.
    Free,
    /// Every configuration of the box is free: the centre's clearance exceeds how far any two
    /// bodies can approach within the box (nothing in it is worth another query).
    FreeThroughout,
    /// Every configuration of the box collides: the centre's deepest overlap is deeper than its
    /// bodies can move within the box.
    Colliding,
    /// The centre collides, the rest of the box may not.
    Unknown,
}

/// What the search asks beyond its bounds: local solves from box centres and, where it looks
/// for free configurations, collisions.
pub trait Oracle {
    /// Solves from a box centre in place: true when it ended within the tolerance and the
    /// limits (and free, where collisions count).
    fn local(&mut self, q: &mut [f64]) -> bool;
    /// The box with centre `centre` and half-widths `half` against collisions; never asked when
    /// [`Oracle::collisions`] is false.
    fn clear(&mut self, centre: &[f64], half: &[f64]) -> Clear;
    /// Whether collisions count: the search then proves that every configuration within the
    /// tolerance collides, or finds a free one.
    fn collisions(&self) -> bool;
}

/// An oracle of local solves alone.
pub(super) struct Solves<F: FnMut(&mut [f64]) -> bool>(pub(super) F);

impl<F: FnMut(&mut [f64]) -> bool> Oracle for Solves<F> {
    fn local(&mut self, q: &mut [f64]) -> bool {
        (self.0)(q)
    }
    fn clear(&mut self, _: &[f64], _: &[f64]) -> Clear {
        Clear::Free
    }
    fn collisions(&self) -> bool {
        false
    }
}

/// Tool motion bound (m) below which a box the bounds keep is checked against collisions: a
/// larger one moves its links further than any overlap is deep.
const COLLISION_CHECK_M: f64 = 0.2;

/// Searches the joint space of `model` for a configuration within `goal`'s tolerance, visiting
/// at most `budget` boxes; `None` when the joint ranges are unbounded. `local` solves from a box
/// centre in place and says whether it ended within the tolerance and the limits (`|_| false`
/// leaves the search to its bounds alone).
pub fn search(model: &Model, goal: &Goal, budget: usize, local: impl FnMut(&mut [f64]) -> bool) -> Option<Search> {
    search_with(model, goal, Radii::REACHED, budget, &mut Solves(local))
}

/// [`search`] against the tolerance `radii`, asking `oracle`: where it counts collisions, a
/// box whose every configuration collides is discarded too, and only a free configuration is
/// found.
pub fn search_with(model: &Model, goal: &Goal, radii: Radii, budget: usize, oracle: &mut dyn Oracle) -> Option<Search> {
    search_helped(model, goal, radii, budget, oracle, &[])
}

/// [`search_with`] with sub-chains that rule boxes out by their first joints.
pub fn search_helped(
    model: &Model,
    goal: &Goal,
    radii: Radii,
    budget: usize,
    oracle: &mut dyn Oracle,
    helpers: &[Helper],
) -> Option<Search> {
    let (lower, upper) = ranges(model)?;
    search_box(model, goal, radii, budget, oracle, helpers, lower, upper)
}

/// [`search_helped`] over the joint values from `lower` to `upper` (within the joint ranges)
/// instead of the whole ranges: what it proves holds for that box alone.
#[allow(clippy::too_many_arguments)] // the search's inputs, and the box it starts from
pub(super) fn search_box(
    model: &Model,
    goal: &Goal,
    radii: Radii,
    budget: usize,
    oracle: &mut dyn Oracle,
    helpers: &[Helper],
    lower: Vec<f64>,
    upper: Vec<f64>,
) -> Option<Search> {
    let mut judge = Judge::new(model, goal, radii);
    judge.separating = budget >= FIRST_ORDER_BUDGET;
    for helper in helpers {
        let mut sub = Judge::new(helper.model, helper.goal, helper.radii);
        sub.separating = judge.separating;
        judge.helpers.push(sub);
    }
    let collisions = oracle.collisions();
    let dof = model.dof();
    // Per box: its bounds (lower then upper, flat: no allocation per box), its parent's tool
    // motion bound, and whether it is known free throughout (a box inside one that is).
    let mut stack: Vec<f64> = [lower.as_slice(), upper.as_slice()].concat();
    let mut parents = vec![(f64::INFINITY, !collisions)];
    let (mut lower, mut upper) = (lower, upper);
    let mut boxes = 0;
    let mut colliding = 0;
    let mut left_open = 0;
    while let Some((parent_moves, mut free)) = parents.pop() {
        let top = stack.len() - 2 * dof;
        lower.copy_from_slice(&stack[top..top + dof]);
        upper.copy_from_slice(&stack[top + dof..]);
        stack.truncate(top);
        if boxes == budget {
            return Some(Search::Open { boxes });
        }
        boxes += 1;
        let (split, moves) = match judge.judge(&lower, &upper) {
            Judged::Inside if free => return Some(Search::Found { q: judge.centre, boxes }),
            Judged::Inside => match oracle.clear(&judge.centre, &judge.half) {
                Clear::Free | Clear::FreeThroughout => return Some(Search::Found { q: judge.centre, boxes }),
                Clear::Colliding => {
                    colliding += 1;
                    continue;
                }
                Clear::Unknown => (judge.widest(), judge.moves[0]),
            },
            Judged::RuledOut => continue,
            Judged::Split(split, moves) => {
                if !free && moves < COLLISION_CHECK_M {
                    match oracle.clear(&judge.centre, &judge.half) {
                        Clear::Colliding => {
                            colliding += 1;
                            continue;
                        }
                        Clear::FreeThroughout => free = true,
                        Clear::Free | Clear::Unknown => {}
                    }
                }
                (split, moves)
            }
        };
        if moves < LOCAL_SOLVE_M && parent_moves >= LOCAL_SOLVE_M {
            let mut q = judge.centre.clone();
            if oracle.local(&mut q) {
                return Some(Search::Found { q, boxes });
            }
        }
        if judge.moves[0] < POINT && judge.turns[0] < POINT {
            // A box shrunk to a point that is neither in the tolerance nor ruled out sits on
            // the tolerance's edge: the bounds cannot decide it at any size, so one local
            // solve tries to step inside, and the box is otherwise left open.
            let mut q = judge.centre.clone();
            if oracle.local(&mut q) {
                return Some(Search::Found { q, boxes });
            }
            left_open += 1;
            continue;
        }
        let middle = judge.centre[split];
        // The upper half first, so the lower one is searched first.
        let top = stack.len();
        stack.extend_from_slice(&lower);
        stack.extend_from_slice(&upper);
        stack[top + split] = middle;
        stack.extend_from_slice(&lower);
        stack.extend_from_slice(&upper);
        stack[top + 3 * dof + split] = middle;
        parents.push((moves, free));
        parents.push((moves, free));
    }
    if left_open > 0 {
        return Some(Search::Open { boxes });
    }
    Some(Search::Proven { boxes, colliding })
}

/// A box's half-widths and its zeroth-order bounds (see [`search`]).
struct Bounds<'a> {
    half: &'a [f64],
    revolute: &'a [bool],
    moves: &'a [f64],
    turns: &'a [f64],
}

/// Mixes of the position test (weight 1) and the orientation test (weight 0) tried per box.
const MIXES: [f64; 7] = [1.0, 0.9, 0.7, 0.5, 0.3, 0.1, 0.0];

/// The first-order test: near a workspace boundary the tool moves across the error direction,
/// and the zeroth-order bound counts that motion as if it went straight at the goal. Here the
/// error is measured along fixed directions, where it is affine in each joint's turn up to a
/// remainder of second order (bounded rigorously: a turn `d` about a fixed axis moves a point
/// at `r` by `d` times its rate plus at most `(d - sin d + 1 - cos d) r`, and by `d` times how
/// far the later joints moved it). Orientation is measured by `tr(R_g^T R)` (`pose`, at least
/// `1 + 2 cos(tol)` within the tolerance) or `z . z_g` (`z_symmetric`), both linear in the
/// tool's axes. A weighted sum of the two normalised excesses that stays positive over the box
/// means one of them always does. `ws` holds the Jacobian at the box centre, the rests are
/// [`remainders`]. True when the box is ruled out.
fn linear_rules_out(
    goal: &Goal,
    radii: Radii,
    ws: &KinematicsWorkspace,
    bounds: &Bounds,
    (position_rest, axis_rest): (&[f64], &[f64]),
    rates: &mut [Rates],
) -> bool {
    let half = bounds.half;
    let tool = &ws.tool_in_world;
    let offset = tool.translation.vector - goal.position;
    let distance = offset.norm();
    if distance < 1e-12 {
        return false;
    }
    let along = offset / distance;
    let measure = Orientation::of(goal, radii, &tool.rotation);
    let dof = half.len();
    for (j, rate) in rates.iter_mut().enumerate() {
        let column = ws.jacobian.column(j);
        let linear = Vector3::new(column[0], column[1], column[2]);
        let axis = Vector3::new(column[3], column[4], column[5]);
        *rate = Rates {
            position: along.dot(&linear),
            orientation: axis.dot(&measure.gradient),
            position_rest: position_rest[j] / radii.position_m,
            orientation_rest: axis_rest[j] * measure.axes / measure.scale,
        };
    }
    // Joint `j`'s share of the first-order bound at weight `mix`: its rate over the box and its
    // remainder, both normalised.
    let share = |j: usize, mix: f64| {
        let r = &rates[j];
        let rate = mix * r.position / radii.position_m - (1.0 - mix) * r.orientation / measure.scale;
        rate.abs() * half[j] + mix * r.position_rest + (1.0 - mix) * r.orientation_rest
    };
    let position_excess = (distance - radii.position_m) / radii.position_m;
    let orientation_excess = (measure.within - measure.value) / measure.scale;
    let mixes: &[f64] = if goal.tolerance == Tolerance::Position {
        &MIXES[..1]
    } else {
        &MIXES
    };
    for &mix in mixes {
        let lowest = (0..dof).fold(mix * position_excess + (1.0 - mix) * orientation_excess, |lowest, j| {
            lowest - share(j, mix)
        });
        if lowest > ROUNDING {
            return true;
        }
    }
    false
}

/// One joint's terms in the first-order test: the rates at the box centre along the error
/// direction and of the orientation measure, and the remainders, normalised.
#[derive(Debug, Clone, Copy, Default)]
struct Rates {
    position: f64,
    orientation: f64,
    position_rest: f64,
    orientation_rest: f64,
}

/// The orientation measure of the first-order test, linear in the tool's axes.
struct Orientation {
    /// `tr(R_g^T R)` (`pose`), `z . z_g` (`z_symmetric`), 0 (`position`).
    value: f64,
    /// Its rate per unit turn about a world axis `a` is `a . gradient`.
    gradient: Vector3<f64>,
    /// The least value within the orientation tolerance.
    within: f64,
    /// Its rate near the tolerance per radian times the tolerance: the excess's unit.
    scale: f64,
    /// Tool axes it reads (each bounds its own remainder).
    axes: f64,
}

impl Orientation {
    fn of(goal: &Goal, radii: Radii, tool: &nalgebra::UnitQuaternion<f64>) -> Self {
        let (rotation, target) = (tool.to_rotation_matrix(), goal.rotation.to_rotation_matrix());
        let tolerance = radii.orientation_rad;
        let read = |columns: std::ops::Range<usize>| {
            columns.fold((0.0, Vector3::zeros()), |(value, gradient), k| {
                let (axis, wanted) = (rotation.matrix().column(k).into_owned(), target.matrix().column(k).into_owned());
                (value + axis.dot(&wanted), gradient + axis.cross(&wanted))
            })
        };
        let (value, gradient, within, scale, axes) = match goal.tolerance {
            Tolerance::Pose => {
                let (value, gradient) = read(0..3);
                (value, gradient, 1.0 + 2.0 * tolerance.cos(), 2.0 * tolerance.sin() * tolerance, 3.0)
            }
            Tolerance::ZSymmetric => {
                let (value, gradient) = read(2..3);
                (value, gradient, tolerance.cos(), tolerance.sin() * tolerance, 1.0)
            }
            Tolerance::Position => (0.0, Vector3::zeros(), 0.0, 1.0, 0.0),
        };
        Self {
            value,
            gradient,
            within,
            scale,
            axes,
        }
    }
}

/// Per joint, the second-order remainders over the box, beyond the centre's rates times the
/// turns: of the tool position (m) and of one tool axis (a unit vector's displacement; the
/// orientation measure of [`Orientation`] reads [`Orientation::axes`] of them).
fn remainders(ws: &KinematicsWorkspace, bounds: &Bounds, position: &mut [f64], orientation: &mut [f64]) {
    let dof = bounds.half.len();
    position.fill(0.0);
    orientation.fill(0.0);
    for j in (0..dof).filter(|&j| bounds.revolute[j]) {
        let h = bounds.half[j];
        // Both terms grow with the turn up to half a turn, the most a box spans.
        let second = h - h.sin() + 1.0 - h.min(PI).cos();
        let lever = ws.jacobian.column(j).fixed_rows::<3>(0).norm();
        let (moved, turned) = (bounds.moves[j + 1], bounds.turns[j + 1]);
        position[j] = second * (lever + moved) + h * moved;
        orientation[j] = second + h * turned;
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use nalgebra::{Isometry3, UnitQuaternion};

    fn run(model: &Model, goal: &Goal, budget: usize) -> Option<Search> {
        let mut solver = super::super::dls::Solver::new(model);
        let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(0);
        search(model, goal, budget, |q| solve_locally(model, &mut solver, goal, q, &mut rng))
    }

    /// A shipped design, for the `ik` modules' unit tests.
    pub(in crate::ik) fn preset(name: &str) -> Model {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("designs")
            .join(format!("{name}.json"));
        crate::pipeline::load_model(&path, &Default::default()).expect("shipped design")
    }

    fn goal_at(pose: &Isometry3<f64>, tolerance: Tolerance) -> Goal {
        Goal {
            name: "g".into(),
            position: pose.translation.vector,
            rotation: pose.rotation,
            tolerance,
            task: None,
        }
    }

    /// Shipped designs of every kind the bounds meet: general, closed-form, spherical wrist,
    /// redundant, and 5 joints.
    const DESIGNS: [&str; 5] = [
        "free-offset-6dof",
        "economic-elbow",
        "abb-irb-2600",
        "free-redundant-7dof",
        "paper-real-world",
    ];

    /// The bounds themselves against FK at the corners of random boxes (where the remainders
    /// are largest) and inside them: displacement, turn, and both first-order remainders.
    #[test]
    fn the_bounds_hold_at_the_corners_and_inside() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for name in DESIGNS {
            let model = preset(name);
            for tolerance in [Tolerance::Pose, Tolerance::ZSymmetric] {
                let q0: Vec<f64> = model.random_configuration(&mut rng);
                let goal = goal_at(&model.tool_pose(&q0), tolerance);
                let mut judge = Judge::new(&model, &goal, Radii::REACHED);
                for _ in 0..300 {
                    let scale = rng.random_range((1e-3_f64).ln()..PI.ln()).exp();
                    let centre = model.random_configuration(&mut rng);
                    let half: Vec<f64> = centre.iter().map(|_| (scale * rng.random_range(0.3..1.0)).min(PI)).collect();
                    let lower: Vec<f64> = centre.iter().zip(&half).map(|(c, h)| c - h).collect();
                    let upper: Vec<f64> = centre.iter().zip(&half).map(|(c, h)| c + h).collect();
                    judge.measure(&lower, &upper);
                    let bounds = Bounds {
                        half: &judge.half,
                        revolute: &judge.revolute,
                        moves: &judge.moves,
                        turns: &judge.turns,
                    };
                    let axes = Orientation::of(&goal, Radii::REACHED, &judge.ws.tool_in_world.rotation).axes;
                    let (mut position_rest, mut axis_rest) = (vec![0.0; model.dof()], vec![0.0; model.dof()]);
                    remainders(&judge.ws, &bounds, &mut position_rest, &mut axis_rest);
                    let orientation_rest: Vec<f64> = axis_rest.iter().map(|r| axes * r).collect();
                    let axis_rest: f64 = axis_rest.iter().sum();
                    let checked_axes: &[usize] = if tolerance == Tolerance::Pose { &[0, 1, 2] } else { &[2] };
                    let at_centre = judge.ws.tool_in_world;
                    let measure = Orientation::of(&goal, Radii::REACHED, &at_centre.rotation);
                    for corner in 0..40 {
                        let delta: Vec<f64> = half
                            .iter()
                            .map(|h| {
                                if corner < 32 {
                                    if rng.random_bool(0.5) {
                                        *h
                                    } else {
                                        -h
                                    }
                                } else {
                                    rng.random_range(-h..*h)
                                }
                            })
                            .collect();
                        let q: Vec<f64> = judge.centre.iter().zip(&delta).map(|(c, d)| c + d).collect();
                        let tool = model.tool_pose(&q);
                        let moved = tool.translation.vector - at_centre.translation.vector;
                        assert!(
                            moved.norm() <= judge.moves[0] + 1e-12,
                            "{name}: moved {} > {}",
                            moved.norm(),
                            judge.moves[0]
                        );
                        let turned = match tolerance {
                            Tolerance::Pose => at_centre.rotation.angle_to(&tool.rotation),
                            _ => super::super::angle_between(&(at_centre.rotation * Vector3::z()), &(tool.rotation * Vector3::z())),
                        };
                        assert!(turned <= judge.turns[0] + 1e-12, "{name}: turned {turned} > {}", judge.turns[0]);
                        let (mut linear, mut rate) = (Vector3::zeros(), 0.0);
                        for (j, d) in delta.iter().enumerate() {
                            let column = judge.ws.jacobian.column(j);
                            linear += Vector3::new(column[0], column[1], column[2]) * *d;
                            rate += Vector3::new(column[3], column[4], column[5]).dot(&measure.gradient) * d;
                        }
                        let rest: f64 = position_rest.iter().sum();
                        assert!(
                            (moved - linear).norm() <= rest + 1e-12,
                            "{name}: position remainder {} > {rest}",
                            (moved - linear).norm()
                        );
                        for &k in checked_axes {
                            let (at, from) = (tool.rotation * Vector3::ith(k, 1.0), at_centre.rotation * Vector3::ith(k, 1.0));
                            let mut linear = Vector3::zeros();
                            for (j, d) in delta.iter().enumerate() {
                                let column = judge.ws.jacobian.column(j);
                                linear += Vector3::new(column[3], column[4], column[5]).cross(&from) * *d;
                            }
                            let off = (at - from - linear).norm();
                            assert!(off <= axis_rest + 1e-12, "{name}: axis {k} remainder {off} > {axis_rest}");
                        }
                        let change = Orientation::of(&goal, Radii::REACHED, &tool.rotation).value - measure.value;
                        let rest: f64 = orientation_rest.iter().sum();
                        assert!(
                            (change - rate).abs() <= rest + 1e-12,
                            "{name}: orientation remainder {} > {rest}",
                            (change - rate).abs()
                        );
                    }
                }
            }
        }
    }

    /// The oracle for every test that discards boxes: a box holding a configuration within the
    /// tolerance (its goal is that configuration's pose, moved by up to the tolerance) is
    /// never ruled out, at any size and wherever the configuration sits in it.
    #[test]
    fn a_box_holding_a_configuration_within_the_tolerance_is_never_ruled_out() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for name in DESIGNS {
            let model = preset(name);
            for tolerance in [Tolerance::Pose, Tolerance::ZSymmetric, Tolerance::Position] {
                for _ in 0..400 {
                    let inside = model.random_configuration(&mut rng);
                    let pose = model.tool_pose(&inside);
                    // Within the tolerance, near its edge: 0.99 mm and 0.99 deg off.
                    let shift = Vector3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    );
                    let turn = Vector3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    );
                    let moved = Isometry3::from_parts(
                        (pose.translation.vector + shift.normalize() * 0.99 * REACHED_POSITION_M).into(),
                        UnitQuaternion::from_scaled_axis(turn.normalize() * 0.99 * REACHED_ORIENTATION_RAD) * pose.rotation,
                    );
                    let goal = goal_at(&moved, tolerance);
                    let scale = rng.random_range((1e-4_f64).ln()..PI.ln()).exp();
                    let (lower, upper): (Vec<f64>, Vec<f64>) = inside
                        .iter()
                        .map(|q| {
                            let (below, above) = (scale * rng.random_range(0.0..1.0), scale * rng.random_range(0.0..1.0));
                            (q - below, q + above)
                        })
                        .unzip();
                    assert!(
                        !rules_out(&model, &goal, &lower, &upper),
                        "{name} {tolerance:?}: a box of scale {scale} holding {inside:?} was ruled out"
                    );
                }
            }
        }
    }

    #[test]
    fn a_pose_of_the_arm_is_found() {
        let model = preset("free-offset-6dof");
        let q = [0.3, -0.7, 1.1, 0.4, -0.9, 2.0];
        let goal = goal_at(&model.tool_pose(&q), Tolerance::Pose);
        let outcome = run(&model, &goal, 2_000_000);
        eprintln!("{outcome:?}");
        let Some(Search::Found { q: found, .. }) = outcome else {
            panic!("a reachable pose must be found");
        };
        let error = goal_error(&goal, &model.tool_pose(&found));
        assert!(error.position_m < REACHED_POSITION_M && error.orientation_rad < REACHED_ORIENTATION_RAD);
    }

    #[test]
    fn a_pose_beyond_reach_is_proven() {
        let model = preset("free-offset-6dof");
        let far = Isometry3::from_parts(nalgebra::Translation3::new(5.0, 0.0, 0.5), UnitQuaternion::identity());
        let goal = goal_at(&far, Tolerance::Pose);
        assert!(matches!(run(&model, &goal, 100_000), Some(Search::Proven { .. })));
    }

    #[test]
    fn a_pose_turned_away_from_the_arm_is_proven_in_reach() {
        // The tool at a reachable point, the pose tilted 10 degrees off every pose the arm has
        // there: the exact solver's job, here by bounds alone (an oracle for the bound: a
        // reachable pose is never proven).
        let model = preset("economic-elbow");
        let q = vec![0.2; model.dof()];
        let mut goal = goal_at(&model.tool_pose(&q), Tolerance::Pose);
        if let Some(Search::Found { .. }) = run(&model, &goal, 1_000_000) {
        } else {
            panic!("the arm's own pose is found");
        }
        goal.position.z += 10.0;
        assert!(matches!(run(&model, &goal, 100_000), Some(Search::Proven { .. })));
    }
}
