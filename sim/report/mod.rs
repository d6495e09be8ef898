//! Consumes a [`Validation`] (every stage's output). Produces the [`Report`]: the criteria it
//! applied, per-goal and trajectory results, each engine's runs, the static load, the paper's
//! loss, the findings and the verdict. Never fails: a failing design is a verdict.

mod describe;
mod findings;
mod inputs;
mod loss;
mod render;
pub mod snapshot;

pub use describe::{describe, scenario_summary};
pub use findings::{Finding, FindingKind, Severity};
pub use inputs::{EngineRuns, Settings, Validation};
pub use loss::PaperLoss;
pub use render::{render, summary, verdict_line};

use crate::collide::{ClearanceByKind, ExcludedPair};
use crate::engine::{ContactInterval, StaticLoad};
use crate::ik::{REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use crate::plan::{GoalStep, SegmentPoint};
use crate::scenario::{Provenance, Tolerance};
use serde::Serialize;

/// Version of the report's layout; bumped whenever a field changes meaning or moves.
pub const SCHEMA_VERSION: u32 = 2;

/// The report of one design on one scenario.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// What "reached", "free" and "held" meant in this run.
    pub criteria: Criteria,
    /// What the run was given: warnings about the input files, and our kinematics against
    /// MuJoCo's on the MJCF export (when the caller ran that check).
    pub inputs: InputsReport,
    /// The robot.
    pub design: DesignSummary,
    /// The scenario.
    pub scenario: ScenarioSummary,
    /// Per goal, course order.
    pub goals: Vec<GoalReport>,
    /// The trajectory through the goals; `None` in a reach-only run.
    pub trajectory: Option<TrajectoryReport>,
    /// Per engine run.
    pub engines: Vec<EngineReport>,
    /// Gravity torques along the trajectory against the ratings (needs MuJoCo).
    pub static_load: Option<StaticLoad>,
    /// The paper's objective for this design on this scenario; `None` (JSON `null`) for a URDF or
    /// MJCF robot: the paper's capsule model and hardware cost are defined on design parameters,
    /// and capsules on a robot file's joint frames would measure a phantom.
    pub paper_loss: Option<PaperLoss>,
    /// Everything noteworthy, failing or not.
    pub findings: Vec<Finding>,
    /// The verdict and its reasons.
    pub verdict: Verdict,
}

/// What the run was given, beyond the design and the scenario.
#[derive(Debug, Clone, Serialize)]
pub struct InputsReport {
    /// Warnings about the input files (also printed on stderr as they are read).
    pub warnings: Vec<String>,
    /// Our kinematics against MuJoCo's on the MJCF export; `None` when not run.
    pub kinematics_check: Option<crate::engine::KinematicsCheck>,
    /// Defaults the model reader chose, each with its reason (for a URDF or MJCF file the tip or
    /// tool frame and the joints left out of the arm as gripper joints; for an economic design the
    /// values a float32 generator rounded, read as their set's named value); also printed on stderr.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub model_choices: Vec<String>,
}

/// The criteria a verdict was reached under.
#[derive(Debug, Clone, Serialize)]
pub struct Criteria {
    /// `full` (IK, certified trajectory, engines) or `reach_only` (the paper's static metric:
    /// a collision-free IK solution per goal, nothing else).
    pub mode: &'static str,
    /// The planner that joined the goals, its sample budget and seed (`None` in reach-only).
    pub planner: Option<crate::plan::PlannerOptions>,
    /// A goal is reached below this position error (m).
    pub position_m: f64,
    /// ... and below this orientation error (deg), judged per the goal's tolerance mode.
    pub orientation_deg: f64,
    /// Clearance every configuration and every trajectory segment must keep (m).
    pub collision_margin_m: f64,
    /// The geometry collisions are judged on.
    pub geometry: &'static str,
    /// Link pairs not checked, with the reason for each.
    pub excluded_pairs: Vec<ExcludedPair>,
    /// Shape pairs not measured within otherwise checked link pairs (pieces that overlap by
    /// construction), with the reason for each: the rest of the two links is checked.
    pub excluded_shapes: Vec<crate::collide::ExcludedShapePair>,
    /// Link pairs with shapes that overlap by construction: their other shape pairs are checked
    /// and count as in contact only deeper than `depth_m`.
    pub structural_allowances: Vec<crate::collide::StructuralAllowance>,
    /// An engine holds a goal when the tool is within this of the reference at the end of the
    /// dwell (m).
    pub hold_position_m: f64,
    /// ... and within this angle (deg).
    pub hold_orientation_deg: f64,
    /// Engine contacts shallower than this are not counted (m).
    pub engine_contact_depth_m: f64,
    /// IK starts per goal and the seed of the random ones.
    pub ik_seeds: usize,
    /// Seed of IK's random starts.
    pub seed: u64,
    /// Engines run.
    pub engines: Vec<&'static str>,
}

/// The robot a report is about.
#[derive(Debug, Clone, Serialize)]
pub struct DesignSummary {
    /// Name.
    pub name: String,
    /// `free`, `economic`, `modular`, `preset`, `urdf` or `mjcf`.
    pub mode: String,
    /// Joints.
    pub dof: usize,
    /// DH rows of a design (d, a, alpha, limits), or none for a URDF.
    pub parameters: Option<serde_json::Value>,
    /// The paper's hardware cost `sum |a| + sum |d|` (m), for designs.
    pub hardware_cost_m: Option<f64>,
}

/// The scenario a report is about.
#[derive(Debug, Clone, Serialize)]
pub struct ScenarioSummary {
    /// Name.
    pub name: String,
    /// How it was generated, if it was.
    pub provenance: Option<Provenance>,
    /// Goals.
    pub goals: usize,
    /// Obstacles.
    pub obstacles: usize,
    /// Whether a floor is present.
    pub floor: bool,
}

/// One goal's results.
#[derive(Debug, Clone, Serialize)]
pub struct GoalReport {
    /// Index in the scenario.
    pub index: usize,
    /// Name.
    pub name: String,
    /// Tolerance mode it is judged by.
    pub tolerance: Tolerance,
    /// `reached` (on a certified path; in reach-only: a collision-free IK solution),
    /// `unreachable` (proven: no collision-free configuration reaches it, see `proven`),
    /// `undecided` (not reached, not proven unreachable: the limits of the search) or `no_path`
    /// (solutions exist, no certified path found within the planner's budget).
    pub outcome: &'static str,
    /// Why no configuration can reach the goal, when that is proven (beyond the arm's reach,
    /// inside an obstacle, or by the closed form's complete solution set); `None` otherwise.
    pub proven: Option<String>,
    /// Why a goal every solution of which is known is still undecided (a solution whose
    /// tolerance neighbourhood may hold a free configuration, a singular pose); `None` otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub undecided: Option<String>,
    /// IK found a collision-free solution within the thresholds.
    pub reached: bool,
    /// Distinct solutions IK found that reach the pose (colliding or not).
    pub solutions_found: usize,
    /// Those are every solution within the joint limits (closed-form IK); left out of the JSON
    /// when false (numeric IK: found from its starts, more may exist).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub solutions_complete: bool,
    /// Of those, collision-free.
    pub solutions_free: usize,
    /// The configuration the trajectory goes to (or IK's best, when none connects).
    pub chosen: Option<Vec<f64>>,
    /// Position error of the chosen configuration (m).
    pub position_error_m: Option<f64>,
    /// Orientation error of the chosen configuration (deg).
    pub orientation_error_deg: Option<f64>,
    /// Exact clearance of the chosen configuration (m).
    pub exact_clearance_m: Option<f64>,
    /// The pair that sets that clearance (`a and b`).
    pub clearance_pair: Option<String>,
    /// The smallest distance of each kind of pair at the chosen configuration (m): obstacles,
    /// self, floor, every pair measured exactly.
    pub clearance_by_kind: Option<crate::collide::ClearanceByKind>,
    /// The paper's capsule model's clearance of the chosen configuration (m).
    pub approximate_clearance_m: Option<f64>,
    /// The trajectory reaches it by a certified path.
    pub on_trajectory: bool,
    /// Engines that held it within the hold tolerance.
    pub held_by: Vec<&'static str>,
}

/// The trajectory's results.
#[derive(Debug, Clone, Serialize)]
pub struct TrajectoryReport {
    /// Start configuration.
    pub home: Vec<f64>,
    /// Clearance at home (m).
    pub home_clearance_m: Option<f64>,
    /// Why the scenario's or the default home was replaced, when it was.
    pub home_replaced: Option<String>,
    /// Goals reached by a certified path.
    pub reached: usize,
    /// Goals proven unreachable.
    pub unreachable: usize,
    /// Goals without a collision-free IK solution found, not proven unreachable.
    pub undecided: usize,
    /// Goals with collision-free solutions but no certified path within the budget.
    pub no_path: usize,
    /// Per goal in order: its certified path, or the attempt of a goal without one.
    pub segments: Vec<SegmentReport>,
    /// Edges of the whole path (a straight segment is one edge).
    pub edges: usize,
    /// Segments the engines replayed: the planned ones and the blocked goals' attempts.
    pub replayed_segments: usize,
    /// The smallest certified clearance over the trajectory (m).
    pub certified_clearance_m: Option<f64>,
    /// The same for each kind of pair: obstacles, the robot itself, the floor.
    pub certified_by_kind: Option<ClearanceByKind>,
    /// Joint-space length (rad and m summed).
    pub joint_length: f64,
    /// Joint-space length before the planner's shortcutting.
    pub joint_length_before_shortcut: f64,
    /// Tool path length (m).
    pub tool_path_m: f64,
    /// Duration of the timed trajectory (s).
    pub duration_s: f64,
}

/// One goal's path on the trajectory, or the attempt of a goal without one.
#[derive(Debug, Clone, Serialize)]
pub struct SegmentReport {
    /// Goal it heads for.
    pub goal: usize,
    /// `reached`, `unreachable` or `no_path`.
    pub outcome: &'static str,
    /// On the trajectory (every edge certified free).
    pub planned: bool,
    /// Edges of the path (1: a straight segment); 0 for a goal without a path.
    pub edges: usize,
    /// Random samples the planner drew for this goal.
    pub samples: usize,
    /// Joint-space length of the path, and before shortcutting.
    pub joint_length: Option<f64>,
    /// Joint-space length of the path the planner found, before shortcutting.
    pub joint_length_before_shortcut: Option<f64>,
    /// Certified lower bound on its clearance (m), over every edge (an attempt: up to where it
    /// stopped).
    pub certified_clearance_m: Option<f64>,
    /// The same bound for each kind of pair: obstacles, the robot itself, the floor.
    pub certified_by_kind: Option<ClearanceByKind>,
    /// Closest approach measured, with the pair.
    pub closest: Option<SegmentPoint>,
    /// Where the planner's closest attempt of a goal without a path stops: pair and
    /// configuration.
    pub stop: Option<SegmentPoint>,
    /// Where the straight segment to the nearest solution (the paper heuristic's motion, the one
    /// the engines replay) of a goal without a path stops: pair and configuration.
    pub attempt_stop: Option<SegmentPoint>,
    /// Joint-space distance the search for a goal without a path stayed from its goal set.
    pub gap: Option<f64>,
    /// Collision queries of the continuous check.
    pub queries: usize,
}

/// One engine's results.
#[derive(Debug, Clone, Serialize)]
pub struct EngineReport {
    /// `rapier` or `mujoco`.
    pub engine: &'static str,
    /// Goals held / goals on the trajectory.
    pub goals_held: usize,
    /// Largest hold errors over the goals (m, deg).
    pub worst_hold_position_m: f64,
    /// Largest hold orientation error (deg).
    pub worst_hold_orientation_deg: f64,
    /// Largest tool deviation from the reference while moving (m).
    pub max_tracking_position_m: f64,
    /// Contacts in the dynamic run.
    pub contacts: Vec<ContactInterval>,
    /// Contacts in the kinematic replay (replay clock: segment k is [k, k + 1)).
    pub replay_contacts: Vec<ContactInterval>,
    /// Peak effort per joint in the dynamic run (N m or N).
    pub peak_effort: Vec<f64>,
    /// Rating per joint, when known (N m or N).
    pub rated_effort: Vec<Option<f64>>,
}

/// Passed or failed, and why.
#[derive(Debug, Clone, Serialize)]
pub struct Verdict {
    /// The design passes the scenario.
    pub passed: bool,
    /// `PASS`; `FAIL` when a failure is proven (an unreachable goal, a contact, a torque over
    /// rating); `UNDECIDED` when nothing failed but something was left open by the harness's
    /// limits (a goal neither reached nor proven unreachable, a path not found in the budget).
    pub word: &'static str,
    /// One line per failing finding kind, with counts; empty when passed.
    pub reasons: Vec<String>,
}

/// Builds the report of a validation.
pub fn build(validation: &Validation) -> Report {
    let settings = &validation.settings;
    let engines: Vec<_> = validation.engines.iter().map(|runs| (runs.dynamic.engine, runs)).collect();
    let hold = (settings.hold_position_m, settings.hold_orientation_rad);
    let criteria = Criteria {
        mode: if settings.reach_only { "reach_only" } else { "full" },
        planner: validation.trajectory.as_ref().map(|t| t.planner),
        position_m: REACHED_POSITION_M,
        orientation_deg: REACHED_ORIENTATION_RAD.to_degrees(),
        collision_margin_m: settings.margin_m,
        geometry: "exact (parry3d-f64: the model's spheres, boxes, cylinders, capsules and triangle meshes as they are)",
        excluded_pairs: validation.excluded.clone(),
        excluded_shapes: validation.excluded_shapes.clone(),
        structural_allowances: validation.structural_allowances.clone(),
        hold_position_m: hold.0,
        hold_orientation_deg: hold.1.to_degrees(),
        engine_contact_depth_m: settings.engine_contact_depth_m,
        ik_seeds: settings.ik_seeds,
        seed: settings.seed,
        engines: engines.iter().map(|(name, _)| *name).collect(),
    };
    let goals = goal_reports(validation, &engines, hold);
    let trajectory = validation.trajectory.as_ref().map(|t| trajectory_report(validation, t));
    let engine_reports = engines
        .iter()
        .map(|(name, runs)| {
            let held = runs
                .dynamic
                .holds
                .iter()
                .filter(|h| h.position_error_m <= hold.0 && h.orientation_error_rad <= hold.1)
                .count();
            EngineReport {
                engine: name,
                goals_held: held,
                worst_hold_position_m: runs.dynamic.holds.iter().map(|h| h.position_error_m).fold(0.0, f64::max),
                worst_hold_orientation_deg: runs
                    .dynamic
                    .holds
                    .iter()
                    .map(|h| h.orientation_error_rad)
                    .fold(0.0, f64::max)
                    .to_degrees(),
                max_tracking_position_m: runs.dynamic.max_tool_position_error_m,
                contacts: runs.dynamic.contacts.clone(),
                replay_contacts: runs.replay.contacts.clone(),
                peak_effort: runs.dynamic.peak_effort.clone(),
                rated_effort: validation.model.joints.iter().map(|j| j.max_effort).collect(),
            }
        })
        .collect();
    let findings = findings::collect(validation, &engines, hold);
    let budget = validation
        .trajectory
        .as_ref()
        .map(|t| if t.planner.kind.samples() { t.planner.budget } else { 0 });
    let verdict = findings::verdict(&findings, settings, budget);
    Report {
        schema_version: SCHEMA_VERSION,
        criteria,
        inputs: InputsReport {
            warnings: validation.input_warnings.clone(),
            kinematics_check: validation.kinematics_check.clone(),
            model_choices: validation.model.source.choices().to_vec(),
        },
        design: design_summary(validation),
        scenario: ScenarioSummary {
            name: validation.scenario.name.clone(),
            provenance: validation.scenario.provenance.clone(),
            goals: validation.scenario.goals.len(),
            obstacles: validation.scenario.obstacles.len(),
            floor: validation.scenario.floor.is_some(),
        },
        goals,
        trajectory,
        engines: engine_reports,
        static_load: validation.static_load.clone(),
        paper_loss: validation.design.is_some().then(|| loss::paper_loss(validation)),
        findings,
        verdict,
    }
}

fn design_summary(validation: &Validation) -> DesignSummary {
    let model = &validation.model;
    match &validation.design {
        Some(design) => DesignSummary {
            name: design.name.clone(),
            mode: serde_json::to_value(design.mode)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default(),
            dof: model.dof(),
            parameters: serde_json::to_value(&design.joints).ok(),
            hardware_cost_m: Some(design.hardware_cost()),
        },
        None => DesignSummary {
            name: model.name.clone(),
            mode: match &model.source {
                crate::model::ModelSource::Design { mode, .. } => mode.clone(),
                crate::model::ModelSource::Urdf { .. } => "urdf".into(),
                crate::model::ModelSource::Mjcf { .. } => "mjcf".into(),
                crate::model::ModelSource::Timor { .. } => "timor".into(),
            },
            dof: model.dof(),
            parameters: None,
            hardware_cost_m: None,
        },
    }
}

fn goal_reports(validation: &Validation, engines: &[(&'static str, &EngineRuns)], hold: (f64, f64)) -> Vec<GoalReport> {
    validation
        .scenario
        .goals
        .iter()
        .enumerate()
        .map(|(index, goal)| {
            let found = validation.solutions.get(index).map(|g| g.solutions.as_slice()).unwrap_or_default();
            let step = validation.trajectory.as_ref().and_then(|t| t.steps.get(index));
            let on_trajectory = matches!(step, Some(GoalStep::Reached { .. }));
            let chosen = match step {
                Some(GoalStep::Reached { q, .. }) => Some(q.clone()),
                _ => found.first().map(|s| s.q.clone()),
            };
            let solution = chosen
                .as_ref()
                .and_then(|q| found.iter().find(|s| same_modulo_turns(&validation.model, &s.q, q)));
            let error = chosen.as_ref().map(|q| crate::ik::goal_error(goal, &validation.model.tool_pose(q)));
            let held_by = engines
                .iter()
                .filter(|(_, runs)| {
                    runs.dynamic
                        .holds
                        .iter()
                        .any(|h| h.goal == index && h.position_error_m <= hold.0 && h.orientation_error_rad <= hold.1)
                })
                .map(|(name, _)| *name)
                .collect();
            let ik_reached = found.first().is_some_and(|s| s.reached);
            let outcome = match step {
                Some(step) => step.outcome(),
                None if ik_reached => "reached",
                None => "unreachable",
            };
            // Unreachable is a proof; a goal IK could not reach without one is open.
            let outcome = match outcome {
                "unreachable" if validation.proof(index).is_none() => "undecided",
                other => other,
            };
            GoalReport {
                index,
                name: goal.name.clone(),
                tolerance: goal.tolerance,
                outcome,
                proven: if outcome == "unreachable" { validation.proof(index) } else { None },
                undecided: match outcome {
                    "undecided" => validation.solutions.get(index).and_then(|g| g.undecided.clone()),
                    _ => None,
                },
                reached: ik_reached,
                solutions_found: found.iter().filter(|s| s.pose_reached).count(),
                solutions_complete: validation.solutions.get(index).is_some_and(|g| g.complete),
                solutions_free: found.iter().filter(|s| s.reached).count(),
                position_error_m: error.map(|e| e.position_m),
                orientation_error_deg: error.map(|e| e.orientation_rad.to_degrees()),
                exact_clearance_m: match step {
                    Some(GoalStep::Reached { clearance, .. }) => clearance.as_ref().map(|c| c.distance_m),
                    _ => solution.and_then(|s| s.clearance.map(|c| c.exact_m)),
                },
                clearance_pair: validation
                    .goal_clearances
                    .get(index)
                    .cloned()
                    .flatten()
                    .map(|c| format!("{} and {}", c.a, c.b)),
                clearance_by_kind: validation.goal_clearances_by_kind.get(index).copied().flatten(),
                approximate_clearance_m: solution
                    .filter(|_| validation.design.is_some())
                    .and_then(|s| s.clearance.map(|c| c.approximate_m)),
                chosen,
                on_trajectory,
                held_by,
            }
        })
        .collect()
}

/// Whether two configurations are the same up to whole turns of revolute joints (to 1e-9).
fn same_modulo_turns(model: &crate::model::Model, a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && model.joints.iter().zip(a.iter().zip(b)).all(|(joint, (x, y))| {
            let difference = if joint.kind == crate::model::JointKind::Prismatic {
                x - y
            } else {
                crate::ik::wrap_angle(x - y)
            };
            difference.abs() <= 1e-9
        })
}

fn trajectory_report(validation: &Validation, trajectory: &crate::plan::Trajectory) -> TrajectoryReport {
    let mut previous = trajectory.home.clone();
    let segments: Vec<SegmentReport> = trajectory
        .steps
        .iter()
        .map(|step| match step {
            GoalStep::Reached {
                goal,
                waypoints,
                segments,
                length_before_shortcut,
                samples,
                q,
                ..
            } => {
                let length = crate::plan::polyline_length(&previous, waypoints);
                previous.clone_from(q);
                SegmentReport {
                    goal: *goal,
                    outcome: step.outcome(),
                    planned: true,
                    edges: segments.len(),
                    samples: *samples,
                    joint_length: Some(length),
                    joint_length_before_shortcut: Some(*length_before_shortcut),
                    certified_clearance_m: segments.iter().map(|s| s.certified_clearance_m).reduce(f64::min),
                    certified_by_kind: segments.iter().map(|s| s.certified_by_kind).reduce(ClearanceByKind::min),
                    closest: segments
                        .iter()
                        .filter_map(|s| s.closest.clone())
                        .min_by(|a, b| a.distance_m.total_cmp(&b.distance_m)),
                    stop: None,
                    attempt_stop: None,
                    gap: None,
                    queries: segments.iter().map(|s| s.queries).sum(),
                }
            }
            GoalStep::Unreachable { goal, .. } => SegmentReport {
                goal: *goal,
                outcome: step.outcome(),
                planned: false,
                edges: 0,
                samples: 0,
                joint_length: None,
                joint_length_before_shortcut: None,
                certified_clearance_m: None,
                certified_by_kind: None,
                closest: None,
                stop: None,
                attempt_stop: None,
                gap: None,
                queries: 0,
            },
            GoalStep::NoPath {
                goal,
                samples,
                stop,
                gap,
                attempt,
                ..
            } => SegmentReport {
                goal: *goal,
                outcome: step.outcome(),
                planned: false,
                edges: 0,
                samples: *samples,
                joint_length: None,
                joint_length_before_shortcut: None,
                certified_clearance_m: attempt.as_ref().map(|a| a.segment.certified_clearance_m),
                certified_by_kind: attempt.as_ref().map(|a| a.segment.certified_by_kind),
                closest: attempt.as_ref().and_then(|a| a.segment.closest.clone()),
                stop: stop.clone(),
                attempt_stop: attempt.as_ref().and_then(|a| a.segment.touch.clone()),
                gap: *gap,
                queries: attempt.as_ref().map_or(0, |a| a.segment.queries),
            },
        })
        .collect();
    let planned = || segments.iter().filter(|s| s.planned);
    let certified = planned().filter_map(|s| s.certified_clearance_m).reduce(f64::min);
    let certified_by_kind = planned().filter_map(|s| s.certified_by_kind).reduce(ClearanceByKind::min);
    TrajectoryReport {
        home: trajectory.home.clone(),
        home_clearance_m: trajectory.home_clearance.as_ref().map(|c| c.distance_m),
        home_replaced: trajectory.home_replaced.clone(),
        reached: trajectory.reached(),
        unreachable: (0..trajectory.steps.len())
            .filter(|&i| trajectory.steps[i].outcome() == "unreachable" && validation.proof(i).is_some())
            .count(),
        undecided: (0..trajectory.steps.len())
            .filter(|&i| trajectory.steps[i].outcome() == "unreachable" && validation.proof(i).is_none())
            .count(),
        no_path: trajectory.count("no_path"),
        edges: segments.iter().map(|s| s.edges).sum(),
        segments,
        replayed_segments: validation.replayed.len(),
        certified_clearance_m: certified,
        certified_by_kind,
        joint_length: trajectory.joint_length,
        joint_length_before_shortcut: trajectory.joint_length_before_shortcut,
        tool_path_m: trajectory.tool_path_m,
        duration_s: trajectory.timed.duration_s(),
    }
}
