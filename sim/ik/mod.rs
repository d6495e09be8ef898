//! Consumes a [`Model`], a [`Goal`] and optionally a collision checker.
//! Produces every distinct IK solution found for the goal (from K seeded starts), each with its
//! errors, clearance and verdict. Never fails: an unreachable goal is a result, not an error.

mod dls;
mod error;
mod loss;
mod reach;
mod refine;

pub use error::{angle_between, goal_error, task_error, GoalError};
pub use loss::{paper_loss_terms, LossTerms, DISTANCE_WEIGHT, HARDWARE_WEIGHT, ROTATION_WEIGHT};
pub use reach::{reach_bound, unreachable_proof};
pub use refine::{Clearance, COLLISION_THRESHOLD_M, COLLISION_WEIGHT};

use crate::collide::CollisionWorld;
use crate::model::Model;
use crate::scenario::{Goal, Scenario};
use dls::{Convergence, Solver};
use rand::SeedableRng;
use refine::Checker;
use serde::Serialize;

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
    /// by error; when none reaches the pose, the single closest attempt.
    pub solutions: Vec<IkSolution>,
    /// Starts tried.
    pub starts: usize,
    /// Jacobian evaluations spent.
    pub iterations: usize,
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
}

impl<'a> Ik<'a> {
    /// A solver for `model` that ignores collisions.
    pub fn new(model: &'a Model, opts: IkOptions) -> Self {
        Self {
            model,
            solver: Solver::new(model),
            checker: None,
            opts,
        }
    }

    /// A solver for `model` in a collision world built for the same model: solutions are checked
    /// with exact geometry, and colliding ones refined.
    pub fn with_collisions(model: &'a Model, world: &'a CollisionWorld, opts: IkOptions) -> Self {
        Self {
            model,
            solver: Solver::new(model),
            checker: Some(Checker::new(model, world)),
            opts,
        }
    }

    /// Solves `goal` (number `goal_index` of its scenario, which seeds its random starts) from
    /// `first_seed` (e.g. the previous goal's solution) and random starts within the limits.
    pub fn solve(&mut self, goal: &Goal, goal_index: usize, first_seed: Option<&[f64]>) -> GoalSolutions {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(self.opts.seed ^ (goal_index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let done = Convergence {
            position_m: 1e-6,
            orientation_rad: 1e-6,
        };
        let mut found: Vec<IkSolution> = Vec::new();
        let mut closest: Option<IkSolution> = None;
        let mut iterations = 0;
        // A NaN or negative margin means none: a NaN would call every configuration colliding.
        let margin = if self.opts.clearance_m.is_finite() {
            self.opts.clearance_m.max(0.0)
        } else {
            0.0
        };
        for start in 0..self.opts.seeds {
            let mut q = match (start, first_seed) {
                (0, Some(seed)) if seed.len() == self.model.dof() => seed.to_vec(),
                _ => self.model.random_configuration(&mut rng),
            };
            iterations += self.solver.solve(goal, &mut q, self.opts.max_iterations, done, &mut rng);
            let mut clearance = None;
            if let Some(checker) = self.checker.as_mut() {
                let mut measured = checker.clearance(&q, false);
                if measured.exact_m <= margin || !is_reached(&goal_error(goal, &self.model.tool_pose(&q))) {
                    checker.margin = margin;
                    refine::refine(&mut self.solver, checker, goal, &mut q, self.opts.refinement_steps, done, &mut rng);
                    measured = checker.clearance(&q, false);
                }
                clearance = Some(measured);
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
            if pose_reached {
                if !found.iter().any(|s| self.same_configuration(&s.q, &solution.q)) {
                    found.push(solution);
                }
            } else if closest.as_ref().is_none_or(|c| rank(&solution.error) < rank(&c.error)) {
                closest = Some(solution);
            }
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
            starts: self.opts.seeds,
            iterations,
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
        .map_init(make, |ik, (index, goal)| ik.solve(goal, index, None))
        .collect()
}
