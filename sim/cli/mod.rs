//! The command line: one module per subcommand, each parsing its arguments into the library's
//! options, calling the library and printing what it returns.

pub(crate) mod convert;
pub(crate) mod generate;
mod help;
pub(crate) mod optimize;
pub(crate) mod snapshot;
pub(crate) mod sweep;
pub(crate) mod validate;
pub(crate) mod workflow;

use clap::{Parser, Subcommand, ValueEnum};
use proving_ground::scenario::Tolerance;

/// Proves or disproves a robot manipulator design in simulation.
#[derive(Debug, Parser)]
#[command(
    name = "validate-design",
    version,
    about,
    after_help = help::AFTER_HELP,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    allow_negative_numbers = true
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Option<Command>,
    #[command(flatten)]
    pub(crate) validate: validate::ValidateArgs,
}

#[derive(Debug, Subcommand)]
pub(crate) enum Command {
    /// Write a generated scenario (the paper's cluttered tasks, its workspace task, or the course
    /// for its real-world robot); an existing file is only replaced with --force.
    Generate(generate::GenerateArgs),
    /// Write a scenario or a Timor / CoBRA task in either format (`--to scenario|timor`); what
    /// the scenario format cannot hold is named in a warning.
    Convert(convert::ConvertArgs),
    /// Run a suite (designs x scenarios x options, a JSON file) and compare every report with its
    /// snapshot in the suite's folder: exit 1 with a diff on any difference, missing snapshot
    /// (written as .snap.new) or orphan; --accept records them.
    Snapshot(snapshot::SnapshotArgs),
    /// Run many designs on many scenarios (reach-only by default, --full for the whole
    /// validation), in parallel and resumable; results as JSON lines, CSV and ranked tables with
    /// the paper's normalised score and percentile.
    Sweep(sweep::SweepArgs),
    /// Join the shard folders of a sweep (`sweep --shard K/N`) into the folder the whole sweep
    /// writes, byte for byte.
    Merge(sweep::MergeArgs),
    /// The paper's Table 1 (UR15, UR20, ABB IRB 2600 on the cluttered tasks), its numbers
    /// beside ours.
    Table1(sweep::Table1Args),
    /// The paper's genetic-algorithm baseline over the 6-slot modular catalog on one scenario
    /// (population 128, 100 generations, single-point crossover, tournament 4, mutation 0.05).
    Ga(sweep::GaArgs),
    /// Fine-tune a design on a scenario with the paper's Adam refinement of its differentiable
    /// objective (200 steps, rates 0.1 for joints and 0.01 for d and a), write the tuned design,
    /// validate both and print their verdicts side by side.
    Optimize(optimize::OptimizeArgs),
    /// The paper's workflow on tasks in one command: candidates (the GA by default, the catalog
    /// brute force, or designs), the reach-only filter, fine-tuning of the best, their full
    /// validation with HTML reports and pictures, and one HTML summary (`summary.html`).
    Workflow(workflow::WorkflowArgs),
}

/// A finite length of at least 0 m.
pub(crate) fn non_negative(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(value) if value.is_finite() && value >= 0.0 => Ok(value),
        Ok(value) => Err(format!("{value} m: expected a finite length of at least 0")),
        Err(error) => Err(format!("`{text}`: {error}")),
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ToleranceArg {
    /// Position and orientation.
    #[value(name = "pose")]
    Pose,
    /// Position and the tool z axis.
    #[value(name = "z_symmetric")]
    ZSymmetric,
    /// Position only.
    #[value(name = "position")]
    Position,
}

impl From<ToleranceArg> for Tolerance {
    fn from(arg: ToleranceArg) -> Self {
        match arg {
            ToleranceArg::Pose => Tolerance::Pose,
            ToleranceArg::ZSymmetric => Tolerance::ZSymmetric,
            ToleranceArg::Position => Tolerance::Position,
        }
    }
}

/// Whatever stops a subcommand: the library's error or an experiment's (each names the file,
/// field or argument); every one exits 2.
#[derive(Debug, thiserror::Error)]
pub(crate) enum Failure {
    /// A run, a load, a write.
    #[error(transparent)]
    Run(#[from] proving_ground::error::Error),
    /// A sweep, merge or GA.
    #[error(transparent)]
    Sweep(#[from] proving_ground::sweep::SweepError),
    /// A fine-tuning.
    #[error(transparent)]
    Optimize(#[from] proving_ground::optimize::OptimizeError),
    /// A snapshot suite.
    #[error(transparent)]
    Suite(#[from] proving_ground::suite::SuiteError),
    /// A workflow.
    #[error(transparent)]
    Workflow(#[from] proving_ground::workflow::WorkflowError),
}

/// Progress on stderr (drawn only on a terminal): a spinner for a stage that cannot be counted,
/// else the items done of all (`unit`: goals, pairs), the time taken and an estimate of the
/// time left; and the notes about the input.
pub(crate) struct Bar {
    pub(crate) bar: indicatif::ProgressBar,
    unit: &'static str,
    /// Print the loader's choices and the SRDF's summary.
    infos: bool,
}

impl Bar {
    /// A bar counting `unit`; hidden with `quiet`, which also drops the notes.
    pub(crate) fn new(unit: &'static str, quiet: bool, infos: bool) -> Self {
        let bar = if quiet {
            indicatif::ProgressBar::hidden()
        } else {
            indicatif::ProgressBar::new_spinner()
        };
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        Self {
            bar,
            unit,
            infos: infos && !quiet,
        }
    }
}

impl proving_ground::progress::Progress for Bar {
    fn stage(&self, name: &str, total: Option<u64>) {
        let style = match total {
            Some(total) => {
                self.bar.set_length(total);
                self.bar.set_position(0);
                self.bar.reset_eta();
                indicatif::ProgressStyle::with_template(&format!(
                    "{{spinner}} {{msg}}: {{pos}}/{{len}} {}, {{elapsed}} (about {{eta}} left)",
                    self.unit
                ))
            }
            None => indicatif::ProgressStyle::with_template("{spinner} {msg}"),
        };
        if let Ok(style) = style {
            self.bar.set_style(style);
        }
        self.bar.set_message(name.to_string());
    }

    fn advance(&self) {
        self.bar.inc(1);
    }

    fn warning(&self, line: &str) {
        self.bar.suspend(|| eprintln!("{line}"));
    }

    fn info(&self, line: &str) {
        if self.infos {
            self.bar.suspend(|| eprintln!("info: {line}"));
        }
    }
}

/// `--threads N`: the global pool's size (the reports do not depend on it).
pub(crate) fn threads(count: Option<u64>) {
    if let Some(threads) = count {
        // Only the first call configures the global pool; a second is harmless.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(usize::try_from(threads).unwrap_or(usize::MAX))
            .build_global();
    }
}

/// Raised by SIGINT or SIGTERM once [`stop_on_signals`] installed its handler.
static STOP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
/// The signal that raised [`STOP`] (0 before one came).
static SIGNAL: std::sync::atomic::AtomicI32 = std::sync::atomic::AtomicI32::new(0);

extern "C" fn on_stop_signal(signal: libc::c_int) {
    // Only async-signal-safe work: two atomic stores, and the default action back, so a
    // second Ctrl-C ends the process at once.
    SIGNAL.store(signal, std::sync::atomic::Ordering::Relaxed);
    STOP.store(true, std::sync::atomic::Ordering::Relaxed);
    // SAFETY: signal(2) is async-signal-safe; SIG_DFL runs no code of ours.
    unsafe {
        libc::signal(signal, libc::SIG_DFL);
    }
}

/// For runs that keep their work as they go (sweeps): SIGINT and SIGTERM raise the returned
/// flag instead of killing the process, so the run stops taking work, saves what finished and
/// exits with [`interrupted_exit_code`]; a second signal kills as usual.
pub(crate) fn stop_on_signals() -> &'static std::sync::atomic::AtomicBool {
    let handler = on_stop_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
    // SAFETY: the handler only stores to atomics and calls signal(2), all async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, handler);
        libc::signal(libc::SIGTERM, handler);
    }
    &STOP
}

/// 128 plus the signal's number, as a shell reports a process the signal ended (130 for
/// SIGINT, 143 for SIGTERM).
pub(crate) fn interrupted_exit_code() -> std::process::ExitCode {
    let signal = SIGNAL.load(std::sync::atomic::Ordering::Relaxed);
    let signal = if signal > 0 { signal } else { libc::SIGINT };
    std::process::ExitCode::from(u8::try_from(128 + signal).unwrap_or(130))
}

/// The exit code of an outcome: 0 pass, 1 fail, 3 undecided (2 is a run that could not be made).
pub(crate) fn exit_code(outcome: proving_ground::run::Outcome) -> std::process::ExitCode {
    match outcome {
        proving_ground::run::Outcome::Pass => std::process::ExitCode::SUCCESS,
        proving_ground::run::Outcome::Fail => std::process::ExitCode::from(1),
        proving_ground::run::Outcome::Undecided => std::process::ExitCode::from(3),
    }
}
