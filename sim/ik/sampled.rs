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
fn offsets(goal: &Goal) -> impl Iterator<Item = Offset> + '_ {
    const BASES: [usize; 6] = [2, 3, 5, 7, 11, 13];
    let (x, y) = (goal.rotation * Vector3::x(), goal.rotation * Vector3::y());
    let zero = Offset {
        position: Vector3::zeros(),
        rotation: Vector3::zeros(),
    };
    std::iter::once(zero).chain((1..).filter_map(move |index| {
        let u: [f64; 6] = std::array::from_fn(|k| 2.0 * halton(index, BASES[k]) - 1.0);
        let position = Vector3::new(u[0], u[1], u[2]);
        let rotation = match goal.tolerance {
            Tolerance::ZSymmetric => x * u[3] + y * u[4],
            _ => Vector3::new(u[3], u[4], u[5]),
        };
        (position.norm() <= 1.0 && rotation.norm() <= 1.0).then(|| Offset {
            position: position * REACH,
            rotation: rotation * REACH,
        })
    }))
}

/// A solution met at a sampled pose, kept to climb from.
struct Start {
    offset: Offset,
    q: Vec<f64>,
    clearance: f64,
}

impl Ik<'_> {
    /// Looks for a free configuration within `goal`'s tolerance by solving poses sampled within
    /// it exactly and climbing from the clearest colliding solutions; `None` where no exact
    /// method lists every solution of a pose for the goal's mode, or the budget is a sweep's.
    pub(super) fn sample_tolerance(&mut self, goal: &Goal) -> Option<Sampled> {
        let poses = (self.opts.search_boxes / BOXES_PER_POSE).min(MOST_POSES);
        if poses == 0 || self.solutions_of(goal).is_none() {
            return None;
        }
        let margin = self.margin();
        // A solution measured is a collision query: meshes make them costly.
        let mut queries = self.collision_queries;
        let mut sampled = Sampled {
            found: None,
            poses: 0,
            solutions: 0,
            clearest: None,
        };
        let mut starts: Vec<Start> = Vec::with_capacity(CLIMBS + 1);
        for offset in offsets(goal).take(poses) {
            if queries == 0 {
                break;
            }
            let at = offset.goal(goal);
            let configurations = self.solutions_of(&at)?;
            sampled.poses += 1;
            for mut q in configurations {
                let (_, size, _) = self.polish(&at, &mut q);
                if size > EXACT || !self.shift_into_limits(&mut q, None) {
                    continue;
                }
                queries = queries.saturating_sub(1);
                sampled.solutions += 1;
                let solution = self.judge(goal, q, None, margin);
                if solution.reached {
                    sampled.found = Some(solution);
                    return Some(sampled);
                }
                let Some(clearance) = solution.clearance.map(|c| c.exact_m) else {
                    // No collision world: a solution within the tolerance would have reached it.
                    continue;
                };
                if !solution.pose_reached {
                    continue;
                }
                sampled.clearest = Some(sampled.clearest.map_or(clearance, |c: f64| c.max(clearance)));
                let at = starts.partition_point(|s| s.clearance >= clearance);
                if at < CLIMBS {
                    starts.insert(
                        at,
                        Start {
                            offset,
                            q: solution.q,
                            clearance,
                        },
                    );
                    starts.truncate(CLIMBS);
                }
            }
        }
        for start in starts {
            if let Some(found) = self.climb(goal, start, margin, &mut queries, &mut sampled.clearest) {
                sampled.found = Some(found);
                break;
            }
        }
        Some(sampled)
    }

    /// Every solution of `goal`'s own pose by the exact method for its mode (a 6R arm on a
    /// `pose` goal, a 5R arm on a `z_symmetric` one), as many joints as the model has.
    fn solutions_of(&self, goal: &Goal) -> Option<Vec<Vec<f64>>> {
        let pose = Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
        let dof = self.model.dof();
        let configurations = match (goal.tolerance, &self.all) {
            (Tolerance::Pose, _) => self.exact_pose(&pose)?.configurations,
            (Tolerance::ZSymmetric, Some((method, Tolerance::ZSymmetric))) => method.solve(&pose).configurations,
            _ => return None,
        };
        Some(configurations.iter().map(|q| q[..dof].to_vec()).collect())
    }

    /// Climbs from a colliding solution within the tolerance along the closest pair's distance
    /// gradient (task space), each step's pose kept within [`REACH`] of the tolerance and
    /// solved by Newton from the last configuration; the free configuration reached, if any.
    fn climb(&mut self, goal: &Goal, start: Start, margin: f64, queries: &mut usize, clearest: &mut Option<f64>) -> Option<IkSolution> {
        let Start {
            mut offset,
            mut q,
            mut clearance,
        } = start;
        let (x, y) = (goal.rotation * Vector3::x(), goal.rotation * Vector3::y());
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
            let at = offset.goal(goal);
            let (h, _) = self.distance_gradient(&at, &q, &pair)?;
            // Per unit of the tolerance: the distance's rate along each offset.
            let position = h.fixed_rows::<3>(0) * REACHED_POSITION_M;
            let rotation = match goal.tolerance {
                Tolerance::ZSymmetric => x * h[3] + y * h[4],
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
            let (_, size, _) = self.polish(&next.goal(goal), &mut moved);
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
        for offset in offsets(&goal).take(2000) {
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
