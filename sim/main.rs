//! `validate-design`: reads a design, a URDF or an MJCF robot, checks our kinematics of it against
//! MuJoCo's, validates it on a scenario (IK, certified trajectory, rapier and MuJoCo), prints the
//! report and exits 0 (passes), 1 (fails, proven), 2 (bad input) or 3 (undecided: a goal neither
//! reached nor proven unreachable, a path not found in the budget); its subcommands generate
//! scenarios, run snapshot suites, sweeps, the GA and fine-tuning. Each subcommand parses its
//! arguments in `cli/`, calls the library and prints; the exit codes are mapped here.

mod cli;

use clap::Parser;
use cli::Failure;
use cli::{Cli, Command};
use proving_ground::error::Error;
use std::process::ExitCode;

fn main() -> ExitCode {
    // A file-size limit (`ulimit -f`) then fails the write with an error, which leaves the old
    // file intact and removes the temporary, instead of killing the process mid-write.
    // Rust ignores SIGPIPE, so printing into a closed pipe (`| head`) would panic; the default
    // ends the process quietly, as other Unix tools do.
    // SAFETY: setting a signal to SIG_IGN or SIG_DFL has no handler to run and happens before
    // any thread.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let result = match &cli.command {
        Some(Command::Generate(args)) => cli::generate::command(args).map_err(|e| Failure::from(Error::from(e))),
        Some(Command::Convert(args)) => cli::convert::command(args).map_err(|e| Failure::from(Error::from(e))),
        Some(Command::Snapshot(args)) => cli::snapshot::command(args),
        Some(Command::Sweep(args)) => cli::sweep::sweep_command(args),
        Some(Command::Merge(args)) => cli::sweep::merge_command(args),
        Some(Command::Table1(args)) => cli::sweep::table1_command(args),
        Some(Command::Ga(args)) => cli::sweep::ga_command(args),
        Some(Command::Optimize(args)) => cli::optimize::optimize_command(args),
        Some(Command::Workflow(args)) => cli::workflow::command(args),
        None => cli::validate::command(&cli.validate).map_err(Failure::from),
    };
    match result {
        Ok(code) => code,
        Err(error @ Failure::Sweep(proving_ground::sweep::SweepError::Interrupted { .. })) => {
            eprintln!("{error}");
            cli::interrupted_exit_code()
        }
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::from(2)
        }
    }
}
