//! `validate-design ROBOT`: the arguments become [`proving_ground::Options`], the library's
//! run ([`proving_ground::run::validate_unwritten`], [`proving_ground::validate`] but for the
//! writes) runs, and what it returns is printed and written: the exports and the report's files
//! as one set.

use super::ToleranceArg;
use proving_ground::error::Error;
use proving_ground::pipeline::{self, Engines};
use proving_ground::plan::PlannerKind;
use proving_ground::run::{self, Exports, Run, Stop, Written};
use proving_ground::{render, report};
use std::path::PathBuf;
use std::process::ExitCode;

/// The robot and how to validate it (the command line without a subcommand).
#[derive(Debug, clap::Args)]
pub(crate) struct ValidateArgs {
    /// Design JSON (free, economic, modular, preset), URDF or MJCF file.
    #[arg(required = true)]
    pub(crate) design: Option<PathBuf>,
    /// URDF: first link of the chain [default: the root link].
    #[arg(long, value_name = "LINK")]
    pub(crate) base: Option<String>,
    /// URDF: last link of the chain; MJCF: a body or a site, the tool frame [default: the arm's
    /// last link, or the link fixed below it named like a tool frame (tcp, tool0, eef, ee_link,
    /// flange, hand); gripper joints are not arm joints].
    #[arg(long, value_name = "LINK")]
    pub(crate) tip: Option<String>,
    /// URDF: leave out the self-collision pairs the SRDF FILE's <disable_collisions> list, with
    /// its reasons (never read unless given).
    #[arg(long, value_name = "FILE")]
    pub(crate) srdf: Option<PathBuf>,
    /// URDF: a root for package://NAME/... mesh URIs (repeatable; searched before ROS_PACKAGE_PATH).
    #[arg(long = "package-path", value_name = "DIR")]
    pub(crate) package_paths: Vec<PathBuf>,
    /// Write the model as URDF to FILE (never over an input file).
    #[arg(long, value_name = "FILE")]
    pub(crate) export_urdf: Option<PathBuf>,
    /// Write the model as MJCF to FILE (never over an input file).
    #[arg(long, value_name = "FILE")]
    pub(crate) export_mjcf: Option<PathBuf>,
    /// With --export-mjcf: write the scenario too (the robot at its base pose, the obstacles, the
    /// floor and a site `goal/K` per goal, in colours, with keyframes for home and each goal's
    /// chosen configuration), so MuJoCo's own viewer shows the whole scene.
    #[arg(long, requires = "export_mjcf")]
    pub(crate) scene: bool,
    /// Write pictures as SVG into DIR (created if missing; only the files named scene.svg,
    /// goal-NNN.svg and clearance.svg are written): four views of the robot in exact geometry per
    /// goal and at home, and the clearance along the trajectory.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["describe", "kinematics_only"])]
    pub(crate) svg: Option<PathBuf>,
    /// The same pictures as PNG into DIR.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["describe", "kinematics_only"])]
    pub(crate) png: Option<PathBuf>,
    /// Write the report as one self-contained HTML page to FILE (opens offline: verdict, goals,
    /// findings, a 3D view with a timeline, the clearance plot).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["describe", "kinematics_only"])]
    pub(crate) html: Option<PathBuf>,
    /// Random configurations at which MuJoCo's kinematics are compared with ours (0 skips).
    #[arg(long, value_name = "N", default_value_t = 100, value_parser = clap::value_parser!(u64).range(0..=100_000))]
    pub(crate) mujoco_checks: u64,
    /// Seed of IK's random starts and of the kinematics check's random configurations.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub(crate) seed: u64,
    /// Print only the joints, links and tool pose; run nothing else.
    #[arg(long, conflicts_with = "kinematics_only")]
    pub(crate) describe: bool,
    /// Treat warnings about the input as errors (exit 2).
    #[arg(long)]
    pub(crate) strict: bool,
    /// Print only the verdict line (warnings about the input and errors still go to stderr).
    #[arg(long)]
    pub(crate) quiet: bool,
    /// Scenario JSON to validate the design on [default: scenarios/course.json, or the same
    /// course built in when that file is not in the current directory].
    #[arg(long, value_name = "FILE")]
    pub(crate) scenario: Option<PathBuf>,
    /// Build, export and check the model against MuJoCo's kinematics only; run no scenario.
    #[arg(long)]
    pub(crate) kinematics_only: bool,
    /// Write the machine-readable report (JSON) to FILE (never over an input file).
    #[arg(long, value_name = "FILE")]
    pub(crate) json: Option<PathBuf>,
    /// Physics engines to run the trajectory in.
    #[arg(long, value_name = "LIST", default_value_t = Engines::all())]
    pub(crate) engines: Engines,
    /// IK starts per goal (the first seeded from the previous goal where the planner re-solves).
    #[arg(long, value_name = "K", default_value_t = 4, value_parser = clap::value_parser!(u64).range(1..=proving_ground::limits::MAX_IK_SEEDS))]
    pub(crate) ik_seeds: u64,
    /// Boxes at most each joint-space search visits (the sub-chains', then the whole arm's,
    /// which below 10 000 boxes runs only where no sub-chain stands in) for
    /// a goal that IK neither reaches nor decides; from 10 000, one pose per 200 boxes is also
    /// sampled within such a goal's tolerance and solved exactly, a colliding solution's
    /// tolerance is cut down to 1/64 (else 1/16), and a UR-type arm's pose beyond reach is
    /// proven part by part (0 turns the searches off: such goals stay
    /// undecided).
    #[arg(long, value_name = "N", default_value_t = proving_ground::ik::SEARCH_BOXES)]
    pub(crate) search_boxes: usize,
    /// Judge every goal by this tolerance mode instead of the scenario's.
    #[arg(long, value_name = "MODE")]
    pub(crate) tolerance: Option<ToleranceArg>,
    /// The home configuration instead of the scenario's: one value per joint (rad or m),
    /// comma-separated, within the joint limits.
    #[arg(long, value_name = "Q,...", value_delimiter = ',', num_args = 1..)]
    pub(crate) home: Option<Vec<f64>>,
    /// Clearance (m) every configuration and trajectory segment must keep.
    #[arg(long, value_name = "M", default_value_t = 0.0, value_parser = super::non_negative)]
    pub(crate) margin: f64,
    /// Engine contacts shallower than M metres are not counted (a tolerance for the engines'
    /// own geometric approximations).
    #[arg(long, value_name = "M", default_value_t = 0.0, value_parser = super::non_negative)]
    pub(crate) contact_depth: f64,
    /// How goals are joined: `rrt-connect` (straight segments first, then a certified
    /// RRT-Connect detour) or `straight` (the paper's heuristic: one straight segment).
    #[arg(long, value_name = "PLANNER", default_value = "rrt-connect")]
    pub(crate) planner: PlannerKind,
    /// Random samples per goal before the planner reports `no_path` (rrt-connect).
    #[arg(long, value_name = "N", default_value_t = proving_ground::plan::DEFAULT_PLAN_BUDGET as u64, value_parser = clap::value_parser!(u64).range(1..=proving_ground::limits::MAX_PLAN_BUDGET))]
    pub(crate) plan_budget: u64,
    /// The paper's static metric only: a collision-free IK solution per goal; no trajectory, no
    /// engines (the fastest mode).
    #[arg(long, conflicts_with_all = ["engines", "planner", "plan_budget"])]
    pub(crate) reach_only: bool,
    /// Worker threads [default: the number of cores]; the report is the same for any number.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=256))]
    pub(crate) threads: Option<u64>,
}

impl ValidateArgs {
    /// The library's options for these arguments.
    fn options(&self) -> Result<proving_ground::Options, Error> {
        let stop = if self.describe {
            Stop::Described
        } else if self.kinematics_only {
            Stop::KinematicsChecked
        } else {
            Stop::Validated
        };
        // clap gives every default; reach-only runs plan nothing, so their defaults stay out.
        let planning = !self.reach_only;
        let named = run::Named {
            base: self.base.clone(),
            tip: self.tip.clone(),
            package_path: self.package_paths.clone(),
            srdf: self.srdf.clone(),
            strict: self.strict,
            tolerance: self.tolerance.map(Into::into),
            home: self.home.clone(),
            mujoco_checks: Some(self.mujoco_checks),
            seed: Some(self.seed),
            ik_seeds: Some(self.ik_seeds),
            search_boxes: Some(self.search_boxes),
            margin: Some(self.margin),
            contact_depth: Some(self.contact_depth),
            engines: planning.then(|| run::Names::Text(self.engines.name())),
            planner: planning.then(|| self.planner.name().to_string()),
            plan_budget: planning.then_some(self.plan_budget),
            reach_only: self.reach_only,
        };
        Ok(proving_ground::Options {
            scenario: self.scenario.clone(),
            stop,
            exports: Exports {
                urdf: self.export_urdf.clone(),
                mjcf: self.export_mjcf.clone(),
                scene: self.scene,
            },
            ..named.options()?
        })
    }
}

/// Validates, prints and writes what was asked; the exit code of the outcome.
pub(crate) fn command(args: &ValidateArgs) -> Result<ExitCode, Error> {
    let input = args.design.as_deref().expect("clap requires DESIGN without a subcommand");
    super::threads(args.threads);
    let describing = args.describe || args.kinematics_only;
    // --describe prints the choices and the SRDF's pairs with the model.
    let bar = super::Bar::new("goals", args.quiet, !describing);
    // The exports are written here, with the report's files, as one set.
    let options = args.options()?;
    let run = run::validate_unwritten(input, &options, &bar);
    bar.bar.finish_and_clear();
    let run = run?;
    let mut set = pipeline::OutputSet::default();
    let exported = run::stage_exports(&mut set, &run, &options.exports)?;
    let pictures = stage_report(&mut set, args, &run)?;
    set.commit()?;
    if !args.quiet && describing {
        print!("{}", report::describe(&run.model, run.hardware_cost_m));
        if let Some(srdf) = &run.srdf {
            println!("{}", srdf.describe());
        }
        println!("{}", report::scenario_summary(&run.scenario));
    }
    if !args.quiet {
        for (what, path) in &exported {
            let what = match what {
                Written::Urdf => "URDF",
                Written::Mjcf => "MJCF",
                Written::Mesh => "mesh",
            };
            println!("wrote {what} {}", path.display());
        }
    }
    if let Some(check) = &run.kinematics_check {
        // A full run prints the line with the report.
        if args.kinematics_only || !check.agree {
            println!("{}", check.line());
        }
        if !check.agree {
            println!(
                "worst at `{}`, q = {:?}",
                check.agreement.worst_element, check.agreement.worst_configuration
            );
        }
    }
    if args.describe && args.quiet {
        println!("{}: {} joints, model built", run.model.name, run.model.dof());
    }
    print_report(args, &run, &pictures);
    Ok(super::exit_code(run.outcome()))
}

/// `--json`, `--svg`, `--png` and `--html` added to `set` (one set with the exports, so a failed
/// write leaves every old file as it was rather than a mix of two runs); the lines that say what
/// was written.
fn stage_report(set: &mut pipeline::OutputSet, args: &ValidateArgs, run: &Run) -> Result<Vec<String>, Error> {
    let (Some(validation), Some(report)) = (&run.validation, &run.report) else {
        return Ok(Vec::new());
    };
    if let Some(path) = &args.json {
        set.add(path, run::report_json(report)?.as_bytes())?;
    }
    stage_pictures(set, args, validation, report)
}

/// The report on stdout, after the lines saying which pictures were written.
fn print_report(args: &ValidateArgs, run: &Run, pictures: &[String]) {
    let Some(report) = &run.report else { return };
    if !args.quiet {
        for line in pictures {
            println!("{line}");
        }
    }
    if args.quiet {
        println!("{}", report::verdict_line(&report.verdict));
    } else {
        print!("{}", report::render(report));
    }
}

/// `--svg DIR`, `--png DIR`, `--html FILE` added to `set`; the lines that say what was written.
fn stage_pictures(
    set: &mut pipeline::OutputSet,
    args: &ValidateArgs,
    validation: &pipeline::Validation,
    report: &report::Report,
) -> Result<Vec<String>, Error> {
    use rayon::prelude::*;
    let mut lines = Vec::new();
    if args.svg.is_some() || args.png.is_some() {
        let pictures = render::pictures(validation, report);
        if let Some(dir) = &args.svg {
            let files: Vec<(String, Vec<u8>)> = pictures
                .iter()
                .map(|p| (format!("{}.svg", p.name), p.svg.clone().into_bytes()))
                .collect();
            set.add_into(dir, &files)?;
            lines.push(format!("wrote {} SVG pictures into {}", files.len(), dir.display()));
        }
        if let Some(dir) = &args.png {
            // Each picture on its own: the order and the bytes do not depend on the threads.
            let files = pictures
                .par_iter()
                .map(|p| Ok((format!("{}.png", p.name), render::png::to_png(&p.name, &p.svg)?)))
                .collect::<Result<Vec<_>, render::RenderError>>()?;
            set.add_into(dir, &files)?;
            lines.push(format!("wrote {} PNG pictures into {}", files.len(), dir.display()));
        }
    }
    if let Some(path) = &args.html {
        set.add(path, render::page(validation, report).as_bytes())?;
        lines.push(format!("wrote HTML report {}", path.display()));
    }
    Ok(lines)
}
