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
use super::timing::{TimedPath, TimingLimits};
use crate::collide::CollisionWorld;
use crate::ik::{GoalSolutions, Ik, IkOptions};
use crate::model::{JointKind, Model};
use crate::scenario::Scenario;
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
}

/// How one goal went.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum GoalStep {
    /// Reached by a certified segment.
    Reached {
        /// Goal index.
        goal: usize,
        /// The configuration chosen.
        q: Vec<f64>,
        /// Which candidate it was, nearest first (0: the nearest solution connected).
        candidate: usize,
        /// Found by solving IK again from the previous configuration.
        resolved: bool,
        /// The segment from the previous configuration.
        segment: SegmentCheck,
    },
    /// No solution connects.
    Blocked {
        /// Goal index.
        goal: usize,
        /// Collision-free solutions tried (0: IK found none).
        tried: usize,
        /// Where the nearest solution's segment stops: the pair and the configuration.
        stop: Option<SegmentPoint>,
        /// The nearest solution's segment that was tried, from the previous configuration:
        /// the motion the paper's heuristic would have made. The engines replay it too.
        attempt: Option<Attempt>,
    },
}

impl GoalStep {
    /// The goal's index.
    pub fn goal(&self) -> usize {
        match self {
            GoalStep::Reached { goal, .. } | GoalStep::Blocked { goal, .. } => *goal,
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
    /// Length of the tool's path (m), measured on 64 points per segment.
    pub tool_path_m: f64,
    /// The timed reference through the reached goals.
    pub timed: TimedPath,
}

impl Trajectory {
    /// Goals reached by a certified segment.
    pub fn reached(&self) -> usize {
        self.steps.iter().filter(|s| matches!(s, GoalStep::Reached { .. })).count()
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

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
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
    let (mut home, replaced) = home_for(model, scenario);
    let mut home_replaced = replaced.map(|reason| reason.to_string());
    let mut checker = SegmentChecker::new(model, world, opts.certify);
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
        if let Some((free, clearance)) = nearest_free(&mut checker, model, &home, threshold, opts.ik.seed) {
            let colliding = home_clearance
                .as_ref()
                .map(|c| format!("{} and {} at {:.1} mm", c.a, c.b, c.distance_m * 1e3));
            let earlier = home_replaced.take().map(|reason| format!("{reason}; ")).unwrap_or_default();
            home_replaced = Some(format!(
                "{earlier}the default home {home:?} is in collision ({}); started from the nearest collision-free of {HOME_SAMPLES} seeded configurations",
                colliding.unwrap_or_default()
            ));
            home = free;
            home_clearance = Some(clearance);
        }
    }
    let mut ik = Ik::with_collisions(model, world, opts.ik.clone());
    let mut previous = home.clone();
    let mut steps = Vec::with_capacity(scenario.goals.len());
    let mut waypoints = vec![home.clone()];
    let mut goals = Vec::new();
    for (index, goal) in scenario.goals.iter().enumerate() {
        let mut tried: Vec<Vec<f64>> = Vec::new();
        let mut stop: Option<SegmentPoint> = None;
        let mut attempt: Option<Attempt> = None;
        let mut step = None;
        let given = solutions.get(index).map(|s| s.solutions.as_slice()).unwrap_or_default();
        for resolved in [false, true] {
            let fresh;
            let found = if resolved {
                fresh = ik.solve(goal, index, Some(&previous));
                fresh.solutions.as_slice()
            } else {
                given
            };
            let mut candidates: Vec<Vec<f64>> = found
                .iter()
                .filter(|s| s.reached)
                .map(|s| nearest_equivalent(model, &s.q, &previous))
                .filter(|q| !tried.iter().any(|t| ik.same_configuration(t, q)))
                .collect();
            candidates.sort_by(|a, b| distance(a, &previous).total_cmp(&distance(b, &previous)));
            for q in candidates {
                let segment = checker.check(&previous, &q);
                tried.push(q.clone());
                if segment.free {
                    step = Some(GoalStep::Reached {
                        goal: index,
                        q,
                        candidate: tried.len() - 1,
                        resolved,
                        segment,
                    });
                    break;
                }
                if attempt.is_none() {
                    stop = segment.touch.clone().or(segment.closest.clone());
                    attempt = Some(Attempt {
                        from: previous.clone(),
                        to: q.clone(),
                        segment,
                    });
                }
            }
            if step.is_some() {
                break;
            }
        }
        let step = step.unwrap_or(GoalStep::Blocked {
            goal: index,
            tried: tried.len(),
            stop,
            attempt,
        });
        if let GoalStep::Reached { q, .. } = &step {
            previous.clone_from(q);
            waypoints.push(q.clone());
            goals.push(Some(index));
        }
        steps.push(step);
    }
    let limits = opts.timing.clone().unwrap_or_else(|| TimingLimits::of(model));
    let timed = TimedPath::through(&waypoints, &goals, &limits);
    let joint_length = waypoints.windows(2).map(|w| distance(&w[0], &w[1])).sum();
    let tool_path_m = tool_path_length(model, &waypoints);
    Ok(Trajectory {
        home,
        home_clearance,
        home_replaced,
        steps,
        joint_length,
        tool_path_m,
        timed,
    })
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
