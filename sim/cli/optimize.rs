//! `validate-design optimize`: the command-line side of [`proving_ground::optimize`].

use super::Failure;
use proving_ground::design::Design;
use proving_ground::error::Error;
use proving_ground::optimize::{self, OptimizeError, OptimizeOptions, Tensors};
use proving_ground::pipeline::{self, Engines, LoadOptions, ValidateOptions};
use proving_ground::report::Report;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub(crate) struct OptimizeArgs {
    /// The design JSONs to fine-tune (free and economic: d, a and the joints; modular and
    /// preset: the joints only). Designs of one dof count and capsule structure are tuned in one
    /// batch, as the paper tunes its generated robots; each ends as it would alone.
    #[arg(value_name = "DESIGN", required = true, num_args = 1..)]
    designs: Vec<PathBuf>,
    /// The scenario whose goals and obstacles the objective uses.
    #[arg(long, value_name = "FILE")]
    scenario: PathBuf,
    /// Where to write: a folder (several designs, an existing folder, or a path ending in `/`)
    /// gets `<input name>-tuned.json` per design; otherwise the tuned design's file. Never over
    /// an input.
    #[arg(long, value_name = "PATH")]
    out: PathBuf,
    /// Adam steps (the paper's 200).
    #[arg(long, value_name = "N", default_value_t = 200, value_parser = clap::value_parser!(u64).range(0..=1_000_000))]
    steps: u64,
    /// Seed of the random starts and of IK (both validations use it too).
    #[arg(long, value_name = "N", default_value_t = 0)]
    seed: u64,
    /// Engines of the two validations.
    #[arg(long, value_name = "LIST", default_value_t = Engines::all())]
    engines: Engines,
    /// Where the tensors live: cpu, or cuda (a build with the `cuda` feature and a GPU).
    #[arg(long, value_name = "DEVICE", default_value = "cpu", value_parser = ["cpu", "cuda"])]
    device: String,
}

/// One input design and what became of it.
struct Tuning {
    path: PathBuf,
    loaded: pipeline::Loaded,
    design: Design,
    /// Where its tuned design is written.
    out: PathBuf,
    tuned: Option<Design>,
    text: String,
    summary: String,
}

pub(crate) fn optimize_command(args: &OptimizeArgs) -> Result<ExitCode, Failure> {
    let engines = args.engines;
    let mut tunings = Vec::with_capacity(args.designs.len());
    for path in &args.designs {
        if pipeline::input_kind(path)? != pipeline::InputKind::Design {
            return Err(Failure::from(OptimizeError::Input(format!(
                "{}: optimize needs a design JSON (DH rows); a URDF or MJCF robot has no design parameters",
                path.display()
            ))));
        }
        let loaded = pipeline::load(path, &LoadOptions::default())?;
        let design = loaded
            .design
            .clone()
            .ok_or_else(|| OptimizeError::Input(format!("{}: not a design", path.display())))?;
        let out = out_path(args, path)?;
        // Compared without case: on a case-insensitive file system `A` and `a` are one file.
        let same = |t: &Tuning| t.out.to_string_lossy().to_lowercase() == out.to_string_lossy().to_lowercase();
        if tunings.iter().any(same) {
            return Err(Failure::from(OptimizeError::Input(format!(
                "{}: another input is also called `{}`; the tuned designs would share `{}`",
                path.display(),
                path.file_stem().unwrap_or_default().to_string_lossy(),
                out.display()
            ))));
        }
        tunings.push(Tuning {
            path: path.clone(),
            loaded,
            design,
            out,
            tuned: None,
            text: String::new(),
            summary: String::new(),
        });
    }
    let scenario = pipeline::load_scenario(&args.scenario)?;
    check_targets(args, &tunings)?;
    let opts = OptimizeOptions {
        steps: usize::try_from(args.steps).unwrap_or(usize::MAX),
        seed: args.seed,
        ..Default::default()
    };
    let mut objective = match args.device.as_str() {
        "cuda" if !cfg!(feature = "cuda") => return Err(OptimizeError::Input(
            "--device cuda: this build has no CUDA support; build with `cargo build --release --features cuda` (needs the CUDA toolkit)"
                .into(),
        )
        .into()),
        "cuda" => Tensors::cuda(0)?,
        _ => Tensors::default(),
    };
    for group in batches(&tunings, &scenario) {
        let designs: Vec<Design> = group.iter().map(|&i| tunings[i].design.clone()).collect();
        let started = std::time::Instant::now();
        let (batch, params) = optimize::starts_of(&designs, &scenario, &opts)?;
        let optimized = optimize::optimize(&mut objective, &batch, &designs, params, &opts)?;
        let elapsed = started.elapsed().as_secs_f64();
        let together = if group.len() > 1 {
            format!(" (one batch of {} designs)", group.len())
        } else {
            String::new()
        };
        for (index, &i) in group.iter().enumerate() {
            let tuning = &mut tunings[i];
            let design = &tuning.design;
            let name = format!("{}-tuned", design.name);
            let tuned = optimize::tuned_design(design, &batch, &optimized.params, index, &name);
            let description = format!(
                "{} fine-tuned on scenario `{}` by validate-design optimize ({} Adam steps, seed {})",
                design.name, scenario.name, opts.steps, opts.seed
            );
            let text = proving_ground::design::to_json(&tuned, &description);
            // The file must read back to exactly the design optimized.
            let back = proving_ground::design::parse(&text, &tuning.out).map_err(Error::from)?;
            if back.joints != tuned.joints {
                return Err(
                    OptimizeError::Input(format!("{}: the tuned design does not read back to itself", tuning.out.display())).into(),
                );
            }
            tuning.summary = format!(
                "optimize {}: {} starts x {} goals, {} steps in {elapsed:.2} s{together}; objective {:.4} -> {:.4} (best at step {}); wrote {}",
                tuning.path.display(),
                opts.seeds,
                scenario.goals.len(),
                opts.steps,
                optimized.objective.0[index],
                optimized.objective.1[index],
                optimized.best_step[index],
                tuning.out.display()
            );
            tuning.tuned = Some(back);
            tuning.text = text;
        }
    }
    if into_folder(args) {
        let files: Vec<(String, Vec<u8>)> = tunings
            .iter()
            .map(|t| {
                let name = t.out.file_name().unwrap_or_default().to_string_lossy().into_owned();
                (name, t.text.clone().into_bytes())
            })
            .collect();
        pipeline::write_files_into(&args.out, &files)?;
    } else {
        for tuning in &tunings {
            pipeline::write_output(&tuning.out, &tuning.text)?;
        }
    }

    let validate_options = ValidateOptions {
        ik: proving_ground::ik::IkOptions {
            seed: args.seed,
            ..Default::default()
        },
        planner: proving_ground::plan::PlannerOptions {
            seed: args.seed,
            ..Default::default()
        },
        engines,
        ..Default::default()
    };
    let (mut failed, mut undecided) = (false, false);
    for tuning in tunings {
        println!("{}", tuning.summary);
        let Some(back) = tuning.tuned else {
            continue;
        };
        let before = validated(&tuning.path, tuning.loaded, &scenario, &validate_options)?;
        let after_loaded = pipeline::Loaded {
            model: proving_ground::model::from_design(&back),
            design: Some(back),
        };
        let after = validated(&tuning.out, after_loaded, &scenario, &validate_options)?;
        print!("{}", side_by_side(&before, &after));
        failed |= after.verdict.word == "FAIL";
        undecided |= after.verdict.word == "UNDECIDED";
    }
    // As a single validation: 1 when a tuned design fails, else 3 when one is undecided.
    Ok(if failed {
        ExitCode::from(1)
    } else if undecided {
        ExitCode::from(3)
    } else {
        ExitCode::SUCCESS
    })
}

/// The report of the run `validate-design` makes of `loaded` (read from `path`) on `scenario`,
/// without MuJoCo's kinematics check.
fn validated(
    path: &Path,
    loaded: pipeline::Loaded,
    scenario: &proving_ground::scenario::Scenario,
    opts: &ValidateOptions,
) -> Result<Report, Failure> {
    let run_opts = proving_ground::Options {
        kinematics_checks: 0,
        validate: opts.clone(),
        ..Default::default()
    };
    let (_, report) = proving_ground::run::validated(path, loaded, scenario.clone(), &run_opts, &proving_ground::progress::Silent)?;
    Ok(report)
}

/// Whether `--out` names a folder: several designs, an existing folder, or a trailing `/`.
fn into_folder(args: &OptimizeArgs) -> bool {
    args.designs.len() > 1 || args.out.is_dir() || args.out.as_os_str().to_string_lossy().ends_with(std::path::MAIN_SEPARATOR)
}

/// Where the tuned design of `input` goes: `--out` itself, or `<input name>-tuned.json` in the
/// `--out` folder.
fn out_path(args: &OptimizeArgs, input: &Path) -> Result<PathBuf, Failure> {
    if !into_folder(args) {
        return Ok(args.out.clone());
    }
    let stem = input
        .file_stem()
        .ok_or_else(|| OptimizeError::Input(format!("{}: no file name", input.display())))?;
    Ok(args.out.join(format!("{}-tuned.json", stem.to_string_lossy())))
}

/// Refuses, before any work, what the writes at the end would refuse: a folder `--out` that is
/// a file, a file `--out` that is a folder, a target that this run read.
fn check_targets(args: &OptimizeArgs, tunings: &[Tuning]) -> Result<(), Failure> {
    if into_folder(args) && args.out.exists() && !args.out.is_dir() {
        return Err(OptimizeError::Input(format!(
            "--out {}: exists and is not a folder; several tuned designs need a folder",
            args.out.display()
        ))
        .into());
    }
    for tuning in tunings {
        if tuning.out.is_dir() {
            return Err(OptimizeError::Input(format!("--out {}: a folder is there, expected a file name", tuning.out.display())).into());
        }
        if proving_ground::files::is_input(&tuning.out) {
            return Err(Error::WouldOverwriteInput { path: tuning.out.clone() }.into());
        }
    }
    Ok(())
}

/// The designs grouped into batches, in input order: a design joins the first batch whose
/// designs it can share one with (dof count and capsule structure), else starts its own.
fn batches(tunings: &[Tuning], scenario: &proving_ground::scenario::Scenario) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, tuning) in tunings.iter().enumerate() {
        let joins = groups.iter_mut().find(|group| {
            let first = &tunings[group[0]].design;
            first.dof() == tuning.design.dof() && optimize::Batch::new(&[first.clone(), tuning.design.clone()], scenario, vec![]).is_ok()
        });
        match joins {
            Some(group) => group.push(i),
            None => groups.push(vec![i]),
        }
    }
    groups
}

/// The two verdicts as a small table.
fn side_by_side(before: &Report, after: &Report) -> String {
    let reached = |r: &Report| format!("{}/{}", r.goals.iter().filter(|g| g.outcome == "reached").count(), r.goals.len());
    let loss = |value: Option<f64>| value.map_or_else(|| "none".into(), |v| format!("{v:.4}"));
    let verdict = |r: &Report| r.verdict.word.to_string();
    let rows = [
        ("", before.design.name.clone(), after.design.name.clone()),
        ("goals reached", reached(before), reached(after)),
        (
            "paper loss (min over IK)",
            loss(before.paper_loss.total),
            loss(after.paper_loss.total),
        ),
        (
            "paper loss (chosen)",
            loss(before.paper_loss.at_chosen),
            loss(after.paper_loss.at_chosen),
        ),
        (
            "hardware cost (m)",
            format!("{:.4}", before.paper_loss.hardware / proving_ground::ik::HARDWARE_WEIGHT),
            format!("{:.4}", after.paper_loss.hardware / proving_ground::ik::HARDWARE_WEIGHT),
        ),
        ("verdict", verdict(before), verdict(after)),
    ];
    let width = rows.iter().map(|r| r.1.len()).max().unwrap_or(0).max(8);
    let mut out = String::new();
    for (label, a, b) in rows {
        out.push_str(&format!("{label:<26} {a:<width$}  {b}\n"));
    }
    for reason in &after.verdict.reasons {
        out.push_str(&format!("tuned: {reason}\n"));
    }
    out
}
