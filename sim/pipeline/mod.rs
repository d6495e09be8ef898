//! Runs the stages in order on a loaded robot and a scenario ([`validate`]); reading the inputs
//! ([`load`], [`scenario_or_default`]), writing the outputs ([`write_output`]) and building the
//! collision world ([`collision_world`]) live in its submodules.

mod load;
mod output;
mod world;

pub use crate::engine::Engines;
pub use load::{input_kind, load, load_model, load_scenario, scenario_or_default, InputKind, LoadOptions, Loaded, DEFAULT_SCENARIO};
pub use output::{write_files_into, write_output, write_output_bytes, OutputSet};
pub use world::collision_world;

use crate::collide;
use crate::error::Error;
use crate::model::Model;
use rayon::prelude::*;

/// Settings of a whole validation run; every field's default is the documented one.
#[derive(Debug, Clone, Default)]
pub struct ValidateOptions {
    /// IK settings (seeds, seed, budgets).
    pub ik: crate::ik::IkOptions,
    /// The continuous check's threshold (collision margin).
    pub certify: crate::plan::CertifyOptions,
    /// Engines to run.
    pub engines: Engines,
    /// Engine step, gravity and contact depth tolerance.
    pub engine: crate::engine::RunOptions,
    /// Controller gain settings (also the hold tolerances).
    pub gains: crate::engine::GainOptions,
    /// Extra self pairs to exclude (e.g. from an SRDF), with reasons.
    pub excluded_pairs: Vec<collide::ExcludedPair>,
    /// The planner joining the goals, its sample budget and seed.
    pub planner: crate::plan::PlannerOptions,
    /// The paper's static metric alone: per goal a collision-free IK solution, no trajectory,
    /// no engines (default false).
    pub reach_only: bool,
    /// Leaves the per-goal clearances of the report (exact, and per kind of pair) unmeasured:
    /// a sweep's record reads none of them (default false).
    pub skip_goal_clearances: bool,
}

impl ValidateOptions {
    /// The defaults with IK and the planner both seeded by `seed`: what every experiment that
    /// takes one seed validates with.
    pub fn seeded(seed: u64) -> Self {
        let mut opts = Self::default();
        opts.ik.seed = seed;
        opts.planner.seed = seed;
        opts
    }
}

/// Runs every stage on a loaded robot and a scenario: collision world, IK, trajectory with the
/// certified continuous check, the engines' dynamic runs and kinematic replays (rapier and
/// MuJoCo in parallel), and the static load.
///
/// # Errors
/// [`Error::NameClash`] for an obstacle named like a robot link, [`Error::NoMass`] for a moving
/// link without mass unless `reach_only`, [`Error::Collide`] for geometry
/// that cannot be built, [`Error::Engine`] when an engine refuses the model.
pub use crate::report::{EngineRuns, Validation};

/// Runs all stages; see [`validate_with_progress`].
///
/// # Errors
/// As [`validate_with_progress`].
pub fn validate(loaded: Loaded, scenario: crate::scenario::Scenario, opts: &ValidateOptions) -> Result<Validation, Error> {
    validate_with_progress(loaded, scenario, opts, &crate::progress::Silent)
}

/// [`validate`], telling `progress` which stage starts (a short phrase, e.g. for a spinner) and,
/// while IK solves and the planner joins the goals, each goal done.
///
/// # Errors
/// As [`validate`].
pub fn validate_with_progress(
    loaded: Loaded,
    scenario: crate::scenario::Scenario,
    opts: &ValidateOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<Validation, Error> {
    progress.stage("building the collision world", None);
    // Contacts and findings name bodies: an obstacle may not share a robot link's name.
    if let Some((index, obstacle)) = scenario
        .obstacles
        .iter()
        .enumerate()
        .find(|(_, o)| loaded.model.links.iter().any(|l| l.name == o.name))
    {
        return Err(Error::NameClash {
            scenario: scenario.name.clone(),
            field: format!("obstacles[{index}].name"),
            name: obstacle.name.clone(),
            robot: loaded.model.name.clone(),
        });
    }
    if !opts.reach_only {
        if let Some((joint, link)) = loaded.model.massless_link() {
            return Err(Error::NoMass {
                robot: loaded.model.name.clone(),
                link: link.name.clone(),
                joint: joint.name.clone(),
            });
        }
    }
    let mut input_warnings: Vec<String> = loaded.model.diagnostics.iter().map(ToString::to_string).collect();
    input_warnings.extend(
        scenario
            .notes
            .iter()
            .map(|note| format!("warning: scenario {}: {note}", scenario.name)),
    );
    let model = loaded.model.placed(&scenario.world_from_base);
    let world = collision_world(&model, &scenario, &opts.excluded_pairs)?;
    progress.stage("solving IK", Some(scenario.goals.len() as u64));
    let ik = crate::ik::IkOptions {
        clearance_m: opts.certify.threshold_m,
        ..opts.ik.clone()
    };
    let solutions = crate::ik::solve_goals_counted(&model, &scenario, Some(&world), &ik, &|| {
        progress.advance();
        !progress.stopped()
    });
    if progress.stopped() {
        return Err(Error::Stopped);
    }
    let proofs: Vec<Option<String>> = scenario
        .goals
        .iter()
        .zip(&solutions)
        .map(|(goal, found)| {
            if found.reached() {
                return None;
            }
            // A proof within the harness's tolerance is no proof for a goal whose own is wider.
            if crate::ik::task_tolerance_gap(goal).is_some() {
                return crate::ik::task_beyond_reach(&model, goal);
            }
            // IK's own proof says more where it has one; else the model's reach proofs (the tool's
            // reach, already tried above, the last joints', the turning axes').
            crate::ik::unreachable_proof(&model, &world, goal)
                .or_else(|| found.proof.is_none().then(|| crate::ik::beyond_reach(&model, goal)).flatten())
        })
        .collect();
    let settings = crate::report::Settings {
        margin_m: opts.certify.threshold_m,
        hold_position_m: opts.gains.position_tolerance_m,
        hold_orientation_rad: opts.gains.orientation_tolerance_rad,
        engine_contact_depth_m: opts.engine.contact_depth_m,
        ik_seeds: opts.ik.seeds,
        seed: opts.ik.seed,
        reach_only: opts.reach_only,
    };
    // The report's paper loss (and the sweeps' task loss): each goal at its best IK solution.
    let task_loss_terms = task_loss_terms(&model, &world, &scenario, &solutions);
    let motion = if opts.reach_only {
        Motion::reach_only(&model, &world, &scenario, &solutions)
    } else {
        Motion::run(&model, &world, &scenario, &solutions, opts, &ik, progress)?
    };
    let (goal_clearances, goal_clearances_by_kind) = if opts.skip_goal_clearances {
        (vec![None; solutions.len()], vec![None; solutions.len()])
    } else {
        let trajectory = motion.trajectory.as_ref();
        (
            goal_clearances(&model, &world, &solutions, trajectory, opts.certify),
            goal_clearances_by_kind(&model, &world, &solutions, trajectory),
        )
    };
    Ok(Validation {
        pairs: world.pairs().to_vec(),
        excluded: world.excluded().to_vec(),
        excluded_shapes: world.excluded_shapes().to_vec(),
        structural_allowances: world.structural_allowances().to_vec(),
        goal_clearances,
        goal_clearances_by_kind,
        input_warnings,
        kinematics_check: None,
        model,
        design: loaded.design,
        scenario,
        solutions,
        proofs,
        trajectory: motion.trajectory,
        replayed: motion.replayed,
        engines: motion.engines,
        static_load: motion.static_load,
        gains: motion.gains,
        loss_terms: motion.loss_terms,
        task_loss_terms,
        settings,
    })
}

/// What a run finds along the trajectory: the planned path and its replay, the engines' runs,
/// the static load, the gains, and the paper's loss terms at the configurations it chose (all
/// empty for reach-only, whose loss terms are at IK's first solutions).
struct Motion {
    trajectory: Option<crate::plan::Trajectory>,
    replayed: Vec<crate::plan::ReplaySegment>,
    engines: Vec<EngineRuns>,
    static_load: Option<crate::engine::StaticLoad>,
    gains: Option<crate::engine::Gains>,
    loss_terms: Vec<Option<crate::ik::LossTerms>>,
}

impl Motion {
    /// The paper's static metric alone: no trajectory, no engines.
    fn reach_only(
        model: &Model,
        world: &collide::CollisionWorld,
        scenario: &crate::scenario::Scenario,
        solutions: &[crate::ik::GoalSolutions],
    ) -> Self {
        let loss_terms = scenario
            .goals
            .iter()
            .zip(solutions)
            .map(|(goal, found)| {
                found
                    .solutions
                    .first()
                    .map(|s| crate::ik::paper_loss_terms(model, world, goal, &s.q))
            })
            .collect();
        Self {
            trajectory: None,
            replayed: Vec::new(),
            engines: Vec::new(),
            static_load: None,
            gains: None,
            loss_terms,
        }
    }

    /// Plans and certifies the trajectory, runs the engines on it and measures the static load.
    fn run(
        model: &Model,
        world: &collide::CollisionWorld,
        scenario: &crate::scenario::Scenario,
        solutions: &[crate::ik::GoalSolutions],
        opts: &ValidateOptions,
        ik: &crate::ik::IkOptions,
        progress: &dyn crate::progress::Progress,
    ) -> Result<Self, Error> {
        progress.stage(
            "planning the trajectory (certified continuous check)",
            Some(scenario.goals.len() as u64),
        );
        let trajectory_options = crate::plan::TrajectoryOptions {
            certify: opts.certify,
            ik: ik.clone(),
            timing: None,
            planner: opts.planner,
        };
        let trajectory = crate::plan::plan_counted(
            model,
            scenario,
            world,
            solutions,
            &trajectory_options,
            &|| progress.advance(),
            &|| progress.stopped(),
        )
        .map_err(|e| match e {
            crate::plan::PlanError::Stopped => Error::Stopped,
            e => e.into(),
        })?;
        let replayed = crate::plan::replay_segments(&trajectory);
        let loss_terms = scenario
            .goals
            .iter()
            .enumerate()
            .map(|(index, goal)| {
                let chosen = match trajectory.steps.get(index) {
                    Some(crate::plan::GoalStep::Reached { q, .. }) => Some(q.as_slice()),
                    _ => solutions.get(index).and_then(|g| g.solutions.first()).map(|s| s.q.as_slice()),
                };
                chosen.map(|q| crate::ik::paper_loss_terms(model, world, goal, q))
            })
            .collect();
        // The engines replay every sample; without them only the static load reads them, one at a
        // time (tens of thousands of goals make millions).
        let samples = if !opts.engines.is_empty() {
            crate::plan::replay_samples(&replayed)
        } else {
            Vec::new()
        };
        let gain_options = crate::engine::GainOptions {
            gravity_m_s2: opts.engine.gravity_m_s2,
            ..opts.gains.clone()
        };
        // With no goal reached the engines still get a path: home, standing still, zero duration.
        let still;
        let timed = if trajectory.timed.segments.is_empty() {
            let limits = crate::plan::TimingLimits::of(model);
            still = crate::plan::TimedPath::through(&[trajectory.home.clone(), trajectory.home.clone()], &[None], &limits);
            &still
        } else {
            &trajectory.timed
        };
        let gains = crate::engine::gains(model, timed, &gain_options);
        // The static load along the trajectory only: a blocked goal's attempt is not a motion the
        // robot makes.
        let on_trajectory = |(clock, _): &(f64, Vec<f64>)| replayed.get(*clock as usize).is_some_and(|segment| segment.planned);
        let configurations = || {
            std::iter::once(trajectory.home.clone()).chain(crate::plan::replay_sample_iter(&replayed).filter(on_trajectory).map(|(_, q)| q))
        };
        let gravity = opts.engine.gravity_m_s2;
        if progress.stopped() {
            return Err(Error::Stopped);
        }
        progress.stage(&format!("running the engines ({:.1} s simulated)", timed.duration_s()), None);
        // The engines are independent and each deterministic: running them side by side changes
        // no number. Each also measures the static load where it can cross-check ours.
        let selected: Vec<&dyn crate::engine::Engine> = opts.engines.selected().collect();
        let results: Vec<Result<(EngineRuns, Option<crate::engine::StaticLoad>), crate::engine::EngineError>> = selected
            .par_iter()
            .map(|engine| {
                let runs = EngineRuns {
                    dynamic: engine.run(model, scenario, world, timed, &gains, &opts.engine)?,
                    replay: engine.replay(model, scenario, world, &samples, &opts.engine)?,
                };
                let load = engine.static_load(model, &mut configurations(), gravity).transpose()?;
                Ok((runs, load))
            })
            .collect();
        let mut engines = Vec::with_capacity(results.len());
        let mut static_load = None;
        for result in results {
            let (mut runs, load) = result?;
            crate::engine::confirm_contacts(model, world, &mut runs.dynamic.contacts);
            crate::engine::measure_reference(model, world, timed, &mut runs.dynamic.contacts);
            crate::engine::confirm_contacts(model, world, &mut runs.replay.contacts);
            static_load = static_load.or(load);
            engines.push(runs);
        }
        let static_load = match static_load {
            Some(load) => load,
            None => crate::engine::static_load_ours(model, configurations(), gravity)?,
        };
        Ok(Self {
            trajectory: Some(trajectory),
            replayed,
            engines,
            static_load: Some(static_load),
            gains: Some(gains),
            loss_terms,
        })
    }
}

/// Per goal, the paper's loss terms at the IK solution that minimises them.
fn task_loss_terms(
    model: &Model,
    world: &collide::CollisionWorld,
    scenario: &crate::scenario::Scenario,
    solutions: &[crate::ik::GoalSolutions],
) -> Vec<Option<crate::ik::LossTerms>> {
    scenario
        .goals
        .iter()
        .zip(solutions)
        .map(|(goal, found)| {
            found
                .solutions
                .iter()
                .map(|s| crate::ik::paper_loss_terms(model, world, goal, &s.q))
                .min_by(|a, b| a.weighted().total_cmp(&b.weighted()))
        })
        .collect()
}

/// Per goal, the configuration the report judges: the one the trajectory reached, else IK's best
/// solution.
fn goal_configuration<'a>(
    index: usize,
    found: &'a crate::ik::GoalSolutions,
    trajectory: Option<&'a crate::plan::Trajectory>,
) -> Option<&'a [f64]> {
    let reached = trajectory.and_then(|t| match t.steps.get(index) {
        Some(crate::plan::GoalStep::Reached { q, .. }) => Some(q.as_slice()),
        _ => None,
    });
    reached.or_else(|| found.solutions.first().map(|s| s.q.as_slice()))
}

/// Per goal, the smallest distance of each kind of pair (obstacles, self, floor) at its
/// configuration ([`goal_configuration`]), every checked pair measured exactly.
fn goal_clearances_by_kind(
    model: &Model,
    world: &collide::CollisionWorld,
    solutions: &[crate::ik::GoalSolutions],
    trajectory: Option<&crate::plan::Trajectory>,
) -> Vec<Option<collide::ClearanceByKind>> {
    let mut ws = model.workspace();
    let mut out = collide::Distances::new();
    solutions
        .iter()
        .enumerate()
        .map(|(index, found)| {
            let q = goal_configuration(index, found, trajectory)?;
            model.forward(q, &mut ws);
            Some(collide::clearance_by_kind(world, &ws.link_in_world, &mut out))
        })
        .collect()
}

/// Per goal, the exact clearance of its configuration ([`goal_configuration`]) and the pair that
/// sets it.
fn goal_clearances(
    model: &Model,
    world: &collide::CollisionWorld,
    solutions: &[crate::ik::GoalSolutions],
    trajectory: Option<&crate::plan::Trajectory>,
    certify: crate::plan::CertifyOptions,
) -> Vec<Option<crate::plan::SegmentPoint>> {
    let mut checker = crate::plan::SegmentChecker::new(model, world, certify);
    solutions
        .iter()
        .enumerate()
        .map(|(index, found)| checker.clearance(goal_configuration(index, found, trajectory)?))
        .collect()
}
