//! The paper's genetic-algorithm baseline over the 6-slot modular catalog, with its settings
//! (appendix: EvoTorch's genetic algorithm, population 128, 100 generations, single-point
//! crossover, tournament selection of size 4, per-gene mutation probability 0.05).
//!
//! Each generation makes as many children as the population: two parents by tournament, one
//! crossover point, two children, every gene of a child redrawn with the mutation probability.
//! The next population is the best of parents and children together (EvoTorch's default elitist
//! survival). Fitness is the task loss of a reach-only validation ([`super::record::Record`]),
//! lower is better, a design with no loss last; a design is evaluated once however often it
//! reappears. Everything random comes from one ChaCha stream of the seed, and evaluations run in
//! parallel but are placed by index, so a seed gives the same run on any number of threads.

use super::inputs::{catalog_entry, ScenarioEntry, CATALOG_SLOTS};
use super::record::{self, Record};
use super::{SweepError, SweepMode};
use crate::design::catalog::SlotOption;
use crate::progress::Progress;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashMap;

/// One robot: the slot option index (into [`SlotOption::ALL`]) of each slot.
pub type Genome = [u8; CATALOG_SLOTS];

/// The GA's settings; the defaults are the paper's.
#[derive(Debug, Clone, Serialize)]
pub struct GaOptions {
    /// Designs per generation (default 128).
    pub population: usize,
    /// Generations after the first (default 100).
    pub generations: usize,
    /// Designs drawn per tournament (default 4).
    pub tournament: usize,
    /// Probability that a child's gene is redrawn (default 0.05).
    pub mutation: f64,
    /// Seed of every random choice (default 0).
    pub seed: u64,
}

impl Default for GaOptions {
    fn default() -> Self {
        Self {
            population: 128,
            generations: 100,
            tournament: 4,
            mutation: 0.05,
            seed: 0,
        }
    }
}

/// One generation's population, summarised.
#[derive(Debug, Clone, Serialize)]
pub struct Generation {
    /// 0 is the random first population.
    pub generation: usize,
    /// The best task loss in the population.
    pub best_loss: Option<f64>,
    /// The best design's id.
    pub best_design: String,
    /// Distinct designs evaluated so far.
    pub evaluated: usize,
}

/// A finished GA run.
#[derive(Debug, Clone, Serialize)]
pub struct GaResult {
    /// The settings.
    pub options: GaOptions,
    /// The scenario's id.
    pub scenario: String,
    /// The best design found, with its record.
    pub best: Record,
    /// Per generation, its best.
    pub history: Vec<Generation>,
    /// Distinct designs evaluated.
    pub evaluations: usize,
    /// Every design evaluated, fittest first (not in the saved file).
    #[serde(skip)]
    pub evaluated: Vec<String>,
}

fn genome_slots(genome: &Genome) -> Vec<SlotOption> {
    genome
        .iter()
        .map(|&g| SlotOption::ALL[usize::from(g) % SlotOption::ALL.len()])
        .collect()
}

fn fitness(record: &Record) -> f64 {
    record.task_loss.unwrap_or(f64::INFINITY)
}

/// The reach-only validation the GA scores designs with: IK seeded by `ik_seed`, with the
/// sweeps' joint-space search budget.
pub fn mode(ik_seed: u64) -> SweepMode {
    SweepMode::ReachOnly {
        ik: crate::ik::IkOptions {
            seed: ik_seed,
            search_boxes: crate::ik::SWEEP_SEARCH_BOXES,
            ..Default::default()
        },
    }
}

/// Where a result's best design stands among a reference sweep's designs on its scenario.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Standing {
    /// The reference designs on the scenario.
    pub designs: usize,
    /// Its score (1 at the reference's best loss, 0 at its worst); `None` without a loss.
    pub score: Option<f64>,
    /// Its percentile among them; `None` without a loss.
    pub percentile: Option<f64>,
}

impl GaResult {
    /// Where the best design stands among `reference` (a sweep's records on this scenario);
    /// `None` when the reference has no design on it.
    pub fn standing(&self, reference: &[Record]) -> Option<Standing> {
        let distributions = super::table::distributions(std::slice::from_ref(&self.best), Some(reference));
        let distribution = distributions.get(&self.best.scenario)?;
        Some(Standing {
            designs: distribution.len(),
            score: distribution.score(self.best.task_loss),
            percentile: distribution.percentile(self.best.task_loss),
        })
    }

    /// Writes the result as pretty JSON to `path`; an existing file only with `force`.
    ///
    /// # Errors
    /// [`SweepError::Write`] naming the file.
    pub fn save(&self, path: &std::path::Path, force: bool) -> Result<(), SweepError> {
        let text = serde_json::to_string_pretty(self).map_err(|e| SweepError::Write {
            path: path.to_path_buf(),
            message: e.to_string(),
        })? + "\n";
        write_new(path, &text, force)
    }

    /// Writes the best design as a design file to `path` (an existing file only with `force`).
    ///
    /// # Errors
    /// [`SweepError::Write`].
    pub fn save_best_design(&self, path: &std::path::Path, force: bool) -> Result<(), SweepError> {
        let error = |message: String| SweepError::Write {
            path: path.to_path_buf(),
            message,
        };
        let design = crate::design::Design::from_catalog_id(&self.best.design)
            .map_err(error)?
            .ok_or_else(|| error(format!("`{}` is not a catalog id (a bug)", self.best.design)))?;
        let description = format!(
            "the best design of validate-design ga on {} (seed {})",
            self.scenario, self.options.seed
        );
        write_new(path, &crate::design::to_json(&design, &description), force)
    }
}

/// Writes `text` to `path`, replacing an existing file only with `force`.
fn write_new(path: &std::path::Path, text: &str, force: bool) -> Result<(), SweepError> {
    crate::files::write_atomic(path, text.as_bytes(), force).map_err(|e| SweepError::Write {
        path: path.to_path_buf(),
        message: match e {
            crate::files::WriteError::Exists => "the file exists; pass --force to replace it".into(),
            other => other.to_string(),
        },
    })
}

/// Runs the GA on `scenario` with reach-only validations of `ik` settings.
///
/// # Errors
/// [`SweepError::Pair`] when a design cannot be evaluated on the scenario.
pub fn run(scenario: &ScenarioEntry, mode: &SweepMode, opts: &GaOptions, progress: &dyn Progress) -> Result<GaResult, SweepError> {
    let options = SlotOption::ALL.len() as u8;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed);
    let mut evaluated: HashMap<Genome, Record> = HashMap::new();
    let evaluate = |genomes: &[Genome], evaluated: &mut HashMap<Genome, Record>| -> Result<(), SweepError> {
        let mut fresh: Vec<Genome> = genomes.iter().copied().filter(|g| !evaluated.contains_key(g)).collect();
        fresh.sort_unstable();
        fresh.dedup();
        let records: Vec<Record> = fresh
            .par_iter()
            .map(|genome| {
                let entry = catalog_entry(&genome_slots(genome));
                let result = record::evaluate(&entry.id, &scenario.id, entry.load(), scenario.scenario.clone(), mode).map_err(|e| {
                    SweepError::Pair {
                        design: entry.id.clone(),
                        scenario: scenario.id.clone(),
                        source: Box::new(e),
                    }
                });
                progress.advance();
                result
            })
            .collect::<Result<_, _>>()?;
        evaluated.extend(fresh.into_iter().zip(records));
        Ok(())
    };
    let rank = |population: &mut Vec<Genome>, evaluated: &HashMap<Genome, Record>| {
        population.sort_by(|a, b| fitness(&evaluated[a]).total_cmp(&fitness(&evaluated[b])).then(a.cmp(b)));
    };
    let summary = |generation: usize, population: &[Genome], evaluated: &HashMap<Genome, Record>| {
        let best = &evaluated[&population[0]];
        Generation {
            generation,
            best_loss: best.task_loss,
            best_design: best.design.clone(),
            evaluated: evaluated.len(),
        }
    };
    progress.stage(
        &format!("GA on {} ({} x {} generations)", scenario.id, opts.population, opts.generations + 1),
        Some((opts.population * (opts.generations + 1)) as u64),
    );
    let mut population: Vec<Genome> = (0..opts.population)
        .map(|_| std::array::from_fn(|_| rng.random_range(0..options)))
        .collect();
    evaluate(&population, &mut evaluated)?;
    rank(&mut population, &evaluated);
    let mut history = vec![summary(0, &population, &evaluated)];
    for generation in 1..=opts.generations {
        let mut children: Vec<Genome> = Vec::with_capacity(opts.population + 1);
        while children.len() < opts.population {
            let first = tournament(&population, &evaluated, opts.tournament, &mut rng);
            let second = tournament(&population, &evaluated, opts.tournament, &mut rng);
            let cut = rng.random_range(1..CATALOG_SLOTS);
            let mut pair = [first, second];
            pair[0][cut..].copy_from_slice(&second[cut..]);
            pair[1][cut..].copy_from_slice(&first[cut..]);
            for mut child in pair {
                for gene in &mut child {
                    if rng.random::<f64>() < opts.mutation {
                        *gene = rng.random_range(0..options);
                    }
                }
                children.push(child);
            }
        }
        children.truncate(opts.population);
        evaluate(&children, &mut evaluated)?;
        population.extend(children);
        rank(&mut population, &evaluated);
        population.truncate(opts.population);
        history.push(summary(generation, &population, &evaluated));
    }
    let best = evaluated[&population[0]].clone();
    let mut ranked: Vec<(&Genome, &Record)> = evaluated.iter().collect();
    ranked.sort_by(|a, b| fitness(a.1).total_cmp(&fitness(b.1)).then(a.0.cmp(b.0)));
    Ok(GaResult {
        evaluated: ranked.into_iter().map(|(_, record)| record.design.clone()).collect(),
        options: opts.clone(),
        scenario: scenario.id.clone(),
        best,
        history,
        evaluations: evaluated.len(),
    })
}

/// The fittest of `size` designs drawn from `population` (with replacement); ties go to the one
/// drawn first.
fn tournament<R: Rng>(population: &[Genome], evaluated: &HashMap<Genome, Record>, size: usize, rng: &mut R) -> Genome {
    let mut best = population[rng.random_range(0..population.len())];
    for _ in 1..size.max(1) {
        let candidate = population[rng.random_range(0..population.len())];
        if fitness(&evaluated[&candidate]) < fitness(&evaluated[&best]) {
            best = candidate;
        }
    }
    best
}
