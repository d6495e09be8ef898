//! `validate-design`: reads a design, a URDF or an MJCF robot, checks our kinematics of it against
//! MuJoCo's, validates it on a scenario (IK, certified trajectory, rapier and MuJoCo), prints the
//! report and exits 0 (passes), 1 (fails, proven), 2 (bad input) or 3 (undecided: a goal neither
//! reached nor proven unreachable, a path not found in the budget); `validate-design generate`
//! writes generated scenarios.

mod optimize_cli;
mod sweep_cli;

use clap::{Parser, Subcommand, ValueEnum};
use proving_ground::engine::check_kinematics;
use proving_ground::error::Error;
use proving_ground::export::{to_mjcf, to_urdf, MjcfOptions, UrdfExportOptions};
use proving_ground::pipeline::{self, LoadOptions};
use proving_ground::render;
use proving_ground::report;
use proving_ground::scenario::{self, generate, ScenarioError, Tolerance};
use std::path::PathBuf;
use std::process::ExitCode;

const AFTER_HELP: &str = "\
Examples:
  validate-design designs/paper-real-world.json                 # the paper's robot on scenarios/course.json
  validate-design designs/ur5e.json --scenario scenarios/cluttered/task-07.json --json ur5e-07.json
  validate-design designs/modular-elbow.json --scenario scenarios/workspace/pose.json --engines none
  validate-design designs/paper-real-world.json --engines mujoco --seed 3 --ik-seeds 8 --contact-depth 0.0005
  validate-design designs/ur10e.json --tolerance position --margin 0.01 --threads 1 --quiet
  validate-design designs/ur5e.json --scenario scenarios/cluttered/task-00.json --planner straight
  validate-design designs/ur20.json --scenario scenarios/cluttered/task-12.json --plan-budget 50000
  validate-design designs/ur5e.json --scenario scenarios/cluttered/task-03.json --reach-only
  validate-design designs/economic-scara.json --scenario scenarios/cluttered/task-24.json --reach-only --search-boxes 1000000
  validate-design designs/urdf/example-robot-data/robots/panda_description/urdf/panda.urdf --srdf designs/urdf/example-robot-data/robots/panda_description/srdf/panda.srdf
  validate-design robot.urdf --base base_link --tip tool0 --package-path ~/ws/src --strict --kinematics-only
  validate-design robot.xml --kinematics-only --mujoco-checks 20
  validate-design designs/ur5e.json --describe --export-urdf ur5e.urdf --export-mjcf ur5e.xml
  validate-design designs/paper-real-world.json --svg pictures --png pictures --html report.html
  validate-design designs/ur5e.json --scenario scenarios/cluttered/task-07.json --export-mjcf scene.xml --scene --describe
  validate-design generate cluttered --all --out scenarios/cluttered --force
  validate-design generate workspace --tolerance z_symmetric --scale 1.2 --out /tmp/workspace.json
  validate-design snapshot --suite proving-ground.json             # your own golden suite
  validate-design snapshot --suite proving-ground.json --accept    # record its new snapshots
  validate-design sweep catalog:modular6 --scenarios scenarios/cluttered/task-00.json --out bf-00   # brute force
  validate-design sweep 'designs/*.json' --scenarios scenarios/cluttered --full --engines none --out runs-1 --shard 1/2
  validate-design merge runs-1 runs-2 --out runs      # the shards joined: what the unsharded sweep writes
  validate-design sweep designs/ur5e.json --scenarios scenarios/cluttered/task-00.json --reference bf-00
  validate-design table1                              # the paper's Table 1 beside ours
  validate-design ga --scenario scenarios/cluttered/task-00.json --seed 1 --reference bf-00 --out ga-00.json

Exit codes:
  0  the design passes the scenario (every goal reached by a certified collision-free path,
     held by every engine run, no contact, no joint over its rating under gravity); with
     --describe or --kinematics-only: the model was built (and MuJoCo agrees with our kinematics)
  1  the design fails, proven: the verdict line (FAIL) lists the reasons: a goal proven
     unreachable, a contact, a joint over its rating (or MuJoCo disagrees with our kinematics
     on the export by more than 1e-9 m / rad)
  2  bad input or usage: the message names the file and the field or line (also a limit
     passed, an output that is a file the run read, a failed write, MuJoCo missing)
  3  undecided: nothing failed, but the harness's limits left something open; the verdict
     line (UNDECIDED) names it: a goal neither reached nor proven unreachable (IK starts), a
     path not found within the planner's budget
  optimize: as validation, of the tuned designs: 1 when one fails, else 3 when one is
     undecided, else 0; 2 bad input
  snapshot: 0 every snapshot matches (or was accepted), 1 a difference, new snapshot or
     orphan, 2 bad input
  sweep, merge, table1, ga: 0 the runs finished (whatever the designs' verdicts: they are in the
     results), 2 bad input, a folder that holds something else, or a pair that could not run

Environment:
  ROS_PACKAGE_PATH  extra ':'-separated roots for package:// mesh URIs
  MUJOCO_LIBRARY    the MuJoCo library file to load instead of the one the build fetched";

/// Proves or disproves a robot manipulator design in simulation.
#[derive(Debug, Parser)]
#[command(
    name = "validate-design",
    version,
    about,
    after_help = AFTER_HELP,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    allow_negative_numbers = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Design JSON (free, economic, modular, preset), URDF or MJCF file.
    #[arg(required = true)]
    design: Option<PathBuf>,
    /// URDF: first link of the chain [default: the root link].
    #[arg(long, value_name = "LINK")]
    base: Option<String>,
    /// URDF: last link of the chain; MJCF: a body or a site, the tool frame [default: the arm's
    /// last link, or the link fixed below it named like a tool frame (tcp, tool0, eef, ee_link,
    /// flange, hand); gripper joints are not arm joints].
    #[arg(long, value_name = "LINK")]
    tip: Option<String>,
    /// URDF: leave out the self-collision pairs the SRDF FILE's <disable_collisions> list, with
    /// its reasons (never read unless given).
    #[arg(long, value_name = "FILE")]
    srdf: Option<PathBuf>,
    /// URDF: a root for package://NAME/... mesh URIs (repeatable; searched before ROS_PACKAGE_PATH).
    #[arg(long = "package-path", value_name = "DIR")]
    package_paths: Vec<PathBuf>,
    /// Write the model as URDF to FILE (never over an input file).
    #[arg(long, value_name = "FILE")]
    export_urdf: Option<PathBuf>,
    /// Write the model as MJCF to FILE (never over an input file).
    #[arg(long, value_name = "FILE")]
    export_mjcf: Option<PathBuf>,
    /// With --export-mjcf: write the scenario too (the robot at its base pose, the obstacles, the
    /// floor and a site `goal/K` per goal), so MuJoCo's own viewer shows the whole scene.
    #[arg(long, requires = "export_mjcf")]
    scene: bool,
    /// Write pictures as SVG into DIR (created if missing; only the files named scene.svg,
    /// goal-NNN.svg and clearance.svg are written): four views of the robot in exact geometry per
    /// goal and at home, and the clearance along the trajectory.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["describe", "kinematics_only"])]
    svg: Option<PathBuf>,
    /// The same pictures as PNG into DIR.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["describe", "kinematics_only"])]
    png: Option<PathBuf>,
    /// Write the report as one self-contained HTML page to FILE (opens offline: verdict, goals,
    /// findings, a 3D view with a timeline, the clearance plot).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["describe", "kinematics_only"])]
    html: Option<PathBuf>,
    /// Random configurations at which MuJoCo's kinematics are compared with ours (0 skips).
    #[arg(long, value_name = "N", default_value_t = 100, value_parser = clap::value_parser!(u64).range(0..=100_000))]
    mujoco_checks: u64,
    /// Seed of IK's random starts and of the kinematics check's random configurations.
    #[arg(long, value_name = "N", default_value_t = 0)]
    seed: u64,
    /// Print only the joints, links and tool pose; run nothing else.
    #[arg(long, conflicts_with = "kinematics_only")]
    describe: bool,
    /// Treat warnings about the input as errors (exit 2).
    #[arg(long)]
    strict: bool,
    /// Print only the verdict line (warnings about the input and errors still go to stderr).
    #[arg(long)]
    quiet: bool,
    /// Scenario JSON to validate the design on [default: scenarios/course.json, or the same
    /// course built in when that file is not in the current directory].
    #[arg(long, value_name = "FILE")]
    scenario: Option<PathBuf>,
    /// Build, export and check the model against MuJoCo's kinematics only; run no scenario.
    #[arg(long)]
    kinematics_only: bool,
    /// Write the machine-readable report (JSON) to FILE (never over an input file).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Physics engines to run the trajectory in.
    #[arg(long, value_name = "LIST", default_value = "rapier,mujoco")]
    engines: EnginesArg,
    /// IK starts per goal (the first seeded from the previous goal where the planner re-solves).
    #[arg(long, value_name = "K", default_value_t = 4, value_parser = clap::value_parser!(u64).range(1..=proving_ground::limits::MAX_IK_SEEDS))]
    ik_seeds: u64,
    /// Boxes at most the joint-space search visits for a goal that IK neither reaches nor
    /// proves out of reach (0 turns it off: such goals stay undecided).
    #[arg(long, value_name = "N", default_value_t = proving_ground::ik::SEARCH_BOXES)]
    search_boxes: usize,
    /// Judge every goal by this tolerance mode instead of the scenario's.
    #[arg(long, value_name = "MODE")]
    tolerance: Option<ToleranceArg>,
    /// Clearance (m) every configuration and trajectory segment must keep.
    #[arg(long, value_name = "M", default_value_t = 0.0, value_parser = non_negative)]
    margin: f64,
    /// Engine contacts shallower than M metres are not counted (a tolerance for the engines'
    /// own geometric approximations).
    #[arg(long, value_name = "M", default_value_t = 0.0, value_parser = non_negative)]
    contact_depth: f64,
    /// How goals are joined: `rrt-connect` (straight segments first, then a certified
    /// RRT-Connect detour) or `straight` (the paper's heuristic: one straight segment).
    #[arg(long, value_name = "PLANNER", default_value = "rrt-connect")]
    planner: PlannerArg,
    /// Random samples per goal before the planner reports `no_path` (rrt-connect).
    #[arg(long, value_name = "N", default_value_t = proving_ground::plan::DEFAULT_PLAN_BUDGET as u64, value_parser = clap::value_parser!(u64).range(1..=proving_ground::limits::MAX_PLAN_BUDGET))]
    plan_budget: u64,
    /// The paper's static metric only: a collision-free IK solution per goal; no trajectory, no
    /// engines (the fastest mode).
    #[arg(long, conflicts_with_all = ["engines", "planner", "plan_budget"])]
    reach_only: bool,
    /// Worker threads [default: the number of cores]; the report is the same for any number.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=256))]
    threads: Option<u64>,
}

/// A finite length of at least 0 m.
fn non_negative(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(value) if value.is_finite() && value >= 0.0 => Ok(value),
        Ok(value) => Err(format!("{value} m: expected a finite length of at least 0")),
        Err(error) => Err(format!("`{text}`: {error}")),
    }
}

/// `--engines`: `rapier,mujoco`, `rapier`, `mujoco` or `none`.
#[derive(Debug, Clone, Copy)]
struct EnginesArg(pipeline::Engines);

impl std::str::FromStr for EnginesArg {
    type Err = String;
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let names: Vec<&str> = if text == "none" {
            vec![]
        } else {
            text.split(',').map(str::trim).collect()
        };
        pipeline::Engines::from_names(names)
            .map(Self)
            .map_err(|other| format!("unknown engine `{other}`; expected rapier,mujoco, rapier, mujoco or none"))
    }
}

/// `--planner`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum PlannerArg {
    /// Straight segments first, then RRT-Connect with certified edges and shortcutting.
    #[value(name = "rrt-connect")]
    RrtConnect,
    /// One straight joint-space segment per goal (the paper's heuristic).
    #[value(name = "straight")]
    Straight,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Write a generated scenario (the paper's cluttered tasks, its workspace task, or the course
    /// for its real-world robot); an existing file is only replaced with --force.
    Generate(GenerateArgs),
    /// Run a suite (designs x scenarios x options, a JSON file) and compare every report with its
    /// snapshot in the suite's folder: exit 1 with a diff on any difference, missing snapshot
    /// (written as .snap.new) or orphan; --accept records them.
    Snapshot(SnapshotArgs),
    /// Run many designs on many scenarios (reach-only by default, --full for the whole
    /// validation), in parallel and resumable; results as JSON lines, CSV and ranked tables with
    /// the paper's normalised score and percentile.
    Sweep(sweep_cli::SweepArgs),
    /// Join the shard folders of a sweep (`sweep --shard K/N`) into the folder the whole sweep
    /// writes, byte for byte.
    Merge(sweep_cli::MergeArgs),
    /// The paper's Table 1 (UR15, UR20, ABB IRB 2600 on the cluttered tasks), its numbers
    /// beside ours.
    Table1(sweep_cli::Table1Args),
    /// The paper's genetic-algorithm baseline over the 6-slot modular catalog on one scenario
    /// (population 128, 100 generations, single-point crossover, tournament 4, mutation 0.05).
    Ga(sweep_cli::GaArgs),
    /// Fine-tune a design on a scenario with the paper's Adam refinement of its differentiable
    /// objective (200 steps, rates 0.1 for joints and 0.01 for d and a), write the tuned design,
    /// validate both and print their verdicts side by side.
    Optimize(optimize_cli::OptimizeArgs),
}

#[derive(Debug, clap::Args)]
struct SnapshotArgs {
    /// The suite file (JSON: snapshots, designs, scenarios, options).
    #[arg(long, value_name = "FILE")]
    suite: PathBuf,
    /// Record this run's snapshots (and delete orphans) instead of failing on a difference.
    #[arg(long)]
    accept: bool,
}

#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
struct GenerateArgs {
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

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ToleranceArg {
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

/// The run's progress on stderr: a spinner for a stage that cannot be counted, else the goals
/// done of all, the time taken and an estimate of the time left.
struct StageBar(indicatif::ProgressBar);

impl proving_ground::progress::Progress for StageBar {
    fn stage(&self, name: &str, total: Option<u64>) {
        let style = match total {
            Some(total) => {
                self.0.set_length(total);
                self.0.set_position(0);
                self.0.reset_eta();
                indicatif::ProgressStyle::with_template("{spinner} {msg}: {pos}/{len} goals, {elapsed} (about {eta} left)")
            }
            None => indicatif::ProgressStyle::with_template("{spinner} {msg}"),
        };
        if let Ok(style) = style {
            self.0.set_style(style);
        }
        self.0.set_message(name.to_string());
    }

    fn advance(&self) {
        self.0.inc(1);
    }
}

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
        Some(Command::Generate(args)) => generate_scenarios(args).map_err(Error::from),
        Some(Command::Snapshot(args)) => snapshot_suite(args),
        Some(Command::Sweep(args)) => sweep_cli::sweep_command(args),
        Some(Command::Merge(args)) => sweep_cli::merge_command(args),
        Some(Command::Table1(args)) => sweep_cli::table1_command(args),
        Some(Command::Ga(args)) => sweep_cli::ga_command(args),
        Some(Command::Optimize(args)) => optimize_cli::optimize_command(args),
        None => run(&cli),
    };
    match result {
        Ok(code) => code,
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: &Cli) -> Result<ExitCode, Error> {
    let design_path = cli.design.as_deref().expect("clap requires DESIGN without a subcommand");
    let opts = LoadOptions {
        base_link: cli.base.clone(),
        tip_link: cli.tip.clone(),
        package_paths: cli.package_paths.clone(),
    };
    let loaded = pipeline::load(design_path, &opts)?;
    let model = &loaded.model;
    for diagnostic in &model.diagnostics {
        eprintln!("{diagnostic}");
    }
    let describing = cli.describe || cli.kinematics_only;
    // --describe prints them with the model.
    if !cli.quiet && !describing {
        for choice in model.source.choices() {
            eprintln!("info: {}: {choice}", design_path.display());
        }
    }
    let srdf = match &cli.srdf {
        Some(path) if pipeline::input_kind(design_path)? != pipeline::InputKind::Urdf => {
            return Err(Error::Srdf {
                path: path.clone(),
                element: "--srdf".into(),
                message: format!("is for URDF input; {} is not a URDF", design_path.display()),
            })
        }
        Some(path) => Some(proving_ground::srdf::exclusions(path, model)?),
        None => None,
    };
    if let (Some(srdf), false, false) = (&srdf, cli.quiet, describing) {
        eprintln!(
            "info: {}: {} self-collision pairs left out ({} entries not applied); listed with --describe and in the JSON report's criteria.excluded_pairs",
            srdf.path.display(),
            srdf.pairs.len(),
            srdf.notes.len()
        );
    }
    if cli.strict && !model.diagnostics.is_empty() {
        let list = model.diagnostics.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n");
        return Err(Error::Strict {
            count: model.diagnostics.len(),
            list,
        });
    }
    if let Some(threads) = cli.threads {
        // Only the first call configures the global pool; a second is harmless.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(usize::try_from(threads).unwrap_or(usize::MAX))
            .build_global();
    }
    let mut scenario = pipeline::scenario_or_default(cli.scenario.as_deref())?;
    if let Some(tolerance) = cli.tolerance {
        for goal in &mut scenario.goals {
            goal.tolerance = tolerance.into();
        }
    }
    if !cli.quiet && (cli.describe || cli.kinematics_only) {
        print!("{}", report::describe(model, loaded.design.as_ref().map(|d| d.hardware_cost())));
        if let Some(srdf) = &srdf {
            println!("{}", srdf.describe());
        }
        println!("{}", report::scenario_summary(&scenario));
    }

    let mjcf = to_mjcf(model, &MjcfOptions::default())?;
    if let Some(path) = &cli.export_urdf {
        pipeline::write_output(path, &to_urdf(model, &UrdfExportOptions::default())?)?;
        if !cli.quiet {
            println!("wrote URDF {}", path.display());
        }
    }
    if let Some(path) = &cli.export_mjcf {
        let text = if cli.scene {
            pipeline::scene_mjcf(model, &scenario)?
        } else {
            mjcf.clone()
        };
        pipeline::write_output(path, &text)?;
        if !cli.quiet {
            println!("wrote MJCF {}", path.display());
        }
    }
    if cli.describe {
        if cli.quiet {
            println!("{}: {} joints, model built", model.name, model.dof());
        }
        return Ok(ExitCode::SUCCESS);
    }

    let mut kinematics_check = None;
    if cli.mujoco_checks > 0 {
        let source = format!("the MJCF export of {}", design_path.display());
        let check = check_kinematics(
            model,
            &mjcf,
            &source,
            usize::try_from(cli.mujoco_checks).unwrap_or(usize::MAX),
            cli.seed,
        )?;
        // A full run prints the line with the report; a disagreement stops here.
        if cli.kinematics_only || !check.agree {
            println!("{}", check.line());
        }
        if !check.agree {
            println!(
                "worst at `{}`, q = {:?}",
                check.agreement.worst_element, check.agreement.worst_configuration
            );
            return Ok(ExitCode::from(1));
        }
        kinematics_check = Some(check);
    }
    if cli.kinematics_only {
        return Ok(ExitCode::SUCCESS);
    }

    let opts = pipeline::ValidateOptions {
        ik: proving_ground::ik::IkOptions {
            seeds: usize::try_from(cli.ik_seeds).unwrap_or(usize::MAX),
            search_boxes: cli.search_boxes,
            seed: cli.seed,
            ..Default::default()
        },
        certify: proving_ground::plan::CertifyOptions { threshold_m: cli.margin },
        engines: cli.engines.0,
        planner: proving_ground::plan::PlannerOptions {
            kind: match cli.planner {
                PlannerArg::RrtConnect => proving_ground::plan::PlannerKind::RrtConnect,
                PlannerArg::Straight => proving_ground::plan::PlannerKind::Straight,
            },
            budget: usize::try_from(cli.plan_budget).unwrap_or(usize::MAX),
            seed: cli.seed,
        },
        reach_only: cli.reach_only,
        excluded_pairs: srdf.map(|s| s.pairs).unwrap_or_default(),
        engine: proving_ground::engine::RunOptions {
            contact_depth_m: cli.contact_depth,
            ..Default::default()
        },
        ..Default::default()
    };
    // On stderr; indicatif draws nothing when stderr is not a terminal.
    let bar = StageBar(if cli.quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new_spinner()
    });
    bar.0.enable_steady_tick(std::time::Duration::from_millis(120));
    let validation = pipeline::validate_with_progress(loaded, scenario, &opts, &bar);
    bar.0.finish_and_clear();
    let mut validation = validation?;
    validation.kinematics_check = kinematics_check;
    let report = report::build(&validation);
    if let Some(path) = &cli.json {
        let text = serde_json::to_string_pretty(&report).map_err(|e| Error::Report { message: e.to_string() })?;
        pipeline::write_output(path, &(text + "\n"))?;
    }
    write_pictures(cli, &validation, &report)?;
    if cli.quiet {
        println!("{}", report::verdict_line(&report.verdict));
    } else {
        print!("{}", report::render(&report));
    }
    Ok(verdict_exit(&report.verdict))
}

/// The exit code of a verdict: 0 pass, 1 fail (proven), 3 undecided.
fn verdict_exit(verdict: &report::Verdict) -> ExitCode {
    match (verdict.passed, verdict.word) {
        (true, _) => ExitCode::SUCCESS,
        (false, "UNDECIDED") => ExitCode::from(3),
        (false, _) => ExitCode::from(1),
    }
}

/// `--svg DIR`, `--png DIR`, `--html FILE`.
fn write_pictures(cli: &Cli, validation: &pipeline::Validation, report: &report::Report) -> Result<(), Error> {
    use rayon::prelude::*;
    if cli.svg.is_some() || cli.png.is_some() {
        let pictures = render::pictures(validation, report);
        if let Some(dir) = &cli.svg {
            let files: Vec<(String, Vec<u8>)> = pictures
                .iter()
                .map(|p| (format!("{}.svg", p.name), p.svg.clone().into_bytes()))
                .collect();
            pipeline::write_files_into(dir, &files)?;
            if !cli.quiet {
                println!("wrote {} SVG pictures into {}", files.len(), dir.display());
            }
        }
        if let Some(dir) = &cli.png {
            // Each picture on its own: the order and the bytes do not depend on the threads.
            let files = pictures
                .par_iter()
                .map(|p| Ok((format!("{}.png", p.name), render::png::to_png(&p.name, &p.svg)?)))
                .collect::<Result<Vec<_>, render::RenderError>>()?;
            pipeline::write_files_into(dir, &files)?;
            if !cli.quiet {
                println!("wrote {} PNG pictures into {}", files.len(), dir.display());
            }
        }
    }
    if let Some(path) = &cli.html {
        pipeline::write_output(path, &render::page(validation, report))?;
        if !cli.quiet {
            println!("wrote HTML report {}", path.display());
        }
    }
    Ok(())
}

/// `validate-design generate ...`: builds the scenarios and writes them.
fn generate_scenarios(args: &GenerateArgs) -> Result<ExitCode, ScenarioError> {
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

/// `validate-design snapshot --suite FILE [--accept]`.
fn snapshot_suite(args: &SnapshotArgs) -> Result<ExitCode, Error> {
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
