//! The planner seam: how the trajectory joins one configuration to a goal's set of
//! configurations, by edges each certified collision-free (see [`SegmentChecker`]).
//!
//! Two planners: [`PlannerKind::Straight`], the paper's hardware heuristic (one straight
//! joint-space segment to a goal configuration, nearest first), and [`PlannerKind::RrtConnect`],
//! the default: the straight segments first, then a bidirectional RRT-Connect in joint space
//! whose every tree edge is certified by conservative advancement, followed by certified
//! shortcutting (see `rrt.rs`). Whatever the planner, a path it returns is a polyline whose every
//! edge was checked by [`SegmentChecker::check`] as it stands.

use super::certify::{SegmentCheck, SegmentChecker, SegmentPoint};
use serde::Serialize;

/// Samples a sampling-based planner may draw per goal before it gives up (`--plan-budget`).
pub const DEFAULT_PLAN_BUDGET: usize = 20_000;

/// Which planner joins consecutive goals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlannerKind {
    /// One straight joint-space segment to a goal configuration, nearest first: the paper's
    /// heuristic for its real-world robot.
    Straight,
    /// Straight segments first, then bidirectional RRT-Connect with certified edges and
    /// certified shortcutting.
    #[default]
    RrtConnect,
}

impl PlannerKind {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            PlannerKind::Straight => "straight",
            PlannerKind::RrtConnect => "rrt-connect",
        }
    }

    /// Whether it draws random samples within [`PlannerOptions::budget`] (a goal it does not
    /// join is then `no_path` within that budget).
    pub fn samples(self) -> bool {
        match self {
            PlannerKind::Straight => false,
            PlannerKind::RrtConnect => true,
        }
    }
}

impl std::str::FromStr for PlannerKind {
    type Err = String;

    /// A planner by [`PlannerKind::name`]; the error says which names there are.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        [PlannerKind::RrtConnect, PlannerKind::Straight]
            .into_iter()
            .find(|kind| kind.name() == text)
            .ok_or_else(|| format!("unknown planner `{text}`; expected rrt-connect or straight"))
    }
}

/// Settings of the planner.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PlannerOptions {
    /// Which planner (default RRT-Connect).
    pub kind: PlannerKind,
    /// Random samples per goal before a sampling planner gives up (default
    /// [`DEFAULT_PLAN_BUDGET`]); counted, never timed, so the result does not depend on the machine.
    pub budget: usize,
    /// Seed of the planner's random streams (default 0); each goal derives its own.
    pub seed: u64,
}

impl Default for PlannerOptions {
    fn default() -> Self {
        Self {
            kind: PlannerKind::default(),
            budget: DEFAULT_PLAN_BUDGET,
            seed: 0,
        }
    }
}

/// A certified path from a start to one configuration of a goal set.
#[derive(Debug, Clone, PartialEq)]
pub struct Path {
    /// The configurations after the start, the last one in the goal set.
    pub waypoints: Vec<Vec<f64>>,
    /// The certified check of each edge, `segments[i]` ending at `waypoints[i]`.
    pub segments: Vec<SegmentCheck>,
    /// Index of the goal configuration reached, in the goal set given.
    pub target: usize,
    /// Joint-space length before shortcutting (rad and m summed as numbers).
    pub length_before_shortcut: f64,
    /// Random samples drawn.
    pub samples: usize,
}

/// Why no path was found, and how close the search came.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// Random samples drawn (the budget, when a sampling planner ran out).
    pub samples: usize,
    /// Where the closest attempt stopped: its blocking pair and configuration.
    pub stop: Option<SegmentPoint>,
    /// Joint-space distance from the search's nearest configuration to the goal set.
    pub gap: Option<f64>,
}

/// Joins a start to a goal set by certified edges.
pub trait Planner {
    /// A certified path from `start` to one of `goals` (collision-free configurations, the
    /// preferred first), or how the search failed. `stream` seeds this call's random choices.
    ///
    /// # Errors
    /// [`Failure`] when no path was found within the planner's budget.
    fn connect(&mut self, checker: &mut SegmentChecker<'_>, start: &[f64], goals: &[Vec<f64>], stream: u64) -> Result<Path, Failure>;
}

/// The paper's heuristic: one straight segment to each goal configuration in the order given.
#[derive(Debug, Clone, Copy, Default)]
pub struct Straight;

impl Planner for Straight {
    fn connect(&mut self, checker: &mut SegmentChecker<'_>, start: &[f64], goals: &[Vec<f64>], _stream: u64) -> Result<Path, Failure> {
        let mut first_stop = None;
        for (target, goal) in goals.iter().enumerate() {
            let segment = checker.check(start, goal);
            if segment.free {
                return Ok(Path {
                    waypoints: vec![goal.clone()],
                    segments: vec![segment],
                    target,
                    length_before_shortcut: distance(start, goal),
                    samples: 0,
                });
            }
            if target == 0 {
                first_stop = segment.touch.or(segment.closest);
            }
        }
        Err(Failure {
            samples: 0,
            stop: first_stop,
            gap: goals.first().map(|g| distance(start, g)),
        })
    }
}

/// Euclidean joint-space distance (rad and m summed as numbers).
pub fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
}

/// Joint-space length of the polyline `start`, `waypoints...`.
pub fn polyline_length(start: &[f64], waypoints: &[Vec<f64>]) -> f64 {
    let mut previous = start;
    let mut length = 0.0;
    for w in waypoints {
        length += distance(previous, w);
        previous = w;
    }
    length
}
