//! One validation run, as `validate-design ROBOT` does it, for every front end: reads the robot
//! (design JSON, URDF or MJCF) and the scenario, applies an SRDF, `strict` and a tolerance
//! override, writes the exports asked for, checks our kinematics against MuJoCo's on the MJCF
//! export, and validates. The CLI parses its arguments into [`Options`], calls [`validate`] and
//! prints the [`Run`]; the library's users get the same run, byte for byte.
//!
//! ```no_run
//! use proving_ground::run::{validate, Options};
//! let opts = Options {
//!     scenario: Some("scenarios/cluttered/task-00.json".into()),
//!     ..Options::default()
//! };
//! let run = validate("designs/ur5e.json".as_ref(), &opts, &proving_ground::progress::Silent)?;
//! if let Some(report) = &run.report {
//!     println!("{}", proving_ground::report::verdict_line(&report.verdict));
//! }
//! # Ok::<(), proving_ground::error::Error>(())
//! ```

use crate::engine::KinematicsCheck;
use crate::error::Error;
use crate::export::{to_mjcf, to_urdf, MjcfOptions, UrdfExportOptions};
use crate::pipeline::{self, InputKind, LoadOptions, Loaded, ValidateOptions, Validation};
use crate::progress::Progress;
use crate::report::Report;
use crate::scenario::{Scenario, Tolerance};
use crate::srdf::SrdfExclusions;
use std::path::{Path, PathBuf};

/// How far a run goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Stop {
    /// Build the model (and write the exports): nothing is run.
    Described,
    /// Also check our kinematics against MuJoCo's; no scenario.
    KinematicsChecked,
    /// The whole validation on the scenario.
    #[default]
    Validated,
}

/// Files a run writes besides the report (never over a file the run read).
#[derive(Debug, Clone, Default)]
pub struct Exports {
    /// The model as URDF.
    pub urdf: Option<PathBuf>,
    /// The model as MJCF.
    pub mjcf: Option<PathBuf>,
    /// The MJCF export holds the scenario too (obstacles, floor, a site per goal).
    pub scene: bool,
}

/// Everything a run takes besides the robot file; every default is `validate-design`'s.
#[derive(Debug, Clone)]
pub struct Options {
    /// How the robot file is read (URDF base and tip, package paths; MJCF tip).
    pub load: LoadOptions,
    /// URDF: an SRDF whose `<disable_collisions>` pairs are left out.
    pub srdf: Option<PathBuf>,
    /// Warnings about the input are errors ([`Error::Strict`]).
    pub strict: bool,
    /// The scenario file; `None`: [`pipeline::scenario_or_default`].
    pub scenario: Option<PathBuf>,
    /// Judge every goal by this tolerance instead of the scenario's.
    pub tolerance: Option<Tolerance>,
    /// The home configuration (rad or m per joint) instead of the scenario's.
    pub home: Option<Vec<f64>>,
    /// Random configurations at which MuJoCo's kinematics are compared with ours (0 skips the
    /// check); seeded with the IK seed.
    pub kinematics_checks: usize,
    /// How far the run goes.
    pub stop: Stop,
    /// Files to write.
    pub exports: Exports,
    /// The validation's settings (IK, planner, engines, margin, reach-only).
    pub validate: ValidateOptions,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            load: LoadOptions::default(),
            srdf: None,
            strict: false,
            scenario: None,
            tolerance: None,
            home: None,
            kinematics_checks: DEFAULT_KINEMATICS_CHECKS,
            stop: Stop::default(),
            exports: Exports::default(),
            validate: ValidateOptions::default(),
        }
    }
}

/// Configurations of the kinematics check unless told otherwise.
pub const DEFAULT_KINEMATICS_CHECKS: usize = 100;

/// What a file of the run's is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Written {
    /// The URDF export.
    Urdf,
    /// The MJCF export (with the scene when asked).
    Mjcf,
    /// A mesh the URDF export names, written as STL beside it (no URDF reader loads its own
    /// file).
    Mesh,
}

/// What a run found, as far as it went.
#[derive(Debug)]
pub struct Run {
    /// The robot file.
    pub input: PathBuf,
    /// The model every stage used (at its own base; the validation holds it placed).
    pub model: crate::model::Model,
    /// The design's hardware cost (m), for design files.
    pub hardware_cost_m: Option<f64>,
    /// The SRDF's exclusions, when one was given.
    pub srdf: Option<SrdfExclusions>,
    /// The scenario, with the tolerance override applied.
    pub scenario: Scenario,
    /// The files written, in order.
    pub written: Vec<(Written, PathBuf)>,
    /// MuJoCo's kinematics against ours; a disagreement ends the run before the scenario.
    pub kinematics_check: Option<KinematicsCheck>,
    /// The validation, when the run got that far.
    pub validation: Option<Validation>,
    /// Its report.
    pub report: Option<Report>,
}

impl Run {
    /// How the run ended, for an exit code: the report's verdict, a kinematics disagreement, or
    /// a run that stopped before the scenario.
    pub fn outcome(&self) -> Outcome {
        if self.kinematics_check.as_ref().is_some_and(|c| !c.agree) {
            return Outcome::Fail;
        }
        self.report.as_ref().map_or(Outcome::Pass, Outcome::of)
    }
}

/// How a run ended, ordered from best to worst (the worst of several runs is their `max`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Outcome {
    /// The design passes (or the model was built and agrees with MuJoCo).
    Pass,
    /// Nothing failed, but the harness's limits left something open.
    Undecided,
    /// The design fails, proven (or MuJoCo disagrees with our kinematics).
    Fail,
}

impl Outcome {
    /// The outcome a report's verdict gives.
    pub fn of(report: &Report) -> Self {
        match (report.verdict.passed, report.verdict.word) {
            (true, _) => Outcome::Pass,
            (false, "UNDECIDED") => Outcome::Undecided,
            (false, _) => Outcome::Fail,
        }
    }
}

/// Runs what `validate-design input` runs with `opts`, telling `progress` the stages and the
/// notes about the input (the loader's warnings and choices, the SRDF's summary).
///
/// # Errors
/// The stages' errors, each naming the file and the field or element: an unreadable robot,
/// scenario or SRDF; [`Error::Strict`]; a failed export or write; MuJoCo refusing the model.
pub fn validate(input: &Path, opts: &Options, progress: &dyn Progress) -> Result<Run, Error> {
    let loaded = pipeline::load(input, &opts.load)?;
    let scenario = pipeline::scenario_or_default(opts.scenario.as_deref())?;
    validate_loaded(input, loaded, scenario, opts, progress)
}

/// [`validate`] without writing the exports: the caller writes [`export_files`] (`opts.exports`
/// is still checked, before any work, not to name a file the run read), for example in one
/// [`pipeline::OutputSet`] with outputs of its own, as the CLI does with the report's files.
///
/// # Errors
/// As [`validate`], but for the writes.
pub fn validate_unwritten(input: &Path, opts: &Options, progress: &dyn Progress) -> Result<Run, Error> {
    let loaded = pipeline::load(input, &opts.load)?;
    let scenario = pipeline::scenario_or_default(opts.scenario.as_deref())?;
    run_stages(input, loaded, scenario, opts, progress)
}

/// [`validate`] on a robot already read from `input` and a scenario already read
/// (`opts.load` and `opts.scenario` are not used).
///
/// # Errors
/// As [`validate`].
pub fn validate_loaded(input: &Path, loaded: Loaded, scenario: Scenario, opts: &Options, progress: &dyn Progress) -> Result<Run, Error> {
    let mut run = run_stages(input, loaded, scenario, opts, progress)?;
    // The exports as one set, after the run: a failure leaves every old file as it was.
    let mut set = pipeline::OutputSet::default();
    let written = stage_exports(&mut set, &run, &opts.exports)?;
    set.commit()?;
    run.written = written;
    Ok(run)
}

/// [`validate_loaded`] without the exports' writes.
fn run_stages(input: &Path, loaded: Loaded, mut scenario: Scenario, opts: &Options, progress: &dyn Progress) -> Result<Run, Error> {
    let model = &loaded.model;
    // Under `--strict` the warnings are the error below, which lists them: printed once.
    if !opts.strict {
        for diagnostic in &model.diagnostics {
            progress.warning(&diagnostic.to_string());
        }
        for note in &scenario.notes {
            progress.warning(&format!("warning: scenario {}: {note}", scenario.name));
        }
    }
    for choice in model.source.choices() {
        progress.info(&format!("{}: {choice}", input.display()));
    }
    let srdf = match &opts.srdf {
        Some(path) if pipeline::input_kind(input)? != InputKind::Urdf => {
            return Err(Error::Srdf(crate::srdf::SrdfError {
                path: path.clone(),
                element: "--srdf".into(),
                message: format!("is for URDF input; {} is not a URDF", input.display()),
            }))
        }
        Some(path) => Some(crate::srdf::exclusions(path, model)?),
        None => None,
    };
    if let Some(srdf) = &srdf {
        progress.info(&format!(
            "{}: {} self-collision pairs left out ({} entries not applied); listed with --describe and in the JSON report's criteria.excluded_pairs",
            srdf.path.display(),
            srdf.pairs.len(),
            srdf.notes.len()
        ));
    }
    if opts.strict && !model.diagnostics.is_empty() {
        let list = model.diagnostics.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n");
        return Err(Error::Strict {
            count: model.diagnostics.len(),
            list,
        });
    }
    if let Some(tolerance) = opts.tolerance {
        for goal in &mut scenario.goals {
            goal.tolerance = tolerance;
        }
    }
    if let Some(home) = &opts.home {
        scenario.home = Some(checked_home(model, home)?);
    }
    // Built only when checked (the export is rendered at the end): a sweep validates thousands
    // of designs.
    let mjcf = if kinematics_checked(opts) {
        to_mjcf(&with_placeholder_masses(model), &MjcfOptions::default())?
    } else {
        String::new()
    };
    // Refused now what the writes at the end would refuse, before any work.
    for path in [&opts.exports.urdf, &opts.exports.mjcf].into_iter().flatten() {
        if crate::files::is_input(path) {
            return Err(Error::WouldOverwriteInput { path: path.clone() });
        }
    }
    if opts.exports.mjcf.is_some() {
        if let Some((joint, link)) = model.massless_link() {
            return Err(crate::export::ExportError::MissingInertial {
                robot: model.name.clone(),
                link: link.name.clone(),
                joint: joint.name.clone(),
            }
            .into());
        }
    }
    let mut run = Run {
        input: input.to_path_buf(),
        model: model.clone(),
        hardware_cost_m: loaded.design.as_ref().map(crate::design::Design::hardware_cost),
        srdf,
        scenario,
        written: Vec::new(),
        kinematics_check: None,
        validation: None,
        report: None,
    };
    if kinematics_checked(opts) {
        let source = format!("the MJCF export of {}", input.display());
        let check = crate::engine::check_kinematics(model, &mjcf, &source, opts.kinematics_checks, opts.validate.ik.seed)?;
        let agree = check.agree;
        run.kinematics_check = Some(check);
        if !agree {
            return Ok(run);
        }
    }
    if opts.stop != Stop::Validated {
        return Ok(run);
    }
    let mut validate_options = opts.validate.clone();
    if let Some(srdf) = &run.srdf {
        validate_options.excluded_pairs.extend(srdf.pairs.iter().cloned());
    }
    let mut validation = pipeline::validate_with_progress(loaded, run.scenario.clone(), &validate_options, progress)?;
    validation.kinematics_check = run.kinematics_check.clone();
    run.report = Some(crate::report::build(&validation));
    run.validation = Some(validation);
    Ok(run)
}

/// A home given for `model` (`--home`): one value per joint, each within its joint's limits.
///
/// # Errors
/// [`Error::Option`] naming `home` and what does not fit.
fn checked_home(model: &crate::model::Model, home: &[f64]) -> Result<Vec<f64>, Error> {
    let invalid = |message: String| Error::Option { name: "home", message };
    if home.len() != model.dof() {
        return Err(invalid(format!(
            "{} values for a robot of {} joints ({}); expected one per joint",
            home.len(),
            model.dof(),
            model.joints.iter().map(|j| j.name.as_str()).collect::<Vec<_>>().join(", ")
        )));
    }
    for (joint, &value) in model.joints.iter().zip(home) {
        if let Some([low, high]) = joint.limits {
            if !(low..=high).contains(&value) {
                return Err(invalid(format!(
                    "{value} for joint `{}` is outside its limits [{low}, {high}]",
                    joint.name
                )));
            }
        }
    }
    Ok(home.to_vec())
}

/// Adds the export files `exports` asks of `run` ([`export_files`]) to `set`; what each is and
/// where it goes.
///
/// # Errors
/// A failed export, or a target [`pipeline::OutputSet::add`] refuses.
pub fn stage_exports(set: &mut pipeline::OutputSet, run: &Run, exports: &Exports) -> Result<Vec<(Written, PathBuf)>, Error> {
    let mut written = Vec::new();
    for (what, path, text) in export_files(run, exports)? {
        match (what, path.parent(), path.file_name()) {
            // The mesh folder beside the URDF is made as the set is written.
            (Written::Mesh, Some(dir), Some(name)) => {
                set.add_into(dir, &[(name.to_string_lossy().into_owned(), text)])?;
            }
            _ => set.add(&path, &text)?,
        }
        written.push((what, path));
    }
    Ok(written)
}

/// The export files `exports` asks of `run`: what each is, where it goes, its text. The scene
/// MJCF's keyframes are the home and, once validated, each goal's chosen configuration.
///
/// # Errors
/// A failed export ([`Error`] of the exporter).
pub fn export_files(run: &Run, exports: &Exports) -> Result<Vec<(Written, PathBuf, Vec<u8>)>, Error> {
    let mut files = Vec::new();
    if let Some(path) = &exports.urdf {
        // Meshes named relative to the file: it loads from any folder, and moves with them.
        let folder = std::path::absolute(path).ok().and_then(|p| p.parent().map(Path::to_path_buf));
        let stem = path
            .file_stem()
            .map_or_else(|| "robot".into(), |s| s.to_string_lossy().into_owned());
        let urdf = UrdfExportOptions {
            mesh_folder: folder.as_ref().map(|f| f.join(format!("{stem}-meshes"))),
            mesh_base: folder,
            ..Default::default()
        };
        files.push((Written::Urdf, path.clone(), to_urdf(&run.model, &urdf)?.into_bytes()));
        for (mesh, bytes) in crate::export::written_meshes(&run.model, &urdf) {
            files.push((Written::Mesh, mesh, bytes));
        }
    }
    if let Some(path) = &exports.mjcf {
        let text = if exports.scene {
            let home = run
                .report
                .as_ref()
                .and_then(|r| r.trajectory.as_ref())
                .map_or_else(|| crate::plan::home_for(&run.model, &run.scenario).0, |t| t.home.clone());
            let goals = run
                .report
                .iter()
                .flat_map(|r| r.goals.iter().enumerate())
                .filter_map(|(k, g)| Some((format!("goal/{k}"), g.chosen.clone()?)));
            let keys = std::iter::once(("home".to_string(), home)).chain(goals).collect();
            crate::export::scene_mjcf(&run.model, &run.scenario, keys)?
        } else {
            to_mjcf(&run.model, &MjcfOptions::default())?
        };
        files.push((Written::Mjcf, path.clone(), text.into_bytes()));
    }
    Ok(files)
}

/// [`validate_loaded`] to the end (`opts.stop` is not used): the validation and its report, as
/// an experiment needs them per run (a sweep pair, a snapshot, a fine-tuning's before and after).
///
/// # Errors
/// As [`validate`].
pub fn validated(
    input: &Path,
    loaded: Loaded,
    scenario: Scenario,
    opts: &Options,
    progress: &dyn Progress,
) -> Result<(Validation, Report), Error> {
    let opts = Options {
        stop: Stop::Validated,
        ..opts.clone()
    };
    let run = validate_loaded(input, loaded, scenario, &opts, progress)?;
    match (run.validation, run.report) {
        (Some(validation), Some(report)) => Ok((validation, report)),
        // Only a kinematics disagreement stops a whole run early.
        _ => Err(Error::Report {
            message: "MuJoCo's kinematics disagree with ours; nothing was validated".into(),
        }),
    }
}

/// `model` with a unit mass on each moving link that has none (a URDF without `<inertial>`),
/// for the MuJoCo kinematics check alone: MuJoCo refuses a massless moving body, and the
/// forward kinematics it is compared on do not depend on mass. Every other use of the model
/// (the engines, the torque check, an export) refuses it instead.
fn with_placeholder_masses(model: &crate::model::Model) -> std::borrow::Cow<'_, crate::model::Model> {
    if model.massless_link().is_none() {
        return std::borrow::Cow::Borrowed(model);
    }
    let mut placed = model.clone();
    for link in &mut placed.links[1..] {
        link.inertial.get_or_insert(crate::model::Inertial {
            mass: 1.0,
            com: nalgebra::Vector3::zeros(),
            inertia: nalgebra::Matrix3::identity() * 1e-3,
        });
    }
    std::borrow::Cow::Owned(placed)
}

/// Whether the run checks our kinematics against MuJoCo's.
fn kinematics_checked(opts: &Options) -> bool {
    opts.kinematics_checks > 0 && opts.stop != Stop::Described
}

/// The report as the JSON file `--json` writes: pretty, with a final newline.
///
/// # Errors
/// [`Error::Report`] (a bug: every field is plain data).
pub fn report_json(report: &Report) -> Result<String, Error> {
    serde_json::to_string_pretty(report)
        .map(|text| text + "\n")
        .map_err(|e| Error::Report { message: e.to_string() })
}

/// A run's options by the names `validate-design` gives them (`_` for `-`): what the CLI's
/// arguments and the Python API's keywords set, mapped to [`Options`] in one place. A name left
/// out keeps the default; every value is checked as the command line checks it.
#[derive(Debug, Clone, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Named {
    /// URDF: first link of the chain.
    pub base: Option<String>,
    /// URDF: last link of the chain; MJCF: a body or a site, the tool frame.
    pub tip: Option<String>,
    /// URDF: roots for `package://` mesh URIs.
    #[serde(default)]
    pub package_path: Vec<PathBuf>,
    /// URDF: an SRDF whose `<disable_collisions>` pairs are left out.
    pub srdf: Option<PathBuf>,
    /// Warnings about the input are errors.
    #[serde(default)]
    pub strict: bool,
    /// Judge every goal by this tolerance mode instead of the scenario's.
    pub tolerance: Option<Tolerance>,
    /// The home configuration, one value per joint (rad or m), instead of the scenario's.
    pub home: Option<Vec<f64>>,
    /// Random configurations of MuJoCo's kinematics check (0 skips it).
    pub mujoco_checks: Option<u64>,
    /// Seed of IK, of the planner and of the kinematics check.
    pub seed: Option<u64>,
    /// IK starts per goal.
    pub ik_seeds: Option<u64>,
    /// Boxes the joint-space search visits at most for an open goal.
    pub search_boxes: Option<usize>,
    /// Clearance (m) every configuration and segment must keep.
    pub margin: Option<f64>,
    /// Engine contacts shallower than this (m) are not counted.
    pub contact_depth: Option<f64>,
    /// Engines, as `--engines` reads them (`rapier,mujoco`, `mujoco`, `none`) or a list.
    pub engines: Option<Names>,
    /// The planner, as `--planner` reads it (`rrt-connect`, `straight`).
    pub planner: Option<String>,
    /// Random samples per goal before the planner reports `no_path`.
    pub plan_budget: Option<u64>,
    /// The paper's static metric only.
    #[serde(default)]
    pub reach_only: bool,
}

/// Names given as one comma-separated text or as a list.
#[derive(Debug, Clone, PartialEq, Eq, serde::Deserialize)]
#[serde(untagged)]
pub enum Names {
    /// `rapier,mujoco`.
    Text(String),
    /// `["rapier", "mujoco"]`; empty is none.
    List(Vec<String>),
}

impl Named {
    /// The run's options: these names set, the defaults elsewhere.
    ///
    /// # Errors
    /// [`Error::Option`] for a value out of its range (`ik_seeds` 1 to
    /// [`limits::MAX_IK_SEEDS`](crate::limits::MAX_IK_SEEDS), `plan_budget` 1 to
    /// [`limits::MAX_PLAN_BUDGET`](crate::limits::MAX_PLAN_BUDGET), a negative or non-finite
    /// `margin` or `contact_depth` or one over [`limits::MAX_LENGTH_M`](crate::limits::MAX_LENGTH_M),
    /// `mujoco_checks` over 100 000), an unknown engine or planner, or `reach_only` with
    /// `engines`, `planner` or `plan_budget`.
    pub fn options(&self) -> Result<Options, Error> {
        let invalid = |name: &'static str, message: String| Error::Option { name, message };
        let within = |name: &'static str, value: u64, low: u64, high: u64| {
            if (low..=high).contains(&value) {
                Ok(usize::try_from(value).unwrap_or(usize::MAX))
            } else {
                Err(invalid(name, format!("{value} is out of range; expected {low} to {high}")))
            }
        };
        let length = |name: &'static str, value: f64| {
            if value.is_finite() && value >= 0.0 {
                Ok(value)
            } else {
                Err(invalid(
                    name,
                    format!("{value} is not a length; expected a finite number of metres, 0 or more"),
                ))
            }
        };
        if self.reach_only {
            let planning = [
                ("engines", self.engines.is_some()),
                ("planner", self.planner.is_some()),
                ("plan_budget", self.plan_budget.is_some()),
            ];
            if let Some((name, _)) = planning.iter().find(|(_, given)| *given) {
                return Err(invalid(name, "does not apply with reach_only (no trajectory, no engines)".into()));
            }
        }
        let mut opts = Options {
            load: LoadOptions {
                base_link: self.base.clone(),
                tip_link: self.tip.clone(),
                package_paths: self.package_path.clone(),
            },
            srdf: self.srdf.clone(),
            strict: self.strict,
            tolerance: self.tolerance,
            home: self.home.clone(),
            ..Options::default()
        };
        if let Some(value) = self.home.iter().flatten().find(|v| !v.is_finite()) {
            return Err(invalid(
                "home",
                format!("{value} is not a joint value; expected finite numbers (rad or m)"),
            ));
        }
        if let Some(n) = self.mujoco_checks {
            opts.kinematics_checks = within("mujoco_checks", n, 0, 100_000)?;
        }
        let validate = &mut opts.validate;
        if let Some(seed) = self.seed {
            validate.ik.seed = seed;
            validate.planner.seed = seed;
        }
        if let Some(k) = self.ik_seeds {
            validate.ik.seeds = within("ik_seeds", k, 1, crate::limits::MAX_IK_SEEDS)?;
        }
        if let Some(boxes) = self.search_boxes {
            validate.ik.search_boxes = boxes;
        }
        if let Some(margin) = self.margin {
            validate.certify.threshold_m = length("margin", margin)?;
        }
        if let Some(depth) = self.contact_depth {
            validate.engine.contact_depth_m = length("contact_depth", depth)?;
        }
        match &self.engines {
            Some(Names::Text(text)) => validate.engines = text.parse().map_err(|message| invalid("engines", message))?,
            Some(Names::List(names)) => {
                validate.engines =
                    crate::engine::Engines::from_names(names.iter().map(String::as_str)).map_err(|message| invalid("engines", message))?;
            }
            None => {}
        }
        if let Some(planner) = &self.planner {
            validate.planner.kind = planner.parse().map_err(|message| invalid("planner", message))?;
        }
        if let Some(budget) = self.plan_budget {
            validate.planner.budget = within("plan_budget", budget, 1, crate::limits::MAX_PLAN_BUDGET)?;
        }
        validate.reach_only = self.reach_only;
        Ok(opts)
    }
}
