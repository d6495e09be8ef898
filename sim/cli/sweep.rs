//! `validate-design sweep`, `merge` and `table1`: the command-line side of [`proving_ground::sweep`].

use super::Failure;
use proving_ground::pipeline::{Engines, LoadOptions};
use proving_ground::sweep::{self, inputs, Shard, SweepMode, SweepOptions};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
#[command(allow_negative_numbers = true)]
pub(crate) struct SweepArgs {
    /// Designs: files (.json, .urdf, .xml), folders (their design files), globs ('designs/*.json',
    /// quoted), or catalog:modular6 (every 6-slot modular robot, 15 625), catalog:table1 (UR15,
    /// UR20, ABB IRB 2600), catalog:presets.
    #[arg(required = true, value_name = "DESIGN")]
    designs: Vec<String>,
    /// Scenarios: files, folders (their .json files) or globs (quoted), e.g. scenarios/cluttered.
    #[arg(long, required = true, num_args = 1.., value_name = "SCENARIO")]
    scenarios: Vec<String>,
    /// Folder for sweep.json, the finished pairs and the results (results.jsonl, results.csv,
    /// table.txt); a folder holding the same sweep is resumed [default: keep them in memory and
    /// print the tables].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// URDF designs: a root for package://NAME/... mesh URIs (repeatable; searched before
    /// ROS_PACKAGE_PATH).
    #[arg(long = "package-path", value_name = "DIR")]
    package_paths: Vec<PathBuf>,
    /// Replace another sweep's files in --out (only this tool's files; nothing else is touched).
    #[arg(long)]
    force: bool,
    /// The whole validation per pair (trajectory, certified check, engines, verdict) instead of
    /// the paper's reach-only metric.
    #[arg(long)]
    full: bool,
    /// With --full: the engines to run.
    #[arg(long, value_name = "LIST", default_value_t = Engines::all(), requires = "full")]
    engines: Engines,
    /// Run the K-th of N shards: the pairs ranked by a fixed hash of their index, dealt round
    /// robin (shard sizes differ by at most one, each a fair sample of the sweep).
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// Score against this finished sweep (e.g. the brute force over catalog:modular6) instead of
    /// the sweep itself.
    #[arg(long, value_name = "DIR")]
    reference: Option<PathBuf>,
    /// Seed of IK's random starts (and of the planner with --full).
    #[arg(long, value_name = "N", default_value_t = 0)]
    seed: u64,
    /// IK starts per goal.
    #[arg(long, value_name = "K", default_value_t = 4, value_parser = clap::value_parser!(u64).range(1..=proving_ground::limits::MAX_IK_SEEDS))]
    ik_seeds: u64,
    /// Boxes at most each joint-space search visits (the sub-chains', then the whole arm's,
    /// which below 10 000 boxes runs only where no sub-chain stands in) for
    /// a goal that IK neither reaches nor decides; from 10 000, one pose per 200 boxes is also
    /// sampled within such a goal's tolerance and solved exactly, a colliding solution's
    /// tolerance is cut down to 1/64 (else 1/16), and a UR-type arm's pose beyond reach is
    /// proven part by part (0 turns the searches off: such goals stay
    /// undecided; validation's default is 200 000).
    #[arg(long, value_name = "N", default_value_t = proving_ground::ik::SWEEP_SEARCH_BOXES)]
    search_boxes: usize,
    /// Rows of each ranked table.
    #[arg(long, value_name = "N", default_value_t = sweep::table::DEFAULT_TOP as u64, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    top: u64,
    /// Order of the per-task tables: `loss` (the paper's: task loss alone) or `solved-first`
    /// (designs that solve the task, then goals solved, then task loss).
    #[arg(long, value_name = "RANKING", default_value = "loss")]
    rank: sweep::table::Ranking,
    /// Worker threads [default: the number of cores]; the results are the same for any number.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=256))]
    threads: Option<u64>,
    /// Print nothing but errors (with --out: the results go nowhere else).
    #[arg(long, requires = "out")]
    quiet: bool,
    /// Write the `--top` best designs of the overall ranking into DIR as design files
    /// (`01-modular6_Ll-Is-Ll-Il-D-Ls.json`, ...), ready for validate-design and optimize.
    #[arg(long, value_name = "DIR")]
    best_designs: Option<PathBuf>,
}

#[derive(Debug, clap::Args)]
pub(crate) struct MergeArgs {
    /// The shard folders (each a finished `sweep --shard K/N --out DIR`).
    #[arg(required = true, value_name = "DIR")]
    shards: Vec<PathBuf>,
    /// Folder for the merged sweep (the files the unsharded sweep writes).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Replace another sweep's files in --out.
    #[arg(long)]
    force: bool,
    /// Score against this finished sweep (as the shards' sweep was asked to).
    #[arg(long, value_name = "DIR")]
    reference: Option<PathBuf>,
    /// Rows of each ranked table.
    #[arg(long, value_name = "N", default_value_t = sweep::table::DEFAULT_TOP as u64, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    top: u64,
    /// Order of the per-task tables: `loss` (the paper's: task loss alone) or `solved-first`
    /// (designs that solve the task, then goals solved, then task loss).
    #[arg(long, value_name = "RANKING", default_value = "loss")]
    rank: sweep::table::Ranking,
    /// Print nothing but errors (with --out: the results go nowhere else).
    #[arg(long, requires = "out")]
    quiet: bool,
}

#[derive(Debug, clap::Args)]
pub(crate) struct Table1Args {
    /// Scenarios [default: scenarios/cluttered, this project's regeneration of the paper's 36
    /// cluttered tasks].
    #[arg(long, num_args = 1.., value_name = "SCENARIO")]
    scenarios: Vec<String>,
    /// Keep the sweep's files here too (see `sweep --out`).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Replace another sweep's files in --out.
    #[arg(long)]
    force: bool,
    /// Seed of IK's random starts.
    #[arg(long, value_name = "N", default_value_t = 0)]
    seed: u64,
    /// Worker threads [default: the number of cores].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=256))]
    threads: Option<u64>,
}

#[derive(Debug, clap::Args)]
pub(crate) struct GaArgs {
    /// The scenario (one task).
    #[arg(long, value_name = "FILE")]
    scenario: String,
    /// Seed of the GA's random choices.
    #[arg(long, value_name = "N", default_value_t = 0)]
    seed: u64,
    /// Seed of IK's random starts (as `sweep --seed`; a --reference must have been run with it).
    #[arg(long, value_name = "N", default_value_t = 0)]
    ik_seed: u64,
    /// Designs per generation.
    #[arg(long, value_name = "N", default_value_t = 128, value_parser = clap::value_parser!(u64).range(2..=100_000))]
    population: u64,
    /// Generations after the random first one.
    #[arg(long, value_name = "N", default_value_t = 100, value_parser = clap::value_parser!(u64).range(0..=100_000))]
    generations: u64,
    /// Score the best design against this finished brute force (`sweep catalog:modular6 --out DIR`).
    #[arg(long, value_name = "DIR")]
    reference: Option<PathBuf>,
    /// Write the run (settings, best design and record, best per generation) as JSON to FILE
    /// (never over an existing file unless --force).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Write the best design as a design file to FILE (never over an existing file unless
    /// --force), ready for validate-design and optimize.
    #[arg(long, value_name = "FILE")]
    best_design: Option<PathBuf>,
    /// Replace --out and --best-design if they exist.
    #[arg(long)]
    force: bool,
    /// Worker threads [default: the number of cores]; the run is the same for any number.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=256))]
    threads: Option<u64>,
    /// Print nothing but errors (with --out: the results go nowhere else).
    #[arg(long, requires = "out")]
    quiet: bool,
}

fn reference(dir: Option<&PathBuf>) -> Result<Option<sweep::Reference>, Failure> {
    Ok(match dir {
        Some(dir) => Some(sweep::read_reference(dir)?),
        None => None,
    })
}

/// `validate-design sweep ...`.
pub(crate) fn sweep_command(args: &SweepArgs) -> Result<ExitCode, Failure> {
    super::threads(args.threads);
    let ik = proving_ground::ik::IkOptions {
        seeds: usize::try_from(args.ik_seeds).unwrap_or(usize::MAX),
        search_boxes: args.search_boxes,
        seed: args.seed,
        ..Default::default()
    };
    let mode = if args.full {
        SweepMode::Full { ik, engines: args.engines }
    } else {
        SweepMode::ReachOnly { ik }
    };
    let shard = args
        .shard
        .as_deref()
        .map(Shard::parse)
        .transpose()
        .map_err(|_| sweep::SweepError::Shard(args.shard.clone().unwrap_or_default()))?;
    let load = LoadOptions {
        package_paths: args.package_paths.clone(),
        ..LoadOptions::default()
    };
    let designs = inputs::resolve_designs(&args.designs, &load)?;
    let scenarios = inputs::resolve_scenarios(&args.scenarios)?;
    let opts = SweepOptions {
        mode,
        out: args.out.clone(),
        force: args.force,
        shard,
        reference: reference(args.reference.as_ref())?,
        top: usize::try_from(args.top).unwrap_or(usize::MAX),
        ranking: args.rank,
        stop: Some(super::stop_on_signals()),
    };
    let progress = super::Bar::new("pairs", args.quiet, false);
    let result = sweep::run(&designs, &scenarios, &opts, &progress);
    progress.bar.finish_and_clear();
    let result = result?;
    let mut best = String::new();
    if let Some(dir) = &args.best_designs {
        let (files, skipped) = sweep::best_designs(&designs, &result.ranking, opts.top);
        proving_ground::pipeline::write_files_into(dir, &files)?;
        let skipped = if skipped.is_empty() {
            String::new()
        } else {
            format!(
                " ({} of the best are robots without a design file: {})",
                skipped.len(),
                skipped.join(", ")
            )
        };
        best = format!("wrote the {} best designs into {}{skipped}", files.len(), dir.display());
    }
    if !args.quiet {
        print!("{}", result.table);
        let lines = |n: usize| if n == 1 { "1 line".to_string() } else { format!("{n} lines") };
        let mut ignored = String::new();
        if result.foreign > 0 {
            ignored += &format!("; {} of another sweep left out", lines(result.foreign));
        }
        if result.damaged > 0 {
            ignored += &format!("; {} cut short or damaged left out", lines(result.damaged));
        }
        eprintln!(
            "{} pairs ({} computed now, {} resumed{ignored}){}",
            result.records.len(),
            result.computed,
            result.records.len() - result.computed,
            args.out.as_ref().map_or(String::new(), |d| format!("; results in {}", d.display()))
        );
        if !best.is_empty() {
            eprintln!("{best}");
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// `validate-design merge ...`.
pub(crate) fn merge_command(args: &MergeArgs) -> Result<ExitCode, Failure> {
    let result = sweep::merge(
        &args.shards,
        &args.out,
        args.force,
        reference(args.reference.as_ref())?,
        usize::try_from(args.top).unwrap_or(usize::MAX),
        args.rank,
    )?;
    if !args.quiet {
        print!("{}", result.table);
        eprintln!(
            "{} records from {} shards; results in {}",
            result.records.len(),
            args.shards.len(),
            args.out.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// `validate-design table1 ...`.
pub(crate) fn table1_command(args: &Table1Args) -> Result<ExitCode, Failure> {
    super::threads(args.threads);
    let scenario_args = if args.scenarios.is_empty() {
        vec![sweep::paper::TABLE_1_SCENARIOS.to_string()]
    } else {
        args.scenarios.clone()
    };
    let designs = inputs::resolve_designs(&[sweep::paper::TABLE_1_DESIGNS.to_string()], &LoadOptions::default())?;
    let scenarios = inputs::resolve_scenarios(&scenario_args)?;
    let opts = SweepOptions {
        stop: Some(super::stop_on_signals()),
        ..sweep::paper::table_1_options(args.seed, args.out.clone(), args.force)
    };
    let progress = super::Bar::new("pairs", false, false);
    let result = sweep::run(&designs, &scenarios, &opts, &progress);
    progress.bar.finish_and_clear();
    let result = result?;
    print!("{}", sweep::paper::table_1(&result.records, scenarios.len()));
    Ok(ExitCode::SUCCESS)
}

/// `validate-design ga ...`.
pub(crate) fn ga_command(args: &GaArgs) -> Result<ExitCode, Failure> {
    super::threads(args.threads);
    let scenario = inputs::resolve_scenarios(std::slice::from_ref(&args.scenario)).map_err(|e| match e {
        sweep::SweepError::Scenarios { message, .. } => sweep::SweepError::Scenarios {
            argument: format!("{} (--scenario)", args.scenario),
            message,
        },
        other => other,
    })?;
    let [scenario] = scenario.as_slice() else {
        return Err(sweep::SweepError::Scenarios {
            argument: args.scenario.clone(),
            message: "the GA runs on one scenario; this names several".into(),
        }
        .into());
    };
    let reference = reference(args.reference.as_ref())?;
    for out in [&args.out, &args.best_design].into_iter().flatten() {
        // Refused now what the write after the whole GA would refuse.
        let refused = if out.is_dir() {
            Some("a folder is there, expected a file name")
        } else if proving_ground::files::is_input(out) {
            Some("it is an input of this run")
        } else if out.exists() && !args.force {
            Some("the file exists; pass --force to replace it")
        } else {
            None
        };
        if let Some(why) = refused {
            return Err(sweep::SweepError::Write {
                path: out.clone(),
                message: why.into(),
            }
            .into());
        }
    }
    let opts = sweep::ga::GaOptions {
        population: usize::try_from(args.population).unwrap_or(usize::MAX),
        generations: usize::try_from(args.generations).unwrap_or(usize::MAX),
        seed: args.seed,
        ..Default::default()
    };
    let mode = sweep::ga::mode(args.ik_seed);
    let reference_records = reference
        .as_ref()
        .map(|r| sweep::reference_records(r, &mode, std::slice::from_ref(scenario)))
        .transpose()?;
    let progress = super::Bar::new("pairs", args.quiet, false);
    let result = sweep::ga::run(scenario, &mode, &opts, &progress);
    progress.bar.finish_and_clear();
    let result = result?;
    if let Some(path) = &args.out {
        result.save(path, args.force)?;
    }
    if let Some(path) = &args.best_design {
        result.save_best_design(path, args.force)?;
    }
    if !args.quiet {
        let best = &result.best;
        println!(
            "GA ({} x {} generations, seed {}) on {}: {} distinct designs evaluated",
            opts.population, opts.generations, opts.seed, result.scenario, result.evaluations
        );
        println!(
            "best {}: task loss {}, {}/{} goals solved{}",
            best.design,
            best.task_loss.map_or_else(|| "none".into(), |l| format!("{l:.4}")),
            best.goals_solved,
            best.goals,
            if best.task_solved { ", task solved" } else { "" }
        );
        let standing = reference_records.as_ref().and_then(|records| result.standing(records));
        if let (Some(reference), Some(standing)) = (&reference, standing) {
            println!(
                "against the {} designs of {}: score {}, percentile {}",
                standing.designs,
                reference.dir.display(),
                standing.score.map_or_else(|| "n/a".into(), |s| format!("{s:.4}")),
                standing.percentile.map_or_else(|| "n/a".into(), |p| format!("{p:.1}"))
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
