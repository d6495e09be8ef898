//! What the report is built from: every stage's output of one validation run.

/// One engine's runs on a validation's trajectory.
#[derive(Debug, Clone, serde::Serialize)]
pub struct EngineRuns {
    /// Following the timed trajectory with motors, gravity on.
    pub dynamic: crate::engine::EngineRun,
    /// Positions set along the replay segments (see [`crate::plan::replay_segments`]).
    pub replay: crate::engine::EngineRun,
}

/// Everything a validation produced, stage by stage.
#[derive(Debug, Clone)]
pub struct Validation {
    /// The model, placed at the scenario's base pose.
    pub model: crate::model::Model,
    /// The design, for design files.
    pub design: Option<crate::design::Design>,
    /// The scenario.
    pub scenario: crate::scenario::Scenario,
    /// Checked pairs and excluded pairs (with reasons), by name.
    pub pairs: Vec<crate::collide::CheckedPair>,
    /// Excluded pairs with their reasons.
    pub excluded: Vec<crate::collide::ExcludedPair>,
    /// Per goal, the exact clearance of its configuration (the trajectory's, else IK's best) and
    /// the pair that sets it.
    pub goal_clearances: Vec<Option<crate::plan::SegmentPoint>>,
    /// Per goal, the smallest distance of each kind of pair (obstacles, self, floor) at the same
    /// configuration.
    pub goal_clearances_by_kind: Vec<Option<crate::collide::ClearanceByKind>>,
    /// Warnings about the input files (what was suspicious and what was assumed).
    pub input_warnings: Vec<String>,
    /// Our kinematics against MuJoCo's on the MJCF export, when the caller ran the check.
    pub kinematics_check: Option<crate::engine::KinematicsCheck>,
    /// Shape pairs of checked link pairs that are not measured (with reasons).
    pub excluded_shapes: Vec<crate::collide::ExcludedShapePair>,
    /// Link pairs whose other shape pairs count only beyond their overlap by construction.
    pub structural_allowances: Vec<crate::collide::StructuralAllowance>,
    /// IK solutions per goal.
    pub solutions: Vec<crate::ik::GoalSolutions>,
    /// Per goal, why no configuration can reach it, where the model and world prove it (see
    /// [`crate::ik::unreachable_proof`], and [`crate::ik::last_joints_beyond_reach`] where IK
    /// has no proof of its own); `None` for goals IK reached or could not prove. Read through
    /// [`Validation::proof`], which adds IK's own proofs.
    pub proofs: Vec<Option<String>>,
    /// The trajectory through the goals; `None` in a reach-only run.
    pub trajectory: Option<crate::plan::Trajectory>,
    /// Segments replayed in the engines, with their certified checks.
    pub replayed: Vec<crate::plan::ReplaySegment>,
    /// The runs of each engine that ran, in [`crate::engine::ENGINES`]' order.
    pub engines: Vec<EngineRuns>,
    /// Gravity torques along the trajectory against ratings (MuJoCo's cross-checked with ours, or
    /// ours alone without MuJoCo).
    pub static_load: Option<crate::engine::StaticLoad>,
    /// Gains both engines used; `None` in a reach-only run.
    pub gains: Option<crate::engine::Gains>,
    /// The paper's loss terms per goal at the chosen configuration (the trajectory's, else IK's
    /// best); `None` for a goal with no configuration at all.
    pub loss_terms: Vec<Option<crate::ik::LossTerms>>,
    /// The paper's loss terms per goal minimised over the goal's IK solutions (the task loss of
    /// design-space sweeps: what the best configuration IK found costs, whatever the trajectory
    /// chose; the report's paper loss); `None` for a goal with no configuration at all.
    pub task_loss_terms: Vec<Option<crate::ik::LossTerms>>,
    /// The settings the run used that the report states as its criteria.
    pub settings: Settings,
}

impl Validation {
    /// Why no configuration can reach goal `index`, when proven: by the model and world (beyond
    /// the arm's reach, inside an obstacle), else by IK's complete solution set (closed form).
    pub fn proof(&self, index: usize) -> Option<String> {
        self.proofs
            .get(index)
            .cloned()
            .flatten()
            .or_else(|| self.solutions.get(index).and_then(|found| found.proof.clone()))
    }
}

/// The settings of a run that decide its verdict.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Settings {
    /// Clearance every configuration and segment had to keep (m).
    pub margin_m: f64,
    /// Hold tolerance at the tool (m).
    pub hold_position_m: f64,
    /// Hold tolerance at the tool (rad).
    pub hold_orientation_rad: f64,
    /// Engine contacts at most this deep were not counted (m).
    pub engine_contact_depth_m: f64,
    /// IK starts per goal.
    pub ik_seeds: usize,
    /// Seed of IK's random starts (and the planner's streams).
    pub seed: u64,
    /// Only the static reach metric ran: no trajectory, no engines.
    pub reach_only: bool,
}
