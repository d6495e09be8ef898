//! Consumes a [`Model`], a [`Goal`] and optionally a collision checker.
//! Produces every distinct IK solution found for the goal (in closed form for UR-type arms and
//! `pose` goals, else from K seeded starts), each with its errors, clearance and verdict, and
//! whether the set is known complete. Never fails: an unreachable goal is a result, not an error.

pub mod analytic;
pub mod general;
mod lines;
mod selfmotion;
pub mod solvers;
pub mod wrist;
mod branches;
mod dls;
mod error;
mod loss;
mod reach;
mod refine;
mod spd6;

pub use error::{angle_between, goal_error, task_error, GoalError};
pub use loss::{paper_loss_terms, LossTerms, DISTANCE_WEIGHT, HARDWARE_WEIGHT, ROTATION_WEIGHT};
pub use reach::{reach_bound, unreachable_proof};
pub use refine::{Clearance, COLLISION_THRESHOLD_M, COLLISION_WEIGHT};

use crate::collide::CollisionWorld;
use crate::model::{JointKind, KinematicsWorkspace, Model};
use crate::scenario::{Goal, Scenario, Tolerance};
use crate::collide::MotionBounds;
use analytic::{AnalyticSolutions, UrArm};
use solvers::AllSolutions;
use dls::{Convergence, Solver};
use nalgebra::{Isometry3, Translation3};
use rand::SeedableRng;
use refine::Checker;
use serde::Serialize;
use std::f64::consts::TAU;

/// Position error below which a goal is reached (m): the paper's 1 mm.
pub const REACHED_POSITION_M: f64 = 1e-3;
/// Orientation error below which a goal is reached (rad): the paper's 1 degree.
pub const REACHED_ORIENTATION_RAD: f64 = std::f64::consts::PI / 180.0;

/// Solver settings.
#[derive(Debug, Clone)]
pub struct IkOptions {
    /// Starts per goal, the first possibly given by the caller (default 4, the paper's).
    pub seeds: usize,
    /// Jacobian evaluations per start (default 50, the paper's numerical IK budget).
    pub max_iterations: usize,
    /// Seed of the random starts (default 0); each goal derives its own stream from it.
    pub seed: u64,
    /// Two solutions closer than this in every joint (rad or m, revolute angles compared
    /// modulo 2 pi) are the same solution (default 1e-3).
    pub distinct_tolerance: f64,
    /// Collision-aware refinement steps per start whose solution collides (default 200, the
    /// paper's Adam budget); each step is one collision query and a few solver iterations.
    pub refinement_steps: usize,
    /// Clearance a solution must keep to count as collision-free (m; default 0): the validation's
    /// collision margin, so IK and the trajectory judge alike.
    pub clearance_m: f64,
    /// Solve `pose` goals of UR-type arms in closed form (default true); false forces the
    /// numeric solver (to compare the two).
    pub analytic: bool,
    /// Starts at most per `pose` goal of a 6R arm placed on the other branches (elbow, wrist,
    /// shoulder flips) of each solution found, until no new one appears (default 32; 0 turns them
    /// off). A UR-type arm has up to 8 solutions; the exact flips of a known one are skipped
    /// unsolved, so the budget goes to the approximate ones.
    pub branch_starts: usize,
}

impl Default for IkOptions {
    fn default() -> Self {
        Self {
            seeds: 4,
            max_iterations: 50,
            seed: 0,
            distinct_tolerance: 1e-3,
            refinement_steps: 200,
            clearance_m: 0.0,
            analytic: true,
            branch_starts: 32,
        }
    }
}

/// One solution of one goal.
#[derive(Debug, Clone, Serialize)]
pub struct IkSolution {
    /// Joint configuration (rad or m).
    pub q: Vec<f64>,
    /// Errors against the goal under its tolerance mode.
    pub error: GoalError,
    /// Position and orientation errors are within 1 mm and 1 degree.
    pub pose_reached: bool,
    /// Smallest signed distance over all checked pairs, exact and approximate geometry; `None`
    /// when solved without a collision world.
    pub clearance: Option<Clearance>,
    /// The verdict: pose reached and (with a collision world) collision-free in exact geometry.
    pub reached: bool,
}

/// Everything IK found for one goal.
#[derive(Debug, Clone, Serialize)]
pub struct GoalSolutions {
    /// Every distinct solution that reaches the pose, reached ones (collision-free) first, then
    /// by error (closed form: by clearance, then branch); when none reaches the pose, the single
    /// closest attempt.
    pub solutions: Vec<IkSolution>,
    /// Numeric starts tried (0 when the closed form found every solution within the limits).
    pub starts: usize,
    /// Jacobian evaluations spent (closed form: the Newton steps polishing its solutions).
    pub iterations: usize,
    /// Every solution of the pose is known and each one within the joint limits is listed
    /// (closed form at a non-singular pose, or a pose proven out of reach): then an unreachable
    /// goal is proven, see `proof`.
    pub complete: bool,
    /// Why no configuration reaches the goal, when the complete set proves it: out of reach, none
    /// within the joint limits, or every solution in collision. `None` otherwise.
    pub proof: Option<String>,
    /// Why a goal whose solutions are all known and none reached is still not proven
    /// unreachable: a solution whose tolerance neighbourhood may hold a free configuration
    /// within the limits, or a pose whose solutions are not isolated. `None` otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub undecided: Option<String>,
}

impl GoalSolutions {
    /// True when some solution is reached (pose within tolerance and, with a collision world,
    /// collision-free).
    pub fn reached(&self) -> bool {
        self.solutions.first().is_some_and(|s| s.reached)
    }
}

/// Reusable IK state for one model (scratch space, no allocation per iteration).
pub struct Ik<'a> {
    model: &'a Model,
    solver: Solver<'a>,
    checker: Option<Checker<'a>>,
    opts: IkOptions,
    /// The closed form, when the model is a UR-type arm.
    analytic: Option<UrArm>,
    /// Every solution of any other 6R arm (5R on `z_symmetric` goals), when a method holds for
    /// its geometry, and the goal mode it decides.
    all: Option<(AllSolutions, Tolerance)>,
    /// How far the links can move per joint turn, for certificates against the tolerance.
    bounds: MotionBounds,
    ws: KinematicsWorkspace,
}

/// Pose error (m and rad) the closed form's solutions are polished to with Newton steps on the
/// model's own FK.
const POLISHED: f64 = 1e-12;
/// Newton steps at most per closed-form solution (one usually suffices, often none).
const POLISH_STEPS: usize = 3;
/// A closed-form solution whose polished error stays above this (m and rad) is not exact: the
/// pose sits on a workspace boundary where rounding decides, and the set is not called complete.
const EXACT: f64 = 1e-9;

impl<'a> Ik<'a> {
    /// A solver for `model` that ignores collisions.
    pub fn new(model: &'a Model, opts: IkOptions) -> Self {
        Self {
            model,
            solver: Solver::new(model),
            checker: None,
            analytic: UrArm::detect(model),
            all: None,
            bounds: MotionBounds::of(model),
            ws: model.workspace(),
            opts,
        }
        .with_general()
    }

    /// A solver for `model` in a collision world built for the same model: solutions are checked
    /// with exact geometry, and colliding ones refined.
    pub fn with_collisions(model: &'a Model, world: &'a CollisionWorld, opts: IkOptions) -> Self {
        Self {
            model,
            solver: Solver::new(model),
            checker: Some(Checker::new(model, world)),
            analytic: UrArm::detect(model),
            all: None,
            bounds: MotionBounds::of(model),
            ws: model.workspace(),
            opts,
        }
        .with_general()
    }

    /// The all-solutions method where no closed form applies.
    fn with_general(mut self) -> Self {
        if self.analytic.is_none() {
            self.all = AllSolutions::of(self.model);
        }
        self
    }

    /// The all-solutions method, when the model has no UR closed form and one applies.
    pub fn all_solutions(&self) -> Option<&AllSolutions> {
        self.all.as_ref().map(|(method, _)| method)
    }

    /// The closed-form parametrisation, when the model is a UR-type arm.
    pub fn closed_form(&self) -> Option<&UrArm> {
        self.analytic.as_ref()
    }

    /// Solves `goal` (number `goal_index` of its scenario, which seeds its random starts).
    ///
    /// A `pose` goal of a UR-type arm gets every solution in closed form, each whole turn moved
    /// into the joint limits nearest `first_seed` (else zero), so the set is complete. Elsewhere:
    /// from `first_seed` (e.g. the previous goal's solution) and random starts within the limits;
    /// the closed form's solutions join as extra starts where it applies but cannot list every
    /// solution (singular poses, poses just beyond reach that the tolerance may still accept,
    /// `z_symmetric` goals: those of the goal's own rotation).
    pub fn solve(&mut self, goal: &Goal, goal_index: usize, first_seed: Option<&[f64]>) -> GoalSolutions {
        let finite = goal.position.iter().chain(goal.rotation.coords.iter()).all(|x| x.is_finite());
        let pose = Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
        let all_solutions = self.opts.analytic && finite && matches!(goal.tolerance, Tolerance::Pose | Tolerance::ZSymmetric);
        let exact = match (&self.analytic, &self.all) {
            (Some(arm), _) if all_solutions => arm.solve(&pose),
            (None, Some((method, mode))) if self.opts.analytic && finite && goal.tolerance == *mode => {
                let found = method.solve(&pose);
                AnalyticSolutions {
                    configurations: found.configurations,
                    finite: found.resolved,
                    out_of_reach: found.out_of_reach,
                }
            }
            (None, Some((method, Tolerance::Pose))) if self.opts.analytic && finite && goal.tolerance == Tolerance::ZSymmetric => {
                let starts = method.solve(&pose).configurations;
                let mut result = self.solve_numeric(goal, goal_index, first_seed, &starts);
                if !result.reached() {
                    self.sweep_free_turn(goal, &mut result);
                }
                return result;
            }
            _ => return self.solve_numeric(goal, goal_index, first_seed, &[]),
        };
        if goal.tolerance == Tolerance::ZSymmetric && self.analytic.is_some() {
            // A continuum of solutions (any turn about tool z): the goal rotation's own are on
            // every branch, good starts, never the whole set; what they miss, the self-motion
            // sweep decides.
            let mut result = self.solve_numeric(goal, goal_index, first_seed, &exact.configurations);
            if !result.reached() {
                self.sweep_free_turn(goal, &mut result);
            }
            return result;
        }
        if exact.finite && !exact.configurations.is_empty() {
            return self.solve_closed_form(goal, goal_index, first_seed, &exact);
        }
        let mut result = self.solve_numeric(goal, goal_index, first_seed, &exact.configurations);
        if !result.reached() {
            let miss = result.solutions.first().map_or(String::new(), |s| {
                format!(
                    " (closest miss from {} IK starts: {:.1} mm, {:.2} deg)",
                    result.starts,
                    s.error.position_m * 1e3,
                    s.error.orientation_rad.to_degrees()
                )
            });
            result.undecided = Some(if exact.finite {
                format!(
                    "{}: the pose itself has no solution, but a configuration within the goal's tolerance is not ruled out{miss}",
                    self.method()
                )
            } else {
                format!(
                    "{}: the pose's solutions are not isolated (a singular pose), so they cannot all be listed{miss}",
                    self.method()
                )
            });
        }
        if let Some(proof) = exact.out_of_reach {
            // Proven beyond the tolerance: no start can have reached it.
            result.complete = !result.solutions.iter().any(|s| s.pose_reached);
            result.proof = result.complete.then_some(proof);
        }
        result
    }

    /// The closed form's solutions, polished, moved into the limits and judged; exact solutions
    /// no whole turn brings within the limits start the numeric solver from their clamped
    /// configuration (a configuration at the limit may still be within the tolerance).
    ///
    /// A goal none of whose solutions is reached is proven unreachable only when each one is
    /// certified against the goal's tolerance: the configurations within 1 mm and 1 degree of a
    /// solution are within `dq` of it (the inverse Jacobian, doubled for the curvature), and a
    /// solution counts only when its closest pair overlaps by more than the links can move over
    /// `dq`, or a joint lies further outside its limits than `dq`.
    fn solve_closed_form(
        &mut self,
        goal: &Goal,
        goal_index: usize,
        first_seed: Option<&[f64]>,
        exact: &AnalyticSolutions,
    ) -> GoalSolutions {
        let margin = self.margin();
        let mut iterations = 0;
        let mut complete = true;
        let mut distinct: Vec<Vec<f64>> = Vec::with_capacity(exact.configurations.len());
        let mut found: Vec<IkSolution> = Vec::with_capacity(exact.configurations.len());
        let mut outside: Vec<Vec<f64>> = Vec::new();
        let mut collisions: Vec<String> = Vec::new();
        let mut open: Vec<String> = Vec::new();
        let dof = self.model.dof();
        for configuration in &exact.configurations {
            // A 5R arm's sixth angle is the virtual joint's.
            let mut q = configuration[..dof].to_vec();
            let (steps, size, error) = self.polish(goal, &mut q);
            iterations += steps;
            complete &= size <= EXACT;
            if distinct.iter().any(|d| self.same_configuration(d, &q)) {
                continue;
            }
            distinct.push(q.clone());
            if self.shift_into_limits(&mut q, first_seed) {
                // The error at the whole-turn equivalent differs by rounding only.
                let mut solution = self.judge(goal, q, Some(error), margin);
                if solution.pose_reached && !solution.reached {
                    match self.collision_certificate(goal, &solution, margin, 0.0) {
                        Ok(pair) => collisions.push(pair),
                        // Not proven: the tolerance may hold a free configuration of this
                        // branch; it stands for the branch when found.
                        Err(why) => match self.free_within_tolerance(goal, &solution.q, margin) {
                            Some(free) => solution = free,
                            None => open.push(why),
                        },
                    }
                }
                found.push(solution);
            } else {
                if let Err(why) = self.limits_certificate(goal, &q, 0.0) {
                    open.push(why);
                }
                outside.push(q);
            }
        }
        let mut starts = 0;
        let mut closest: Option<IkSolution> = None;
        if !outside.is_empty() {
            let mut rng = self.rng(goal_index);
            let done = CONVERGED;
            for mut q in outside.iter().cloned() {
                starts += 1;
                iterations += self.solver.solve(goal, &mut q, self.opts.max_iterations, done, &mut rng);
                let solution = self.judge(goal, q, None, margin);
                if solution.pose_reached {
                    if !found.iter().any(|s| self.same_configuration(&s.q, &solution.q)) {
                        found.push(solution);
                    }
                } else if closest.as_ref().is_none_or(|c| rank(&solution.error) < rank(&c.error)) {
                    closest = Some(solution);
                }
            }
        }
        // The errors are all rounding: order by clearance (the best attempt first when none is
        // free), else keep the branch order.
        found.sort_by(|a, b| {
            b.reached.cmp(&a.reached).then_with(|| {
                let clearance = |s: &IkSolution| s.clearance.map_or(0.0, |c| c.exact_m);
                clearance(b).total_cmp(&clearance(a))
            })
        });
        let poses = found.len();
        if found.is_empty() {
            found.extend(closest);
        }
        let reached = found.first().is_some_and(|s| s.reached);
        let method = self.method();
        let decided = complete && open.is_empty();
        let proof = (decided && !reached).then(|| {
            let total = distinct.len();
            let within = total - outside.len();
            let limits = if outside.is_empty() {
                String::new()
            } else {
                format!(" ({within} of the {total} within the joint limits)")
            };
            let what = if margin > 0.0 {
                format!("collide or keep less than the {margin} m margin")
            } else {
                "collide".to_string()
            };
            if poses == 0 {
                format!("{method}: none of the pose's {total} solutions is within the joint limits, nor within the goal's tolerance of them")
            } else {
                format!("{method}: all {poses} solutions of the pose{limits} {what}, throughout the goal's tolerance ({})", summary(&collisions))
            }
        });
        let undecided = if reached {
            None
        } else if !complete {
            Some(format!("{method}: the pose is singular or on the workspace boundary: its solutions are not isolated"))
        } else {
            (!open.is_empty()).then(|| format!("{method}: every solution is known, but {}", summary(&open)))
        };
        GoalSolutions {
            solutions: found,
            starts,
            iterations,
            complete,
            proof,
            undecided,
        }
    }

    /// Every solution of a world pose by the closed form or the all-solutions method, when the
    /// model is a 6R arm that has one.
    fn exact_pose(&self, pose: &Isometry3<f64>) -> Option<AnalyticSolutions> {
        match (&self.analytic, &self.all) {
            (Some(arm), _) => Some(arm.solve(pose)),
            (None, Some((method, Tolerance::Pose))) => {
                let found = method.solve(pose);
                Some(AnalyticSolutions {
                    configurations: found.configurations,
                    finite: found.resolved,
                    out_of_reach: found.out_of_reach,
                })
            }
            _ => None,
        }
    }

    /// Why no configuration reaches pose `pose`, turned by up to `turn` about tool z, within
    /// the tolerance, when the closed form or the all-solutions method proves it.
    fn exact_out_of_reach(&self, pose: &Isometry3<f64>, turn: f64) -> Option<String> {
        match (&self.analytic, &self.all) {
            (Some(arm), _) => arm.out_of_reach_over_turn(pose, turn),
            (None, Some((method, Tolerance::Pose))) => method.out_of_reach_over_turn(pose, turn),
            _ => None,
        }
    }

    /// Which all-solutions method this solver uses, for proofs.
    fn method(&self) -> &'static str {
        match (&self.analytic, &self.all) {
            (Some(_), _) => "closed-form IK",
            (None, Some((method, _))) => method.name(),
            (None, None) => "numeric IK",
        }
    }

    /// How far each joint may be from solution `q` while the tool stays within the goal's
    /// tolerance: the inverse Jacobian's rows against 1 mm and 1 degree, doubled for the
    /// curvature; with `turn` > 0 also the branch's motion over that much of the free turn about
    /// tool z; `None` near a singularity, where that is no bound.
    fn neighbourhood(&mut self, goal: &Goal, q: &[f64], turn: f64) -> Option<Vec<f64>> {
        // Columns: constrained rows (position first); the rotation rows' error is at most the
        // tolerance angle in whichever directions are constrained.
        let inverse = self.constrained_inverse(goal, q)?;
        let z = goal.rotation * nalgebra::Vector3::z();
        let reach: Vec<f64> = (0..q.len())
            .map(|i| {
                let position = inverse.view((i, 0), (1, 3)).norm();
                let rotation = inverse.view((i, 3), (1, 3)).norm();
                // The branch's joint rate along the free turn: the inverse applied to a turn
                // about tool z.
                let along = (0..3).map(|k| inverse[(i, 3 + k)] * z[k]).sum::<f64>().abs();
                TOLERANCE_CURVATURE * (position * REACHED_POSITION_M + rotation * REACHED_ORIENTATION_RAD + along * turn)
            })
            .collect();
        reach.iter().all(|r| r.is_finite() && *r <= LINEAR_REACH_RAD).then_some(reach)
    }

    /// The colliding pair that stays colliding throughout the tolerance neighbourhood of
    /// `solution` (the checker's last query), named with its depth; else why not.
    ///
    /// With `turn` > 0 the solution is a sample of a self-motion (a 6R arm on a `z_symmetric`
    /// goal, see [`selfmotion`]) and the neighbourhood also covers the branch over `turn` (rad)
    /// of the free turn about tool z either side.
    fn collision_certificate(&mut self, goal: &Goal, solution: &IkSolution, margin: f64, turn: f64) -> Result<String, String> {
        let clearance = solution.clearance.map_or(f64::INFINITY, |c| c.exact_m);
        let pair = self.checker.as_ref().and_then(|c| c.closest_pair());
        let Some(pair) = pair else {
            return Err("a solution's collision was not measured".into());
        };
        let name = &pair.name;
        let Some(reach) = self.neighbourhood(goal, &solution.q, turn) else {
            return Err(format!("a solution near a singularity has {name} at {:.1} mm, and the goal's tolerance may move them far", clearance * 1e3));
        };
        // The whole-body bound, or the pair's distance gradient over the tolerance (first order,
        // doubled for the curvature like the reach): the smaller.
        let whole = self.bounds.relative_motion(pair.bodies[0], pair.bodies[1], &reach);
        let z = goal.rotation * nalgebra::Vector3::z();
        let first_order = self.distance_gradient(goal, &solution.q, &pair).map_or(f64::INFINITY, |h| {
            TOLERANCE_CURVATURE * (Self::tolerance_gain(&h) + h.fixed_rows::<3>(3).dot(&z).abs() * turn)
        });
        let motion = whole.min(first_order);
        if clearance + motion <= margin {
            Ok(format!("{name} {:.1} mm", clearance * 1e3))
        } else {
            Err(format!(
                "a solution's {name} are at {:.1} mm, within the {:.1} mm the goal's tolerance can move them",
                clearance * 1e3,
                motion * 1e3
            ))
        }
    }

    /// The pair's distance gradient at `q` in task space: `h` with `d(q + dq) ~ d(q) + h . J dq`
    /// over the goal's constrained directions (position first), from the witness points'
    /// velocities along the normal; `None` where the Jacobian is singular.
    fn distance_gradient(&mut self, goal: &Goal, q: &[f64], pair: &refine::ClosestPair) -> Option<nalgebra::Vector6<f64>> {
        let inverse = self.constrained_inverse(goal, q)?;
        self.model.forward(q, &mut self.ws);
        let mut h = nalgebra::Vector6::zeros();
        for (i, joint) in self.model.joints.iter().enumerate() {
            let frame = &self.ws.link_in_world[i + 1];
            let axis = frame.rotation * joint.axis.into_inner();
            // Joint i moves links i + 1 onwards; obstacles and the floor stay.
            let velocity = |body: crate::collide::Body, point: &nalgebra::Vector3<f64>| match body {
                crate::collide::Body::Link(k) if k > i => match joint.kind {
                    JointKind::Prismatic => axis,
                    _ => axis.cross(&(point - frame.translation.vector)),
                },
                _ => nalgebra::Vector3::zeros(),
            };
            let rate = pair
                .normal
                .dot(&(velocity(pair.bodies[1], &pair.points[1]) - velocity(pair.bodies[0], &pair.points[0])));
            for k in 0..6 {
                h[k] += inverse[(i, k)] * rate;
            }
        }
        Some(h)
    }

    /// The most the pair's distance can grow over the goal's tolerance to first order (the
    /// gradient's position part times 1 mm plus its rotation part times 1 degree).
    fn tolerance_gain(h: &nalgebra::Vector6<f64>) -> f64 {
        h.fixed_rows::<3>(0).norm() * REACHED_POSITION_M + h.fixed_rows::<3>(3).norm() * REACHED_ORIENTATION_RAD
    }

    /// A collision-free configuration within the goal's tolerance near colliding exact solution
    /// `q`, when moving the tool within 90 % of the tolerance along the closest pair's
    /// separating direction finds one (a few steps, each re-measured exactly).
    fn free_within_tolerance(&mut self, goal: &Goal, q: &[f64], margin: f64) -> Option<IkSolution> {
        if goal.tolerance != Tolerance::Pose {
            return None;
        }
        let mut current = q.to_vec();
        for _ in 0..TOLERANCE_SEARCH_STEPS {
            let pair = self.checker.as_mut().map(|c| {
                c.clearance(&current, true);
                c.closest_pair()
            })??;
            let h = self.distance_gradient(goal, &current, &pair)?;
            let (position, rotation) = (h.fixed_rows::<3>(0).into_owned(), h.fixed_rows::<3>(3).into_owned());
            let towards = |v: nalgebra::Vector3<f64>, size: f64| {
                let norm = v.norm();
                if norm > 0.0 {
                    v * (TOLERANCE_USED * size / norm)
                } else {
                    v
                }
            };
            let shifted = Goal {
                position: goal.position + towards(position, REACHED_POSITION_M),
                rotation: nalgebra::UnitQuaternion::from_scaled_axis(towards(rotation, REACHED_ORIENTATION_RAD)) * goal.rotation,
                ..goal.clone()
            };
            let mut next = current.clone();
            let (_, size, _) = self.polish(&shifted, &mut next);
            if size > EXACT {
                return None;
            }
            let solution = self.judge(goal, next.clone(), None, margin);
            if solution.reached {
                return Some(solution);
            }
            current = next;
        }
        None
    }

    /// Whether solution `q`, none of whose whole-turn equivalents is within the limits, stays
    /// outside them throughout the goal's tolerance; else why not.
    fn limits_certificate(&mut self, goal: &Goal, q: &[f64], turn: f64) -> Result<(), String> {
        let Some(reach) = self.neighbourhood(goal, q, turn) else {
            return Err("a solution outside the joint limits is near a singularity".into());
        };
        let mut closest: Option<(usize, f64)> = None;
        for (i, (joint, value)) in self.model.joints.iter().zip(q).enumerate() {
            let gap = limit_gap(joint, *value);
            if gap > reach[i] {
                return Ok(());
            }
            if gap > 0.0 && closest.is_none_or(|(_, g)| gap < g) {
                closest = Some((i, gap));
            }
        }
        Err(match closest {
            Some((i, gap)) => format!(
                "a solution is {:.2} deg outside joint {}'s limits, within what the goal's tolerance allows",
                gap.to_degrees(),
                i + 1
            ),
            None => "a solution is at the joint limits".into(),
        })
    }

    /// Newton steps on the model's own FK until the pose error is below [`POLISHED`] (the
    /// closed form is usually there already: one FK, no Jacobian); returns the steps taken, the
    /// larger of the final position (m) and orientation (rad) errors, and the goal error.
    fn polish(&mut self, goal: &Goal, q: &mut [f64]) -> (usize, f64, GoalError) {
        let error_of = |tool: &Isometry3<f64>| {
            let e = task_error(goal, tool);
            let (position, rotation) = (e.fixed_rows::<3>(0).norm(), e.fixed_rows::<3>(3).norm());
            // `max` would drop a NaN, and a NaN goal would pass for exact.
            (
                e,
                if position.is_nan() || rotation.is_nan() {
                    f64::INFINITY
                } else {
                    position.max(rotation)
                },
            )
        };
        let mut tool = self.model.tool_pose(q);
        let (mut e, mut size) = error_of(&tool);
        let mut steps = 0;
        let mut next = vec![0.0; q.len()];
        while size > POLISHED && steps < POLISH_STEPS {
            let Some(step) = self.newton_step(goal, q, &e) else { break };
            for ((n, value), delta) in next.iter_mut().zip(q.iter()).zip(step.iter()) {
                *n = wrap_angle(value + delta);
            }
            steps += 1;
            let next_tool = self.model.tool_pose(&next);
            let (next_e, next_size) = error_of(&next_tool);
            if next_size >= size {
                // Near a singularity Newton may overshoot: keep the closed form's answer.
                break;
            }
            q.copy_from_slice(&next);
            (tool, e, size) = (next_tool, next_e, next_size);
        }
        (steps, size, goal_error(goal, &tool))
    }

    /// The joint step that removes task error `e` at `q` to first order, over the directions
    /// the goal constrains (six for `pose`; five for `z_symmetric`: no turn about goal z); `None`
    /// when they are not as many as the joints, or the Jacobian is singular there.
    fn newton_step(&mut self, goal: &Goal, q: &[f64], e: &nalgebra::Vector6<f64>) -> Option<Vec<f64>> {
        let inverse = self.constrained_inverse(goal, q)?;
        let constrained = constrained_rows(goal) * e;
        Some((0..q.len()).map(|i| (0..6).map(|k| inverse[(i, k)] * constrained[k]).sum()).collect())
    }

    /// The inverse of the Jacobian's constrained rows at `q` (joints by 6, the unconstrained
    /// rows' columns zero); `None` as in [`Self::newton_step`].
    fn constrained_inverse(&mut self, goal: &Goal, q: &[f64]) -> Option<nalgebra::DMatrix<f64>> {
        self.model.tool_jacobian(q, &mut self.ws);
        let dof = q.len();
        let rows = constrained_rows(goal);
        let constrained = match goal.tolerance {
            Tolerance::Pose => 6,
            Tolerance::ZSymmetric => 5,
            Tolerance::Position => 3,
        };
        if constrained != dof {
            return None;
        }
        let projected = rows * &self.ws.jacobian;
        let square = projected.rows(0, dof).into_owned();
        let inverse = square.try_inverse()?;
        let mut out = nalgebra::DMatrix::zeros(dof, 6);
        out.view_mut((0, 0), (dof, dof)).copy_from(&inverse);
        Some(out)
    }

    /// Moves each revolute angle of `q` by whole turns into its limits, to the equivalent nearest
    /// `near` (else zero); false when some joint has no equivalent within its limits.
    fn shift_into_limits(&self, q: &mut [f64], near: Option<&[f64]>) -> bool {
        let near = near.filter(|n| n.len() == q.len());
        for (i, (value, joint)) in q.iter_mut().zip(&self.model.joints).enumerate() {
            if !value.is_finite() {
                return false;
            }
            if joint.kind == JointKind::Prismatic {
                if joint.limits.is_some_and(|[lower, upper]| *value < lower || *value > upper) {
                    return false;
                }
                continue;
            }
            let target = near.map_or(0.0, |n| n[i]);
            let target = if target.is_finite() { target } else { 0.0 };
            let mut turns = ((target - *value) / TAU).round();
            if let Some([lower, upper]) = joint.limits {
                let (fewest, most) = (((lower - *value) / TAU).ceil(), ((upper - *value) / TAU).floor());
                if fewest > most {
                    return false;
                }
                turns = turns.clamp(fewest, most);
            }
            if turns != 0.0 {
                *value += turns * TAU;
            }
        }
        true
    }

    /// The solution record of configuration `q` (its `error` when known): errors, exact
    /// clearance, verdict.
    fn judge(&mut self, goal: &Goal, q: Vec<f64>, error: Option<GoalError>, margin: f64) -> IkSolution {
        let clearance = self.checker.as_mut().map(|checker| checker.clearance(&q, true));
        let error = error.unwrap_or_else(|| goal_error(goal, &self.model.tool_pose(&q)));
        let pose_reached = is_reached(&error);
        IkSolution {
            reached: pose_reached && clearance.is_none_or(|c| c.exact_m > margin),
            q,
            error,
            pose_reached,
            clearance,
        }
    }

    /// The clearance a solution must keep; a NaN or negative margin means none (a NaN would call
    /// every configuration colliding).
    fn margin(&self) -> f64 {
        if self.opts.clearance_m.is_finite() {
            self.opts.clearance_m.max(0.0)
        } else {
            0.0
        }
    }

    /// The random stream of goal `goal_index`.
    fn rng(&self, goal_index: usize) -> rand_chacha::ChaCha8Rng {
        rand_chacha::ChaCha8Rng::seed_from_u64(self.opts.seed ^ (goal_index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15))
    }

    /// The numeric solver: `first_seed`, random starts and then `extra` starts (closed-form
    /// configurations); then, for `pose` goals of 6R arms, starts on the other branches of each
    /// solution found (see [`branches`]).
    fn solve_numeric(&mut self, goal: &Goal, goal_index: usize, first_seed: Option<&[f64]>, extra: &[[f64; 6]]) -> GoalSolutions {
        let mut rng = self.rng(goal_index);
        let mut found: Vec<IkSolution> = Vec::new();
        let mut closest: Option<IkSolution> = None;
        let mut iterations = 0;
        let margin = self.margin();
        let mut starts = self.opts.seeds + extra.len();
        for start in 0..starts {
            let q = match (start, first_seed) {
                _ if start >= self.opts.seeds => extra[start - self.opts.seeds].to_vec(),
                (0, Some(seed)) if seed.len() == self.model.dof() => seed.to_vec(),
                _ => self.model.random_configuration(&mut rng),
            };
            if start >= self.opts.seeds && found.iter().any(|s| self.same_configuration(&s.q, &q)) {
                continue;
            }
            let (solution, used) = self.attempt(goal, q, true, margin, &mut rng);
            iterations += used;
            self.keep(solution, &mut found, &mut closest);
        }
        if goal.tolerance == Tolerance::Pose && branches::applies(self.model) {
            let (branch_starts, used) = self.branch_restarts(goal, &mut found, &mut closest, margin, &mut rng);
            starts += branch_starts;
            iterations += used;
        }
        // Clearances were estimated while searching (overlap depths from bounding capsules, gaps
        // unpolished); the solutions kept are measured exactly.
        if let Some(checker) = self.checker.as_mut() {
            for solution in found.iter_mut().chain(closest.iter_mut()) {
                if solution.clearance.is_some() {
                    let exact = checker.clearance(&solution.q, true);
                    // Touching within rounding, GJK's overlap test and EPA may disagree on the sign.
                    solution.reached = solution.pose_reached && exact.exact_m > margin;
                    solution.clearance = Some(exact);
                }
            }
        }
        found.sort_by(|a, b| b.reached.cmp(&a.reached).then(rank(&a.error).total_cmp(&rank(&b.error))));
        if found.is_empty() {
            found.extend(closest);
        }
        GoalSolutions {
            solutions: found,
            starts,
            iterations,
            complete: false,
            proof: None,
            undecided: None,
        }
    }

    /// Starts on the other branches of every solution in `found` (of the `closest` attempt when
    /// none reaches the pose: a local minimum of one branch is a fair guess at the others'), the
    /// new solutions' own branches included, until none is new or [`IkOptions::branch_starts`]
    /// are spent; returns the starts and iterations used. Starts that are already a known
    /// solution (the flip was exact) are not solved.
    fn branch_restarts<R: rand::Rng>(
        &mut self,
        goal: &Goal,
        found: &mut Vec<IkSolution>,
        closest: &mut Option<IkSolution>,
        margin: f64,
        rng: &mut R,
    ) -> (usize, usize) {
        let (mut starts, mut iterations) = (0, 0);
        let mut origins: Vec<Vec<f64>> = found.iter().map(|s| s.q.clone()).collect();
        if origins.is_empty() {
            origins.extend(closest.as_ref().map(|c| c.q.clone()));
        }
        let mut tried: Vec<Vec<f64>> = Vec::new();
        let mut next = 0;
        while next < origins.len() && starts < self.opts.branch_starts {
            let tolerance = self.opts.distinct_tolerance;
            let shoulder_known = |angle: f64| found.iter().any(|s| wrap_angle(s.q[0] - angle).abs() <= tolerance);
            let candidates = branches::flips(self.model, &mut self.ws, &origins[next], &goal.position, &shoulder_known);
            next += 1;
            for q in candidates {
                if starts >= self.opts.branch_starts {
                    break;
                }
                let known = |ik: &Self, q: &[f64]| {
                    found.iter().any(|s| ik.same_configuration(&s.q, q)) || tried.iter().any(|t| ik.same_configuration(t, q))
                };
                if known(self, &q) {
                    continue;
                }
                tried.push(q.clone());
                starts += 1;
                // No collision refinement: a colliding branch is a solution of its own, and
                // refining it would only look for another branch, which this loop does.
                let (solution, used) = self.attempt(goal, q, false, margin, rng);
                iterations += used;
                let before = found.len();
                self.keep(solution, found, closest);
                if found.len() > before {
                    origins.push(found[before].q.clone());
                }
            }
        }
        (starts, iterations)
    }

    /// Solves from start `q`, refining a colliding or unreached result when `refine` is set (and
    /// there is a collision world); returns the solution, its clearance estimated, and the
    /// iterations used.
    fn attempt<R: rand::Rng>(&mut self, goal: &Goal, mut q: Vec<f64>, refine: bool, margin: f64, rng: &mut R) -> (IkSolution, usize) {
        let done = CONVERGED;
        let iterations = self.solver.solve(goal, &mut q, self.opts.max_iterations, done, rng);
        let mut clearance = None;
        if let Some(checker) = self.checker.as_mut() {
            // An unreached pose is refined whatever its clearance: measure only what is kept.
            let unreached = refine && !is_reached(&goal_error(goal, &self.model.tool_pose(&q)));
            let mut measured = (!unreached).then(|| checker.clearance(&q, false));
            if refine && measured.is_none_or(|m| m.exact_m <= margin) {
                checker.margin = margin;
                refine::refine(&mut self.solver, checker, goal, &mut q, self.opts.refinement_steps, done, rng);
                measured = Some(checker.clearance(&q, false));
            }
            clearance = measured;
        }
        let error = goal_error(goal, &self.model.tool_pose(&q));
        let pose_reached = is_reached(&error);
        let reached = pose_reached && clearance.is_none_or(|c| c.exact_m > margin);
        let solution = IkSolution {
            q,
            error,
            pose_reached,
            clearance,
            reached,
        };
        (solution, iterations)
    }

    /// Adds `solution` to `found` when it reaches the pose and is new, else keeps it as
    /// `closest` when it is the best miss so far.
    fn keep(&self, solution: IkSolution, found: &mut Vec<IkSolution>, closest: &mut Option<IkSolution>) {
        if solution.pose_reached {
            if !found.iter().any(|s| self.same_configuration(&s.q, &solution.q)) {
                found.push(solution);
            }
        } else if closest.as_ref().is_none_or(|c| rank(&solution.error) < rank(&c.error)) {
            *closest = Some(solution);
        }
    }

    /// The solver's settings.
    pub fn options(&self) -> &IkOptions {
        &self.opts
    }

    /// Whether two configurations are the same solution: every joint within the tolerance,
    /// revolute angles compared modulo 2 pi.
    pub fn same_configuration(&self, a: &[f64], b: &[f64]) -> bool {
        self.model.joints.iter().zip(a.iter().zip(b)).all(|(joint, (x, y))| {
            let difference = if joint.kind == crate::model::JointKind::Prismatic {
                x - y
            } else {
                wrap_angle(x - y)
            };
            difference.abs() <= self.opts.distinct_tolerance
        })
    }
}

/// Doubles the linearised tolerance neighbourhood of a solution: the pose error is not linear
/// in the joints, and a certificate must hold for all of it.
const TOLERANCE_CURVATURE: f64 = 2.0;
/// Steps of the search for a free configuration within a colliding solution's tolerance.
const TOLERANCE_SEARCH_STEPS: usize = 4;
/// The part of the tolerance that search may use: the configuration it finds must stay within
/// the tolerance after rounding.
const TOLERANCE_USED: f64 = 0.9;
/// Joint motions (rad) beyond which the linearised neighbourhood is no bound (near a
/// singularity the tolerance may reach a different branch).
const LINEAR_REACH_RAD: f64 = 0.5;

/// The rows of the task error a goal constrains, first: all six for `pose`; for `z_symmetric`
/// the position and the two turns across goal z (the last row zero); the position alone for
/// `position`.
fn constrained_rows(goal: &Goal) -> nalgebra::Matrix6<f64> {
    let mut rows = nalgebra::Matrix6::identity();
    match goal.tolerance {
        Tolerance::Pose => {}
        Tolerance::ZSymmetric => {
            let x = goal.rotation * nalgebra::Vector3::x();
            let y = goal.rotation * nalgebra::Vector3::y();
            rows.fixed_view_mut::<3, 3>(3, 3).fill(0.0);
            rows.fixed_view_mut::<1, 3>(3, 3).copy_from(&x.transpose());
            rows.fixed_view_mut::<1, 3>(4, 3).copy_from(&y.transpose());
        }
        Tolerance::Position => rows.fixed_view_mut::<3, 3>(3, 3).fill(0.0),
    }
    rows
}

/// How far (rad or m) joint value `value` is outside the joint's limits, over its whole-turn
/// equivalents for a revolute joint; 0 when within them or unlimited.
fn limit_gap(joint: &crate::model::Joint, value: f64) -> f64 {
    let Some([lower, upper]) = joint.limits else { return 0.0 };
    let outside = |v: f64| (lower - v).max(v - upper).max(0.0);
    if joint.kind == JointKind::Prismatic {
        return outside(value);
    }
    let turns = [((lower - value) / TAU).floor(), ((upper - value) / TAU).ceil()];
    (turns[0] as i64..=turns[1] as i64)
        .map(|k| outside(value + k as f64 * TAU))
        .fold(f64::INFINITY, f64::min)
}

/// The first few of `items`, and how many more.
fn summary(items: &[String]) -> String {
    const SHOWN: usize = 3;
    let mut text = items.iter().take(SHOWN).cloned().collect::<Vec<_>>().join("; ");
    if items.len() > SHOWN {
        text.push_str(&format!("; {} more", items.len() - SHOWN));
    }
    text
}

/// Convergence of the numeric solver: far tighter than "reached" (1 mm, 1 degree).
const CONVERGED: Convergence = Convergence {
    position_m: 1e-6,
    orientation_rad: 1e-6,
};

/// `angle` wrapped into (-pi, pi].
pub fn wrap_angle(angle: f64) -> f64 {
    let two_pi = 2.0 * std::f64::consts::PI;
    let wrapped = angle.rem_euclid(two_pi);
    if wrapped > std::f64::consts::PI {
        wrapped - two_pi
    } else {
        wrapped
    }
}

fn is_reached(error: &GoalError) -> bool {
    error.position_m < REACHED_POSITION_M && error.orientation_rad < REACHED_ORIENTATION_RAD
}

/// One number to rank attempts by: position error plus orientation error at 0.5 m per rad.
fn rank(error: &GoalError) -> f64 {
    error.position_m + 0.5 * error.orientation_rad
}

/// Solves every goal of a scenario with the robot mounted at the scenario's base pose
/// (`model` must already be placed, see [`Model::placed`]), in course order, each goal from its
/// own seeded random starts. With a collision world, solutions are checked and refined with
/// exact geometry.
pub fn solve_goals(model: &Model, scenario: &Scenario, world: Option<&CollisionWorld>, opts: &IkOptions) -> Vec<GoalSolutions> {
    solve_goals_counted(model, scenario, world, opts, &|| {})
}

/// [`solve_goals`], calling `done` after each goal (from the thread that solved it), for a
/// progress count.
pub fn solve_goals_counted(
    model: &Model,
    scenario: &Scenario,
    world: Option<&CollisionWorld>,
    opts: &IkOptions,
    done: &(dyn Fn() + Sync),
) -> Vec<GoalSolutions> {
    use rayon::prelude::*;
    // Each goal's starts are seeded by its index alone, so goals solve independently, on any
    // number of threads, with the same result.
    let make = || match world {
        Some(world) => Ik::with_collisions(model, world, opts.clone()),
        None => Ik::new(model, opts.clone()),
    };
    scenario
        .goals
        .par_iter()
        .enumerate()
        .map_init(make, |ik, (index, goal)| {
            let found = ik.solve(goal, index, None);
            done();
            found
        })
        .collect()
}
