//! `validate-design snapshot`: a user's golden suite run and compared with its snapshots.

use super::Failure;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub(crate) struct SnapshotArgs {
    /// The suite file (JSON: snapshots, designs, scenarios, options).
    #[arg(long, value_name = "FILE")]
    suite: PathBuf,
    /// Record this run's snapshots (and delete orphans) instead of failing on a difference.
    #[arg(long)]
    accept: bool,
}

/// `validate-design snapshot --suite FILE [--accept]`.
pub(crate) fn command(args: &SnapshotArgs) -> Result<ExitCode, Failure> {
    use proving_ground::suite::{self, Outcome};
    let result = suite::run(&args.suite, args.accept)?;
    for entry in &result.entries {
        let status = match (&entry.outcome, result.accepted) {
            (Outcome::Same, _) => "same",
            (Outcome::New, true) => "written",
            (Outcome::Changed(_), true) => "updated",
            (Outcome::New, false) => "NEW",
            (Outcome::Changed(_), false) => "CHANGED",
        };
        println!("{status:<8} {}  {}", entry.name, entry.verdict);
        if let (Outcome::Changed(diff), false) = (&entry.outcome, result.accepted) {
            print!("{diff}");
        }
    }
    for orphan in &result.orphans {
        let what = if result.accepted {
            "deleted orphan"
        } else {
            "ORPHAN (no run writes it)"
        };
        println!("{what} {}", orphan.display());
    }
    let differing = result.entries.iter().filter(|e| e.outcome != Outcome::Same).count();
    println!(
        "{} snapshots: {} same, {} {}, {} orphans{}",
        result.entries.len(),
        result.entries.len() - differing,
        differing,
        if result.accepted {
            "recorded"
        } else {
            "differ (new ones written as .snap.new)"
        },
        result.orphans.len(),
        if result.passed() || result.accepted {
            ""
        } else {
            "; review the diffs, then run again with --accept"
        }
    );
    Ok(if result.passed() { ExitCode::SUCCESS } else { ExitCode::from(1) })
}
