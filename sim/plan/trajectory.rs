//! The trajectory through a course: the paper's real-world heuristic, done thoroughly.
//!
//! From the home configuration, for each goal in course order: among the goal's collision-free
//! IK solutions (each revolute angle moved by whole turns to the equivalent nearest the previous
//! configuration, within its limits), the nearest in joint space whose straight segment from the
//! previous configuration is certified free; else the others in order of distance; else IK
//! solved again from the previous configuration, and its solutions tried the same way. A goal no
//! solution connects is blocked (with the pair and configuration that stop the nearest
//! solution's segment), and the trajectory goes on from the last reached configuration.

use super::certify::{CertifyOptions, SegmentCheck, SegmentChecker, SegmentPoint};
use super::planner::{distance, polyline_length, Planner, PlannerKind, PlannerOptions, Straight};
use super::rrt::RrtConnect;
use super::timing::{TimedPath, TimingLimits};
use crate::collide::CollisionWorld;
use crate::ik::{GoalSolutions, Ik, IkOptions, IkSolution};
use crate::model::{JointKind, Model};
use crate::scenario::{Goal, Scenario};
use serde::Serialize;
use std::f64::consts::TAU;

/// Configurations tried for a collision-free home when the default one collides.
const HOME_SAMPLES: usize = 1000;
/// Clearance a replacement home keeps beyond the threshold (m), so the tour does not start grazing.
const HOME_CLEARANCE_M: f64 = 0.01;

/// Tool positions sampled per segment to measure the tool path length.
const TOOL_PATH_SAMPLES: usize = 64;

/// Why a trajectory cannot be planned at all.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// The caller stopped the planning (see [`plan_counted`]).
    #[error("stopped before the planning finished")]
    Stopped,
    /// The scenario's `home` does not fit the model.
    #[error("scenario {scenario}: `home` has {found} values, the robot has {dof} joints")]
    HomeLength {
        /// Scenario name.
        scenario: String,
        /// Values given.
        found: usize,
        /// Joints of the model.
        dof: usize,
    },
    /// The scenario's `home` is outside a joint's limits.
    #[error("scenario {scenario}: `home[{index}]` = {value} is outside joint `{joint}`'s limits [{lower}, {upper}]")]
    HomeOutsideLimits {
        /// Scenario name.
        scenario: String,
        /// Joint index.
        index: usize,
        /// Joint name.
        joint: String,
        /// The value given.
        value: f64,
        /// Lower limit.
        lower: f64,
        /// Upper limit.
        upper: f64,
    },
}

/// Settings of the planner.
#[derive(Debug, Clone, Default)]
pub struct TrajectoryOptions {
    /// The continuous check's threshold.
    pub certify: CertifyOptions,
    /// IK settings for re-solving from the previous configuration.
    pub ik: IkOptions,
    /// Timing limits; `None`: [`TimingLimits::of`] the model.
    pub timing: Option<TimingLimits>,
    /// Which planner joins the goals, its budget and seed.
    pub planner: PlannerOptions,
}

/// How one goal went.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum GoalStep {
    /// Reached by a certified path.
    Reached {
        /// Goal index.
        goal: usize,
        /// The configuration chosen.
        q: Vec<f64>,
        /// Which goal configuration it was, in the order tried (0: the nearest solution).
        candidate: usize,
        /// Found by solving IK again from the previous configuration.
        resolved: bool,
        /// The path's configurations after the previous one, ending at `q`.
        waypoints: Vec<Vec<f64>>,
        /// The certified check of each edge of the path, `segments[i]` ending at `waypoints[i]`.
        segments: Vec<SegmentCheck>,
        /// Joint-space length of the path before shortcutting.
        length_before_shortcut: f64,
        /// Random samples the planner drew (0: a straight segment).
        samples: usize,
        /// Exact clearance of `q` and the pair that sets it.
        clearance: Option<SegmentPoint>,
    },
    /// IK found no collision-free configuration reaching the goal.
    Unreachable {
        /// Goal index.
        goal: usize,
        /// IK starts per solve (the scenario's solve and the re-solve from the previous
        /// configuration each used this many).
        starts: usize,
        /// Seed of IK's random starts.
        seed: u64,
    },
    /// Collision-free configurations exist; no certified path to any was found.
    NoPath {
        /// Goal index.
        goal: usize,
        /// Collision-free goal configurations searched for (IK solutions and their whole-turn
        /// equivalents).
        tried: usize,
        /// The planner's sample budget.
        budget: usize,
        /// Samples drawn.
        samples: usize,
        /// Where the closest attempt stopped: the pair and the configuration.
        stop: Option<SegmentPoint>,
        /// Joint-space distance from the search's nearest configuration to the goal set.
        gap: Option<f64>,
        /// The straight segment to the nearest solution, from the previous configuration: the
        /// motion the paper's heuristic would have made. The engines replay it too. Boxed: a
        /// step that reached its goal need not be as large.
        attempt: Option<Box<Attempt>>,
    },
}

impl GoalStep {
    /// The goal's index.
    pub fn goal(&self) -> usize {
        match self {
            GoalStep::Reached { goal, .. } | GoalStep::Unreachable { goal, .. } | GoalStep::NoPath { goal, .. } => *goal,
        }
    }

    /// The outcome's name: `reached`, `unreachable` or `no_path`.
    pub fn outcome(&self) -> &'static str {
        match self {
            GoalStep::Reached { .. } => "reached",
            GoalStep::Unreachable { .. } => "unreachable",
            GoalStep::NoPath { .. } => "no_path",
        }
    }

    /// The tried segment that is not free, for a goal not reached.
    pub fn attempt(&self) -> Option<&Attempt> {
        match self {
            GoalStep::Reached { .. } | GoalStep::Unreachable { .. } => None,
            GoalStep::NoPath { attempt, .. } => attempt.as_deref(),
        }
    }
}

/// A segment that was tried and is not free.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Attempt {
    /// Start configuration (the previous reached one).
    pub from: Vec<f64>,
    /// The solution it heads for.
    pub to: Vec<f64>,
    /// Its continuous check.
    pub segment: SegmentCheck,
}

/// The planned trajectory.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trajectory {
    /// The planner that joined the goals.
    pub planner: PlannerOptions,
    /// Start configuration.
    pub home: Vec<f64>,
    /// Clearance at home and its closest pair (a home in collision is a finding).
    pub home_clearance: Option<SegmentPoint>,
    /// Why the scenario's home or the default home was not used, when it was not.
    pub home_replaced: Option<String>,
    /// One step per goal, course order.
    pub steps: Vec<GoalStep>,
    /// Joint-space length of the motion (rad and m summed as numbers).
    pub joint_length: f64,
    /// Joint-space length the planner found before shortcutting.
    pub joint_length_before_shortcut: f64,
    /// Length of the tool's path (m), measured on 64 points per edge.
    pub tool_path_m: f64,
    /// The timed reference through the reached goals.
    pub timed: TimedPath,
}

impl Trajectory {
    /// Goals reached by a certified path.
    pub fn reached(&self) -> usize {
        self.steps.iter().filter(|s| matches!(s, GoalStep::Reached { .. })).count()
    }

    /// Goals with the given outcome (`reached`, `unreachable`, `no_path`).
    pub fn count(&self, outcome: &str) -> usize {
        self.steps.iter().filter(|s| s.outcome() == outcome).count()
    }
}

/// The design's own home: zero for each joint, or the middle of its range where zero is outside
/// the limits.
pub fn default_home(model: &Model) -> Vec<f64> {
    model
        .joints
        .iter()
        .map(|j| match j.limits {
            Some([lo, hi]) if !(lo..=hi).contains(&0.0) => 0.5 * (lo + hi),
            _ => 0.0,
        })
        .collect()
}

/// The home configuration: the scenario's, else [`default_home`]. A scenario home that does not
/// fit the robot (written for another robot, e.g. the course's for the 5-joint paper robot) is
/// replaced by the default home, and the reason returned: a scenario serves every design.
pub fn home_for(model: &Model, scenario: &Scenario) -> (Vec<f64>, Option<PlanError>) {
    match home_configuration(model, scenario) {
        Ok(home) => (home, None),
        Err(reason) => (default_home(model), Some(reason)),
    }
}

/// The home configuration: the scenario's, else [`default_home`].
///
/// # Errors
/// [`PlanError`] when the scenario's home has the wrong length or leaves a joint's limits.
pub fn home_configuration(model: &Model, scenario: &Scenario) -> Result<Vec<f64>, PlanError> {
    let Some(home) = &scenario.home else {
        return Ok(default_home(model));
    };
    if home.len() != model.dof() {
        return Err(PlanError::HomeLength {
            scenario: scenario.name.clone(),
            found: home.len(),
            dof: model.dof(),
        });
    }
    for (index, (joint, value)) in model.joints.iter().zip(home).enumerate() {
        if let Some([lower, upper]) = joint.limits {
            if !(lower..=upper).contains(value) {
                return Err(PlanError::HomeOutsideLimits {
                    scenario: scenario.name.clone(),
                    index,
                    joint: joint.name.clone(),
                    value: *value,
                    lower,
                    upper,
                });
            }
        }
    }
    Ok(home.clone())
}

/// `q` with each revolute angle moved by whole turns to the equivalent nearest `near`, staying
/// within its limits (an angle with no equivalent inside the limits nearer than itself stays).
pub fn nearest_equivalent(model: &Model, q: &[f64], near: &[f64]) -> Vec<f64> {
    model
        .joints
        .iter()
        .zip(q.iter().zip(near))
        .map(|(joint, (&x, &n))| {
            if joint.kind == JointKind::Prismatic {
                return x;
            }
            let turns = ((n - x) / TAU).round();
            let inside = |v: f64| joint.limits.is_none_or(|[lo, hi]| (lo..=hi).contains(&v));
            // The nearest whole-turn shift inside the limits: the nearest, its neighbours, or none
            // (zero turns written as `x` itself, so an unshifted angle keeps its bits).
            [turns, turns - 1.0, turns + 1.0, 0.0]
                .into_iter()
                .map(|k| if k == 0.0 { x } else { x + k * TAU })
                .filter(|v| inside(*v))
                .min_by(|a, b| (a - n).abs().total_cmp(&(b - n).abs()))
                .unwrap_or(x)
        })
        .collect()
}

/// The configuration nearest `home` in joint space, among [`HOME_SAMPLES`] seeded uniform ones
/// within the limits, that keeps [`HOME_CLEARANCE_M`] beyond the threshold; with its clearance.
fn nearest_free(checker: &mut SegmentChecker, model: &Model, home: &[f64], threshold: f64, seed: u64) -> Option<(Vec<f64>, SegmentPoint)> {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x484f_4d45);
    let mut samples: Vec<Vec<f64>> = (0..HOME_SAMPLES).map(|_| model.random_configuration(&mut rng)).collect();
    samples.sort_by(|a, b| distance(a, home).total_cmp(&distance(b, home)));
    samples.into_iter().find_map(|q| {
        let clearance = checker.clearance(&q)?;
        (clearance.distance_m > threshold + HOME_CLEARANCE_M).then_some((q, clearance))
    })
}

/// A collision-free IK solution to start a tour from: the first, in goal order, that keeps the
/// clearance a replacement home keeps, else the clearest that is free of the threshold.
fn first_free_solution(
    checker: &mut SegmentChecker,
    solutions: &[GoalSolutions],
    threshold: f64,
) -> Option<(usize, Vec<f64>, SegmentPoint)> {
    let mut clearest: Option<(usize, Vec<f64>, SegmentPoint)> = None;
    for (goal, found) in solutions.iter().enumerate() {
        for solution in found.solutions.iter().filter(|s| s.reached) {
            let q = solution.q.clone();
            let Some(clearance) = checker.clearance(&q) else { continue };
            if clearance.distance_m > threshold + HOME_CLEARANCE_M {
                return Some((goal, q, clearance));
            }
            let free = clearance.distance_m > threshold + super::certify::TOUCH_TOLERANCE_M;
            if free && clearest.as_ref().is_none_or(|(_, _, c)| clearance.distance_m > c.distance_m) {
                clearest = Some((goal, q, clearance));
            }
        }
    }
    clearest
}

/// Most whole-turn equivalents of one solution put in a goal set (the nearest the start kept).
const MAX_EQUIVALENTS: usize = 64;

/// `q` and its whole-turn equivalents: each revolute angle moved by whole turns within its
/// limits (a joint without limits by the one shift nearest `near`), the nearest `near` first, at
/// most 64.
pub fn whole_turn_equivalents(model: &Model, q: &[f64], near: &[f64]) -> Vec<Vec<f64>> {
    let nearest = nearest_equivalent(model, q, near);
    let options: Vec<Vec<f64>> = model
        .joints
        .iter()
        .zip(&nearest)
        .map(|(joint, &x)| match (joint.kind, joint.limits) {
            (JointKind::Prismatic, _) | (_, None) => vec![x],
            (_, Some([lo, hi])) => {
                let below = ((x - lo) / TAU).floor() as i64;
                let above = ((hi - x) / TAU).floor() as i64;
                // Zero turns written as `x` itself, so the nearest equivalent keeps its bits.
                (-below.min(4)..=above.min(4))
                    .map(|k| if k == 0 { x } else { x + k as f64 * TAU })
                    .filter(|v| (lo..=hi).contains(v))
                    .collect()
            }
        })
        .collect();
    let mut all = vec![Vec::with_capacity(q.len())];
    for choices in &options {
        let mut next = Vec::with_capacity(all.len() * choices.len());
        for partial in &all {
            for &v in choices {
                let mut grown = partial.clone();
                grown.push(v);
                next.push(grown);
            }
        }
        all = next;
        if all.len() > 4096 {
            break;
        }
    }
    all.retain(|c| c.len() == q.len());
    if all.is_empty() {
        return vec![nearest];
    }
    all.sort_by(|a, b| distance(a, near).total_cmp(&distance(b, near)));
    all.truncate(MAX_EQUIVALENTS);
    all
}

/// Plans the trajectory of `model` (placed) through `scenario` from its home, with the goals'
/// IK `solutions` (scenario order, as [`crate::ik::solve_goals`] gives them) and the same `world`.
///
/// # Errors
/// None today (a scenario home that does not fit is replaced, see [`home_for`]); the `Result`
/// keeps room for inputs the planner cannot use.
pub fn plan(
    model: &Model,
    scenario: &Scenario,
    world: &CollisionWorld,
    solutions: &[GoalSolutions],
    opts: &TrajectoryOptions,
) -> Result<Trajectory, PlanError> {
    plan_counted(model, scenario, world, solutions, opts, &|| {}, &|| false)
}

/// [`plan`], calling `done` after each goal is joined (or given up), for a progress count, and
/// stopping (between goals, or within a goal's sampling) once `stopped` answers `true`.
///
/// # Errors
/// As [`plan`], and [`PlanError::Stopped`] when it stopped.
pub fn plan_counted(
    model: &Model,
    scenario: &Scenario,
    world: &CollisionWorld,
    solutions: &[GoalSolutions],
    opts: &TrajectoryOptions,
    done: &dyn Fn(),
    stopped: &dyn Fn() -> bool,
) -> Result<Trajectory, PlanError> {
    let (mut home, replaced) = home_for(model, scenario);
    let mut home_replaced = replaced.map(|reason| reason.to_string());
    let mut checker = SegmentChecker::new(model, world, opts.certify).with_stop(stopped);
    let mut home_clearance = checker.clearance(&home);
    let threshold = opts.certify.threshold_m;
    // A default home in collision (zero folds many modular arms onto themselves) would block every
    // goal: start from the nearest collision-free configuration instead, and say so. A home the
    // scenario gives is the user's and stays, colliding or not.
    let default_used = scenario.home.is_none() || home_replaced.is_some();
    if default_used
        && home_clearance
            .as_ref()
            .is_some_and(|c| c.distance_m <= threshold + super::certify::TOUCH_TOLERANCE_M)
    {
        // Under a margin a home can be clear of contact yet too close: say which it is.
        let (state, pair) = home_clearance.as_ref().map_or(("is in collision", String::new()), |c| {
            let touching = c.distance_m <= super::certify::TOUCH_TOLERANCE_M;
            let state = if touching {
                "is in collision"
            } else {
                "keeps less than the margin"
            };
            (state, format!(" ({} and {} at {:+.1} mm)", c.a, c.b, c.distance_m * 1e3))
        });
        let earlier = home_replaced.take().map(|reason| format!("{reason}; ")).unwrap_or_default();
        let margin = if threshold > 0.0 {
            format!(" (margin {:.1} mm)", threshold * 1e3)
        } else {
            String::new()
        };
        let default = format!("{earlier}the default home {home:?} {state}{margin}{pair}");
        if let Some((free, clearance)) = nearest_free(&mut checker, model, &home, threshold, opts.ik.seed) {
            home_replaced = Some(format!(
                "{default}; started from the nearest collision-free of {HOME_SAMPLES} seeded configurations"
            ));
            home = free;
            home_clearance = Some(clearance);
        } else if let Some((goal, q, clearance)) = first_free_solution(&mut checker, solutions, threshold) {
            // The home is ours to choose, not the design's: a tour that starts in collision
            // would fail every goal for the harness's choice. Start where the first goal with a
            // collision-free solution is reached instead.
            home_replaced = Some(format!(
                "{default}, and none of {HOME_SAMPLES} seeded configurations is free; started from goal {goal}'s first collision-free IK solution"
            ));
            home = q;
            home_clearance = Some(clearance);
        } else {
            home_replaced = Some(default);
        }
    }
    let mut ik = Ik::with_collisions(model, world, opts.ik.clone());
    let mut planner = goal_planner(model, &opts.planner);
    let mut previous = home.clone();
    let mut steps = Vec::with_capacity(scenario.goals.len());
    let mut waypoints = vec![home.clone()];
    let mut goals = Vec::new();
    let mut length_before_shortcut = 0.0;
    for (index, goal) in scenario.goals.iter().enumerate() {
        let given = solutions.get(index).map(|s| s.solutions.as_slice()).unwrap_or_default();
        let stream = opts.planner.seed ^ (index as u64 + 1).wrapping_mul(0xA076_1D64_78BD_642F);
        let request = Request {
            goal,
            index,
            given,
            previous: &previous,
            stream,
        };
        let step = planner.step(&mut ik, &mut checker, model, &request);
        done();
        if stopped() {
            return Err(PlanError::Stopped);
        }
        let mut step = step;
        if let GoalStep::Reached { q, clearance, .. } = &mut step {
            *clearance = checker.clearance(q);
        }
        if let GoalStep::Reached {
            q,
            waypoints: path,
            length_before_shortcut: before,
            ..
        } = &step
        {
            length_before_shortcut += before;
            for (k, w) in path.iter().enumerate() {
                waypoints.push(w.clone());
                goals.push((k + 1 == path.len()).then_some(index));
            }
            previous.clone_from(q);
        }
        steps.push(step);
    }
    let limits = opts.timing.clone().unwrap_or_else(|| TimingLimits::of(model));
    let timed = TimedPath::through(&waypoints, &goals, &limits);
    let joint_length = polyline_length(&waypoints[0], &waypoints[1..]);
    let tool_path_m = tool_path_length(model, &waypoints);
    Ok(Trajectory {
        planner: opts.planner,
        home,
        home_clearance,
        home_replaced,
        steps,
        joint_length,
        joint_length_before_shortcut: length_before_shortcut,
        tool_path_m,
        timed,
    })
}

/// The collision-free solutions IK found, as configurations nearest `previous` (whole turns),
/// not already in `tried`, nearest first.
fn free_candidates(ik: &Ik<'_>, model: &Model, found: &[IkSolution], previous: &[f64], tried: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut candidates: Vec<Vec<f64>> = found
        .iter()
        .filter(|s| s.reached)
        .map(|s| nearest_equivalent(model, &s.q, previous))
        .filter(|q| !tried.iter().any(|t| ik.same_configuration(t, q)))
        .collect();
    candidates.sort_by(|a, b| distance(a, previous).total_cmp(&distance(b, previous)));
    candidates
}

/// One goal to join: where the arm is, the goal, and the solutions IK gave it.
struct Request<'r> {
    goal: &'r Goal,
    index: usize,
    /// The goal's solutions from the IK stage.
    given: &'r [IkSolution],
    /// The configuration the arm is in.
    previous: &'r [f64],
    /// Seeds this goal's random choices.
    stream: u64,
}

/// How a planner joins the arm's configuration to one goal: which configurations it aims at,
/// and the path it certifies there (see [`super::planner::Planner`]).
trait GoalPlanner {
    fn step(&mut self, ik: &mut Ik<'_>, checker: &mut SegmentChecker<'_>, model: &Model, request: &Request<'_>) -> GoalStep;
}

/// The planner [`PlannerOptions::kind`] names, with its budget.
fn goal_planner(model: &Model, opts: &super::PlannerOptions) -> Box<dyn GoalPlanner> {
    match opts.kind {
        PlannerKind::Straight => Box::new(Straight),
        PlannerKind::RrtConnect => Box::new(RrtConnect {
            limits: model.joints.iter().map(|j| j.limits).collect(),
            budget: opts.budget,
            straight_attempts: 0,
        }),
    }
}

/// The paper's heuristic: among the goal's solutions, the nearest one a straight certified
/// segment reaches; else IK solved again from the previous configuration, and the same.
impl GoalPlanner for Straight {
    fn step(&mut self, ik: &mut Ik<'_>, checker: &mut SegmentChecker<'_>, model: &Model, request: &Request<'_>) -> GoalStep {
        let Request {
            goal,
            index,
            given,
            previous,
            stream,
        } = *request;
        let mut tried: Vec<Vec<f64>> = Vec::new();
        let mut failure = None;
        let mut fresh = None;
        for resolved in [false, true] {
            if resolved {
                fresh = Some(ik.solve(goal, index, Some(previous)));
            }
            let found = fresh.as_ref().map_or(given, |f| f.solutions.as_slice());
            let candidates = free_candidates(ik, model, found, previous, &tried);
            let offset = tried.len();
            tried.extend(candidates.iter().cloned());
            match self.connect(checker, previous, &candidates, stream) {
                Ok(path) => return reached(index, path, offset, resolved),
                Err(f) if failure.is_none() && !candidates.is_empty() => failure = Some((f, candidates[0].clone())),
                Err(_) => {}
            }
        }
        not_reached(checker, ik, index, tried.len(), 0, previous, failure)
    }
}

/// The default: straight segments to the goal set, then the sampling planner towards every
/// collision-free solution (the scenario's and those of IK solved again from the previous
/// configuration) and their whole-turn equivalents.
impl GoalPlanner for RrtConnect {
    fn step(&mut self, ik: &mut Ik<'_>, checker: &mut SegmentChecker<'_>, model: &Model, request: &Request<'_>) -> GoalStep {
        let Request {
            goal,
            index,
            given,
            previous,
            stream,
        } = *request;
        let mut candidates = free_candidates(ik, model, given, previous, &[]);
        // The scenario's solutions come first in the goal set, so a straight segment with room
        // to one of them is the answer whatever IK solved again would add: it is tried before
        // that (costly) solve, with the same result.
        let tried = match super::rrt::straight_with_room(checker, previous, &candidates) {
            Ok(path) => return reached(index, path, 0, false),
            Err(tried) => tried,
        };
        let fresh = ik.solve(goal, index, Some(previous));
        let from_given = candidates.len();
        candidates.extend(free_candidates(ik, model, &fresh.solutions, previous, &candidates));
        if candidates.is_empty() {
            return not_reached(checker, ik, index, 0, 0, previous, None);
        }
        // The goal set: each candidate (nearest first) and then every whole-turn equivalent.
        let mut goal_set = candidates.clone();
        for candidate in &candidates {
            goal_set.extend(
                whole_turn_equivalents(model, candidate, previous)
                    .into_iter()
                    .filter(|e| e != candidate),
            );
        }
        self.straight_attempts = candidates.len();
        // The straight segments to the scenario's solutions (the goal set's first) are not
        // checked again.
        let tried = (from_given > 0).then_some((from_given, tried));
        match self.connect_after(checker, previous, &goal_set, stream, tried) {
            Ok(path) => {
                // Which solution the reached configuration came from.
                let origin = if path.target < candidates.len() {
                    path.target
                } else {
                    candidates
                        .iter()
                        .position(|c| ik.same_configuration(c, &goal_set[path.target]))
                        .unwrap_or(0)
                };
                reached(index, path, 0, origin >= from_given)
            }
            Err(failure) => {
                let first = candidates[0].clone();
                not_reached(checker, ik, index, goal_set.len(), self.budget, previous, Some((failure, first)))
            }
        }
    }
}

fn reached(index: usize, path: super::planner::Path, offset: usize, resolved: bool) -> GoalStep {
    GoalStep::Reached {
        goal: index,
        q: path.waypoints.last().cloned().unwrap_or_default(),
        candidate: offset + path.target,
        resolved,
        waypoints: path.waypoints,
        segments: path.segments,
        length_before_shortcut: path.length_before_shortcut,
        samples: path.samples,
        clearance: None,
    }
}

/// A goal not reached: `unreachable` when no collision-free solution was found, else `no_path`
/// with the failure and the straight attempt to the nearest solution (for the engines' replay).
fn not_reached(
    checker: &mut SegmentChecker<'_>,
    ik: &Ik<'_>,
    index: usize,
    tried: usize,
    budget: usize,
    previous: &[f64],
    failure: Option<(super::planner::Failure, Vec<f64>)>,
) -> GoalStep {
    match failure {
        None => GoalStep::Unreachable {
            goal: index,
            starts: ik.options().seeds,
            seed: ik.options().seed,
        },
        Some((failure, nearest)) => GoalStep::NoPath {
            goal: index,
            tried,
            budget,
            samples: failure.samples,
            stop: failure.stop,
            gap: failure.gap,
            attempt: Some(Box::new(Attempt {
                from: previous.to_vec(),
                segment: checker.check(previous, &nearest),
                to: nearest,
            })),
        },
    }
}

fn tool_path_length(model: &Model, waypoints: &[Vec<f64>]) -> f64 {
    let mut length = 0.0;
    let mut q = vec![0.0; model.dof()];
    for pair in waypoints.windows(2) {
        let mut last = model.tool_pose(&pair[0]).translation.vector;
        for i in 1..=TOOL_PATH_SAMPLES {
            let s = i as f64 / TOOL_PATH_SAMPLES as f64;
            for (x, (a, b)) in q.iter_mut().zip(pair[0].iter().zip(&pair[1])) {
                *x = a + s * (b - a);
            }
            let here = model.tool_pose(&q).translation.vector;
            length += (here - last).norm();
            last = here;
        }
    }
    length
}
