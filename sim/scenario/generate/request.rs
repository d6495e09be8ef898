//! What `validate-design generate` asks for, checked and turned into the scenarios to write: the
//! options that do not apply to a generator are errors, and nothing is written when one output
//! exists and `force` is not given.

use super::{cluttered, course, workspace, CLUTTERED_MASTER_SEED, CLUTTERED_TASKS, COURSE_SEED, WORKSPACE_GOALS, WORKSPACE_SEED};
use crate::scenario::{Scenario, ScenarioError, Tolerance};
use std::path::PathBuf;

/// Which generator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Generator {
    /// The paper's cluttered benchmark tasks.
    Cluttered,
    /// The paper's workspace task.
    Workspace,
    /// The course for the paper's real-world robot.
    Course,
}

impl Generator {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Generator::Cluttered => "cluttered",
            Generator::Workspace => "workspace",
            Generator::Course => "course",
        }
    }
}

/// One `generate` request; `None` is the generator's default.
#[derive(Debug, Clone)]
pub struct Request {
    /// Which generator.
    pub generator: Generator,
    /// Seed (default: the generator's).
    pub seed: Option<u64>,
    /// cluttered: one task.
    pub task: Option<usize>,
    /// cluttered: all tasks, `out` a folder.
    pub all: bool,
    /// workspace: number of poses.
    pub count: Option<usize>,
    /// workspace: box scale.
    pub scale: Option<f64>,
    /// workspace: tolerance mode.
    pub tolerance: Option<Tolerance>,
    /// Output file (a folder with cluttered `all`).
    pub out: PathBuf,
    /// Replace existing files.
    pub force: bool,
}

/// The scenarios a request writes, with their paths.
///
/// # Errors
/// [`ScenarioError::Parameter`] for an option that does not apply or is missing, a generator's
/// own parameter errors, and [`ScenarioError::Write`] when an output exists without `force`.
pub fn outputs(request: &Request) -> Result<Vec<(PathBuf, Scenario)>, ScenarioError> {
    let name = request.generator.name();
    let not_for = |flag: &str, given: bool| -> Result<(), ScenarioError> {
        if given {
            return Err(ScenarioError::Parameter {
                generator: name.into(),
                parameter: flag.into(),
                message: format!("does not apply to the {name} generator"),
            });
        }
        Ok(())
    };
    let workspace_flags = [
        ("--count", request.count.is_some()),
        ("--scale", request.scale.is_some()),
        ("--tolerance", request.tolerance.is_some()),
    ];
    let cluttered_flags = [("--task", request.task.is_some()), ("--all", request.all)];
    let outputs: Vec<(PathBuf, Scenario)> = match request.generator {
        Generator::Cluttered => {
            for (flag, given) in workspace_flags {
                not_for(flag, given)?;
            }
            let seed = request.seed.unwrap_or(CLUTTERED_MASTER_SEED);
            match (request.task, request.all) {
                (Some(task), _) => vec![(request.out.clone(), cluttered(task, seed))],
                (None, true) => (0..CLUTTERED_TASKS)
                    .map(|task| (request.out.join(format!("task-{task:02}.json")), cluttered(task, seed)))
                    .collect(),
                (None, false) => {
                    return Err(ScenarioError::Parameter {
                        generator: name.into(),
                        parameter: "--task".into(),
                        message: format!("is missing: give --task K or --all (tasks 0 to {})", CLUTTERED_TASKS - 1),
                    })
                }
            }
        }
        Generator::Workspace => {
            for (flag, given) in cluttered_flags {
                not_for(flag, given)?;
            }
            let scenario = workspace(
                request.count.unwrap_or(WORKSPACE_GOALS),
                request.scale.unwrap_or(1.0),
                request.tolerance.unwrap_or(Tolerance::Pose),
                request.seed.unwrap_or(WORKSPACE_SEED),
            )?;
            vec![(request.out.clone(), scenario)]
        }
        Generator::Course => {
            for (flag, given) in workspace_flags.into_iter().chain(cluttered_flags) {
                not_for(flag, given)?;
            }
            vec![(request.out.clone(), course(request.seed.unwrap_or(COURSE_SEED)))]
        }
    };
    // Refuse before writing anything, so a run without --force never leaves half a set behind.
    if !request.force {
        if let Some((path, _)) = outputs.iter().find(|(path, _)| path.exists()) {
            return Err(ScenarioError::Write {
                path: path.clone(),
                source: std::io::Error::new(std::io::ErrorKind::AlreadyExists, "the file exists; pass --force to replace it"),
            });
        }
    }
    Ok(outputs)
}
