//! Consumes a [`Model`], a [`Goal`] and optionally a collision checker.
//! Produces every distinct IK solution found for the goal (in closed form for UR-type arms and
//! `pose` goals, else from K seeded starts), each with its errors, clearance and verdict, and
//! whether the set is known complete. Never fails: an unreachable goal is a result, not an error.

pub mod analytic;
mod axes;
mod bilinear;
mod branches;
mod cap;
mod cells;
mod certify;
mod coaxial;
mod deflate;
mod dls;
mod eigen;
mod enclose;
mod error;
pub mod general;
mod lines;
mod loss;
pub mod parallel;
mod parts;
mod planar;
mod prefix;
mod reach;
mod reduce;
mod refine;
mod sampled;
pub mod search;
mod selfmotion;
mod separate;
pub mod solutions;
pub mod solvers;
mod spd6;
mod toward;
pub mod wrist;

pub use axes::turning_axes_out_of_reach;
pub use error::{angle_between, goal_error, task_error, GoalError};
pub use loss::{paper_loss_terms, LossTerms, DISTANCE_WEIGHT, HARDWARE_WEIGHT, ROTATION_WEIGHT};
pub use planar::{planar_group_out_of_reach, planar_numbers, PLANAR_BOXES};
pub use reach::{beyond_reach, last_joints_beyond_reach, reach_bound, task_beyond_reach, unreachable_proof};
pub use refine::{Clearance, COLLISION_THRESHOLD_M, COLLISION_WEIGHT};

use crate::collide::CollisionWorld;
use crate::collide::MotionBounds;
use crate::model::{JointKind, KinematicsWorkspace, Model};
use crate::scenario::{Goal, Scenario, Tolerance};
use analytic::{AnalyticSolutions, UrArm};
use dls::{Convergence, Solver};
use nalgebra::{Isometry3, Translation3};
use rand::SeedableRng;
use refine::Checker;
use serde::Serialize;
use solvers::{AllSolutions, HeldJoint};
use std::f64::consts::TAU;
use std::sync::Arc;

/// Position error below which a goal is reached (m): the paper's 1 mm.
pub const REACHED_POSITION_M: f64 = 1e-3;
/// Orientation error below which a goal is reached (rad): the paper's 1 degree.
pub const REACHED_ORIENTATION_RAD: f64 = std::f64::consts::PI / 180.0;
/// Closest numeric miss (m, rad) within which poses around an exactly unreachable goal are
/// tried: ten times the tolerance in position, about six in orientation.
const NEARBY_MISS_M: f64 = 0.01;
const NEARBY_MISS_RAD: f64 = 0.1;
/// How a merged arm's proof from its pose's solutions ends (see [`Ik::merged_out_of_reach`]).
const NONE_APPEARS: &str = "and no other solution appears within the tolerance: every complex root of the determinant stays off the real angles by more than four times what the tolerance can move it (first order)";
/// Parts of a goal's tolerance the general elimination's roots' proof may cut it into (each up
/// to seven eliminations, about 0.3 ms): a validation's, never a sweep's.
const GENERAL_PARTS: usize = 256;

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
    /// Boxes at most the joint-space search visits for a goal nothing else decides (default
    /// 200 000; 0 turns it off), see [`search`].
    pub search_boxes: usize,
    /// Per goal (scenario order), configurations tried as starts beside the random ones: an
    /// optimizer's configurations, so that what it found is what the validation checks (default
    /// none). A goal whose solutions the closed form lists tries them only when none of those is
    /// collision-free, refined against collisions as any start.
    pub goal_starts: Vec<Vec<Vec<f64>>>,
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
            search_boxes: SEARCH_BOXES,
            goal_starts: Vec::new(),
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

/// The all-solutions methods of one model: the UR closed form, else another method for its
/// geometry.
struct Methods {
    analytic: Option<UrArm>,
    all: Option<(AllSolutions, Tolerance)>,
    redundant: Option<HeldJoint>,
    sub_chains: Vec<reduce::SubChain>,
    coaxial: Option<coaxial::Merged>,
    merged_six: Option<Arc<MergedArm>>,
    merged_five: Option<Arc<MergedArm>>,
}

/// The arm with its coaxial joints merged, for pose goals as a 6R arm
/// ([`coaxial::Merged::six_joints`]), for `z_symmetric` ones as the five joints they are, and
/// its methods: shared by a batch's solvers, the model outliving each solver it lends itself to.
struct MergedArm {
    model: Model,
    methods: Methods,
}

impl Methods {
    fn of(model: &Model) -> Self {
        Self::merging(model, true)
    }

    /// The methods of `model`; with `merge`, those of its merged arm too (not of a merged arm's:
    /// a virtual joint on its last joint's axis would merge again).
    fn merging(model: &Model, merge: bool) -> Self {
        let analytic = UrArm::detect(model);
        let all = if analytic.is_none() { AllSolutions::of(model) } else { None };
        let redundant = HeldJoint::of(model);
        let sub_chains = reduce::sub_chains(model);
        let coaxial = coaxial::Merged::of(model);
        // Only for an arm no method lists the solutions of, and no redundant arm's either: the
        // merged arm proves out of reach what its own continua hide.
        let merged = coaxial.as_ref().filter(|_| merge && analytic.is_none() && all.is_none());
        let merged_six = merged.and_then(coaxial::Merged::six_joints).and_then(|six| {
            let methods = Methods::merging(&six, false);
            let decides = methods.analytic.is_some() || matches!(methods.all, Some((_, Tolerance::Pose)));
            decides.then(|| Arc::new(MergedArm { model: six, methods }))
        });
        let merged_five = merged.filter(|m| m.model.dof() == 5).and_then(|m| {
            let methods = Methods::merging(&m.model, false);
            let decides = matches!(methods.all, Some((_, Tolerance::ZSymmetric)));
            decides.then(|| {
                Arc::new(MergedArm {
                    model: m.model.clone(),
                    methods,
                })
            })
        });
        Self {
            analytic,
            all,
            redundant,
            sub_chains,
            coaxial,
            merged_six,
            merged_five,
        }
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
    /// Every solution of a 7R arm's pose with joint 7 held, when a method holds for the six
    /// others.
    redundant: Option<HeldJoint>,
    /// The joint held still by Newton steps and certificates while a self-motion is swept by
    /// it (see [`selfmotion`]).
    held: Option<usize>,
    /// Parts of tolerances the goal being solved may still cut (see [`cells`]).
    parts_left: usize,
    /// Parts of its tolerance the goal being solved may still prove out of reach (see
    /// [`parts`]).
    reach_parts_left: usize,
    /// The goal being solved's closest distinct misses from the numeric solver, best first:
    /// starts for aiming at its tolerance (see [`toward`]).
    misses: Vec<IkSolution>,
    /// Sub-chains the joint-space search tries before the whole arm (see [`reduce`]).
    sub_chains: Vec<reduce::SubChain>,
    /// The arm with its coaxial joints merged, which the search tries after the arm's own
    /// sub-chains (see [`coaxial`]).
    coaxial: Option<coaxial::Merged>,
    /// The merged arm as a 6R arm with its methods, where they list its solutions.
    merged_six: Option<Arc<MergedArm>>,
    /// The merged arm of five joints with its methods, where they list its `z_symmetric`
    /// goals' solutions.
    merged_five: Option<Arc<MergedArm>>,
    /// A solver lent to a merged arm for its proofs alone: the numeric attempts that could only
    /// add a closest miss after its exact solutions are certified are skipped.
    proving_only: bool,
    /// Collision queries at most per goal's searches ([`COLLISION_QUERIES`], fewer with meshes).
    collision_queries: usize,
    /// Parts of tolerances each goal may cut ([`cell_parts`]).
    cell_parts: usize,
    /// How far the links can move per joint turn, for certificates against the tolerance.
    bounds: MotionBounds,
    /// Whether the arm's first joints collide wherever they are (see [`prefix`]), once asked:
    /// the proof every goal that nothing else decides gets.
    collides_everywhere: Everywhere<'a>,
    /// The goal being solved is a pose the all-solutions method found no solution of.
    without_solution: bool,
    /// The goal being solved's colliding configurations within its tolerance that sampling
    /// found (see [`enclose`]).
    members: Vec<enclose::Member>,
    ws: KinematicsWorkspace,
}

/// Where a solver keeps its answer to "do the first joints collide wherever they are": its
/// own, or one shared by the solvers of a batch of goals (the answer is the arm's in its world,
/// whichever goal asks; rayon makes several solvers per batch).
enum Everywhere<'a> {
    Own(Option<Option<String>>),
    Shared(&'a std::sync::OnceLock<Option<String>>),
}

/// What a sub-chain's search proved, from "joints 1 to k for ...": out of the goal's reach, or
/// (with `colliding` boxes) in collision wherever within it.
fn sub_chain_proof(chain: &reduce::SubChain, reduced: &reduce::Reduced, boxes: usize, colliding: usize) -> String {
    let direction = if reduced.goal.tolerance == Tolerance::ZSymmetric {
        format!(" and its direction within {:.2} deg", reduced.radii.orientation_rad.to_degrees())
    } else {
        String::new()
    };
    let (joints, what, radius) = (chain.joints, &chain.what, reduced.radii.position_m * 1e3);
    if colliding == 0 {
        format!(
            "joints 1 to {joints} for {what}: no configuration of them within their limits brings it within {radius:.2} mm{direction} of where the goal puts it, as every configuration within the goal's tolerance must ({boxes} boxes, each ruled out by how far it can move within it)"
        )
    } else {
        format!(
            "joints 1 to {joints} for {what}: every configuration of them within their limits that brings it within {radius:.2} mm{direction} of where the goal puts it, as every configuration within the goal's tolerance must, collides among links 1 to {joints}, the obstacles and the floor ({boxes} boxes: {colliding} collide throughout, their centre's overlap deeper than their bodies can move within them; the others are ruled out by how far it can move within them)"
        )
    }
}

/// Pose error (m and rad) the closed form's solutions are polished to with Newton steps on the
/// model's own FK.
const POLISHED: f64 = 1e-12;
/// Newton steps at most per closed-form solution (one usually suffices, often none).
const POLISH_STEPS: usize = 3;
/// A closed-form solution whose polished error stays above this (m and rad) is not exact: the
/// pose sits on a workspace boundary where rounding decides, and the set is not called complete.
const EXACT: f64 = 1e-9;
/// Default of [`IkOptions::search_boxes`]: about 0.3 s a goal where the search runs out, and
/// enough to decide the goals of the shipped 4- and 5-joint designs on the cluttered tasks and
/// 86 of the 90 misses of the 5-joint real-world robot on the workspace task.
pub const SEARCH_BOXES: usize = 200_000;
/// The search's budget in sweeps: proofs that come cheap (the shipped 4-joint design's goals
/// take 3 to 123 boxes). The brute force's undecided goals are mostly on arms whose solutions
/// form continua: 2 000 boxes decided none of them and took the whole brute force from 53-64 s
/// to 97 s, [`SEARCH_BOXES`] decides 2.6 % of them at 28 times the time.
pub const SWEEP_SEARCH_BOXES: usize = 200;

impl<'a> Ik<'a> {
    /// A solver for `model` that ignores collisions.
    pub fn new(model: &'a Model, opts: IkOptions) -> Self {
        Self::build(model, None, opts, &Methods::of(model), Everywhere::Own(None))
    }

    /// A solver for `model` in a collision world built for the same model: solutions are checked
    /// with exact geometry, and colliding ones refined.
    pub fn with_collisions(model: &'a Model, world: &'a CollisionWorld, opts: IkOptions) -> Self {
        Self::build(model, Some(world), opts, &Methods::of(model), Everywhere::Own(None))
    }

    /// A solver with the model's methods already found (one detection for many solvers).
    fn build(
        model: &'a Model,
        world: Option<&'a CollisionWorld>,
        opts: IkOptions,
        methods: &Methods,
        collides_everywhere: Everywhere<'a>,
    ) -> Self {
        Self {
            model,
            solver: Solver::new(model),
            checker: world.map(|world| Checker::new(model, world)),
            analytic: methods.analytic.clone(),
            all: methods.all.clone(),
            redundant: methods.redundant.clone(),
            held: None,
            parts_left: cell_parts(model),
            cell_parts: cell_parts(model),
            reach_parts_left: parts::PARTS_PER_GOAL,
            misses: Vec::new(),
            sub_chains: methods.sub_chains.clone(),
            coaxial: methods.coaxial.clone(),
            merged_six: methods.merged_six.clone(),
            merged_five: methods.merged_five.clone(),
            proving_only: false,
            collision_queries: collision_queries(model),
            bounds: MotionBounds::of(model),
            collides_everywhere,
            without_solution: false,
            members: Vec::new(),
            ws: model.workspace(),
            opts,
        }
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
    ///
    /// A goal that none of this reaches and none of it proves out of reach goes to the
    /// joint-space search, which proves that no configuration within the limits is within the
    /// tolerance, or finds one.
    pub fn solve(&mut self, goal: &Goal, goal_index: usize, first_seed: Option<&[f64]>) -> GoalSolutions {
        self.parts_left = self.cell_parts;
        self.reach_parts_left = parts::PARTS_PER_GOAL;
        self.misses.clear();
        self.members.clear();
        self.without_solution = false;
        let mut result = self.solve_by_methods(goal, goal_index, first_seed);
        self.search_joint_space(goal, goal_index, &mut result);
        judge_task_tolerance(self.model, goal, &mut result);
        result
    }

    /// [`Self::solve`] without the joint-space search.
    fn solve_by_methods(&mut self, goal: &Goal, goal_index: usize, first_seed: Option<&[f64]>) -> GoalSolutions {
        let finite = goal.position.iter().chain(goal.rotation.coords.iter()).all(|x| x.is_finite());
        let pose = Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
        let all_solutions = self.opts.analytic && finite && matches!(goal.tolerance, Tolerance::Pose | Tolerance::ZSymmetric);
        let exact = match (&self.analytic, &self.all) {
            (Some(arm), _) if all_solutions => arm.solve(&pose),
            (None, Some((method, mode))) if self.opts.analytic && finite && goal.tolerance == *mode => {
                let found = method.solve_proving(&pose, self.cap_evaluations());
                self.without_solution = found.configurations.is_empty() && found.resolved;
                AnalyticSolutions {
                    configurations: found.configurations,
                    finite: found.resolved,
                    out_of_reach: found.out_of_reach,
                }
            }
            (None, Some((method, Tolerance::Pose))) if self.opts.analytic && finite && goal.tolerance == Tolerance::ZSymmetric => {
                let starts = method.solve(&pose).configurations;
                let mut result = self.solve_numeric(goal, goal_index, first_seed, &starts, true);
                if !result.reached() {
                    self.sweep_free_turn(goal, &mut result);
                }
                return result;
            }
            (None, None) if self.redundant.is_some() && self.opts.analytic && finite && goal.tolerance == Tolerance::Pose => {
                let mut result = self.solve_numeric(goal, goal_index, first_seed, &[], true);
                if !result.reached() {
                    self.sweep_held_joint(goal, &mut result);
                }
                return result;
            }
            _ => {
                let mut result = self.solve_numeric(goal, goal_index, first_seed, &[], true);
                let posed = result.solutions.iter().any(|s| s.pose_reached);
                let decided = matches!(goal.tolerance, Tolerance::Pose | Tolerance::ZSymmetric);
                if !posed && self.opts.analytic && finite && decided {
                    if let Some(proof) = self.merged_out_of_reach(goal, goal_index) {
                        result.complete = true;
                        result.proof = Some(proof);
                    }
                }
                return result;
            }
        };
        if goal.tolerance == Tolerance::ZSymmetric && self.analytic.is_some() {
            // A continuum of solutions (any turn about tool z): the goal rotation's own are on
            // every branch, good starts, never the whole set; what they miss, the self-motion
            // sweep decides.
            let mut result = self.solve_numeric(goal, goal_index, first_seed, &exact.configurations, true);
            if !result.reached() {
                self.sweep_free_turn(goal, &mut result);
            }
            return result;
        }
        if exact.finite && !exact.configurations.is_empty() {
            return self.solve_closed_form(goal, goal_index, first_seed, &exact);
        }
        let mut result = self.solve_numeric(goal, goal_index, first_seed, &exact.configurations, true);
        // A pose within the tolerance has solutions only where the workspace's boundary passes
        // within it; the numeric search then ends close to the goal. Far misses skip the
        // nearby poses (48 exact solves, the brute force's largest cost), undecided all the same.
        let close = result
            .solutions
            .first()
            .is_some_and(|s| s.error.position_m < NEARBY_MISS_M && s.error.orientation_rad < NEARBY_MISS_RAD);
        let open = !result.reached() && exact.finite && close && goal.tolerance == Tolerance::Pose;
        if open && exact.out_of_reach.is_none() && reach::beyond_reach(self.model, goal).is_none() {
            // No exact solution, not ruled out: poses just off it may have some.
            if let Some(solution) = self.reach_nearby(goal, selfmotion::Parameter::Turn, 0.0) {
                result.solutions.insert(0, solution);
                return result;
            }
        }
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
                found.push(self.judge(goal, q, Some(error), margin));
            } else {
                match self.outside_limits_certificate(goal, &q, 0.0) {
                    Ok(pair) => collisions.extend(pair),
                    Err(why) => open.push(why),
                }
                outside.push(q);
            }
        }
        let mut starts = 0;
        let mut closest: Option<IkSolution> = None;
        // A merged arm's solver proves alone: its certified solutions need no closest miss.
        let certified = self.proving_only && open.is_empty();
        if !outside.is_empty() && !certified {
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
        if !found.iter().any(|s| s.reached) {
            // The caller's starts may hold a free configuration within the tolerance that the
            // exact solutions' refinement would not reach.
            let mut rng = self.rng(goal_index);
            for q in self.given_starts(goal_index) {
                starts += 1;
                let (solution, used) = self.attempt(goal, q, true, margin, &mut rng);
                iterations += used;
                if solution.reached {
                    // A free configuration of a colliding exact solution's branch stands for it.
                    found.retain(|s| !self.same_configuration(&s.q, &solution.q));
                    found.insert(0, solution);
                    break;
                }
            }
        }
        if !found.iter().any(|s| s.reached) {
            // Only a goal nothing reaches needs its colliding solutions certified.
            for solution in found.iter_mut() {
                if !solution.pose_reached || solution.reached {
                    continue;
                }
                // The checker's closest pair must be this solution's.
                if let Some(checker) = self.checker.as_mut() {
                    checker.clearance(&solution.q, true);
                }
                match self.collision_certificate(goal, solution, margin, 0.0) {
                    Ok(pair) => collisions.push(pair),
                    // Not proven: the tolerance may hold a free configuration of this branch;
                    // it stands for the branch when found, and the goal is reached.
                    Err(why) => {
                        let q = solution.q.clone();
                        if let Some(free) = self.free_within_tolerance(goal, &q, margin) {
                            *solution = free;
                            break;
                        }
                        match self.cut_tolerance(goal, goal, &q, margin, 0.0) {
                            cells::Cells::Settled(pair) => collisions.push(pair),
                            cells::Cells::Free(free) => {
                                *solution = free;
                                break;
                            }
                            cells::Cells::Open(cut) => open.push(format!("{why}; cut into parts, {cut}")),
                            cells::Cells::Untried => open.push(why),
                        }
                    }
                }
            }
        }
        // The errors are all rounding: order by clearance (the best attempt first when none is
        // free), else keep the branch order. Clearances are compared to the nanometre: a wrist
        // flip's configurations are often equally clear (the closest pair is a link before the
        // wrist), and which comes first must not follow the last bits of their arithmetic.
        found.sort_by(|a, b| {
            b.reached.cmp(&a.reached).then_with(|| {
                let clearance = |s: &IkSolution| (s.clearance.map_or(0.0, |c| c.exact_m) * 1e9).round() as i64;
                clearance(b).cmp(&clearance(a))
            })
        });
        let poses = found.len();
        if found.is_empty() {
            found.extend(closest);
        }
        let reached = found.first().is_some_and(|s| s.reached);
        let method = self.method();
        if complete && open.is_empty() && !reached {
            // Before a proof, the numeric search as a cross-check: near a workspace boundary a
            // pose within the tolerance can have solutions the exact pose lacks (a branch pair
            // born inside the tolerance), which no certificate around the exact ones covers.
            // Its question is where the pose can be reached, not whether freely: its attempts
            // are not refined around collisions (the exact branches' are certified above).
            let numeric = self.solve_numeric(goal, goal_index, first_seed, &[], false);
            if numeric.reached() {
                return numeric;
            }
            let off_branch = numeric.solutions.iter().filter(|s| s.pose_reached).find(|s| {
                !distinct
                    .iter()
                    .any(|d| d.iter().zip(&s.q).all(|(a, b)| wrap_angle(a - b).abs() <= OFF_BRANCH_RAD))
            });
            if let Some(stray) = off_branch {
                open.push(format!(
                    "the numeric search found a configuration within the tolerance ({:.2} mm, {:.3} deg) off every exact solution: solutions appear within the tolerance",
                    stray.error.position_m * 1e3,
                    stray.error.orientation_rad.to_degrees()
                ));
            }
        }
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
            if poses == 0 && collisions.is_empty() {
                format!(
                    "{method}: none of the pose's {total} solutions is within the joint limits, nor within the goal's tolerance of them"
                )
            } else if poses == 0 {
                format!(
                    "{method}: none of the pose's {total} solutions is within the joint limits, and those the goal's tolerance may bring within them collide throughout it ({})",
                    summary(&collisions)
                )
            } else {
                format!(
                    "{method}: all {poses} solutions of the pose{limits} {what}, throughout the goal's tolerance ({})",
                    summary(&collisions)
                )
            }
        });
        let undecided = if reached {
            None
        } else if !complete {
            Some(format!(
                "{method}: the pose is singular or on the workspace boundary: its solutions are not isolated"
            ))
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

    /// Decides by the joint-space search a goal that nothing reached within the pose's tolerance
    /// and nothing proved out of reach: a proof, a free configuration within the tolerance, or
    /// the budget named as the limit. Poses out of the tool's reach keep their cheaper proof.
    ///
    /// Where no configuration within the tolerance is known, the tolerance is first aimed at
    /// directly ([`toward`]), then sub-chains try to prove it out of reach ([`reduce`]). The
    /// search itself, with a collision world, discards boxes that collide throughout as well as
    /// those out of the tolerance: it proves that every configuration within the tolerance
    /// collides, or finds a free one (goals whose colliding solutions no certificate covers:
    /// near a singularity, branches born within the tolerance).
    fn search_joint_space(&mut self, goal: &Goal, goal_index: usize, result: &mut GoalSolutions) {
        if result.reached() || result.proof.is_some() || self.opts.search_boxes == 0 {
            return;
        }
        let finite = goal.position.iter().chain(goal.rotation.coords.iter()).all(|x| x.is_finite());
        if !finite || reach::beyond_reach(self.model, goal).is_some() {
            return;
        }
        if let Some(proof) = self.collides_everywhere() {
            result.complete = true;
            result.undecided = None;
            result.proof = Some(proof);
            return;
        }
        let mut posed = result.solutions.iter().any(|s| s.pose_reached);
        if posed && self.checker.is_none() {
            return;
        }
        if !posed {
            // The numeric solver's other misses too: its closest may lie on a branch whose
            // configurations within the tolerance collide while another's are free.
            let mut misses = std::mem::take(&mut self.misses);
            misses.extend(result.solutions.iter().cloned());
            if let Some(solution) = self.reach_tolerance(goal, goal_index, &misses) {
                result.starts += 1;
                if solution.reached {
                    result.undecided = None;
                    add_found(result, solution);
                    return;
                }
                let clearance = solution
                    .clearance
                    .as_ref()
                    .map_or(String::new(), |c| format!(" (clearance {:.1} mm)", c.exact_m * 1e3));
                result.undecided = Some(format!(
                    "{}: the pose itself has no solution; a configuration within the goal's tolerance ({:.2} mm, {:.2} deg off) collides{clearance}",
                    self.method(),
                    solution.error.position_m * 1e3,
                    solution.error.orientation_rad.to_degrees()
                ));
                add_found(result, solution);
                posed = true;
            }
        }
        // Three numbers or fewer: about a thousand boxes, before the searches below. After the
        // aim at the tolerance: a configuration it finds within the tolerance meets the planar
        // conditions, so the search could never finish and would split until its budget runs
        // out (20 000 boxes, 5 to 9 ms; the aim takes microseconds). Where the search proves
        // the goal out of reach, the aim finds nothing.
        if !posed && self.planar_proof(goal, 3, planar::PLANAR_BOXES, result) {
            return;
        }
        // Each sub-chain's goal, by its index in `sub_chains`.
        let reduced: Vec<(usize, reduce::Reduced)> = self
            .sub_chains
            .iter()
            .enumerate()
            .filter_map(|(index, chain)| Some((index, chain.reduce(goal)?)))
            .collect();
        let mut queries = self.collision_queries;
        // The arm with its coaxial joints merged after the arm's own sub-chains: a proof it
        // adds, none it replaces (its boxes split differently, and with a sweep's budget each
        // finds proofs the other misses).
        let proof = self
            .search_sub_chains(&reduced, &mut queries)
            .or_else(|| if posed { None } else { self.search_merged(goal) });
        if let Some(proof) = proof {
            result.complete = true;
            result.undecided = None;
            result.proof = Some(proof);
            return;
        }
        if self.opts.search_boxes < search::FIRST_ORDER_BUDGET && !posed && self.roots_stay_complex(goal, result, false) {
            return;
        }
        if !reduced.is_empty() && self.opts.search_boxes < search::FIRST_ORDER_BUDGET {
            // A sweep's few boxes over every joint rule out nothing the sub-chains' searches
            // just left open: on the 36 cluttered tasks (200 random 6R designs, 312 modular
            // ones; 65 045 such searches at 200 boxes, 678 more at 9 999 on task 03) they
            // decided no goal, and took a seventh of a sweep's time.
            return;
        }
        if posed && self.opts.search_boxes < search::FIRST_ORDER_BUDGET {
            // A sweep's few boxes never get small enough to be certified in collision (the
            // brute force on task 00: the same records without them, 51.0 s against 52.9 s).
            return;
        }
        if !posed && self.opts.search_boxes >= search::FIRST_ORDER_BUDGET {
            if let Some(proof) = self.out_of_reach_in_parts(goal) {
                result.complete = true;
                result.undecided = None;
                result.proof = Some(proof);
                return;
            }
        }
        if self.opts.search_boxes >= search::FIRST_ORDER_BUDGET && self.reach_by_sampling(goal, result) {
            return;
        }
        let mut rng = self.rng(goal_index);
        let margin = self.margin();
        let mut oracle = SearchOracle {
            model: self.model,
            goal,
            solver: &mut self.solver,
            // Collisions count only where a configuration within the tolerance is known: else
            // the tolerance alone decides most boxes, and a query per box would only slow them.
            checker: self.checker.as_mut().filter(|_| posed),
            bounds: &self.bounds,
            margin,
            rng: &mut rng,
            queries: &mut queries,
        };
        let helpers: Vec<search::Helper> = reduced
            .iter()
            .map(|(index, reduced)| search::Helper {
                model: &self.sub_chains[*index].model,
                goal: &reduced.goal,
                radii: reduced.radii,
            })
            .collect();
        // Where a configuration within the tolerance is known, only collisions can decide, and
        // each box may cost a query: a quarter of the budget (the 5-joint arm's proofs in
        // collision on the cluttered tasks take up to 26 000 boxes; 6- and 7-joint arms' rarely
        // finish at any budget, their sub-chains decide them).
        let budget = if posed {
            self.opts.search_boxes / 4
        } else {
            self.opts.search_boxes
        };
        let outcome = search::search_helped(self.model, goal, search::Radii::REACHED, budget, &mut oracle, &helpers);
        // What the searches leave open, the first-order proof may still decide.
        let open = !matches!(outcome, Some(search::Search::Proven { .. } | search::Search::Found { .. }));
        let in_parts = self.opts.search_boxes >= search::FIRST_ORDER_BUDGET;
        if open && !posed && self.roots_stay_complex(goal, result, in_parts) {
            return;
        }
        if open && posed && in_parts && !self.members.is_empty() {
            let members = std::mem::take(&mut self.members);
            if let Some(proof) = self.enclose_tolerance(goal, &members) {
                result.complete = true;
                result.undecided = None;
                result.proof = Some(format!("{}: {proof}", self.method()));
                return;
            }
        }
        // Four numbers at most, a validation's budget, where the searches above leave it open
        // (the searches of three or fewer again too: they may need more than their own budget).
        if open && !posed && in_parts && self.planar_proof(goal, 4, self.opts.search_boxes, result) {
            return;
        }
        let Some(outcome) = outcome else {
            return;
        };
        let before = result.undecided.take().map_or(String::new(), |open| format!("{open}; "));
        match outcome {
            search::Search::Proven { boxes, colliding: 0 } if !posed => {
                result.complete = true;
                result.proof = Some(format!(
                    "joint-space search: no configuration within the joint limits comes within the goal's tolerance ({boxes} boxes, each ruled out by how far the tool can move within it)"
                ));
            }
            search::Search::Proven { boxes, colliding } => {
                result.complete = true;
                result.proof = Some(format!(
                    "joint-space search: every configuration within the joint limits that comes within the goal's tolerance collides ({boxes} boxes: {colliding} collide throughout, their centre's overlap deeper than their bodies can move within them; the others are ruled out by how far the tool can move within them)"
                ));
            }
            search::Search::Found { q, boxes } => {
                let (solved, used) = self.attempt(goal, q.clone(), true, margin, &mut rng);
                // Judged again: the attempt's clearance is an estimate, the verdict's is exact.
                let solution = if solved.reached {
                    self.judge(goal, solved.q, Some(solved.error), margin)
                } else {
                    self.judge(goal, q, None, margin)
                };
                result.starts += 1;
                result.iterations += used;
                if !solution.reached {
                    result.undecided = Some(format!(
                        "{before}the joint-space search found a configuration within the goal's tolerance ({boxes} boxes), but it collides"
                    ));
                }
                add_found(result, solution);
            }
            search::Search::Open { boxes } => {
                let miss = result.solutions.first().filter(|s| !s.pose_reached).map_or(String::new(), |s| {
                    format!(
                        "no solution from {} IK starts (seed {}), closest miss {:.1} mm, {:.2} deg; ",
                        result.starts,
                        self.opts.seed,
                        s.error.position_m * 1e3,
                        s.error.orientation_rad.to_degrees()
                    )
                });
                let miss = if before.is_empty() { miss } else { before };
                let what = if posed {
                    "neither proved every configuration within the goal's tolerance in collision nor found a free one"
                } else {
                    "neither ruled out a configuration within the goal's tolerance nor found one"
                };
                result.undecided = Some(format!("{miss}a joint-space search of {boxes} boxes (its budget) {what}"));
            }
        }
    }

    /// The general elimination's proof that a pose without solution has none within the goal's
    /// tolerance either ([`general::General6R::out_of_reach_within`]: first order, its roots'
    /// distance from the real angles against four times their motion), for a goal the exact
    /// searches left open, written into `result`; whether it holds. Not where a reach bound
    /// proves the goal: the report gives that exact proof instead. With `in_parts`, where the
    /// proof over the whole tolerance fails, the tolerance is cut ([`parts`], at most
    /// [`GENERAL_PARTS`] parts): a pose a millimetre or two beyond a fold of the arm's
    /// solutions has roots nearer the real angles than four times their motion over the whole
    /// tolerance, but not over a part of it; and the proof over the whole tolerance is
    /// [`general::General6R::out_of_reach_checked`], which solves the roots again at more poses
    /// of the tolerance's boundary.
    fn roots_stay_complex(&self, goal: &Goal, result: &mut GoalSolutions, in_parts: bool) -> bool {
        let Some((AllSolutions::General(general), Tolerance::Pose | Tolerance::ZSymmetric)) = self.all.as_ref() else {
            return false;
        };
        if !self.without_solution || reach::last_joints_beyond_reach(self.model, goal).is_some() {
            return false;
        }
        let pose = Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
        // A validation's proof checks more poses on the tolerance's boundary.
        let whole = if in_parts {
            general.out_of_reach_checked(&pose, search::Radii::REACHED, 0.0)
        } else {
            general.out_of_reach_within(&pose, search::Radii::REACHED, 0.0)
        };
        let proof = whole.or_else(|| {
            let mut budget = GENERAL_PARTS;
            in_parts.then(|| general.out_of_reach_in_parts(goal, &mut budget)).flatten()
        });
        let Some(proof) = proof else {
            return false;
        };
        result.complete = true;
        result.undecided = None;
        result.proof = Some(format!("{}: {proof}", self.method()));
        true
    }

    /// The proof that every configuration collides, whatever the goal (see [`prefix`]): found
    /// once per solver, with the budget of one search (a box is one collision query).
    fn collides_everywhere(&mut self) -> Option<String> {
        let margin = self.margin();
        let budget = self.opts.search_boxes.min(self.collision_queries);
        let (model, bounds, checker) = (self.model, &self.bounds, &mut self.checker);
        let find = || {
            checker
                .as_mut()
                .and_then(|checker| prefix::first_joints_collide(model, checker, bounds, margin, budget))
                .map(|proof| proof.describe())
        };
        match &mut self.collides_everywhere {
            Everywhere::Own(known) => known.get_or_insert_with(find).clone(),
            Everywhere::Shared(known) => known.get_or_init(find).clone(),
        }
    }

    /// A proof that no free configuration reaches `goal`, from the first sub-chain whose search
    /// rules out every configuration of its joints (`reduced`, see [`reduce`]): out of its
    /// tolerance, or, with a collision world, in collision throughout among the links the
    /// sub-chain moves (and the obstacles and floor). Each search has the whole budget. A
    /// sub-chain that reaches its own goal free proves nothing: the joints left out may not
    /// follow.
    fn search_sub_chains(&mut self, reduced: &[(usize, reduce::Reduced)], queries: &mut usize) -> Option<String> {
        let margin = self.margin();
        let budget = self.opts.search_boxes;
        for (index, reduced) in reduced {
            let chain = &self.sub_chains[*index];
            let mut oracle = SubChainOracle {
                levels: self.checker.as_ref().map(|c| c.pairs_up_to(chain.joints)).unwrap_or_default(),
                checker: self.checker.as_mut(),
                bounds: &self.bounds,
                margin,
                queries: &mut *queries,
                q: vec![0.0; self.model.dof()],
                model: &chain.model,
                solver: Solver::new(&chain.model),
                reduced,
                rng: rand_chacha::ChaCha8Rng::seed_from_u64(self.opts.seed),
            };
            let outcome = search::search_with(&chain.model, &reduced.goal, reduced.radii, budget, &mut oracle);
            let Some(search::Search::Proven { boxes, colliding }) = outcome else {
                continue;
            };
            return Some(format!(
                "joint-space search of {}",
                sub_chain_proof(chain, reduced, boxes, colliding)
            ));
        }
        None
    }

    /// The searches of the arm with its coaxial joints merged ([`coaxial`]): its sub-chains',
    /// then (from [`search::FIRST_ORDER_BUDGET`] boxes, or without sub-chains) its own; the
    /// proof when one rules the goal's tolerance out.
    fn search_merged(&self, goal: &Goal) -> Option<String> {
        let merged = self.coaxial.as_ref()?;
        let budget = self.opts.search_boxes;
        let mut oracle = coaxial::BoundsAlone;
        let reduced: Vec<(&reduce::SubChain, reduce::Reduced)> = merged
            .sub_chains
            .iter()
            .filter_map(|chain| Some((chain, chain.reduce(goal)?)))
            .collect();
        for (chain, reduced) in &reduced {
            if let Some(search::Search::Proven { boxes, colliding }) =
                search::search_with(&chain.model, &reduced.goal, reduced.radii, budget, &mut oracle)
            {
                let words = sub_chain_proof(chain, reduced, boxes, colliding);
                return Some(format!("{}: joint-space search of its {words}", merged.describe()));
            }
        }
        if !reduced.is_empty() && budget < search::FIRST_ORDER_BUDGET {
            return None;
        }
        let helpers: Vec<search::Helper> = reduced
            .iter()
            .map(|(chain, reduced)| search::Helper {
                model: &chain.model,
                goal: &reduced.goal,
                radii: reduced.radii,
            })
            .collect();
        match search::search_helped(&merged.model, goal, search::Radii::REACHED, budget, &mut oracle, &helpers)? {
            search::Search::Proven { boxes, .. } => Some(format!(
                "{}: joint-space search of the arm so merged: no configuration within the joint limits comes within the goal's tolerance ({boxes} boxes, each ruled out by how far the tool can move within it)",
                merged.describe()
            )),
            _ => None,
        }
    }

    /// Why no configuration reaches `goal` within its tolerance, from the arm with its coaxial
    /// joints merged ([`MergedArm`]: a pose goal's as a 6R arm, a `z_symmetric` goal's as the
    /// five joints, whose method adds the virtual joint the goal's free turn is): its solutions
    /// stand for the arm's continua, each once, so a proof of its holds for the arm. Either the
    /// pose has solutions, each certified outside the limits (a pose goal's virtual joint's
    /// `[0, 0]` among them) throughout the tolerance, and the elimination's complex roots stay
    /// off the real angles throughout it (no pair born off them: a numeric cross-check rarely
    /// lands on a five-joint arm's thin set of poses), or it has none and none appears within
    /// the tolerance (the roots' proof). Asked only where the arm's numeric search found no
    /// configuration within the tolerance.
    fn merged_out_of_reach(&self, goal: &Goal, goal_index: usize) -> Option<String> {
        let merged = self.coaxial.as_ref()?;
        let arm = match goal.tolerance {
            Tolerance::Pose => self.merged_six.as_ref()?,
            Tolerance::ZSymmetric => self.merged_five.as_ref()?,
            Tolerance::Position => return None,
        };
        // Field by field: the caller's goal starts are not the merged arm's, and not cloned.
        let opts = IkOptions {
            seeds: 0,
            branch_starts: 0,
            goal_starts: Vec::new(),
            max_iterations: self.opts.max_iterations,
            seed: self.opts.seed,
            distinct_tolerance: self.opts.distinct_tolerance,
            refinement_steps: self.opts.refinement_steps,
            clearance_m: self.opts.clearance_m,
            analytic: true,
            search_boxes: self.opts.search_boxes,
        };
        let mut ik = Ik::build(&arm.model, None, opts, &arm.methods, Everywhere::Own(None));
        ik.proving_only = true;
        let mut result = ik.solve_by_methods(goal, goal_index, None);
        if result.solutions.iter().any(|s| s.pose_reached) {
            return None;
        }
        if result.proof.is_some() && !ik.without_solution {
            // The pose's solutions are certified over the tolerance; a pair born within it, off
            // them all, the numeric cross-check alone would miss (five joints have a thin set
            // of poses: its starts rarely land there).
            let pose = Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
            let none_appears = match ik.all.as_ref() {
                Some((AllSolutions::General(general), _)) => general.no_solution_appears_within(&pose, search::Radii::REACHED, 0.0),
                _ => false,
            };
            if !none_appears {
                return None;
            }
            result.proof = result.proof.map(|proof| format!("{proof}; {NONE_APPEARS}"));
        }
        if result.proof.is_none() {
            let in_parts = self.opts.search_boxes >= search::FIRST_ORDER_BUDGET;
            ik.roots_stay_complex(goal, &mut result, in_parts);
        }
        let proof = result.proof?;
        let described = if goal.tolerance == Tolerance::Pose {
            merged.describe_six()
        } else {
            merged.describe()
        };
        Some(format!("{described}: {proof}"))
    }

    /// The planar run's proof over at most `most` numbers within `budget` boxes, when it proves
    /// `goal` out of reach: `result` takes it.
    fn planar_proof(&self, goal: &Goal, most: usize, budget: usize, result: &mut GoalSolutions) -> bool {
        let Some(proof) = planar::planar_group_out_of_reach(self.model, goal, most, budget) else {
            return false;
        };
        result.complete = true;
        result.undecided = None;
        result.proof = Some(proof);
        true
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
    /// `radii` (the tolerance, or a part of it), when the closed form or the all-solutions
    /// method proves it (a spherical wrist's within `evaluations` of its cap).
    fn exact_out_of_reach_within(&self, pose: &Isometry3<f64>, radii: search::Radii, turn: f64, evaluations: usize) -> Option<String> {
        match (&self.analytic, &self.all) {
            (Some(arm), _) => arm.out_of_reach_within(pose, radii, turn),
            (None, Some((method, Tolerance::Pose))) => method.out_of_reach_within(pose, radii, turn, evaluations),
            _ => None,
        }
    }

    /// A pose goal of a UR-type arm that no pose within its tolerance is known to reach, whose
    /// closed-form proof over the whole tolerance and sub-chain searches fell short, proven out
    /// of reach part by part ([`parts`]: the closed form's proof at each part's centre, about a
    /// microsecond each); `None` where a small part's centre pose has solutions, or the parts
    /// run out. A pose a millimetre or two beyond the arm's shell is the usual case: its
    /// reachable neighbours lie closer than the whole tolerance's slack.
    fn out_of_reach_in_parts(&mut self, goal: &Goal) -> Option<String> {
        let arm = self.analytic.as_ref()?;
        if goal.tolerance != Tolerance::Pose {
            return None;
        }
        let pose_of = |part: &Goal| Isometry3::from_parts(Translation3::from(part.position), part.rotation);
        let mut budget = self.reach_parts_left;
        let proof = parts::out_of_reach_by_parts(
            goal,
            &mut budget,
            parts::LEVER_M,
            |part, extent| arm.out_of_reach_within(&pose_of(part), extent.radii, 0.0).ok_or(None),
            |part| !arm.solve(&pose_of(part)).configurations.is_empty(),
        );
        self.reach_parts_left = budget;
        proof
    }

    /// What a spherical wrist's out-of-reach proof may spend on the tolerance's cap.
    fn cap_evaluations(&self) -> usize {
        cap::evaluations_for(self.opts.search_boxes)
    }

    /// Which all-solutions method this solver uses, for proofs.
    fn method(&self) -> &'static str {
        match (&self.analytic, &self.all) {
            (Some(_), _) => "closed-form IK",
            (None, Some((method, _))) => method.name(),
            (None, None) => match &self.redundant {
                Some(held) => held.method.name(),
                None => "numeric IK",
            },
        }
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

    /// Moves each revolute angle of `q` by whole turns into its limits, to the equivalent nearest
    /// `near` (else zero); false when some joint has no equivalent within its limits.
    fn shift_into_limits(&self, q: &mut [f64], near: Option<&[f64]>) -> bool {
        let near = near.filter(|n| n.len() == q.len());
        for (i, (value, joint)) in q.iter_mut().zip(&self.model.joints).enumerate() {
            if !value.is_finite() {
                return false;
            }
            if joint.kind == JointKind::Prismatic {
                if let Some([lower, upper]) = joint.limits {
                    if *value < lower - LIMIT_ROUNDING || *value > upper + LIMIT_ROUNDING {
                        return false;
                    }
                    // max then min: no panic on limits a loader would have refused.
                    *value = value.max(lower).min(upper);
                }
                continue;
            }
            let target = near.map_or(0.0, |n| n[i]);
            let target = if target.is_finite() { target } else { 0.0 };
            let mut turns = ((target - *value) / TAU).round();
            if let Some([lower, upper]) = joint.limits {
                let fewest = ((lower - LIMIT_ROUNDING - *value) / TAU).ceil();
                let most = ((upper + LIMIT_ROUNDING - *value) / TAU).floor();
                if fewest > most {
                    return false;
                }
                turns = turns.clamp(fewest, most);
                *value += turns * TAU;
                // An angle a rounding past a limit (a sample at the limit wrapped into
                // (-pi, pi] and back) is at the limit.
                *value = value.max(lower).min(upper);
            } else if turns != 0.0 {
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
    fn solve_numeric(
        &mut self,
        goal: &Goal,
        goal_index: usize,
        first_seed: Option<&[f64]>,
        extra: &[[f64; 6]],
        refine: bool,
    ) -> GoalSolutions {
        let mut rng = self.rng(goal_index);
        let mut found: Vec<IkSolution> = Vec::new();
        let mut closest: Option<IkSolution> = None;
        let mut iterations = 0;
        let margin = self.margin();
        let mut starts = self.opts.seeds + extra.len();
        for start in 0..starts {
            let q = match (start, first_seed) {
                // A 5R arm's exact configurations carry the virtual joint's angle last.
                _ if start >= self.opts.seeds => extra[start - self.opts.seeds].iter().take(self.model.dof()).copied().collect(),
                (0, Some(seed)) if seed.len() == self.model.dof() => seed.to_vec(),
                _ => self.model.random_configuration(&mut rng),
            };
            if start >= self.opts.seeds && found.iter().any(|s| self.same_configuration(&s.q, &q)) {
                continue;
            }
            let (solution, used) = self.attempt(goal, q, refine, margin, &mut rng);
            iterations += used;
            self.keep_miss(&solution);
            self.keep(solution, &mut found, &mut closest);
        }
        if goal.tolerance == Tolerance::Pose && branches::applies(self.model) {
            let (branch_starts, used) = self.branch_restarts(goal, &mut found, &mut closest, margin, &mut rng);
            starts += branch_starts;
            iterations += used;
        }
        // The caller's starts last, on a stream of their own: everything above runs as without
        // them, and they can only add solutions.
        let mut given_rng = self.rng(goal_index);
        for q in self.given_starts(goal_index) {
            if found.iter().any(|s| self.same_configuration(&s.q, &q)) {
                continue;
            }
            starts += 1;
            let (solution, used) = self.attempt(goal, q, refine, margin, &mut given_rng);
            iterations += used;
            self.keep_miss(&solution);
            self.keep(solution, &mut found, &mut closest);
        }
        // Clearances were estimated while searching (overlap depths from bounding capsules, gaps
        // unpolished), misses not measured at all; the solutions kept are measured exactly.
        if let Some(checker) = self.checker.as_mut() {
            for solution in found.iter_mut().chain(closest.iter_mut()) {
                let exact = checker.clearance(&solution.q, true);
                // Touching within rounding, GJK's overlap test and EPA may disagree on the sign.
                solution.reached = solution.pose_reached && exact.exact_m > margin;
                solution.clearance = Some(exact);
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
                self.keep_miss(&solution);
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
        let mut error = goal_error(goal, &self.model.tool_pose(&q));
        if let Some(checker) = self.checker.as_mut() {
            let miss = !is_reached(&error);
            // A miss is refined whatever its clearance (measure only what is kept), except where
            // the arm has as many joints as the goal constrains (six on a pose goal): there the
            // solutions are isolated points, closed forms list them where they exist, and the
            // refinement could only restart the miss at random, as the solve's stall restarts
            // do. With more joints it moves along the null space; with fewer, the tolerance
            // holds every solution there is, and its restarts are the search for one.
            let refine_miss = refine && miss && self.model.dof() != refine::constrained_dimensions(goal.tolerance);
            // A miss that is not refined is measured only if kept ([`Self::solve_numeric`]).
            let mut measured = (!miss).then(|| checker.clearance(&q, false));
            let colliding = refine && measured.is_some_and(|m| m.exact_m <= margin);
            if refine_miss || colliding {
                checker.margin = margin;
                refine::refine(&mut self.solver, checker, goal, &mut q, self.opts.refinement_steps, done, rng);
                measured = Some(checker.clearance(&q, false));
                error = goal_error(goal, &self.model.tool_pose(&q));
            }
            clearance = measured;
        }
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

    /// Adds `solution` to [`Self::misses`] when it misses the pose and is among the
    /// [`toward::STARTS`] closest distinct misses so far.
    fn keep_miss(&mut self, solution: &IkSolution) {
        if solution.pose_reached || self.misses.iter().any(|m| self.same_configuration(&m.q, &solution.q)) {
            return;
        }
        let at = self.misses.partition_point(|m| rank(&m.error) <= rank(&solution.error));
        if at < toward::STARTS {
            self.misses.insert(at, solution.clone());
            self.misses.truncate(toward::STARTS);
        }
    }

    /// The solver's settings.
    pub fn options(&self) -> &IkOptions {
        &self.opts
    }

    /// The caller's starts for goal `goal_index` ([`IkOptions::goal_starts`]) that fit the model.
    fn given_starts(&self, goal_index: usize) -> Vec<Vec<f64>> {
        self.opts
            .goal_starts
            .get(goal_index)
            .map(|starts| {
                starts
                    .iter()
                    .filter(|q| q.len() == self.model.dof() && q.iter().all(|x| x.is_finite()))
                    .cloned()
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Whether two configurations are the same solution: every joint within the tolerance,
    /// revolute angles compared modulo 2 pi.
    pub fn same_configuration(&self, a: &[f64], b: &[f64]) -> bool {
        self.model
            .joints
            .iter()
            .zip(a.iter().zip(b))
            .all(|(joint, (x, y))| joint_difference(joint, *x, *y).abs() <= self.opts.distinct_tolerance)
    }
}

/// `a - b` for a joint: revolute angles the shortest way round (modulo 2 pi).
fn joint_difference(joint: &crate::model::Joint, a: f64, b: f64) -> f64 {
    if joint.kind == crate::model::JointKind::Prismatic {
        a - b
    } else {
        wrap_angle(a - b)
    }
}

/// Puts a solution the joint-space search led to first; one within the pose's tolerance
/// replaces the closest miss kept when nothing reached the pose.
fn add_found(result: &mut GoalSolutions, solution: IkSolution) {
    if solution.pose_reached {
        result.solutions.retain(|s| s.pose_reached);
    }
    result.solutions.insert(0, solution);
}

/// Collision queries at most that one goal's joint-space searches make (about 15 us each among
/// primitives, with exact depths): the searches' boxes cost a microsecond, so without a cap a
/// goal whose configurations within the tolerance collide but are not certified would cost
/// seconds.
const COLLISION_QUERIES: usize = 20_000;
/// The same with mesh links: an exact depth between meshes costs up to 5 ms (the Panda's),
/// 20 000 of them 100 s a goal.
const MESH_COLLISION_QUERIES: usize = 200;

/// [`cell_parts`] with mesh links.
const MESH_CELL_PARTS: usize = 256;

/// Takes one of the collision queries `left`; false when none is.
fn take_query(left: &mut usize) -> bool {
    let Some(fewer) = left.checked_sub(1) else {
        return false;
    };
    *left = fewer;
    true
}

fn has_meshes(model: &Model) -> bool {
    model
        .links
        .iter()
        .any(|link| link.colliders.iter().any(|c| matches!(c.shape, crate::model::Shape::Mesh(_))))
}

fn collision_queries(model: &Model) -> usize {
    if has_meshes(model) {
        MESH_COLLISION_QUERIES
    } else {
        COLLISION_QUERIES
    }
}

/// Parts of tolerances a goal may cut ([`cells`]; each part is one exact collision query):
/// with mesh links, about as many as the other stages' queries ([`MESH_COLLISION_QUERIES`]).
/// Measured: ROS-Industrial's Fanuc M-20iB/25 (meshes of 400 to 3 800 triangles, a forearm
/// 28 mm deep in its upper arm at most poses) took 57 s on cluttered task 00 with 8 192, one
/// goal left undecided either way.
fn cell_parts(model: &Model) -> usize {
    if has_meshes(model) {
        MESH_CELL_PARTS
    } else {
        cells::PARTS_PER_GOAL
    }
}

/// The joint-space search's oracle for one goal: local solves by the numeric solver, and with a
/// collision world, free centres and boxes certified in collision.
struct SearchOracle<'s, 'a> {
    model: &'a Model,
    goal: &'s Goal,
    solver: &'s mut Solver<'a>,
    checker: Option<&'s mut Checker<'a>>,
    bounds: &'s MotionBounds,
    margin: f64,
    rng: &'s mut rand_chacha::ChaCha8Rng,
    /// Collision queries left to the goal's searches (see [`COLLISION_QUERIES`]).
    queries: &'s mut usize,
}

impl search::Oracle for SearchOracle<'_, '_> {
    fn local(&mut self, q: &mut [f64]) -> bool {
        if !search::solve_locally(self.model, self.solver, self.goal, q, self.rng) {
            return false;
        }
        let Some(checker) = self.checker.as_mut() else {
            return true;
        };
        if !take_query(self.queries) {
            return false;
        }
        // The sign of the exact clearance decides; the depth is not needed.
        checker.clearance(q, false).exact_m > self.margin
    }

    fn clear(&mut self, centre: &[f64], half: &[f64]) -> search::Clear {
        let Some(checker) = self.checker.as_mut() else {
            return search::Clear::Free;
        };
        if !take_query(self.queries) {
            return search::Clear::Unknown;
        }
        let clearance = checker.clearance(centre, true).exact_m;
        judge_box(checker, self.bounds, self.model.links.len(), half, clearance, self.margin)
    }

    fn collisions(&self) -> bool {
        self.checker.is_some()
    }
}

/// A box of half-widths `half` (joint by joint) whose centre has `clearance` (the checker's
/// last query) against collisions. Free at the centre: free throughout when no two bodies can
/// approach by the room it keeps beyond the margin (each link moves by at most its bound
/// against the world, a pair of links by at most both). In collision: throughout when the
/// closest pair's overlap is deeper than its bodies can move apart within the box.
fn judge_box(checker: &Checker, bounds: &MotionBounds, links: usize, half: &[f64], clearance: f64, margin: f64) -> search::Clear {
    if clearance > margin {
        let farthest = (1..links)
            .map(|link| bounds.relative_motion(crate::collide::Body::Link(link), crate::collide::Body::Floor, half))
            .fold(0.0, f64::max);
        return if 2.0 * farthest < clearance - margin {
            search::Clear::FreeThroughout
        } else {
            search::Clear::Free
        };
    }
    let Some(pair) = checker.closest_pair() else {
        return search::Clear::Unknown;
    };
    let motion = bounds.relative_motion(pair.bodies[0], pair.bodies[1], half);
    if clearance + motion <= margin {
        search::Clear::Colliding
    } else {
        search::Clear::Unknown
    }
}

/// The oracle of a sub-chain's search ([`reduce`]): local solves toward the sub-chain's own
/// goal, and with a collision world the pairs among the links it moves.
struct SubChainOracle<'s, 'a> {
    model: &'s Model,
    solver: Solver<'s>,
    reduced: &'s reduce::Reduced,
    rng: rand_chacha::ChaCha8Rng,
    checker: Option<&'s mut Checker<'a>>,
    levels: Vec<Option<f64>>,
    bounds: &'s MotionBounds,
    margin: f64,
    queries: &'s mut usize,
    /// A whole configuration of the arm: the sub-chain's joints in front, the others at zero
    /// (they move no link the pairs hold).
    q: Vec<f64>,
}

impl search::Oracle for SubChainOracle<'_, '_> {
    /// A free configuration of the sub-chain within its goal's radii ends its search: what it
    /// shows is that the sub-chain proves nothing.
    fn local(&mut self, q: &mut [f64]) -> bool {
        let goal = &self.reduced.goal;
        self.solver.solve(goal, q, search::LOCAL_ITERATIONS, CONVERGED, &mut self.rng);
        if !self.reduced.radii.holds(&goal_error(goal, &self.model.tool_pose(q))) {
            return false;
        }
        let Some(checker) = self.checker.as_mut() else {
            return true;
        };
        if !take_query(self.queries) {
            return false;
        }
        self.q[..q.len()].copy_from_slice(q);
        checker.clearance_among(&self.q, &self.levels, false) > self.margin
    }

    fn clear(&mut self, centre: &[f64], half: &[f64]) -> search::Clear {
        let Some(checker) = self.checker.as_mut() else {
            return search::Clear::Free;
        };
        if !take_query(self.queries) {
            return search::Clear::Unknown;
        }
        self.q[..centre.len()].copy_from_slice(centre);
        let clearance = checker.clearance_among(&self.q, &self.levels, true);
        judge_box(checker, self.bounds, self.model.links.len(), half, clearance, self.margin)
    }

    fn collisions(&self) -> bool {
        self.checker.is_some()
    }
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

/// How far (rad or m) past a joint limit a value counts as at it: rounding (an angle wrapped
/// into (-pi, pi] and back, 2.2e-16 rad off), not a configuration outside the limits.
pub(super) const LIMIT_ROUNDING: f64 = 1e-12;

/// A configuration within the tolerance further than this (rad, every joint) from each exact
/// solution is on another branch.
const OFF_BRANCH_RAD: f64 = 0.1;

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

/// [`wrap_angle`] without its remainder for an angle already in (-pi, pi] (an `atan2`'s, a
/// difference of two wrapped angles within half a turn): the closed forms' hot path. The same
/// value for those, up to the remainder's rounding.
pub(crate) fn wrapped(angle: f64) -> f64 {
    if angle > -std::f64::consts::PI && angle <= std::f64::consts::PI {
        angle
    } else {
        wrap_angle(angle)
    }
}

/// Why a proof within the harness's tolerance does not decide `goal`, if it does not: the goal's
/// own (task) tolerance accepts poses further away.
pub fn task_tolerance_gap(goal: &Goal) -> Option<String> {
    let task = goal.task.as_ref()?;
    task.proof_gap(REACHED_POSITION_M, REACHED_ORIENTATION_RAD, goal.tolerance != Tolerance::Position)
}

/// Holds IK's answer for `goal` to the goal's own tolerance, where it has one: a solution outside
/// it reaches nothing, and a proof within the harness's tolerance that does not cover it gives
/// way to one that does (the goal further beyond reach than the task accepts) or leaves the goal
/// undecided.
fn judge_task_tolerance(model: &Model, goal: &Goal, result: &mut GoalSolutions) {
    let Some(task) = &goal.task else { return };
    let judged = goal.tolerance != Tolerance::Position;
    for solution in &mut result.solutions {
        if solution.pose_reached && !task.accepts(solution.error.position_m, solution.error.orientation_rad, judged) {
            solution.pose_reached = false;
            solution.reached = false;
        }
    }
    // Reached ones first, as everywhere else.
    result.solutions.sort_by_key(|s| !s.reached);
    if result.proof.is_some() {
        if let Some(gap) = task_tolerance_gap(goal) {
            result.proof = task_beyond_reach(model, goal);
            if result.proof.is_none() {
                result.undecided = Some(gap);
            }
        }
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
    solve_goals_counted(model, scenario, world, opts, &|| true)
}

/// [`solve_goals`], calling `done` after each goal (from the thread that solved it), for a
/// progress count; when it answers `false` the goals not yet started are left unsolved (no
/// solution, not complete): the caller is stopping the run and discards them.
pub fn solve_goals_counted(
    model: &Model,
    scenario: &Scenario,
    world: Option<&CollisionWorld>,
    opts: &IkOptions,
    done: &(dyn Fn() -> bool + Sync),
) -> Vec<GoalSolutions> {
    use rayon::prelude::*;
    // Each goal's starts are seeded by its index alone, so goals solve independently, on any
    // number of threads, with the same result.
    // The methods are detected once; each thread's solver gets a copy.
    let methods = Methods::of(model);
    let everywhere = std::sync::OnceLock::new();
    let make = || Ik::build(model, world, opts.clone(), &methods, Everywhere::Shared(&everywhere));
    let stop = std::sync::atomic::AtomicBool::new(false);
    scenario
        .goals
        .par_iter()
        .enumerate()
        .map_init(make, |ik, (index, goal)| {
            if stop.load(std::sync::atomic::Ordering::Relaxed) {
                return GoalSolutions {
                    solutions: Vec::new(),
                    starts: 0,
                    iterations: 0,
                    complete: false,
                    proof: None,
                    undecided: None,
                };
            }
            let found = ik.solve(goal, index, None);
            if !done() {
                stop.store(true, std::sync::atomic::Ordering::Relaxed);
            }
            found
        })
        .collect()
}
