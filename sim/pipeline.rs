//! Runs the stages in order; no domain logic of its own.

use crate::error::Error;
use crate::model::{self, Model, UrdfOptions};
use crate::{collide, design, export};
use std::path::{Path, PathBuf};

/// How to read the robot a run is about.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// URDF: first link of the chain (default: the root).
    pub base_link: Option<String>,
    /// URDF: last link of the chain; MJCF: a body or site holding the tool frame (default: the
    /// arm's tool frame, see [`crate::model::from_urdf`] and [`crate::model::from_mjcf`]).
    pub tip_link: Option<String>,
    /// URDF: roots for `package://` URIs, searched before `ROS_PACKAGE_PATH`.
    pub package_paths: Vec<PathBuf>,
}

/// What kind of robot description a file is, from its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// Design JSON.
    Design,
    /// URDF.
    Urdf,
    /// MJCF (`.xml`, `.mjcf`), loaded through MuJoCo.
    Mjcf,
}

/// The kind of a robot description file.
///
/// # Errors
/// [`Error::UnknownInput`] for an extension other than `.json`, `.urdf`, `.xml` or `.mjcf`.
pub fn input_kind(path: &Path) -> Result<InputKind, Error> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("json") => Ok(InputKind::Design),
        Some("urdf") => Ok(InputKind::Urdf),
        Some("xml" | "mjcf") => Ok(InputKind::Mjcf),
        _ => Err(Error::UnknownInput { path: path.to_path_buf() }),
    }
}

/// A loaded robot: the model, and the design when it came from one.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The model every stage uses.
    pub model: Model,
    /// The validated design, for design files.
    pub design: Option<design::Design>,
}

/// Reads a design JSON, a URDF or an MJCF file into a model.
///
/// # Errors
/// The design or model stage's error, naming the file and the field or element.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Loaded, Error> {
    match input_kind(path)? {
        InputKind::Design => {
            let design = design::load(path)?;
            Ok(Loaded {
                model: model::from_design(&design),
                design: Some(design),
            })
        }
        InputKind::Urdf => {
            let urdf = UrdfOptions {
                base_link: opts.base_link.clone(),
                tip_link: opts.tip_link.clone(),
                package_paths: opts.package_paths.clone(),
            };
            Ok(Loaded {
                model: model::from_urdf(path, &urdf)?,
                design: None,
            })
        }
        InputKind::Mjcf => {
            // The base of an MJCF chain is where its first joint hangs; a URDF-style base link
            // would be silently meaningless.
            if opts.base_link.is_some() {
                return Err(model::ModelError::UnsupportedMjcf {
                    path: path.to_path_buf(),
                    element: "--base".into(),
                    problem: "is for URDF input; an MJCF chain runs from the body holding its first joint".into(),
                }
                .into());
            }
            Ok(Loaded {
                model: model::from_mjcf_to(path, opts.tip_link.as_deref())?,
                design: None,
            })
        }
    }
}

/// Reads a design JSON, a URDF or an MJCF file into a model.
///
/// # Errors
/// As [`load`].
pub fn load_model(path: &Path, opts: &LoadOptions) -> Result<Model, Error> {
    Ok(load(path, opts)?.model)
}

/// Reads and validates a scenario file.
///
/// # Errors
/// [`Error::Scenario`] naming the file and the field.
pub fn load_scenario(path: &Path) -> Result<crate::scenario::Scenario, Error> {
    Ok(crate::scenario::load(path)?)
}

/// Scenario loaded when none is given, relative to the current directory, when it exists there.
pub const DEFAULT_SCENARIO: &str = "scenarios/course.json";

/// The scenario at `path`; with none, [`DEFAULT_SCENARIO`] when that file exists under the
/// current directory, else the same course built in.
///
/// # Errors
/// [`Error::Scenario`] naming the file and the field.
pub fn scenario_or_default(path: Option<&Path>) -> Result<crate::scenario::Scenario, Error> {
    match path {
        Some(path) => load_scenario(path),
        None if Path::new(DEFAULT_SCENARIO).is_file() => load_scenario(Path::new(DEFAULT_SCENARIO)),
        // The committed course is this generator's output, byte for byte (tests/scenario.rs).
        None => Ok(crate::scenario::generate::course(crate::scenario::generate::COURSE_SEED)),
    }
}

/// Writes text to `path` atomically (see [`crate::files::write_atomic`]), replacing an existing
/// output but never a file this process has read (the design, the scenario, a mesh, a file an
/// MJCF includes, or a link to any of them).
///
/// # Errors
/// [`Error::WouldOverwriteInput`] or [`Error::Write`] (the old file is then intact).
pub fn write_output(path: &Path, text: &str) -> Result<(), Error> {
    write_output_bytes(path, text.as_bytes())
}

/// [`write_output`] for bytes (a PNG).
///
/// # Errors
/// As [`write_output`].
pub fn write_output_bytes(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    crate::files::write_atomic(path, bytes, true).map_err(|error| match error {
        crate::files::WriteError::Input => Error::WouldOverwriteInput { path: path.to_path_buf() },
        other => Error::Write {
            path: path.to_path_buf(),
            source: std::io::Error::other(other.to_string()),
        },
    })
}

/// Writes `files` (file name, bytes) into the folder `dir`, creating it: only these names are
/// written (a file of the same name is replaced, never an input of this run); anything else in
/// the folder is left alone. Returns the paths written, in order.
///
/// # Errors
/// [`Error::PictureFolder`] when `dir` is not a folder or a name in it is a folder,
/// [`Error::WouldOverwriteInput`] or [`Error::Write`] as [`write_output`].
pub fn write_files_into(dir: &Path, files: &[(String, Vec<u8>)]) -> Result<Vec<PathBuf>, Error> {
    let folder_error = |message: String| Error::PictureFolder {
        path: dir.to_path_buf(),
        message,
    };
    if dir.exists() && !dir.is_dir() {
        return Err(folder_error("it exists and is not a folder".into()));
    }
    std::fs::create_dir_all(dir).map_err(|e| folder_error(format!("cannot create it: {e}")))?;
    let mut written = Vec::with_capacity(files.len());
    for (name, bytes) in files {
        let path = dir.join(name);
        if path.is_dir() {
            return Err(folder_error(format!("{name} in it is a folder")));
        }
        write_output_bytes(&path, bytes)?;
        written.push(path);
    }
    Ok(written)
}

/// MJCF text for a model with default export options.
///
/// # Errors
/// [`Error::Export`].
pub fn mjcf_of(model: &Model) -> Result<String, Error> {
    Ok(export::to_mjcf(model, &export::MjcfOptions::default())?)
}

/// MJCF text of the whole scene: the model at the scenario's base pose, the obstacles as static
/// geoms named as in the scenario, the floor plane `floor`, and a site `goal/K` at each goal's
/// frame, so MuJoCo's viewer shows what the run checks.
///
/// # Errors
/// [`Error::Export`] (e.g. an obstacle named like a link geom).
pub fn scene_mjcf(model: &Model, scenario: &crate::scenario::Scenario) -> Result<String, Error> {
    let placed = model.placed(&scenario.world_from_base);
    let world_colliders = scenario
        .obstacles
        .iter()
        .map(|o| crate::model::Collider {
            link_from_shape: o.world_from_shape,
            shape: o.shape.clone(),
            label: o.name.clone(),
        })
        .collect();
    let world_sites = scenario
        .goals
        .iter()
        .enumerate()
        .map(|(k, goal)| {
            let pose = nalgebra::Isometry3::from_parts(goal.position.into(), goal.rotation);
            (format!("goal/{k}"), pose)
        })
        .collect();
    let opts = export::MjcfOptions {
        world_colliders,
        floor_height: scenario.floor.map(|f| f.height),
        world_sites,
        ..Default::default()
    };
    Ok(export::to_mjcf(&placed, &opts)?)
}

/// The exact collision world of a placed model in a scenario, with the model's structurally
/// overlapping self pairs excluded (each with its reason, see [`collide::structural_overlaps`])
/// plus `extra` exclusions (e.g. from an SRDF).
///
/// # Errors
/// [`Error::Collide`] when the geometry cannot be built or an exclusion names an unknown link.
pub fn collision_world(
    placed: &Model,
    scenario: &crate::scenario::Scenario,
    extra: &[collide::ExcludedPair],
) -> Result<collide::CollisionWorld, Error> {
    let structural = collide::structural_overlaps(placed, &collide::StructuralOptions::default())?;
    let mut excluded_pairs = structural.pairs;
    excluded_pairs.extend_from_slice(extra);
    let opts = collide::CollideOptions {
        excluded_pairs,
        excluded_shapes: structural.shapes,
        structural_allowances: structural.allowances,
    };
    Ok(collide::world(placed, scenario, &opts)?)
}

/// Which physics engines a validation runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Engines {
    /// rapier (multibody, f32).
    pub rapier: bool,
    /// MuJoCo (the official library).
    pub mujoco: bool,
}

impl Engines {
    /// The engines named (`rapier`, `mujoco`); no name gives no engine.
    ///
    /// # Errors
    /// The first name that is not an engine.
    pub fn from_names<'a>(names: impl IntoIterator<Item = &'a str>) -> Result<Self, String> {
        let mut engines = Self {
            rapier: false,
            mujoco: false,
        };
        for name in names {
            match name {
                "rapier" => engines.rapier = true,
                "mujoco" => engines.mujoco = true,
                other => return Err(other.to_string()),
            }
        }
        Ok(engines)
    }

    /// The names, comma-separated (`rapier,mujoco`), or `none`.
    pub fn name(self) -> String {
        match (self.rapier, self.mujoco) {
            (true, true) => "rapier,mujoco".into(),
            (true, false) => "rapier".into(),
            (false, true) => "mujoco".into(),
            (false, false) => "none".into(),
        }
    }
}

impl std::str::FromStr for Engines {
    type Err = String;

    /// A comma-separated list of engines (`rapier,mujoco`, `rapier`, `mujoco`), or `none`; the
    /// error names what is not an engine and what was expected.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let names: Vec<&str> = if text.trim() == "none" {
            Vec::new()
        } else {
            text.split(',').map(str::trim).collect()
        };
        Self::from_names(names).map_err(|other| format!("unknown engine `{other}`; expected rapier,mujoco, rapier, mujoco or none"))
    }
}

impl Default for Engines {
    fn default() -> Self {
        Self {
            rapier: true,
            mujoco: true,
        }
    }
}

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
}

/// Runs every stage on a loaded robot and a scenario: collision world, IK, trajectory with the
/// certified continuous check, the engines' dynamic runs and kinematic replays (rapier and
/// MuJoCo in parallel), and the static load.
///
/// # Errors
/// [`Error::NameClash`] for an obstacle named like a robot link, [`Error::Collide`] for geometry
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
    let input_warnings: Vec<String> = loaded.model.diagnostics.iter().map(ToString::to_string).collect();
    let model = loaded.model.placed(&scenario.world_from_base);
    let world = collision_world(&model, &scenario, &opts.excluded_pairs)?;
    progress.stage("solving IK", Some(scenario.goals.len() as u64));
    let ik = crate::ik::IkOptions {
        clearance_m: opts.certify.threshold_m,
        ..opts.ik.clone()
    };
    let solutions = crate::ik::solve_goals_counted(&model, &scenario, Some(&world), &ik, &|| progress.advance());
    let proofs: Vec<Option<String>> = scenario
        .goals
        .iter()
        .zip(&solutions)
        .map(|(goal, found)| {
            if found.reached() {
                return None;
            }
            crate::ik::unreachable_proof(&model, &world, goal).or_else(|| {
                found
                    .proof
                    .is_none()
                    .then(|| crate::ik::last_joints_beyond_reach(&model, goal))
                    .flatten()
            })
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
    if opts.reach_only {
        let loss_terms = scenario
            .goals
            .iter()
            .zip(&solutions)
            .map(|(goal, found)| {
                found
                    .solutions
                    .first()
                    .map(|s| crate::ik::paper_loss_terms(&model, &world, goal, &s.q))
            })
            .collect();
        return Ok(Validation {
            pairs: world.pairs().to_vec(),
            excluded: world.excluded().to_vec(),
            excluded_shapes: world.excluded_shapes().to_vec(),
            structural_allowances: world.structural_allowances().to_vec(),
            goal_clearances: goal_clearances(&model, &world, &solutions, None, opts.certify),
            input_warnings,
            kinematics_check: None,
            model,
            design: loaded.design,
            scenario,
            solutions,
            proofs,
            trajectory: None,
            replayed: Vec::new(),
            rapier: None,
            mujoco: None,
            static_load: None,
            gains: None,
            loss_terms,
            task_loss_terms,
            settings,
        });
    }
    progress.stage(
        "planning the trajectory (certified continuous check)",
        Some(scenario.goals.len() as u64),
    );
    let trajectory_options = crate::plan::TrajectoryOptions {
        certify: opts.certify,
        ik,
        timing: None,
        planner: crate::plan::PlannerOptions {
            seed: opts.ik.seed,
            ..opts.planner
        },
    };
    let trajectory = crate::plan::plan_counted(&model, &scenario, &world, &solutions, &trajectory_options, &|| progress.advance())?;
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
            chosen.map(|q| crate::ik::paper_loss_terms(&model, &world, goal, q))
        })
        .collect();
    // The engines replay every sample; without them only the static load reads them, one at a
    // time (tens of thousands of goals make millions).
    let samples = if opts.engines.rapier || opts.engines.mujoco {
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
        let limits = crate::plan::TimingLimits::of(&model);
        still = crate::plan::TimedPath::through(&[trajectory.home.clone(), trajectory.home.clone()], &[None], &limits);
        &still
    } else {
        &trajectory.timed
    };
    let gains = crate::engine::gains(&model, timed, &gain_options);
    let run_rapier = || -> Result<Option<EngineRuns>, crate::engine::EngineError> {
        if !opts.engines.rapier {
            return Ok(None);
        }
        Ok(Some(EngineRuns {
            dynamic: crate::engine::run_rapier(&model, &scenario, &world, timed, &gains, &opts.engine)?,
            replay: crate::engine::replay_rapier(&model, &scenario, &world, &samples, &opts.engine)?,
        }))
    };
    // The static load along the trajectory only: a blocked goal's attempt is not a motion the
    // robot makes.
    let on_trajectory = |(clock, _): &(f64, Vec<f64>)| replayed.get(*clock as usize).is_some_and(|segment| segment.planned);
    let configurations =
        || std::iter::once(trajectory.home.clone()).chain(crate::plan::replay_sample_iter(&replayed).filter(on_trajectory).map(|(_, q)| q));
    let gravity = opts.engine.gravity_m_s2;
    let run_mujoco = || -> Result<(Option<EngineRuns>, crate::engine::StaticLoad), crate::engine::EngineError> {
        if !opts.engines.mujoco {
            return Ok((None, crate::engine::static_load_without_mujoco(&model, configurations(), gravity)?));
        }
        let runs = EngineRuns {
            dynamic: crate::engine::run_mujoco(&model, &scenario, &world, timed, &gains, &opts.engine)?,
            replay: crate::engine::replay_mujoco(&model, &scenario, &world, &samples, &opts.engine)?,
        };
        Ok((Some(runs), crate::engine::static_load(&model, configurations(), gravity)?))
    };
    progress.stage(&format!("running the engines ({:.1} s simulated)", timed.duration_s()), None);
    // The engines are independent and each deterministic: running them side by side changes
    // no number.
    let (rapier, mujoco) = rayon::join(run_rapier, run_mujoco);
    let mut rapier = rapier?;
    let (mut mujoco, static_load) = mujoco?;
    for runs in rapier.iter_mut().chain(mujoco.iter_mut()) {
        crate::engine::confirm_contacts(&model, &world, &mut runs.dynamic.contacts);
        crate::engine::measure_reference(&model, &world, timed, &mut runs.dynamic.contacts);
        crate::engine::confirm_contacts(&model, &world, &mut runs.replay.contacts);
    }
    Ok(Validation {
        pairs: world.pairs().to_vec(),
        excluded: world.excluded().to_vec(),
        excluded_shapes: world.excluded_shapes().to_vec(),
        structural_allowances: world.structural_allowances().to_vec(),
        goal_clearances: goal_clearances(&model, &world, &solutions, Some(&trajectory), opts.certify),
        input_warnings,
        kinematics_check: None,
        model,
        design: loaded.design,
        scenario,
        solutions,
        proofs,
        trajectory: Some(trajectory),
        replayed,
        rapier,
        mujoco,
        static_load: Some(static_load),
        gains: Some(gains),
        loss_terms,
        task_loss_terms,
        settings,
    })
}

/// Per goal, the exact clearance of its configuration and the pair that sets it: the one the
/// trajectory reached, else IK's best solution.
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
        .map(|(index, found)| {
            let reached = trajectory.and_then(|t| match t.steps.get(index) {
                Some(crate::plan::GoalStep::Reached { q, .. }) => Some(q.as_slice()),
                _ => None,
            });
            let q = reached.or_else(|| found.solutions.first().map(|s| s.q.as_slice()))?;
            checker.clearance(q)
        })
        .collect()
}
