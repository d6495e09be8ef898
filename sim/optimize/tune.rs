//! Fine-tuning a set of designs on one scenario as `validate-design optimize` does it: designs
//! that can share a batch are tuned together, each tuned design is named and described, checked
//! to read back to itself, and validated before and after under the same seeded options; a
//! tuned design that loses ground on its original is not returned ([`lost_ground`]).

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
    /// The optimizer's configurations of the tuned design, per goal (one per start): IK's
    /// starts when the tuned design is validated ([`crate::ik::IkOptions::goal_starts`]).
    pub configurations: Vec<Vec<Vec<f64>>>,
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
            let mut configurations = vec![Vec::new(); scenario.goals.len()];
            for (sample, q) in batch.samples.iter().zip(optimized.params.q.chunks(batch.dof)) {
                if sample.design == index {
                    if let Some(goal) = configurations.get_mut(sample.goal) {
                        goal.push(q.to_vec());
                    }
                }
            }
            tuned[i] = Some(Tuned {
                configurations,
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
/// `tuned_path`), on `scenario` under the same options (the tuned design's IK also starts from
/// `configurations`, the optimizer's per goal): before, after.
///
/// # Errors
/// As [`crate::run::validated`].
pub fn before_and_after(
    path: &Path,
    loaded: Loaded,
    tuned_path: &Path,
    tuned: &Design,
    configurations: &[Vec<Vec<f64>>],
    scenario: &Scenario,
    opts: &ValidateOptions,
) -> Result<(Report, Report), crate::error::Error> {
    let before = validation(path, loaded, scenario, opts)?;
    let after_loaded = Loaded {
        model: crate::model::from_design(tuned),
        design: Some(tuned.clone()),
    };
    let mut after_opts = opts.clone();
    after_opts.ik.goal_starts = configurations.to_vec();
    let after = validation(tuned_path, after_loaded, scenario, &after_opts)?;
    Ok((before, after))
}

/// The report of the run `validate-design` makes of `loaded` (read from `path`) on `scenario`,
/// without MuJoCo's kinematics check.
///
/// # Errors
/// As [`crate::run::validated`].
pub fn validation(path: &Path, loaded: Loaded, scenario: &Scenario, opts: &ValidateOptions) -> Result<Report, crate::error::Error> {
    let run_opts = crate::run::Options {
        kinematics_checks: 0,
        validate: opts.clone(),
        ..Default::default()
    };
    let (_, report) = crate::run::validated(path, loaded, scenario.clone(), &run_opts, &crate::progress::Silent)?;
    Ok(report)
}

/// Why `design` has nothing continuous to tune (modular and preset designs: their lengths are
/// their modules' or the robot's; only the joints would move), or `None` for free and economic
/// designs.
pub fn nothing_to_tune(design: &Design) -> Option<&'static str> {
    match design.mode {
        crate::design::DesignMode::Free | crate::design::DesignMode::Economic => None,
        crate::design::DesignMode::Modular => {
            Some("a modular design's lengths are its modules': nothing continuous to tune (only the joints would move)")
        }
        crate::design::DesignMode::Preset => Some("a preset is a published robot: nothing continuous to tune (only the joints would move)"),
    }
}

/// Where the full validation of a tuned design (`after`) falls behind its original's
/// (`before`), one reason per loss: a goal the original reaches that the tuned design does not,
/// a worse outcome (PASS, UNDECIDED, FAIL), a higher paper loss (the least over the goals' IK
/// solutions) without a goal gained for it. Empty when the tuned design keeps all the ground the
/// original holds: only then is it returned.
pub fn lost_ground(before: &Report, after: &Report) -> Vec<String> {
    let reached = |r: &Report| r.goals.iter().filter(|g| g.outcome == "reached").count();
    let mut reasons = Vec::new();
    for (old, new) in before.goals.iter().zip(&after.goals) {
        if old.outcome == "reached" && new.outcome != "reached" {
            reasons.push(format!(
                "goal {} ({}) is reached by the original, {} after tuning",
                old.index, old.name, new.outcome
            ));
        }
    }
    let outcome = |r: &Report| crate::run::Outcome::of(r);
    if outcome(after) > outcome(before) {
        reasons.push(format!("the verdict falls from {} to {}", before.verdict.word, after.verdict.word));
    }
    let loss = |r: &Report| r.paper_loss.as_ref().and_then(|p| p.total);
    match (loss(before), loss(after)) {
        (Some(old), Some(new)) if new > old && reasons.is_empty() && reached(after) <= reached(before) => {
            reasons.push(format!("the paper loss (min over IK) rises from {old:.4} to {new:.4}"))
        }
        (Some(_), None) => reasons.push("a goal of the tuned design has no configuration at all (no paper loss)".into()),
        _ => {}
    }
    reasons
}

/// What `optimize` writes for one design and what it says of it.
#[derive(Debug, Clone)]
pub struct Choice {
    /// The design file written.
    pub text: String,
    /// Which design it is and why (`the tuned design (...)`, `the original design, kept: ...`).
    pub said: String,
    /// The outcome of the written design's validation.
    pub outcome: crate::run::Outcome,
}

/// The candidate (`candidate_text`, called `what`) when [`lost_ground`] finds nothing between
/// the original's report (`before`) and the candidate's (`after`); else the original design,
/// its file saying why (`how` names what made the candidate: `tuning`, `its best module swap`).
pub fn choose(original: &Design, candidate_text: String, what: &str, how: &str, before: &Report, after: &Report) -> Choice {
    let lost = lost_ground(before, after);
    if lost.is_empty() {
        return Choice {
            text: candidate_text,
            said: format!("{what} (it reaches every goal the original reaches, with no worse verdict or loss)"),
            outcome: crate::run::Outcome::of(after),
        };
    }
    let why = lost.join("; ");
    let description = format!(
        "{} as it was: validate-design optimize kept it because {how} lost ground ({why})",
        original.name
    );
    Choice {
        text: crate::design::to_json(original, &description),
        said: format!("the original design, kept: {why}"),
        outcome: crate::run::Outcome::of(before),
    }
}

/// A modular design's neighbours: the designs with one slot's module swapped for another
/// catalog module (base and tool kept), in slot order then catalog order; none for other
/// designs.
pub fn module_swaps(design: &Design) -> Vec<(String, Design)> {
    use crate::design::catalog::SlotOption;
    let Some(slots) = &design.modules else { return Vec::new() };
    let mut swaps = Vec::new();
    for (k, &current) in slots.iter().enumerate() {
        for option in SlotOption::ALL.into_iter().filter(|&o| o != current) {
            let mut changed = slots.clone();
            changed[k] = option;
            let what = format!("slot {} {} -> {}", k + 1, current.name(), option.name());
            let neighbour = Design {
                base: design.base,
                tool: design.tool,
                ..Design::modular(&format!("{}-tuned", design.name), &changed)
            };
            swaps.push((what, neighbour));
        }
    }
    swaps
}

/// The discrete analogue of fine-tuning for a modular design: its module swaps
/// ([`module_swaps`]) and itself scored by the paper's reach-only metric on `scenario` (goals
/// solved, then the task loss), in parallel; the best swap when it beats the design by that
/// metric (what it changes, the design, its record and the design's own), else `None`.
///
/// # Errors
/// A design the pipeline cannot build or evaluate.
pub fn best_module_swap(
    design: &Design,
    scenario: &Scenario,
    ik: &crate::ik::IkOptions,
) -> Result<Option<(String, Design, crate::sweep::record::Record, crate::sweep::record::Record)>, crate::error::Error> {
    use rayon::prelude::*;
    let mode = crate::sweep::SweepMode::ReachOnly { ik: ik.clone() };
    let record = |name: &str, d: &Design| {
        let loaded = Loaded {
            model: crate::model::from_design(d),
            design: Some(d.clone()),
        };
        crate::sweep::record::evaluate(name, &scenario.name, loaded, scenario.clone(), &mode)
    };
    let own = record(&design.name, design)?;
    let swaps = module_swaps(design);
    let records = swaps.par_iter().map(|(what, d)| record(what, d)).collect::<Result<Vec<_>, _>>()?;
    // Goals solved first, then the loss (none last); the first of equals, for determinism.
    let better = |a: &crate::sweep::record::Record, b: &crate::sweep::record::Record| {
        let loss = |r: &crate::sweep::record::Record| r.task_loss.unwrap_or(f64::INFINITY);
        a.goals_solved > b.goals_solved || (a.goals_solved == b.goals_solved && loss(a) < loss(b))
    };
    let mut best: Option<usize> = None;
    for (i, r) in records.iter().enumerate() {
        if best.is_none_or(|b| better(r, &records[b])) {
            best = Some(i);
        }
    }
    Ok(best.filter(|&b| better(&records[b], &own)).map(|b| {
        let (what, d) = swaps[b].clone();
        (what, d, records[b].clone(), own)
    }))
}
