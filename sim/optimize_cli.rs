//! `validate-design optimize`: the command-line side of [`proving_ground::optimize`].

use proving_ground::error::Error;
use proving_ground::optimize::{self, OptimizeError, OptimizeOptions, Tensors};
use proving_ground::pipeline::{self, Engines, LoadOptions, ValidateOptions};
use proving_ground::report::{self, Report};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub(crate) struct OptimizeArgs {
    /// The design JSON to fine-tune (free and economic: d, a and the joints; modular and
    /// preset: the joints only).
    #[arg(value_name = "DESIGN")]
    design: PathBuf,
    /// The scenario whose goals and obstacles the objective uses.
    #[arg(long, value_name = "FILE")]
    scenario: PathBuf,
    /// Where to write the tuned design (never over an input).
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// Adam steps (the paper's 200).
    #[arg(long, value_name = "N", default_value_t = 200, value_parser = clap::value_parser!(u64).range(0..=1_000_000))]
    steps: u64,
    /// Seed of the random starts and of IK (both validations use it too).
    #[arg(long, value_name = "N", default_value_t = 0)]
    seed: u64,
    /// Engines of the two validations.
    #[arg(long, value_name = "LIST", default_value = "rapier,mujoco")]
    engines: String,
    /// Where the tensors live: cpu, or cuda (a build with the `cuda` feature and a GPU).
    #[arg(long, value_name = "DEVICE", default_value = "cpu", value_parser = ["cpu", "cuda"])]
    device: String,
}

pub(crate) fn optimize_command(args: &OptimizeArgs) -> Result<ExitCode, Error> {
    if pipeline::input_kind(&args.design)? != pipeline::InputKind::Design {
        return Err(Error::from(OptimizeError::Input(format!(
            "{}: optimize needs a design JSON (DH rows); a URDF or MJCF robot has no design parameters",
            args.design.display()
        ))));
    }
    let names = args.engines.split(',').map(str::trim).filter(|s| !s.is_empty() && *s != "none");
    let engines = Engines::from_names(names)
        .map_err(|name| OptimizeError::Input(format!("--engines: `{name}` is not an engine; expected rapier, mujoco or none")))?;
    let loaded = pipeline::load(&args.design, &LoadOptions::default())?;
    let design = loaded.design.clone().expect("a design file gives a design");
    let scenario = pipeline::load_scenario(&args.scenario)?;
    let opts = OptimizeOptions {
        steps: usize::try_from(args.steps).unwrap_or(usize::MAX),
        seed: args.seed,
        ..Default::default()
    };
    let mut objective = match args.device.as_str() {
        "cuda" => Tensors::cuda(0)?,
        _ => Tensors::default(),
    };
    let started = std::time::Instant::now();
    let (batch, params) = optimize::starts(&design, &scenario, &opts)?;
    let optimized = optimize::optimize(&mut objective, &batch, std::slice::from_ref(&design), params, &opts)?;
    let elapsed = started.elapsed().as_secs_f64();
    let name = format!("{}-tuned", design.name);
    let tuned = optimize::tuned_design(&design, &batch, &optimized.params, 0, &name);
    let description = format!(
        "{} fine-tuned on scenario `{}` by validate-design optimize ({} Adam steps, seed {})",
        design.name, scenario.name, opts.steps, opts.seed
    );
    let text = optimize::write::design_json(&tuned, &description);
    // The file must read back to exactly the design optimized.
    let back = proving_ground::design::parse(&text, &args.out)?;
    if back.joints != tuned.joints {
        return Err(OptimizeError::Input(format!("{}: the tuned design does not read back to itself", args.out.display())).into());
    }
    pipeline::write_output(&args.out, &text)?;
    println!(
        "optimize: {} starts x {} goals, {} steps in {elapsed:.2} s; objective {:.4} -> {:.4} (best at step {}); wrote {}",
        opts.seeds,
        scenario.goals.len(),
        opts.steps,
        optimized.objective.0[0],
        optimized.objective.1[0],
        optimized.best_step[0],
        args.out.display()
    );

    let validate_options = ValidateOptions {
        ik: proving_ground::ik::IkOptions {
            seed: args.seed,
            ..Default::default()
        },
        engines,
        ..Default::default()
    };
    let before = report::build(&pipeline::validate(loaded, scenario.clone(), &validate_options)?);
    let after_loaded = pipeline::Loaded {
        model: proving_ground::model::from_design(&back),
        design: Some(back),
    };
    let after = report::build(&pipeline::validate(after_loaded, scenario, &validate_options)?);
    print!("{}", side_by_side(&before, &after));
    Ok(if after.verdict.passed {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// The two verdicts as a small table.
fn side_by_side(before: &Report, after: &Report) -> String {
    let reached = |r: &Report| format!("{}/{}", r.goals.iter().filter(|g| g.outcome == "reached").count(), r.goals.len());
    let loss = |value: Option<f64>| value.map_or_else(|| "none".into(), |v| format!("{v:.4}"));
    let verdict = |r: &Report| if r.verdict.passed { "PASS" } else { "FAIL" }.to_string();
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
