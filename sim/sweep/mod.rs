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
    /// The stop flag was raised (SIGINT or SIGTERM): the running pairs finished and were kept.
    #[error("interrupted: {kept} of {total} pairs finished and kept{}", resume_hint(out.as_deref()))]
    Interrupted {
        /// Pairs finished (resumed or computed) and saved.
        kept: usize,
        /// Pairs of the sweep (or its shard).
        total: usize,
        /// The folder they are saved in.
        out: Option<PathBuf>,
    },
}

fn resume_hint(out: Option<&Path>) -> String {
    out.map_or_else(
        || " (in memory only: without --out nothing is saved)".into(),
        |dir| format!(" in {}; run the same command again to resume", dir.display()),
    )
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

/// One shard of a sweep. The pairs (canonical order) are ranked by a fixed hash of their index
/// and dealt round-robin: each shard is a uniform sample of the sweep, whatever the structure of
/// the design list (the catalog's `i mod 40` would give shard 1 of 40 only robots whose slot 6 is
/// `D`), and shards differ in size by at most one pair.
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

    /// The pairs of a sweep of `total` this shard holds, ascending.
    fn pairs(self, total: usize) -> Vec<usize> {
        let mut ranked: Vec<usize> = (0..total).collect();
        ranked.sort_by_key(|&i| (splitmix64(i as u64), i));
        let mut held: Vec<usize> = ranked.into_iter().skip(self.k - 1).step_by(self.n).collect();
        held.sort_unstable();
        held
    }

    fn text(self) -> String {
        format!("{}/{}", self.k, self.n)
    }
}

/// SplitMix64's output function (Steele, Lea, Flood 2014): a fixed, well-mixed hash of `x`.
fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
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
    /// A finished sweep to score against (the brute force); `None` scores against the sweep
    /// itself.
    pub reference: Option<Reference>,
    /// Rows per ranked table.
    pub top: usize,
    /// How the per-task tables order designs (the tables only: records are the same).
    pub ranking: table::Ranking,
    /// Raised to stop early (the CLI's SIGINT and SIGTERM): no pair starts after it, the running
    /// ones finish and are saved, and the run ends with [`SweepError::Interrupted`].
    pub stop: Option<&'static std::sync::atomic::AtomicBool>,
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
    /// Lines of the folder's partial log left out as another sweep's; their pairs were computed.
    pub foreign: usize,
    /// Lines of the partial log left out as not whole records (cut short by a kill, damaged by
    /// a crash); their pairs were computed again.
    pub damaged: usize,
    /// Every design's id in the overall table's order (tasks solved, goals solved, mean score).
    pub ranking: Vec<String>,
}

/// The design files of the first `top` designs of `ranking` that are designs (a URDF or MJCF
/// robot has no design file: its id is in the second list), named `RANK-NAME.json` (a catalog
/// id with `/` as `_`, a file's stem: `01-modular6_Ll-Is-Ll-Il-D-Ls.json`, `02-ur5e.json`),
/// each a design JSON any command takes.
pub fn best_designs(designs: &[DesignEntry], ranking: &[String], top: usize) -> (Vec<(String, Vec<u8>)>, Vec<String>) {
    let mut files = Vec::new();
    let mut skipped = Vec::new();
    let digits = top.min(ranking.len()).max(1).to_string().len().max(2);
    for (rank, id) in ranking.iter().take(top).enumerate() {
        let description = format!("rank {} of a validate-design sweep: {id}", rank + 1);
        let entry = designs.iter().find(|d| &d.id == id);
        if let Some(DesignEntry {
            source: inputs::DesignSource::Timor(set, order),
            ..
        }) = entry
        {
            // A Timor assembly as an assembly file, named after its modules.
            let name = format!("{:0digits$}-{}.json", rank + 1, order.join("-").replace(['/', '\\'], "_"));
            files.push((name, set.assembly_json(order, &description).into_bytes()));
            continue;
        }
        let Some(design) = entry.and_then(|d| d.load().design) else {
            skipped.push(id.clone());
            continue;
        };
        // A file's stem (the rank keeps equal stems apart), a catalog id with `_` for `/`.
        let path = Path::new(id);
        let base = match (path.extension(), path.file_stem()) {
            (Some(_), Some(stem)) => stem.to_string_lossy().into_owned(),
            _ => id.replace(['/', '\\'], "_"),
        };
        let name = format!("{:0digits$}-{base}.json", rank + 1);
        files.push((name, crate::design::to_json(&design, &description).into_bytes()));
    }
    (files, skipped)
}

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
        designs: designs
            .iter()
            .map(|d| store::DesignRef {
                id: d.id.clone(),
                sha256: d.sha256.clone(),
            })
            .collect(),
        scenarios: scenarios
            .iter()
            .map(|s| store::ScenarioRef {
                id: s.id.clone(),
                sha256: s.sha256.clone(),
            })
            .collect(),
        shard: opts.shard.map(Shard::text),
        reference: opts.reference.as_ref().map(|r| r.sha256.clone()),
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
    let reference = opts
        .reference
        .as_ref()
        .map(|r| reference_records(r, &opts.mode, scenarios))
        .transpose()?;
    // Held until the run returns: one writer per folder.
    let _lock = opts.out.as_deref().map(store::lock).transpose()?;
    let resumed = match &opts.out {
        Some(dir) => store::open(dir, &manifest, opts.force)?,
        None => store::Resumed::default(),
    };
    let (foreign, damaged) = (resumed.foreign, resumed.damaged);
    let mut done = resumed.records;
    let total = designs.len() * scenarios.len();
    let indices: Vec<usize> = match opts.shard {
        Some(shard) => shard.pairs(total),
        None => (0..total).collect(),
    };
    let pairs: Vec<(usize, usize)> = indices.into_iter().map(|i| (i / scenarios.len(), i % scenarios.len())).collect();
    let finished: std::collections::HashSet<(String, String)> = done.iter().map(|r| (r.design.clone(), r.scenario.clone())).collect();
    // A line of another sweep in the folder is found before any work, not after it.
    let expected: std::collections::HashSet<(&str, &str)> = pairs
        .iter()
        .map(|&(d, s)| (designs[d].id.as_str(), scenarios[s].id.as_str()))
        .collect();
    if let Some(record) = done.iter().find(|r| !expected.contains(&(r.design.as_str(), r.scenario.as_str()))) {
        return Err(SweepError::Folder {
            dir: opts.out.clone().unwrap_or_default(),
            message: format!(
                "holds a record of design `{}` on `{}`, which this sweep does not have",
                record.design, record.scenario
            ),
        });
    }
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
    // Each record is logged as its pair finishes (no batches: a killed sweep loses only the
    // pairs still running, and no core waits for a batch's slowest pair).
    let log = opts
        .out
        .as_deref()
        .map(|dir| store::Log::open(dir, &manifest))
        .transpose()?
        .map(std::sync::Mutex::new);
    let stopped = || opts.stop.is_some_and(|flag| flag.load(std::sync::atomic::Ordering::Relaxed));
    let records: Vec<Option<Record>> = todo
        .par_iter()
        .map(|&(d, s)| {
            if stopped() {
                return Ok(None);
            }
            let (design, scenario) = (&designs[d], &scenarios[s]);
            let record = record::evaluate(&design.id, &scenario.id, design.load(), scenario.scenario.clone(), &opts.mode).map_err(|e| {
                SweepError::Pair {
                    design: design.id.clone(),
                    scenario: scenario.id.clone(),
                    source: Box::new(e),
                }
            })?;
            if let Some(log) = &log {
                log.lock().unwrap_or_else(std::sync::PoisonError::into_inner).write(&record)?;
            }
            progress.advance();
            Ok(Some(record))
        })
        .collect::<Result<_, SweepError>>()?;
    if let Some(log) = log {
        log.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner).sync()?;
    }
    let skipped = records.iter().filter(|r| r.is_none()).count();
    if skipped > 0 {
        return Err(SweepError::Interrupted {
            kept: done.len() + records.len() - skipped,
            total: pairs.len(),
            out: opts.out.clone(),
        });
    }
    done.extend(records.into_iter().flatten());
    let records = canonical(done, designs, scenarios, &pairs);
    let reference_name = reference_name(opts.reference.as_ref());
    let distributions = table::distributions(&records, reference.as_deref());
    let overall = table::ranked(&records, &distributions);
    let text = table::text(&records, &distributions, &overall, &reference_name, opts.top, opts.ranking);
    if let Some(dir) = &opts.out {
        store::finish(dir, &records, &table::csv(&records, &distributions), &text)?;
    }
    let ranking = overall.into_iter().map(|o| o.design).collect();
    Ok(SweepResult {
        records,
        table: text,
        computed,
        foreign,
        damaged,
        ranking,
    })
}

/// The records in pair order (every record is of a pair: checked before computing).
fn canonical(done: Vec<Record>, designs: &[DesignEntry], scenarios: &[ScenarioEntry], pairs: &[(usize, usize)]) -> Vec<Record> {
    let mut by_pair: std::collections::HashMap<(String, String), Record> =
        done.into_iter().map(|r| ((r.design.clone(), r.scenario.clone()), r)).collect();
    pairs
        .iter()
        .filter_map(|&(d, s)| by_pair.remove(&(designs[d].id.clone(), scenarios[s].id.clone())))
        .collect()
}

/// A finished sweep to score against.
#[derive(Debug, Clone)]
pub struct Reference {
    /// Its folder, for messages.
    pub dir: PathBuf,
    /// What it was asked.
    pub manifest: store::Manifest,
    /// Its records.
    pub records: Vec<Record>,
    /// SHA-256 of its `results.jsonl`.
    pub sha256: String,
}

/// How the tables name the reference: no path, so a merged sweep's tables are the unsharded
/// sweep's whatever the folder was called.
fn reference_name(reference: Option<&Reference>) -> String {
    match reference {
        Some(r) => format!(
            "a reference sweep of {} designs (results sha256 {})",
            r.manifest.designs.len(),
            r.sha256.get(..12).unwrap_or(&r.sha256)
        ),
        None => "this sweep's designs".into(),
    }
}

/// Reads a finished, whole sweep to score against.
///
/// # Errors
/// [`SweepError::Reference`] when `dir` holds no finished sweep, or a shard of one.
pub fn read_reference(dir: &Path) -> Result<Reference, SweepError> {
    let error = |message: String| SweepError::Reference {
        dir: dir.to_path_buf(),
        message,
    };
    let manifest = store::read_manifest(dir)?.ok_or_else(|| error(format!("holds no sweep (no {})", store::MANIFEST)))?;
    if let Some(shard) = &manifest.shard {
        return Err(error(format!(
            "holds shard {shard} of a sweep: merge the shards and give the merged folder"
        )));
    }
    let results = dir.join(store::RESULTS);
    if !results.exists() {
        return Err(error("holds no finished sweep (no results.jsonl): run it to the end first".into()));
    }
    let (records, sha256) = store::read_input_records(&results)?;
    // Scores and percentiles over a cut or edited file shift without a sign: refused instead.
    let expected = manifest.designs.len() * manifest.scenarios.len();
    let mut pairs = std::collections::HashSet::with_capacity(records.len());
    for record in &records {
        let listed = manifest.designs.iter().any(|d| d.id == record.design) && manifest.scenarios.iter().any(|s| s.id == record.scenario);
        if !listed || !pairs.insert((record.design.as_str(), record.scenario.as_str())) {
            return Err(error(format!(
                "results.jsonl holds design `{}` on `{}` {}: the file was edited; run its sweep again (with --force) to rebuild it",
                record.design,
                record.scenario,
                if listed { "twice" } else { "which its sweep.json does not list" }
            )));
        }
    }
    if records.len() != expected {
        return Err(error(format!(
            "results.jsonl holds {} records where its sweep.json lists {} designs x {} scenarios = {expected} pairs: the file was cut short or edited; run its sweep again to rebuild it",
            records.len(),
            manifest.designs.len(),
            manifest.scenarios.len()
        )));
    }
    Ok(Reference {
        dir: dir.to_path_buf(),
        manifest,
        records,
        sha256,
    })
}

/// The reference's records of `scenarios` (matched by content, renamed to this sweep's ids),
/// once the reference is known to have been computed as this sweep computes.
///
/// # Errors
/// [`SweepError::Reference`] for another mode, seed or IK seed count, or a scenario it lacks.
pub fn reference_records(reference: &Reference, mode: &SweepMode, scenarios: &[ScenarioEntry]) -> Result<Vec<Record>, SweepError> {
    let error = |message: String| SweepError::Reference {
        dir: reference.dir.clone(),
        message,
    };
    let theirs = &reference.manifest;
    let (name, engines) = match mode {
        SweepMode::ReachOnly { .. } => ("reach_only", None),
        SweepMode::Full { engines, .. } => ("full", Some(engines.name())),
    };
    if theirs.mode != name || theirs.engines != engines {
        return Err(error(format!(
            "was run in mode {}, this run is {name}: scores compare like with like",
            theirs.mode
        )));
    }
    let ik = mode.ik();
    if (theirs.seed, theirs.ik_seeds) != (ik.seed, ik.seeds) {
        return Err(error(format!(
            "was run with IK seed {} and {} IK starts, this run with {} and {}",
            theirs.seed, theirs.ik_seeds, ik.seed, ik.seeds
        )));
    }
    let mut records = Vec::new();
    for scenario in scenarios {
        let same = theirs.scenarios.iter().find(|s| s.sha256 == scenario.sha256).ok_or_else(|| {
            error(format!(
                "has no results for scenario `{}` (no scenario with its contents)",
                scenario.id
            ))
        })?;
        records.extend(reference.records.iter().filter(|r| r.scenario == same.id).map(|r| Record {
            scenario: scenario.id.clone(),
            ..r.clone()
        }));
    }
    Ok(records)
}

/// Joins the shard folders `dirs` into `out`: the files the unsharded sweep writes, byte for
/// byte. Everything is checked before `out` is touched.
///
/// # Errors
/// [`SweepError::Merge`] for folders that are not the finished shards of one sweep, or a
/// reference other than the shards'; [`SweepError::Folder`] for an `out` that holds something
/// else (unless `force`) or is one of the shards.
pub fn merge(
    dirs: &[PathBuf],
    out: &Path,
    force: bool,
    reference: Option<Reference>,
    top: usize,
    ranking: table::Ranking,
) -> Result<SweepResult, SweepError> {
    // Taken first: a folder being written by a sweep is not merged into.
    let _lock = store::lock(out)?;
    let (manifest, records) = store::read_shards(dirs)?;
    let merge_error = |message: String| SweepError::Merge {
        dir: out.to_path_buf(),
        message,
    };
    if manifest.reference != reference.as_ref().map(|r| r.sha256.clone()) {
        return Err(merge_error(match &manifest.reference {
            Some(sha) => format!("the shards were scored against a reference (results sha256 {sha}): give the same --reference"),
            None => "the shards were not scored against a reference: leave out --reference".into(),
        }));
    }
    let position = |id: &str, list: &[&str]| list.iter().position(|x| *x == id);
    let design_ids: Vec<&str> = manifest.designs.iter().map(|d| d.id.as_str()).collect();
    let scenario_ids: Vec<&str> = manifest.scenarios.iter().map(|s| s.id.as_str()).collect();
    let mut keyed = Vec::with_capacity(records.len());
    for record in records {
        let (Some(d), Some(s)) = (position(&record.design, &design_ids), position(&record.scenario, &scenario_ids)) else {
            return Err(merge_error(format!(
                "a shard holds design `{}` on `{}`, which its manifest does not list",
                record.design, record.scenario
            )));
        };
        keyed.push(((d, s), record));
    }
    keyed.sort_by_key(|(key, _)| *key);
    let expected = design_ids.len() * scenario_ids.len();
    if keyed.len() != expected || keyed.windows(2).any(|w| w[0].0 == w[1].0) {
        return Err(merge_error(format!("the shards hold {} records for {expected} pairs", keyed.len())));
    }
    let records: Vec<Record> = keyed.into_iter().map(|(_, r)| r).collect();
    // The reference's records renamed to the shards' scenario ids, matched by content as the
    // sweep matched them (the sweep checked mode and seeds; the manifest holds its hash).
    let reference_records = reference.as_ref().map(|r| {
        let mut renamed = Vec::new();
        for ours in &manifest.scenarios {
            if let Some(theirs) = r.manifest.scenarios.iter().find(|s| s.sha256 == ours.sha256) {
                renamed.extend(r.records.iter().filter(|x| x.scenario == theirs.id).map(|x| Record {
                    scenario: ours.id.clone(),
                    ..x.clone()
                }));
            }
        }
        renamed
    });
    store::open(out, &manifest, force)?;
    let distributions = table::distributions(&records, reference_records.as_deref());
    let overall = table::ranked(&records, &distributions);
    let text = table::text(
        &records,
        &distributions,
        &overall,
        &reference_name(reference.as_ref()),
        top,
        ranking,
    );
    store::finish(out, &records, &table::csv(&records, &distributions), &text)?;
    let ranking = overall.into_iter().map(|o| o.design).collect();
    Ok(SweepResult {
        records,
        table: text,
        computed: 0,
        foreign: 0,
        damaged: 0,
        ranking,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_are_fair_samples_that_cover_the_sweep_once() {
        // The catalog's 15 625 robots on one task: slot 6 is the index's last base-5 digit.
        let total = 15_625;
        let n = 40;
        let mut seen = vec![0u8; total];
        for k in 1..=n {
            let shard = Shard::parse(&format!("{k}/{n}")).expect("valid");
            let held = shard.pairs(total);
            assert!(held.len() == total / n || held.len() == total / n + 1, "shard {k}: {}", held.len());
            let mut slot6 = [0usize; 5];
            for &i in &held {
                seen[i] += 1;
                slot6[i % 5] += 1;
            }
            // A uniform sample: each option near a fifth (binomial spread about +-4 sigma).
            for count in slot6 {
                assert!((count as f64 - held.len() as f64 / 5.0).abs() < 60.0, "shard {k}: slot 6 {slot6:?}");
            }
        }
        assert!(seen.iter().all(|&c| c == 1), "every pair in exactly one shard");
    }
}
