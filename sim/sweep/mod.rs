//! Design-space experiments: many designs on many scenarios, as the paper's brute force, its
//! baselines and its Table 1 need them.
//!
//! A sweep runs every design (files, folders, globs, or a catalog such as every 6-slot modular
//! robot) on every scenario, kinematic by default (`reach_only`: the paper's static metric, per
//! goal a collision-free IK solution) or the full validation, in parallel over pairs. Each pair is
//! exactly what `validate-design DESIGN --scenario S [--reach-only]` computes, condensed into a
//! [`record::Record`]. A sweep with `--out DIR` keeps its pairs as they finish, so an interrupted
//! sweep resumes where it stopped; `--shard K/N` runs every N-th pair, and [`merge`] joins the
//! shards into the folder the whole sweep would have written, byte for byte.

pub mod ga;
pub mod inputs;
pub mod paper;
pub mod record;
pub mod store;
pub mod table;

use crate::progress::Progress;
use inputs::{DesignEntry, ScenarioEntry};
use rayon::prelude::*;
use record::Record;
use std::path::{Path, PathBuf};

/// Why a sweep could not run.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A design argument names nothing usable.
    #[error("design argument `{argument}`: {message}")]
    Designs {
        /// The argument as given.
        argument: String,
        /// What is wrong.
        message: String,
    },
    /// A scenario argument names nothing usable.
    #[error("--scenarios `{argument}`: {message}")]
    Scenarios {
        /// The argument as given.
        argument: String,
        /// What is wrong.
        message: String,
    },
    /// A design or scenario file could not be loaded, or a pair could not be evaluated.
    #[error("{0}")]
    Load(Box<crate::error::Error>),
    /// A pair could not be evaluated (geometry, names, an engine refusing the model).
    #[error("design `{design}` on scenario `{scenario}`: {source}")]
    Pair {
        /// The design's id.
        design: String,
        /// The scenario's id.
        scenario: String,
        /// Why.
        #[source]
        source: Box<crate::error::Error>,
    },
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A file could not be written.
    #[error("cannot write {path}: {message}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The output folder cannot take this sweep.
    #[error("--out {dir}: {message}")]
    Folder {
        /// The folder.
        dir: PathBuf,
        /// Why.
        message: String,
    },
    /// Shard folders that do not make one sweep.
    #[error("merge: {dir}: {message}")]
    Merge {
        /// The folder.
        dir: PathBuf,
        /// Why.
        message: String,
    },
    /// A `--shard` that is not `K/N` with 1 <= K <= N.
    #[error("--shard `{0}`: expected K/N with 1 <= K <= N, e.g. 2/8")]
    Shard(String),
    /// A `--reference` folder that cannot serve.
    #[error("--reference {dir}: {message}")]
    Reference {
        /// The folder.
        dir: PathBuf,
        /// Why.
        message: String,
    },
}

/// What each pair runs.
#[derive(Debug, Clone)]
pub enum SweepMode {
    /// The paper's static metric: per goal a collision-free IK solution; no trajectory, no engines.
    ReachOnly {
        /// IK settings (seeds, seed).
        ik: crate::ik::IkOptions,
    },
    /// The whole validation: trajectory, certified check, engines, verdict.
    Full {
        /// IK settings (seeds, seed; the planner uses the same seed).
        ik: crate::ik::IkOptions,
        /// The engines to run.
        engines: crate::pipeline::Engines,
    },
}

impl SweepMode {
    fn ik(&self) -> &crate::ik::IkOptions {
        match self {
            Self::ReachOnly { ik } | Self::Full { ik, .. } => ik,
        }
    }
}

/// One shard of a sweep: pair `i` (canonical order) belongs to shard `i mod N + 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    k: usize,
    n: usize,
}

impl Shard {
    /// Reads `K/N`.
    ///
    /// # Errors
    /// The message when it is not `K/N` with `1 <= K <= N`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let parsed = text
            .split_once('/')
            .and_then(|(k, n)| Some((k.trim().parse::<usize>().ok()?, n.trim().parse::<usize>().ok()?)));
        match parsed {
            Some((k, n)) if k >= 1 && k <= n => Ok(Self { k, n }),
            _ => Err(format!("shard `{text}`: expected K/N with 1 <= K <= N, e.g. 2/8")),
        }
    }

    /// `(K, N)`.
    pub fn parts(self) -> (usize, usize) {
        (self.k, self.n)
    }

    fn holds(self, pair: usize) -> bool {
        pair % self.n + 1 == self.k
    }

    fn text(self) -> String {
        format!("{}/{}", self.k, self.n)
    }
}

/// A sweep's settings.
#[derive(Debug, Clone)]
pub struct SweepOptions {
    /// What each pair runs.
    pub mode: SweepMode,
    /// Folder for the manifest, the finished pairs and the results; `None` keeps everything in
    /// memory.
    pub out: Option<PathBuf>,
    /// Replace another sweep's files in `out`.
    pub force: bool,
    /// Run this shard only.
    pub shard: Option<Shard>,
    /// Records to score against (a brute-force sweep's `results.jsonl`), per scenario id; `None`
    /// scores against the sweep itself.
    pub reference: Option<(String, Vec<Record>)>,
    /// Rows per ranked table.
    pub top: usize,
}

/// A finished sweep.
#[derive(Debug, Clone)]
pub struct SweepResult {
    /// Every record of the sweep (or of its shard), canonical order.
    pub records: Vec<Record>,
    /// The ranked tables.
    pub table: String,
    /// Pairs computed by this run (the others were resumed).
    pub computed: usize,
}

/// Pairs computed between two writes of the partial log: enough to keep every core busy, few
/// enough that an interruption loses seconds.
const PAIRS_PER_BATCH: usize = 256;

fn manifest(designs: &[DesignEntry], scenarios: &[ScenarioEntry], opts: &SweepOptions) -> store::Manifest {
    let (mode, engines) = match &opts.mode {
        SweepMode::ReachOnly { .. } => ("reach_only", None),
        SweepMode::Full { engines, .. } => ("full", Some(engines.name())),
    };
    store::Manifest {
        format: store::FORMAT,
        mode: mode.into(),
        engines,
        seed: opts.mode.ik().seed,
        ik_seeds: opts.mode.ik().seeds,
        designs: designs.iter().map(|d| d.id.clone()).collect(),
        scenarios: scenarios
            .iter()
            .map(|s| store::ScenarioRef {
                id: s.id.clone(),
                sha256: s.sha256.clone(),
            })
            .collect(),
        shard: opts.shard.map(Shard::text),
    }
}

/// Runs every pair of `designs` x `scenarios` (of the shard) not yet finished in `opts.out`,
/// then writes the results there.
///
/// # Errors
/// [`SweepError`]: the folder cannot take the sweep, a pair cannot be evaluated (its error names
/// the design and the scenario), a write fails.
pub fn run(
    designs: &[DesignEntry],
    scenarios: &[ScenarioEntry],
    opts: &SweepOptions,
    progress: &dyn Progress,
) -> Result<SweepResult, SweepError> {
    let manifest = manifest(designs, scenarios, opts);
    let mut done = match &opts.out {
        Some(dir) => store::open(dir, &manifest, opts.force)?,
        None => Vec::new(),
    };
    let total = designs.len() * scenarios.len();
    let pairs: Vec<(usize, usize)> = (0..total)
        .filter(|&i| opts.shard.is_none_or(|s| s.holds(i)))
        .map(|i| (i / scenarios.len(), i % scenarios.len()))
        .collect();
    let finished: std::collections::HashSet<(String, String)> = done.iter().map(|r| (r.design.clone(), r.scenario.clone())).collect();
    let todo: Vec<(usize, usize)> = pairs
        .iter()
        .copied()
        .filter(|&(d, s)| !finished.contains(&(designs[d].id.clone(), scenarios[s].id.clone())))
        .collect();
    progress.stage(
        &format!("{} of {} design-scenario pairs to run", todo.len(), pairs.len()),
        Some(pairs.len() as u64),
    );
    for _ in 0..pairs.len() - todo.len() {
        progress.advance();
    }
    let computed = todo.len();
    for batch in todo.chunks(PAIRS_PER_BATCH) {
        let records: Vec<Record> = batch
            .par_iter()
            .map(|&(d, s)| {
                let (design, scenario) = (&designs[d], &scenarios[s]);
                let record =
                    record::evaluate(&design.id, &scenario.id, design.load(), scenario.scenario.clone(), &opts.mode).map_err(|e| {
                        SweepError::Pair {
                            design: design.id.clone(),
                            scenario: scenario.id.clone(),
                            source: Box::new(e),
                        }
                    });
                progress.advance();
                record
            })
            .collect::<Result<_, _>>()?;
        if let Some(dir) = &opts.out {
            store::append(dir, &records)?;
        }
        done.extend(records);
    }
    let records = canonical(done, designs, scenarios, &pairs)?;
    let reference_name = opts
        .reference
        .as_ref()
        .map_or("this sweep's designs".to_string(), |(name, _)| name.clone());
    let reference = opts.reference.as_ref().map(|(_, r)| r.as_slice());
    check_reference(&records, reference, opts)?;
    let distributions = table::distributions(&records, reference);
    let text = table::text(&records, &distributions, &reference_name, opts.top);
    if let Some(dir) = &opts.out {
        store::finish(dir, &records, &table::csv(&records, &distributions), &text)?;
    }
    Ok(SweepResult {
        records,
        table: text,
        computed,
    })
}

/// The records in pair order; a record the manifest has no pair for is an error (a foreign line).
fn canonical(
    done: Vec<Record>,
    designs: &[DesignEntry],
    scenarios: &[ScenarioEntry],
    pairs: &[(usize, usize)],
) -> Result<Vec<Record>, SweepError> {
    let mut by_pair: std::collections::HashMap<(String, String), Record> =
        done.into_iter().map(|r| ((r.design.clone(), r.scenario.clone()), r)).collect();
    let records: Vec<Record> = pairs
        .iter()
        .filter_map(|&(d, s)| by_pair.remove(&(designs[d].id.clone(), scenarios[s].id.clone())))
        .collect();
    if let Some(((design, scenario), _)) = by_pair.into_iter().next() {
        return Err(SweepError::Folder {
            dir: PathBuf::new(),
            message: format!("holds a record of design `{design}` on `{scenario}`, which this sweep does not have"),
        });
    }
    Ok(records)
}

fn check_reference(records: &[Record], reference: Option<&[Record]>, opts: &SweepOptions) -> Result<(), SweepError> {
    let (Some(reference), Some((name, _))) = (reference, &opts.reference) else {
        return Ok(());
    };
    for record in records {
        if !reference.iter().any(|r| r.scenario == record.scenario) {
            return Err(SweepError::Reference {
                dir: PathBuf::from(name),
                message: format!("has no results for scenario `{}`", record.scenario),
            });
        }
    }
    Ok(())
}

/// Reads a finished sweep's records to score against.
///
/// # Errors
/// [`SweepError::Reference`] when `dir` holds no finished sweep.
pub fn read_reference(dir: &Path) -> Result<(String, Vec<Record>), SweepError> {
    let results = dir.join(store::RESULTS);
    if !results.exists() {
        return Err(SweepError::Reference {
            dir: dir.to_path_buf(),
            message: "holds no finished sweep (no results.jsonl)".into(),
        });
    }
    let records = store::read_input_records(&results)?;
    let designs = records
        .iter()
        .map(|r| r.design.as_str())
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    Ok((format!("the {designs} designs of {}", dir.display()), records))
}

/// Joins the shard folders `dirs` into `out`: the files the unsharded sweep writes, byte for
/// byte.
///
/// # Errors
/// [`SweepError::Merge`] for folders that are not the finished shards of one sweep;
/// [`SweepError::Folder`] for an `out` that holds something else (unless `force`).
pub fn merge(
    dirs: &[PathBuf],
    out: &Path,
    force: bool,
    reference: Option<(String, Vec<Record>)>,
    top: usize,
) -> Result<SweepResult, SweepError> {
    let (manifest, records) = store::read_shards(dirs)?;
    store::open(out, &manifest, force)?;
    let position = |id: &str, list: &[String]| list.iter().position(|x| x == id);
    let scenario_ids: Vec<String> = manifest.scenarios.iter().map(|s| s.id.clone()).collect();
    let mut keyed = Vec::with_capacity(records.len());
    for record in records {
        let (Some(d), Some(s)) = (
            position(&record.design, &manifest.designs),
            position(&record.scenario, &scenario_ids),
        ) else {
            return Err(SweepError::Merge {
                dir: out.to_path_buf(),
                message: format!(
                    "a shard holds design `{}` on `{}`, which its manifest does not list",
                    record.design, record.scenario
                ),
            });
        };
        keyed.push(((d, s), record));
    }
    keyed.sort_by_key(|(key, _)| *key);
    let expected = manifest.designs.len() * manifest.scenarios.len();
    if keyed.len() != expected || keyed.windows(2).any(|w| w[0].0 == w[1].0) {
        return Err(SweepError::Merge {
            dir: out.to_path_buf(),
            message: format!("the shards hold {} records for {expected} pairs", keyed.len()),
        });
    }
    let records: Vec<Record> = keyed.into_iter().map(|(_, r)| r).collect();
    let reference_name = reference
        .as_ref()
        .map_or("this sweep's designs".to_string(), |(name, _)| name.clone());
    let distributions = table::distributions(&records, reference.as_ref().map(|(_, r)| r.as_slice()));
    let text = table::text(&records, &distributions, &reference_name, top);
    store::finish(out, &records, &table::csv(&records, &distributions), &text)?;
    Ok(SweepResult {
        records,
        table: text,
        computed: 0,
    })
}
