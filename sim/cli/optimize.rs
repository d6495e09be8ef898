//! `validate-design optimize`: the command-line side of [`proving_ground::optimize`].

use super::Failure;
use proving_ground::design::Design;
use proving_ground::error::Error;
use proving_ground::optimize::{self, Fused, OptimizeError, OptimizeOptions};
use proving_ground::pipeline::{self, Engines, LoadOptions, ValidateOptions};
use proving_ground::report::Report;
use proving_ground::run::Outcome;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub(crate) struct OptimizeArgs {
    /// The design JSONs to fine-tune (free and economic: d, a and the joints; modular: the best
    /// single-module swap instead; preset: nothing to tune). Designs of one dof count and capsule
    /// structure are tuned in one batch, as the paper tunes its generated robots; each ends as it
    /// would alone. A tuned design is written only if it keeps every goal of the original.
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
    /// Replace tuned-design files already there (without it an existing file is refused before
    /// any work).
    #[arg(long)]
    force: bool,
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

/// One input design: where it came from and where its tuned design goes.
struct Input {
    path: PathBuf,
    loaded: pipeline::Loaded,
    design: Design,
    out: PathBuf,
}

pub(crate) fn optimize_command(args: &OptimizeArgs) -> Result<ExitCode, Failure> {
    let mut inputs: Vec<Input> = Vec::with_capacity(args.designs.len());
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
        let same = |t: &Input| t.out.to_string_lossy().to_lowercase() == out.to_string_lossy().to_lowercase();
        if inputs.iter().any(same) {
            return Err(Failure::from(OptimizeError::Input(format!(
                "{}: another input is also called `{}`; the tuned designs would share `{}`",
                path.display(),
                path.file_stem().unwrap_or_default().to_string_lossy(),
                out.display()
            ))));
        }
        inputs.push(Input {
            path: path.clone(),
            loaded,
            design,
            out,
        });
    }
    let scenario = pipeline::load_scenario(&args.scenario)?;
    check_targets(args, &inputs)?;
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
        "cuda" => Fused::cuda(0)?,
        _ => Fused::cpu(),
    };
    // Only free and economic designs have lengths to tune; the others are validated as they are.
    let tunable: Vec<usize> = (0..inputs.len())
        .filter(|&i| optimize::nothing_to_tune(&inputs[i].design).is_none())
        .collect();
    let designs: Vec<Design> = tunable.iter().map(|&i| inputs[i].design.clone()).collect();
    let mut tuned: Vec<Option<optimize::Tuned>> = vec![None; inputs.len()];
    for (&i, t) in tunable.iter().zip(optimize::tune(&designs, &scenario, &opts, &mut objective)?) {
        tuned[i] = Some(t);
    }

    let validate_options = ValidateOptions {
        engines: args.engines,
        ..ValidateOptions::seeded(args.seed)
    };
    // Everything is validated before anything is written: what is written is what passed the
    // comparison, and the files are one set.
    let mut worst = Outcome::Pass;
    let mut files: Vec<(PathBuf, String)> = Vec::with_capacity(inputs.len());
    let mut lines: Vec<String> = Vec::new();
    for (input, tuned) in inputs.into_iter().zip(tuned) {
        let Some(t) = tuned else {
            let why = optimize::nothing_to_tune(&input.design).unwrap_or_default();
            let swaps = optimize::module_swaps(&input.design).len();
            let best = if swaps > 0 {
                optimize::best_module_swap(&input.design, &scenario, &validate_options.ik)?
            } else {
                None
            };
            let Some((what, neighbour, theirs, own)) = best else {
                let report = optimize::validation(&input.path, input.loaded, &scenario, &validate_options)?;
                let swapped = if swaps > 0 {
                    format!("; none of its {swaps} module swaps beats it by the reach-only metric")
                } else {
                    String::new()
                };
                println!("optimize {}: {why}{swapped}; verdict {}", input.path.display(), report.verdict.word);
                let description = format!(
                    "{} as it was: validate-design optimize found nothing to tune in it",
                    input.design.name
                );
                files.push((input.out.clone(), proving_ground::design::to_json(&input.design, &description)));
                lines.push(format!("wrote {}: the design unchanged", input.out.display()));
                worst = worst.max(Outcome::of(&report));
                continue;
            };
            let loss = |v: Option<f64>| v.map_or_else(|| "none".into(), |v| format!("{v:.4}"));
            println!(
                "optimize {}: {why}; the discrete analogue, its {swaps} module swaps by the reach-only metric: best {what} ({}/{} goals solved, task loss {}; the design itself {}/{}, {})",
                input.path.display(),
                theirs.goals_solved,
                theirs.goals,
                loss(theirs.task_loss),
                own.goals_solved,
                own.goals,
                loss(own.task_loss)
            );
            let original = input.design.clone();
            let (before, after) =
                optimize::before_and_after(&input.path, input.loaded, &input.out, &neighbour, &[], &scenario, &validate_options)?;
            print!("{}", side_by_side(&before, &after));
            let description = format!(
                "{} with {what}: the best module swap found by validate-design optimize",
                original.name
            );
            let candidate = proving_ground::design::to_json(&neighbour, &description);
            let choice = optimize::choose(
                &original,
                candidate,
                &format!("the design with {what}"),
                "its best module swap",
                &before,
                &after,
            );
            lines.push(format!("wrote {}: {}", input.out.display(), choice.said));
            files.push((input.out.clone(), choice.text));
            worst = worst.max(choice.outcome);
            continue;
        };
        let together = if t.batch_size > 1 {
            format!(" (one batch of {} designs)", t.batch_size)
        } else {
            String::new()
        };
        println!(
            "optimize {}: {} starts x {} goals, {} steps in {:.2} s{together}; objective {:.4} -> {:.4} (best at step {})",
            input.path.display(),
            opts.seeds,
            scenario.goals.len(),
            opts.steps,
            t.seconds,
            t.objective.0,
            t.objective.1,
            t.best_step,
        );
        let original = input.design.clone();
        let (before, after) = optimize::before_and_after(
            &input.path,
            input.loaded,
            &input.out,
            &t.design,
            &t.configurations,
            &scenario,
            &validate_options,
        )?;
        print!("{}", side_by_side(&before, &after));
        if let Some(validated) = after.paper_loss.as_ref().and_then(|p| p.total) {
            println!(
                "objective {:.4} at the optimizer's own configurations; paper loss {validated:.4} at the IK solutions the validation found for the tuned design (IK solves each goal again, from its own starts and the optimizer's configurations: a goal it reaches costs no distance, a missed one its closest attempt)",
                t.objective.1
            );
        }
        let choice = optimize::choose(&original, t.text.clone(), "the tuned design", "tuning", &before, &after);
        lines.push(format!("wrote {}: {}", input.out.display(), choice.said));
        files.push((input.out.clone(), choice.text));
        worst = worst.max(choice.outcome);
    }
    if into_folder(args) {
        let named: Vec<(String, Vec<u8>)> = files
            .into_iter()
            .map(|(path, text)| {
                (
                    path.file_name().unwrap_or_default().to_string_lossy().into_owned(),
                    text.into_bytes(),
                )
            })
            .collect();
        pipeline::write_files_into(&args.out, &named)?;
    } else {
        let mut set = pipeline::OutputSet::default();
        for (path, text) in &files {
            set.add(path, text.as_bytes())?;
        }
        set.commit()?;
    }
    for line in lines {
        println!("{line}");
    }
    // As a single validation of what was written: 1 when one fails, else 3 when one is undecided.
    Ok(super::exit_code(worst))
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
fn check_targets(args: &OptimizeArgs, inputs: &[Input]) -> Result<(), Failure> {
    if into_folder(args) && args.out.exists() && !args.out.is_dir() {
        return Err(OptimizeError::Input(format!(
            "--out {}: exists and is not a folder; several tuned designs need a folder",
            args.out.display()
        ))
        .into());
    }
    for input in inputs {
        if input.out.is_dir() {
            return Err(OptimizeError::Input(format!("--out {}: a folder is there, expected a file name", input.out.display())).into());
        }
        if proving_ground::files::is_input(&input.out) {
            return Err(Error::WouldOverwriteInput { path: input.out.clone() }.into());
        }
        if input.out.exists() && !args.force {
            return Err(OptimizeError::Input(format!(
                "--out {}: the file exists; pass --force to replace it",
                input.out.display()
            ))
            .into());
        }
    }
    Ok(())
}

/// The two verdicts as a small table.
fn side_by_side(before: &Report, after: &Report) -> String {
    let reached = |r: &Report| format!("{}/{}", r.goals.iter().filter(|g| g.outcome == "reached").count(), r.goals.len());
    let loss = |value: Option<f64>| value.map_or_else(|| "none".into(), |v| format!("{v:.4}"));
    let verdict = |r: &Report| r.verdict.word.to_string();
    let cost = |r: &Report| r.design.hardware_cost_m.map_or_else(|| "none".into(), |c| format!("{c:.4}"));
    let rows = [
        ("", before.design.name.clone(), after.design.name.clone()),
        ("goals reached", reached(before), reached(after)),
        (
            "paper loss (min over IK)",
            loss(before.paper_loss.as_ref().and_then(|p| p.total)),
            loss(after.paper_loss.as_ref().and_then(|p| p.total)),
        ),
        (
            "paper loss (chosen)",
            loss(before.paper_loss.as_ref().and_then(|p| p.at_chosen)),
            loss(after.paper_loss.as_ref().and_then(|p| p.at_chosen)),
        ),
        ("hardware cost (m)", cost(before), cost(after)),
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
