//! The paper's workflow in one call, per task: candidates (the catalog brute force, the GA, or
//! any designs a sweep takes), the reach-only filter (a sweep of the candidates, ranked tasks
//! solved first), fine-tuning of the best `top` (Adam on free and economic designs, the best
//! module swap on modular ones; a result that loses ground is not kept), the full validation of
//! each with its HTML report and pictures, and one HTML summary of the batch.

mod summary;

pub use summary::summary_html;

use crate::error::Error as RunError;
use crate::optimize::{self, Fused, OptimizeOptions};
use crate::pipeline::{Loaded, ValidateOptions};
use crate::progress::Progress;
use crate::report::Report;
use crate::sweep::inputs::{self, DesignEntry, ScenarioEntry};
use crate::sweep::{self, ga, SweepMode, SweepOptions};
use std::path::{Path, PathBuf};

/// Where a workflow's candidates come from.
#[derive(Debug, Clone)]
pub enum Candidates {
    /// The paper's GA over the 6-slot catalog, on each task; every design it evaluated is a
    /// candidate.
    Ga(ga::GaOptions),
    /// Design arguments as `sweep` takes them (`catalog:modular6`, folders, globs, files,
    /// `timor:SET@N`).
    Designs(Vec<String>),
}

/// A workflow's settings.
#[derive(Debug, Clone)]
pub struct WorkflowOptions {
    /// The candidates.
    pub candidates: Candidates,
    /// How many of the reach-only ranking go on to fine-tuning and full validation.
    pub top: usize,
    /// Seed of IK, the optimizer and the planner.
    pub seed: u64,
    /// The folder everything is written into.
    pub out: PathBuf,
    /// Replace the files of an earlier workflow in `out`.
    pub force: bool,
    /// The full validation's settings (engines, planner).
    pub validate: ValidateOptions,
}

/// One design that reached the end of a task's workflow.
#[derive(Debug, Clone)]
pub struct Finalist {
    /// Its place in the reach-only ranking, from 1.
    pub rank: usize,
    /// The candidate's id.
    pub candidate: String,
    /// Its reach-only record.
    pub reach: sweep::record::Record,
    /// What fine-tuning made of it (`the tuned design (...)`, `the original design, kept: ...`).
    pub refined: String,
    /// The design file written (`None` for robot files, validated as they are).
    pub design_file: Option<PathBuf>,
    /// The full validation's report.
    pub report: Report,
    /// The HTML report, relative to the workflow's folder.
    pub report_html: PathBuf,
    /// The scene picture (PNG), relative to the workflow's folder.
    pub picture: PathBuf,
}

/// One task's workflow.
#[derive(Debug, Clone)]
pub struct TaskOutcome {
    /// The task's scenario id.
    pub scenario: String,
    /// Candidates and how they were made.
    pub candidates: usize,
    /// Where they came from, in words.
    pub source: String,
    /// The finalists, by reach-only rank.
    pub finalists: Vec<Finalist>,
    /// Wall time (s).
    pub seconds: f64,
}

/// Why a workflow stopped.
#[derive(Debug, thiserror::Error)]
pub enum WorkflowError {
    /// A run, a load, a write.
    #[error(transparent)]
    Run(#[from] RunError),
    /// The candidates' sweep or the GA.
    #[error(transparent)]
    Sweep(#[from] crate::sweep::SweepError),
    /// A fine-tuning.
    #[error(transparent)]
    Optimize(#[from] optimize::OptimizeError),
    /// A design file the workflow wrote does not read back.
    #[error(transparent)]
    Design(#[from] crate::design::DesignError),
    /// A picture.
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    /// The folder holds an earlier workflow.
    #[error("{0}: a workflow was written here; pass --force to replace it")]
    Exists(PathBuf),
}

type Error = WorkflowError;

/// A folder name for `id`: letters, digits, `-`, `_` and `.` kept, the rest `_`.
fn folder_name(id: &str) -> String {
    id.chars()
        .map(|c| if c.is_ascii_alphanumeric() || "-_.".contains(c) { c } else { '_' })
        .collect()
}

/// Runs the workflow on every task and writes `summary.html` into `opts.out`.
///
/// # Errors
/// The stages' errors (an unreadable task or candidate, a failed write), each naming its file.
pub fn run(tasks: &[String], opts: &WorkflowOptions, progress: &dyn Progress) -> Result<Vec<TaskOutcome>, Error> {
    let scenarios = inputs::resolve_scenarios(tasks)?;
    // Given designs are read once, before any task; the GA runs on each task.
    let pool = match &opts.candidates {
        Candidates::Designs(arguments) => Pool::Designs(inputs::resolve_designs(arguments, &Default::default())?),
        Candidates::Ga(ga_options) => Pool::Ga(ga_options),
    };
    let summary_path = opts.out.join("summary.html");
    if summary_path.exists() && !opts.force {
        return Err(WorkflowError::Exists(opts.out.clone()));
    }
    let mut outcomes = Vec::with_capacity(scenarios.len());
    for scenario in &scenarios {
        outcomes.push(task(scenario, &pool, opts, progress)?);
    }
    crate::pipeline::write_files_into(&opts.out, &[("summary.html".to_string(), summary_html(&outcomes).into_bytes())])?;
    Ok(outcomes)
}

/// Where a task's candidates come from, once the given designs are read.
enum Pool<'a> {
    /// The designs given, the same for every task.
    Designs(Vec<DesignEntry>),
    /// The GA's, run on each task.
    Ga(&'a ga::GaOptions),
}

fn reach_mode(seed: u64) -> SweepMode {
    SweepMode::ReachOnly {
        ik: crate::ik::IkOptions {
            seed,
            search_boxes: crate::ik::SWEEP_SEARCH_BOXES,
            ..Default::default()
        },
    }
}

fn task(scenario: &ScenarioEntry, pool: &Pool, opts: &WorkflowOptions, progress: &dyn Progress) -> Result<TaskOutcome, Error> {
    let started = std::time::Instant::now();
    let dir = opts.out.join(folder_name(&scenario.scenario.name));
    let (designs, source) = match pool {
        Pool::Designs(designs) => (designs.clone(), "the designs given".to_string()),
        Pool::Ga(ga_options) => {
            let result = ga::run(scenario, &ga::mode(opts.seed), ga_options, progress)?;
            let designs: Vec<DesignEntry> = result
                .evaluated
                .iter()
                .filter_map(|id| match crate::design::catalog::parse_id(id) {
                    Ok(Some(crate::design::catalog::CatalogId::Modular(slots))) => Some(inputs::catalog_entry(&slots)),
                    _ => None,
                })
                .collect();
            let source = format!(
                "every design the GA evaluated ({} x {} generations, seed {})",
                ga_options.population, ga_options.generations, ga_options.seed
            );
            (designs, source)
        }
    };
    progress.stage(&format!("reach-only filter on {}", scenario.id), Some(designs.len() as u64));
    let sweep_opts = SweepOptions {
        mode: reach_mode(opts.seed),
        out: Some(dir.join("candidates")),
        force: opts.force,
        shard: None,
        reference: None,
        top: opts.top.max(10),
        ranking: sweep::table::Ranking::SolvedFirst,
        stop: None,
    };
    let swept = sweep::run(&designs, std::slice::from_ref(scenario), &sweep_opts, progress)?;
    let mut finalists = Vec::new();
    for (k, id) in swept.ranking.iter().take(opts.top).enumerate() {
        let Some(entry) = designs.iter().find(|d| &d.id == id) else {
            continue;
        };
        let Some(reach) = swept.records.iter().find(|r| &r.design == id).cloned() else {
            continue;
        };
        progress.stage(&format!("fine-tuning and validating {id}"), None);
        finalists.push(finalist(k + 1, entry, reach, scenario, &dir, opts)?);
    }
    Ok(TaskOutcome {
        scenario: scenario.scenario.name.clone(),
        candidates: designs.len(),
        source,
        finalists,
        seconds: started.elapsed().as_secs_f64(),
    })
}

fn finalist(
    rank: usize,
    entry: &DesignEntry,
    reach: sweep::record::Record,
    scenario: &ScenarioEntry,
    dir: &Path,
    opts: &WorkflowOptions,
) -> Result<Finalist, Error> {
    let loaded = entry.load();
    let stem = format!("{rank:02}-{}", folder_name(&loaded.model.name));
    let design_path = dir.join(format!("{stem}.json"));
    let scenario_value = &scenario.scenario;
    let validate = &opts.validate;
    let (refined, final_loaded, design_file) = match loaded.design.clone() {
        Some(design) => {
            let (text, said) = refine(&design, &loaded, &design_path, scenario_value, opts, validate)?;
            let chosen = crate::design::parse(&text, &design_path)?;
            let final_loaded = Loaded {
                model: crate::model::from_design(&chosen),
                design: Some(chosen),
            };
            crate::pipeline::write_files_into(dir, &[(format!("{stem}.json"), text.into_bytes())])?;
            (said, final_loaded, Some(design_path.clone()))
        }
        None => ("a robot file: nothing to tune, validated as it is".to_string(), loaded, None),
    };
    let input = design_file.clone().unwrap_or_else(|| PathBuf::from(&entry.id));
    let run_opts = crate::run::Options {
        kinematics_checks: 0,
        validate: validate.clone(),
        ..Default::default()
    };
    let (validation, report) = crate::run::validated(&input, final_loaded, scenario_value.clone(), &run_opts, &crate::progress::Silent)?;
    let pictures = crate::render::pictures(&validation, &report);
    let mut files = vec![(format!("{stem}.html"), crate::render::page(&validation, &report).into_bytes())];
    for picture in pictures.iter().filter(|p| p.name == "scene" || p.name == "clearance") {
        files.push((
            format!("{stem}-{}.png", picture.name),
            crate::render::png::to_png(&picture.name, &picture.svg)?,
        ));
    }
    crate::pipeline::write_files_into(dir, &files)?;
    let task_dir = PathBuf::from(folder_name(&scenario_value.name));
    Ok(Finalist {
        rank,
        candidate: entry.id.clone(),
        reach,
        refined,
        design_file,
        report,
        report_html: task_dir.join(format!("{stem}.html")),
        picture: task_dir.join(format!("{stem}-scene.png")),
    })
}

/// The design file to validate for `design` and what was done: the tuned design (free and
/// economic) or the best module swap (modular), where its full validation keeps the ground
/// the original holds; else the original.
fn refine(
    design: &crate::design::Design,
    loaded: &Loaded,
    path: &Path,
    scenario: &crate::scenario::Scenario,
    opts: &WorkflowOptions,
    validate: &ValidateOptions,
) -> Result<(String, String), Error> {
    let unchanged = |why: &str| {
        let description = format!("{} as it was: the workflow found nothing to tune in it", design.name);
        (crate::design::to_json(design, &description), format!("the original design: {why}"))
    };
    let Some(why) = optimize::nothing_to_tune(design) else {
        let optimize_opts = OptimizeOptions {
            seed: opts.seed,
            ..Default::default()
        };
        let tuned = optimize::tune(std::slice::from_ref(design), scenario, &optimize_opts, &mut Fused::cpu())?;
        let Some(t) = tuned.into_iter().next() else {
            return Ok(unchanged("the optimizer returned nothing"));
        };
        let (before, after) = optimize::before_and_after(path, loaded.clone(), path, &t.design, &t.configurations, scenario, validate)?;
        let choice = optimize::choose(design, t.text.clone(), "the tuned design", "tuning", &before, &after);
        return Ok((choice.text, choice.said));
    };
    if optimize::module_swaps(design).is_empty() {
        return Ok(unchanged(why));
    }
    let Some((what, neighbour, _, _)) = optimize::best_module_swap(design, scenario, &validate.ik)? else {
        return Ok(unchanged(&format!(
            "{why}; none of its module swaps beats it by the reach-only metric"
        )));
    };
    let (before, after) = optimize::before_and_after(path, loaded.clone(), path, &neighbour, &[], scenario, validate)?;
    let description = format!("{} with {what}: the best module swap found by the workflow", design.name);
    let candidate = crate::design::to_json(&neighbour, &description);
    let choice = optimize::choose(
        design,
        candidate,
        &format!("the design with {what}"),
        "its best module swap",
        &before,
        &after,
    );
    Ok((choice.text, choice.said))
}
