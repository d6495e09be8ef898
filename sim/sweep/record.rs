//! One design on one scenario: the validation a single `validate-design` run would do, cut down
//! to the numbers a design-space table compares.

use super::SweepMode;
use crate::pipeline::{self, Loaded};
use crate::scenario::Scenario;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Decimals kept of lengths in metres (micrometres) and of losses: far below what a goal's 1 mm
/// criterion distinguishes, and enough that ranks by loss do not tie by rounding.
const METRE_DECIMALS: i32 = 6;
/// Decimals of errors in millimetres and degrees.
const ERROR_DECIMALS: i32 = 4;

/// The result of one design on one scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// The design's id (see [`super::inputs::DesignEntry::id`]).
    pub design: String,
    /// The scenario's id (its path as resolved).
    pub scenario: String,
    /// Goals of the scenario.
    pub goals: usize,
    /// Goals with a collision-free IK solution within 1 mm and 1 degree (reach-only), or reached
    /// on the certified trajectory (full).
    pub goals_solved: usize,
    /// Goals proven unreachable (every solution known, or out of reach).
    pub goals_proven_unreachable: usize,
    /// Goals neither solved nor proven unreachable: the limits of the search (IK starts, the
    /// planner's budget). Records written before it existed read 0.
    #[serde(default)]
    pub goals_undecided: usize,
    /// Every goal solved (full: and the verdict passed).
    pub task_solved: bool,
    /// Mean over goals of the position error (mm) of IK's best configuration of the goal.
    pub position_error_mm: Option<f64>,
    /// Mean over goals of the orientation error (deg, under the goal's tolerance mode).
    pub orientation_error_deg: Option<f64>,
    /// The paper's hardware cost `sum |a| + |d|` (m); `None` for URDF and MJCF robots.
    pub hardware_cost_m: Option<f64>,
    /// The task loss: per goal the paper's `w_d d + w_col c_col` minimised over the goal's IK
    /// solutions, summed, plus `w_c c_h`; `None` when a goal has no configuration at all.
    pub task_loss: Option<f64>,
    /// Full validation: the verdict's word, `PASS`, `FAIL` or `UNDECIDED`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verdict: Option<String>,
}

fn round(value: f64, decimals: i32) -> f64 {
    let scale = 10f64.powi(decimals);
    let rounded = (value * scale).round() / scale;
    // -0.0 prints as "-0"; a record must read the same whichever side of zero rounding came from.
    if rounded == 0.0 {
        0.0
    } else {
        rounded
    }
}

/// Validates `loaded` on `scenario` and condenses the result.
///
/// # Errors
/// As [`pipeline::validate`]: geometry that cannot be built, a name clash, an engine refusing
/// the model.
pub fn evaluate(
    design_id: &str,
    scenario_id: &str,
    loaded: Loaded,
    scenario: Scenario,
    mode: &SweepMode,
) -> Result<Record, crate::error::Error> {
    let opts = match mode {
        SweepMode::ReachOnly { ik } => pipeline::ValidateOptions {
            ik: ik.clone(),
            reach_only: true,
            skip_goal_clearances: true,
            ..Default::default()
        },
        SweepMode::Full { ik, engines } => pipeline::ValidateOptions {
            ik: ik.clone(),
            engines: *engines,
            ..pipeline::ValidateOptions::seeded(ik.seed)
        },
    };
    let hardware_cost_m = loaded.design.as_ref().map(crate::design::Design::hardware_cost);
    // The run `validate-design` makes, without MuJoCo's kinematics check.
    let run_opts = crate::run::Options {
        kinematics_checks: 0,
        validate: opts,
        ..Default::default()
    };
    let (validation, report) = crate::run::validated(Path::new(design_id), loaded, scenario, &run_opts, &crate::progress::Silent)?;
    let goals = validation.scenario.goals.len();
    let best: Vec<_> = validation.solutions.iter().map(|g| g.solutions.first()).collect();
    let mean = |values: Vec<f64>| (values.len() == goals && goals > 0).then(|| values.iter().sum::<f64>() / goals as f64);
    let position_error_mm = mean(best.iter().flatten().map(|s| s.error.position_m * 1e3).collect());
    let orientation_error_deg = mean(best.iter().flatten().map(|s| s.error.orientation_rad.to_degrees()).collect());
    let goals_proven_unreachable = (0..goals)
        .filter(|&i| !validation.solutions[i].reached() && validation.proof(i).is_some())
        .count();
    // The report's paper loss, each goal at its best IK solution: one home for the sum.
    let task_loss = report.paper_loss.as_ref().and_then(|p| p.total);
    let (goals_solved, task_solved, verdict) = match mode {
        SweepMode::ReachOnly { .. } => {
            let solved = validation.solutions.iter().filter(|g| g.reached()).count();
            (solved, solved == goals, None)
        }
        SweepMode::Full { .. } => {
            let solved = report.goals.iter().filter(|g| g.outcome == "reached").count();
            let passed = report.verdict.passed;
            (solved, passed, Some(report.verdict.word.to_string()))
        }
    };
    Ok(Record {
        design: design_id.to_string(),
        scenario: scenario_id.to_string(),
        goals,
        goals_solved,
        goals_proven_unreachable,
        goals_undecided: goals.saturating_sub(goals_solved + goals_proven_unreachable),
        task_solved,
        position_error_mm: position_error_mm.map(|v| round(v, ERROR_DECIMALS)),
        orientation_error_deg: orientation_error_deg.map(|v| round(v, ERROR_DECIMALS)),
        hardware_cost_m: hardware_cost_m.map(|v| round(v, METRE_DECIMALS)),
        task_loss: task_loss.map(|v| round(v, METRE_DECIMALS)),
        verdict,
    })
}

/// [`evaluate`] for each of `designs` (an id and the robot) on one scenario, in parallel on
/// rayon's current pool; the records in the order of `designs`, each depending on its design
/// alone, so the thread count changes no number. `stop` is read before each design: once it is
/// set the designs not yet started are skipped and the batch gives `None` (a front end's
/// Ctrl-C), without a barrier that would idle threads while the batch runs.
///
/// # Errors
/// The first design's error in the order of `designs`, as [`evaluate`].
pub fn evaluate_batch(
    designs: Vec<(String, Loaded)>,
    scenario_id: &str,
    scenario: &Scenario,
    mode: &SweepMode,
    stop: &std::sync::atomic::AtomicBool,
) -> Result<Option<Vec<Record>>, crate::error::Error> {
    use rayon::prelude::*;
    use std::sync::atomic::Ordering;
    let records: Vec<Option<Record>> = designs
        .into_par_iter()
        .map(|(id, loaded)| {
            if stop.load(Ordering::Relaxed) {
                return Ok(None);
            }
            evaluate(&id, scenario_id, loaded, scenario.clone(), mode).map(Some)
        })
        .collect::<Result<_, _>>()?;
    Ok(records.into_iter().collect())
}
