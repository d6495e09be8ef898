//! Fine-tuning a set of designs on one scenario as `validate-design optimize` does it: designs
//! that can share a batch are tuned together, each tuned design is named and described, checked
//! to read back to itself, and validated before and after under the same seeded options.

use super::{optimize, starts_of, tuned_design, Batch, Objective, OptimizeError, OptimizeOptions};
use crate::design::Design;
use crate::pipeline::{Loaded, ValidateOptions};
use crate::report::Report;
use crate::scenario::Scenario;
use std::path::Path;

/// One design after [`tune`].
#[derive(Debug, Clone)]
pub struct Tuned {
    /// The tuned design (`<name>-tuned`), as its file reads back.
    pub design: Design,
    /// Its design file.
    pub text: String,
    /// The objective at the start and at the result.
    pub objective: (f64, f64),
    /// The Adam step the result comes from (0: the start was kept).
    pub best_step: usize,
    /// How many designs shared its batch.
    pub batch_size: usize,
    /// Wall time of its batch (s).
    pub seconds: f64,
}

/// The designs grouped into batches, in input order: a design joins the first batch whose
/// designs it can share one with (dof count and capsule structure), else starts its own.
pub fn batches(designs: &[Design], scenario: &Scenario) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, design) in designs.iter().enumerate() {
        let joins = groups.iter_mut().find(|group| {
            let first = &designs[group[0]];
            first.dof() == design.dof() && Batch::new(&[first.clone(), design.clone()], scenario, vec![]).is_ok()
        });
        match joins {
            Some(group) => group.push(i),
            None => groups.push(vec![i]),
        }
    }
    groups
}

/// Fine-tunes every design on `scenario` (batched as [`batches`] groups them; each ends as it
/// would alone), one [`Tuned`] per design in input order.
///
/// # Errors
/// The optimizer's errors, and [`OptimizeError::Input`] when a tuned design's file does not
/// read back to the design (a bug, never silently written).
pub fn tune(
    designs: &[Design],
    scenario: &Scenario,
    opts: &OptimizeOptions,
    objective: &mut dyn Objective,
) -> Result<Vec<Tuned>, OptimizeError> {
    let mut tuned: Vec<Option<Tuned>> = vec![None; designs.len()];
    for group in batches(designs, scenario) {
        let members: Vec<Design> = group.iter().map(|&i| designs[i].clone()).collect();
        let started = std::time::Instant::now();
        let (batch, params) = starts_of(&members, scenario, opts)?;
        let optimized = optimize(objective, &batch, &members, params, opts)?;
        let seconds = started.elapsed().as_secs_f64();
        for (index, &i) in group.iter().enumerate() {
            let design = &designs[i];
            let result = tuned_design(design, &batch, &optimized.params, index, &format!("{}-tuned", design.name));
            let description = format!(
                "{} fine-tuned on scenario `{}` by validate-design optimize ({} Adam steps, seed {})",
                design.name, scenario.name, opts.steps, opts.seed
            );
            let text = crate::design::to_json(&result, &description);
            let name = format!("{}.json", result.name);
            let back = crate::design::parse(&text, Path::new(&name)).map_err(|e| OptimizeError::Input(e.to_string()))?;
            if back.joints != result.joints {
                return Err(OptimizeError::Input(format!(
                    "{name}: the tuned design does not read back to itself"
                )));
            }
            tuned[i] = Some(Tuned {
                design: back,
                text,
                objective: (optimized.objective.0[index], optimized.objective.1[index]),
                best_step: optimized.best_step[index],
                batch_size: group.len(),
                seconds,
            });
        }
    }
    Ok(tuned.into_iter().flatten().collect())
}

/// The reports of the runs `validate-design` makes (without MuJoCo's kinematics check) of the
/// design as it was (`loaded`, read from `path`) and as tuned (`tuned`, written to
/// `tuned_path`), on `scenario` under the same options: before, after.
///
/// # Errors
/// As [`crate::run::validated`].
pub fn before_and_after(
    path: &Path,
    loaded: Loaded,
    tuned_path: &Path,
    tuned: &Design,
    scenario: &Scenario,
    opts: &ValidateOptions,
) -> Result<(Report, Report), crate::error::Error> {
    let run_opts = crate::run::Options {
        kinematics_checks: 0,
        validate: opts.clone(),
        ..Default::default()
    };
    let silent = &crate::progress::Silent;
    let (_, before) = crate::run::validated(path, loaded, scenario.clone(), &run_opts, silent)?;
    let after_loaded = Loaded {
        model: crate::model::from_design(tuned),
        design: Some(tuned.clone()),
    };
    let (_, after) = crate::run::validated(tuned_path, after_loaded, scenario.clone(), &run_opts, silent)?;
    Ok((before, after))
}
