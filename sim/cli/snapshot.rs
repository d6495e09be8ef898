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
    /// Print each snapshot's status and what changed in its summary, without the diffs (for a
    /// pull-request comment).
    #[arg(long)]
    summary: bool,
}

/// `validate-design snapshot --suite FILE [--accept] [--summary]`.
pub(crate) fn command(args: &SnapshotArgs) -> Result<ExitCode, Failure> {
    use proving_ground::suite::{self, Outcome};
    let result = suite::run(&args.suite, args.accept)?;
    for entry in &result.entries {
        let status = match (&entry.outcome, result.accepted) {
            (Outcome::Same, _) => "same",
            (Outcome::New, true) => "written",
            (Outcome::Changed { .. }, true) => "updated",
            (Outcome::New, false) => "NEW",
            (Outcome::Changed { .. }, false) => "CHANGED",
        };
        match &entry.outcome {
            Outcome::Changed { diff, summary } => {
                // The verdict's change on the status line; the other summary lines below it.
                let (head, rest) = match summary.split_first() {
                    Some((first, rest)) if first.starts_with("verdict: ") => (first.clone(), rest),
                    _ => (format!("{} (verdict unchanged)", entry.verdict), &summary[..]),
                };
                println!("{status:<8} {}  {head}", entry.name);
                for line in rest {
                    println!("{:<8} {line}", "");
                }
                if !result.accepted && !args.summary {
                    print!("{diff}");
                }
            }
            _ => println!("{status:<8} {}  {}", entry.name, entry.verdict),
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
