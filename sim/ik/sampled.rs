//! A free configuration within a goal's tolerance that no exact solution of the pose leads to.
//!
//! Near a workspace boundary the poses within 1 mm and 1 degree of the goal can have solutions
//! the goal's own pose lacks: a pair of branches born inside the tolerance (measured on the
//! paper's real-world arm on its workspace task: goal 79's pose has 2 solutions, both with
//! link2 and link5 34 mm deep; a quarter of the poses within its tolerance have 4, and some of
//! those keep 22 mm of clearance). No certificate around the exact solutions sees them, and the
//! joint-space search has to shrink its boxes to the tolerance's thin shell near the fold
//! before a centre falls inside it.
//!
//! Here the tolerance itself is sampled: poses at quasi-random offsets within it (a Halton
//! sequence, so the same on every machine and thread count), each solved exactly by the closed
//! form or the all-solutions method, every solution polished to its pose, moved into the
//! limits and measured exactly. The clearest colliding ones then climb: the tool moves within
//! the tolerance along the gradient of the closest pair's distance (the pair's witness points
//! through the inverse Jacobian), each step solved again by Newton from the last configuration
//! and measured exactly. A configuration found is a witness, checked as every solution is: its
//! pose error by FK against the goal, its clearance by the exact geometry. Finding none proves
//! nothing; the goal stays open with the clearest configuration seen named.
//!
//! Where the solutions form curves the sample has one more coordinate, the self-motion's
//! parameter (as [`super::selfmotion`] sweeps it): a 6R arm on a `z_symmetric` goal solves a
//! `pose` goal turned about tool z by a sampled angle; a 7R arm on a `pose` goal holds joint 7
//! at a sampled angle of its range and solves the six others. A climb keeps that coordinate.

use super::{add_found, GoalSolutions, Ik, IkSolution, EXACT, REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use crate::scenario::{Goal, Tolerance};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// Joint-space boxes of [`super::IkOptions::search_boxes`] one sampled pose stands in for: the
/// default budget solves 1 000 poses (about 0.1 s on a general 6R arm).
const BOXES_PER_POSE: usize = 200;
/// Poses sampled at most, whatever the budget.
const MOST_POSES: usize = 4096;
/// How far into each part of the tolerance (the position's ball, the rotation's) samples and
/// climbs go: a configuration found must keep its error within the tolerance after rounding.
const REACH: f64 = 0.99;
/// Colliding solutions climbed from, the clearest first.
const CLIMBS: usize = 8;
/// Steps of one climb at most.
const CLIMB_STEPS: usize = 24;
/// A climb's first step, in units of the tolerance; halved on each step that gains nothing.
const FIRST_STEP: f64 = 0.5;
/// The step below which a climb stops.
const SMALLEST_STEP: f64 = 1.0 / 128.0;

/// What sampling the tolerance found.
pub(super) struct Sampled {
    /// A free configuration within the limits and the tolerance.
    pub(super) found: Option<IkSolution>,
    /// Poses solved exactly.
    pub(super) poses: usize,
    /// Solutions within the limits measured.
    pub(super) solutions: usize,
    /// The clearest of them (m), when any.
    pub(super) clearest: Option<f64>,
    /// The colliding ones within the tolerance, with their deepest pairs (the first
    /// [`super::enclose::MOST_MEMBERS`]).
    pub(super) members: Vec<super::enclose::Member>,
}

impl Sampled {
    /// What was tried, for an undecided goal's reason.
    pub(super) fn describe(&self) -> String {
        match self.clearest {
            None => format!(
                "none of {} poses sampled within the goal's tolerance has a solution within the joint limits",
                self.poses
            ),
            Some(clearest) => format!(
                "{} poses sampled within the goal's tolerance gave {} solutions within the joint limits, none free (the clearest, after climbing the closest pair's distance: {:.2} mm)",
                self.poses,
                self.solutions,
                clearest * 1e3
            ),
        }
    }
}

/// An offset from the goal's pose in units of its tolerance: the position (world axes, mm)
/// and the rotation vector (world axes, degrees; across goal z for a `z_symmetric` goal, whose
/// turn about z is free).
#[derive(Debug, Clone, Copy)]
struct Offset {
    position: Vector3<f64>,
    rotation: Vector3<f64>,
}

impl Offset {
    /// The goal moved by the offset.
    fn goal(&self, goal: &Goal) -> Goal {
        Goal {
            position: goal.position + self.position * REACHED_POSITION_M,
            rotation: UnitQuaternion::from_scaled_axis(self.rotation * REACHED_ORIENTATION_RAD) * goal.rotation,
            ..goal.clone()
        }
    }

    /// Each part pulled back within [`REACH`] of the tolerance.
    fn within(mut self) -> Self {
        for part in [&mut self.position, &mut self.rotation] {
            let norm = part.norm();
            if norm > REACH {
                *part *= REACH / norm;
            }
        }
        self
    }
}

/// The radical inverse of `index` in base `base`: the Halton sequence's coordinate.
fn halton(mut index: usize, base: usize) -> f64 {
    let (mut value, mut scale) = (0.0, 1.0);
    while index > 0 {
        scale /= base as f64;
        value += scale * (index % base) as f64;
        index /= base;
    }
    value
}

/// Offsets filling the tolerance evenly: Halton points of the cube (position then rotation),
/// those with both parts within the unit ball kept and scaled by [`REACH`]; the first is zero.
fn offsets(goal: &Goal) -> impl Iterator<Item = (usize, Offset)> + '_ {
    const BASES: [usize; 6] = [2, 3, 5, 7, 11, 13];
    let (x, y) = (goal.rotation * Vector3::x(), goal.rotation * Vector3::y());
    let zero = Offset {
        position: Vector3::zeros(),
        rotation: Vector3::zeros(),
    };
    std::iter::once((0, zero)).chain((1..).filter_map(move |index| {
        let u: [f64; 6] = std::array::from_fn(|k| 2.0 * halton(index, BASES[k]) - 1.0);
        let position = Vector3::new(u[0], u[1], u[2]);
        let rotation = match goal.tolerance {
            Tolerance::ZSymmetric => x * u[3] + y * u[4],
            _ => Vector3::new(u[3], u[4], u[5]),
        };
        (position.norm() <= 1.0 && rotation.norm() <= 1.0).then(|| {
            (
                index,
                Offset {
                    position: position * REACH,
                    rotation: rotation * REACH,
                },
            )
        })
    }))
}

/// How a sampled pose is solved exactly.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Family {
    /// As many joints as the goal constrains (6R on `pose`, 5R on `z_symmetric`).
    Exact,
    /// A 6R arm on a `z_symmetric` goal: a `pose` goal turned about tool z by the parameter.
    Turn,
    /// A 7R arm on a `pose` goal: joint 7 held at the parameter.
    Held,
}

/// The parameter's `k`-th sampled value (Halton, base 17) in `range`.
fn parameter(index: usize, [lower, upper]: [f64; 2]) -> f64 {
    lower + (upper - lower) * halton(index, 17)
}

/// A solution met at a sampled pose, kept to climb from.
struct Start {
    offset: Offset,
    value: f64,
    q: Vec<f64>,
    clearance: f64,
}

impl Ik<'_> {
    /// Looks for a free configuration within `goal`'s tolerance by solving poses sampled within
    /// it exactly and climbing from the clearest colliding solutions; `None` where no exact
    /// method lists every solution of a pose (or of a self-motion's sample) for the goal's mode,
    /// or the budget is a sweep's.
    pub(super) fn sample_tolerance(&mut self, goal: &Goal) -> Option<Sampled> {
        let poses = (self.opts.search_boxes / BOXES_PER_POSE).min(MOST_POSES);
        let (family, range) = self.family(goal)?;
        if poses == 0 {
            return None;
        }
        // Newton steps and gradients keep joint 7 where its sample put it.
        let held = self.held;
        if family == Family::Held {
            self.held = Some(self.model.dof() - 1);
        }
        let sampled = self.sample_family(goal, family, range, poses);
        self.held = held;
        Some(sampled)
    }

    /// How `goal`'s sampled poses are solved, and the range of the self-motion's parameter.
    fn family(&self, goal: &Goal) -> Option<(Family, [f64; 2])> {
        let whole = [-std::f64::consts::PI, std::f64::consts::PI];
        // What [`Ik::exact_pose`] solves with.
        let six = self.analytic.is_some() || matches!(self.all, Some((_, Tolerance::Pose)));
        match (goal.tolerance, &self.all) {
            (Tolerance::Pose, _) if six => Some((Family::Exact, whole)),
            (Tolerance::ZSymmetric, Some((_, Tolerance::ZSymmetric))) => Some((Family::Exact, whole)),
            (Tolerance::ZSymmetric, _) if six => Some((Family::Turn, whole)),
            (Tolerance::Pose, _) if self.model.dof() == 7 && self.redundant.is_some() => {
                let range = match self.model.joints[6].limits {
                    Some([lower, upper]) if lower.is_finite() && upper.is_finite() && upper > lower => {
                        [lower, upper.min(lower + std::f64::consts::TAU)]
                    }
                    _ => whole,
                };
                Some((Family::Held, range))
            }
            _ => None,
        }
    }

    /// [`Self::sample_tolerance`] for a family whose method applies.
    fn sample_family(&mut self, goal: &Goal, family: Family, range: [f64; 2], poses: usize) -> Sampled {
        let margin = self.margin();
        // A solution measured is a collision query: meshes make them costly.
        let mut queries = self.collision_queries;
        let mut sampled = Sampled {
            found: None,
            poses: 0,
            solutions: 0,
            clearest: None,
            members: Vec::new(),
        };
        let mut starts: Vec<Start> = Vec::with_capacity(CLIMBS + 1);
        for (index, offset) in offsets(goal).take(poses) {
            if queries == 0 {
                break;
            }
            let value = parameter(index, range);
            let at = self.problem(goal, family, &offset, value);
            sampled.poses += 1;
            for mut q in self.solutions_of(&at, family, value) {
                let (_, size, _) = self.polish(&at, &mut q);
                if size > EXACT || !self.shift_into_limits(&mut q, None) {
                    continue;
                }
                queries = queries.saturating_sub(1);
                sampled.solutions += 1;
                let solution = self.judge(goal, q, None, margin);
                if solution.reached {
                    sampled.found = Some(solution);
                    return sampled;
                }
                let Some(clearance) = solution.clearance.map(|c| c.exact_m) else {
                    // No collision world: a solution within the tolerance would have reached it.
                    continue;
                };
                if !solution.pose_reached {
                    continue;
                }
                // The pair is asked for only while members are still kept.
                let pair = (sampled.members.len() < super::enclose::MOST_MEMBERS)
                    .then(|| {
                        self.checker
                            .as_ref()
                            .and_then(|checker| super::enclose::member_pair(checker, self.model.dof()))
                    })
                    .flatten();
                if let Some(pair) = pair {
                    sampled.members.push(super::enclose::Member {
                        q: solution.q.clone(),
                        pair,
                    });
                }
                sampled.clearest = Some(sampled.clearest.map_or(clearance, |c: f64| c.max(clearance)));
                let at = starts.partition_point(|s| s.clearance >= clearance);
                if at < CLIMBS {
                    let start = Start {
                        offset,
                        value,
                        q: solution.q,
                        clearance,
                    };
                    starts.insert(at, start);
                    starts.truncate(CLIMBS);
                }
            }
        }
        for start in starts {
            if let Some(found) = self.climb(goal, family, start, margin, &mut queries, &mut sampled.clearest) {
                sampled.found = Some(found);
                break;
            }
        }
        sampled
    }

    /// The goal a sample solves: `goal` moved by `offset`, a `pose` goal turned about tool z by
    /// `value` for [`Family::Turn`].
    fn problem(&self, goal: &Goal, family: Family, offset: &Offset, value: f64) -> Goal {
        let moved = offset.goal(goal);
        match family {
            Family::Turn => Goal {
                rotation: moved.rotation * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), value),
                tolerance: Tolerance::Pose,
                ..moved
            },
            Family::Exact | Family::Held => moved,
        }
    }

    /// Every solution of the sample's goal `at` (joint 7 at `value` for [`Family::Held`]), as
    /// many joints as the model has.
    fn solutions_of(&self, at: &Goal, family: Family, value: f64) -> Vec<Vec<f64>> {
        let pose = Isometry3::from_parts(Translation3::from(at.position), at.rotation);
        let dof = self.model.dof();
        let configurations = match (family, &self.all, &self.redundant) {
            (Family::Held, _, Some(held)) => {
                let six = held.method.solve(&held.pose_of_six(&pose, value)).configurations;
                return six.iter().map(|q| q.iter().copied().chain([value]).collect()).collect();
            }
            (Family::Exact, Some((method, Tolerance::ZSymmetric)), _) if at.tolerance == Tolerance::ZSymmetric => {
                method.solve(&pose).configurations
            }
            _ => self.exact_pose(&pose).map(|e| e.configurations).unwrap_or_default(),
        };
        configurations.iter().map(|q| q[..dof].to_vec()).collect()
    }

    /// Climbs from a colliding solution within the tolerance along the closest pair's distance
    /// gradient (task space), each step's pose kept within [`REACH`] of the tolerance and
    /// solved by Newton from the last configuration (the self-motion's parameter kept); the
    /// free configuration reached, if any.
    fn climb(
        &mut self,
        goal: &Goal,
        family: Family,
        start: Start,
        margin: f64,
        queries: &mut usize,
        clearest: &mut Option<f64>,
    ) -> Option<IkSolution> {
        let Start {
            mut offset,
            value,
            mut q,
            mut clearance,
        } = start;
        let mut step = FIRST_STEP;
        for _ in 0..CLIMB_STEPS {
            if step < SMALLEST_STEP || *queries < 2 {
                break;
            }
            *queries -= 1;
            let pair = self.checker.as_mut().and_then(|checker| {
                checker.clearance(&q, true);
                checker.closest_pair()
            })?;
            let at = self.problem(goal, family, &offset, value);
            let (h, _) = self.distance_gradient(&at, &q, &pair)?;
            // Per unit of the tolerance: the distance's rate along each offset.
            let position = h.fixed_rows::<3>(0) * REACHED_POSITION_M;
            let rotation = match at.tolerance {
                Tolerance::ZSymmetric => at.rotation * Vector3::x() * h[3] + at.rotation * Vector3::y() * h[4],
                _ => h.fixed_rows::<3>(3).into_owned(),
            } * REACHED_ORIENTATION_RAD;
            let norm = (position.norm_squared() + rotation.norm_squared()).sqrt();
            if !(norm > 0.0 && norm.is_finite()) {
                break;
            }
            let next = Offset {
                position: offset.position + position * (step / norm),
                rotation: offset.rotation + rotation * (step / norm),
            }
            .within();
            let mut moved = q.clone();
            let (_, size, _) = self.polish(&self.problem(goal, family, &next, value), &mut moved);
            if size > EXACT || !self.shift_into_limits(&mut moved, Some(&q)) {
                step /= 2.0;
                continue;
            }
            *queries -= 1;
            let solution = self.judge(goal, moved, None, margin);
            if solution.reached {
                return Some(solution);
            }
            match solution.clearance.map(|c| c.exact_m) {
                Some(better) if solution.pose_reached && better > clearance => {
                    *clearest = Some(clearest.map_or(better, |c: f64| c.max(better)));
                    (offset, q, clearance) = (next, solution.q, better);
                }
                _ => step /= 2.0,
            }
        }
        None
    }

    /// Decides by [`Self::sample_tolerance`] a goal nothing else reached: the free configuration
    /// becomes its first solution (true), else what was tried joins its reason.
    pub(super) fn reach_by_sampling(&mut self, goal: &Goal, result: &mut GoalSolutions) -> bool {
        let Some(sampled) = self.sample_tolerance(goal) else {
            return false;
        };
        if let Some(solution) = sampled.found {
            result.starts += 1;
            result.undecided = None;
            add_found(result, solution);
            return true;
        }
        let tried = sampled.describe();
        self.members = sampled.members;
        result.undecided = Some(match result.undecided.take() {
            Some(before) => format!("{before}; {tried}"),
            None => tried,
        });
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_offsets_stay_within_the_tolerance_and_a_z_symmetric_goal_never_turns_about_z() {
        let goal = Goal {
            name: "g".into(),
            position: Vector3::new(0.3, 0.1, 0.4),
            rotation: UnitQuaternion::from_euler_angles(0.3, -0.7, 1.1),
            tolerance: Tolerance::ZSymmetric,
            task: None,
        };
        let z = goal.rotation * Vector3::z();
        for (_, offset) in offsets(&goal).take(2000) {
            assert!(offset.position.norm() <= REACH + 1e-12 && offset.rotation.norm() <= REACH + 1e-12);
            assert!(offset.rotation.dot(&z).abs() < 1e-12);
            let moved = offset.goal(&goal);
            let error = crate::ik::goal_error(&goal, &Isometry3::from_parts(Translation3::from(moved.position), moved.rotation));
            assert!(error.position_m < REACHED_POSITION_M && error.orientation_rad < REACHED_ORIENTATION_RAD);
        }
    }

    #[test]
    fn halton_points_are_the_radical_inverses() {
        assert_eq!(halton(1, 2), 0.5);
        assert_eq!(halton(6, 2), 0.375);
        assert!((halton(5, 3) - (2.0 / 3.0 + 1.0 / 9.0)).abs() < 1e-15);
    }
}
