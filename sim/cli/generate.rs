//! `validate-design generate`: the scenario generators' outputs written as files.

use super::ToleranceArg;
use clap::ValueEnum;
use proving_ground::scenario::{self, generate, ScenarioError, Tolerance};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub(crate) struct GenerateArgs {
    /// Which generator.
    generator: Generator,
    /// Generator seed [default: cluttered 2025 (master seed), workspace 1000, course 3].
    #[arg(long, value_name = "N")]
    seed: Option<u64>,
    /// cluttered: the task number (its seed is derived from --seed and the task).
    #[arg(long, value_name = "K", conflicts_with = "all")]
    task: Option<usize>,
    /// cluttered: write all 36 tasks as OUT/task-00.json .. task-35.json.
    #[arg(long)]
    all: bool,
    /// workspace: number of poses [default: 1000].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=proving_ground::limits::MAX_GOALS as u64))]
    count: Option<u64>,
    /// workspace: box scale factor, 0.5 to 1.5 [default: 1].
    #[arg(long, value_name = "S")]
    scale: Option<f64>,
    /// workspace: how goal orientations are judged [default: pose].
    #[arg(long, value_name = "MODE")]
    tolerance: Option<ToleranceArg>,
    /// Output file (a folder with cluttered --all).
    #[arg(long, value_name = "PATH")]
    out: PathBuf,
    /// Replace existing files.
    #[arg(long)]
    force: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Generator {
    /// The paper's cluttered benchmark tasks: 8 goals, 8 sphere obstacles.
    Cluttered,
    /// The paper's workspace task: poses uniform in a 0.8 x 1.0 x 0.8 m box.
    Workspace,
    /// The course for the paper's real-world robot: 3 obstacles, 36 goals.
    Course,
}

/// `validate-design generate ...`: builds the scenarios and writes them.
pub(crate) fn command(args: &GenerateArgs) -> Result<ExitCode, ScenarioError> {
    let request = generate::Request {
        generator: match args.generator {
            Generator::Cluttered => generate::Generator::Cluttered,
            Generator::Workspace => generate::Generator::Workspace,
            Generator::Course => generate::Generator::Course,
        },
        seed: args.seed,
        task: args.task,
        all: args.all,
        count: args.count.map(|n| usize::try_from(n).unwrap_or(usize::MAX)),
        scale: args.scale,
        tolerance: args.tolerance.map(Tolerance::from),
        out: args.out.clone(),
        force: args.force,
    };
    for (path, scenario) in &generate::outputs(&request)? {
        scenario::save(scenario, path, args.force)?;
        println!(
            "wrote {} ({}: {} obstacles, {} goals)",
            path.display(),
            scenario.name,
            scenario.obstacles.len(),
            scenario.goals.len()
        );
    }
    Ok(ExitCode::SUCCESS)
}
