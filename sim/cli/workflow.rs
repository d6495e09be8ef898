//! `validate-design workflow`: the paper's workflow on tasks in one command.

use super::Failure;
use proving_ground::pipeline::{Engines, ValidateOptions};
use proving_ground::run::Outcome;
use proving_ground::sweep::ga::GaOptions;
use proving_ground::workflow::{self, Candidates, WorkflowOptions};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub(crate) struct WorkflowArgs {
    /// Tasks: scenario or Timor task files, folders, globs.
    #[arg(required = true, value_name = "TASK")]
    tasks: Vec<String>,
    /// Candidates: `ga` (the paper's GA over the 6-slot catalog, on each task), or designs as
    /// `sweep` takes them (`catalog:modular6` for the brute force, a folder of generated designs,
    /// `timor:SET@N`).
    #[arg(long, value_name = "DESIGNS", num_args = 1.., default_values_t = ["ga".to_string()])]
    candidates: Vec<String>,
    /// How many of the reach-only ranking are fine-tuned and validated in full.
    #[arg(long, value_name = "K", default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100))]
    top: u64,
    /// Seed of the GA, IK, the optimizer and the planner.
    #[arg(long, value_name = "N", default_value_t = 0)]
    seed: u64,
    /// Engines of the full validations.
    #[arg(long, value_name = "LIST", default_value_t = Engines::all())]
    engines: Engines,
    /// The folder everything goes into: per task the candidates' sweep, the finalists' design
    /// files, HTML reports and pictures; `summary.html` for the batch.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Replace an earlier workflow's files in --out.
    #[arg(long)]
    force: bool,
    /// Worker threads [default: the number of cores]; the results are the same for any number.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=256))]
    threads: Option<u64>,
    /// Print nothing but errors and the closing line.
    #[arg(long)]
    quiet: bool,
}

/// `validate-design workflow TASK... --out DIR`.
pub(crate) fn command(args: &WorkflowArgs) -> Result<ExitCode, Failure> {
    super::threads(args.threads);
    let candidates = if args.candidates == ["ga"] {
        Candidates::Ga(GaOptions {
            seed: args.seed,
            ..Default::default()
        })
    } else {
        Candidates::Designs(args.candidates.clone())
    };
    let opts = WorkflowOptions {
        candidates,
        top: usize::try_from(args.top).unwrap_or(usize::MAX),
        seed: args.seed,
        out: args.out.clone(),
        force: args.force,
        validate: ValidateOptions {
            engines: args.engines,
            ..ValidateOptions::seeded(args.seed)
        },
    };
    let progress = super::Bar::new("items", args.quiet, false);
    let outcomes = workflow::run(&args.tasks, &opts, &progress);
    progress.bar.finish_and_clear();
    let outcomes = outcomes?;
    let mut best = Outcome::Fail;
    for outcome in &outcomes {
        if !args.quiet {
            println!(
                "task {}: {} candidates ({}), {:.1} s",
                outcome.scenario, outcome.candidates, outcome.source, outcome.seconds
            );
        }
        for f in &outcome.finalists {
            let reached = f.report.goals.iter().filter(|g| g.outcome == "reached").count();
            if !args.quiet {
                println!(
                    "  {}. {}: reach-only {}/{}; {}; verdict {} ({reached}/{} reached); {}",
                    f.rank,
                    f.candidate,
                    f.reach.goals_solved,
                    f.reach.goals,
                    f.refined,
                    f.report.verdict.word,
                    f.report.goals.len(),
                    args.out.join(&f.report_html).display()
                );
            }
            best = best.min(Outcome::of(&f.report));
        }
    }
    println!("wrote {}", args.out.join("summary.html").display());
    // As a validation of the best finalist: 0 when one passes, 3 when the best is undecided.
    Ok(super::exit_code(best))
}
