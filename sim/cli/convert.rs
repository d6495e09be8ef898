//! `validate-design convert`: a scenario or a Timor / CoBRA task written in either format.

use proving_ground::scenario::{self, ScenarioError};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub(crate) struct ConvertArgs {
    /// The scenario or Timor task to read (the format is told by its keys).
    input: PathBuf,
    /// The format to write.
    #[arg(long, value_name = "FORMAT")]
    to: Format,
    /// Output file.
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// Replace an existing file.
    #[arg(long)]
    force: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Format {
    /// A proving-ground scenario.
    Scenario,
    /// A Timor / CoBRA task.
    Timor,
}

/// `validate-design convert INPUT --to FORMAT --out FILE`: reads, says what was left unchecked,
/// writes.
pub(crate) fn command(args: &ConvertArgs) -> Result<ExitCode, ScenarioError> {
    let scenario = scenario::load(&args.input)?;
    for note in &scenario.notes {
        eprintln!("warning: {}: {note}", args.input.display());
    }
    match args.to {
        Format::Scenario => scenario::save(&scenario, &args.out, args.force)?,
        Format::Timor => scenario::save_timor_task(&scenario, &args.out, args.force)?,
    }
    println!(
        "wrote {} ({}: {} obstacles, {} goals)",
        args.out.display(),
        scenario.name,
        scenario.obstacles.len(),
        scenario.goals.len()
    );
    Ok(ExitCode::SUCCESS)
}
