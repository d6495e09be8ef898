//! A sweep's folder: what it was asked (`sweep.json`), the pairs finished so far
//! (`pairs.partial.jsonl`, appended as they finish, in any order) and, once every pair of the
//! sweep is done, the results in canonical order (`results.jsonl`, `results.csv`, `table.txt`),
//! which depend only on the manifest and the records: a resumed, sharded-and-merged or
//! differently threaded sweep writes the same bytes.

use super::record::Record;
use super::SweepError;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The manifest's file name.
pub const MANIFEST: &str = "sweep.json";
/// The finished pairs of an unfinished sweep, one JSON record per line.
pub const PARTIAL: &str = "pairs.partial.jsonl";
/// Every record, canonical order (design-major, then scenario), one JSON object per line.
pub const RESULTS: &str = "results.jsonl";
/// Every record with its score and percentile.
pub const CSV: &str = "results.csv";
/// The ranked tables.
pub const TABLE: &str = "table.txt";
/// Version of the folder's layout and the record's fields.
pub const FORMAT: u32 = 1;

/// What a sweep was asked to do; two runs with equal manifests compute the same records.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// [`FORMAT`].
    pub format: u32,
    /// `reach_only` or `full`.
    pub mode: String,
    /// Full validation: the engines (`rapier,mujoco`, `none`, ...).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub engines: Option<String>,
    /// Seed of IK's random starts (and of the planner, in full mode).
    pub seed: u64,
    /// IK starts per goal.
    pub ik_seeds: usize,
    /// The designs, in order: id and, for a file, SHA-256 of its bytes and its model.
    pub designs: Vec<DesignRef>,
    /// The scenarios, in order: id and SHA-256 of the file.
    pub scenarios: Vec<ScenarioRef>,
    /// `K/N` when this folder holds one shard of the sweep.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<String>,
    /// The reference scored against: SHA-256 of its `results.jsonl` (records do not depend on
    /// it, the CSV and tables do).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<String>,
}

/// A design as the manifest names it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DesignRef {
    /// Its id.
    pub id: String,
    /// Files: SHA-256 of the file and of the model read from it (meshes included), so an edited
    /// design is not taken for the one already run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sha256: Option<String>,
}

/// A scenario as the manifest names it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScenarioRef {
    /// Its path as resolved.
    pub id: String,
    /// SHA-256 of its bytes (hex).
    pub sha256: String,
}

/// Lower-case hex SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

fn write(path: &Path, text: &str) -> Result<(), SweepError> {
    crate::files::write_atomic(path, text.as_bytes(), true).map_err(|e| SweepError::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// Results of 15 625 designs x 36 tasks run to about 150 MB.
const MAX_RESULTS_BYTES: u64 = 1 << 30;

/// Reads one of the sweep's own files, which it rewrites when it finishes: not recorded as an
/// input of the run (an input is never overwritten).
fn read_text(path: &Path) -> Result<String, SweepError> {
    let error = |source: std::io::Error| SweepError::Read {
        path: path.to_path_buf(),
        source,
    };
    let size = std::fs::metadata(path).map_err(error)?.len();
    if size > MAX_RESULTS_BYTES {
        return Err(error(std::io::Error::other(format!(
            "{size} bytes; at most {MAX_RESULTS_BYTES} are read"
        ))));
    }
    std::fs::read_to_string(path).map_err(error)
}

/// Reads `DIR/sweep.json`; `None` when there is none.
///
/// # Errors
/// [`SweepError::Folder`] for a manifest that is not one.
pub fn read_manifest(dir: &Path) -> Result<Option<Manifest>, SweepError> {
    let path = dir.join(MANIFEST);
    if !path.exists() {
        return Ok(None);
    }
    let text = read_text(&path)?;
    serde_json::from_str(&text).map(Some).map_err(|e| SweepError::Folder {
        dir: dir.to_path_buf(),
        message: format!("{MANIFEST} is not a sweep manifest of this version: {e}"),
    })
}

/// Prepares `dir` for `manifest`: a new or empty folder gets the manifest; a folder holding the
/// same sweep is resumed (its finished records returned); anything else is refused unless
/// `force`, which removes this tool's files there (and nothing else) and starts over.
///
/// # Errors
/// [`SweepError::Folder`] naming the first difference, or a file that is not ours.
pub fn open(dir: &Path, manifest: &Manifest, force: bool) -> Result<Vec<Record>, SweepError> {
    std::fs::create_dir_all(dir).map_err(|e| SweepError::Write {
        path: dir.to_path_buf(),
        message: e.to_string(),
    })?;
    let existing = read_manifest(dir)?;
    match existing {
        Some(found) if &found == manifest && !force => {
            if dir.join(RESULTS).exists() {
                return read_records(&dir.join(RESULTS));
            }
            let partial = dir.join(PARTIAL);
            if partial.exists() {
                let records = read_partial(&partial)?;
                // A line cut short by an interruption is dropped here and in the file, so the
                // next batch appends after whole lines.
                let mut text = String::new();
                for record in &records {
                    text.push_str(&record_line(record)?);
                }
                rewrite_log(&partial, &text)?;
                return Ok(records);
            }
            Ok(Vec::new())
        }
        Some(found) if !force && only_designs_differ(&found, manifest) => changed_designs(dir, &found, manifest),
        Some(found) if !force => Err(SweepError::Folder {
            dir: dir.to_path_buf(),
            message: format!(
                "holds another sweep ({}); pass --force to replace it, or another --out",
                difference(&found, manifest)
            ),
        }),
        _ => {
            let ours = [MANIFEST, PARTIAL, RESULTS, CSV, TABLE];
            let entries = std::fs::read_dir(dir).map_err(|e| SweepError::Write {
                path: dir.to_path_buf(),
                message: e.to_string(),
            })?;
            let foreign: Vec<String> = entries
                .filter_map(Result::ok)
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|name| !ours.contains(&name.as_str()))
                .collect();
            if existing.is_none() {
                let mut present: Vec<String> = ours
                    .iter()
                    .filter(|name| dir.join(name).exists())
                    .map(|name| (*name).to_string())
                    .collect();
                present.extend(foreign);
                if !present.is_empty() {
                    return Err(SweepError::Folder {
                        dir: dir.to_path_buf(),
                        message: format!(
                            "is not empty and holds no sweep ({}): give a new or empty folder",
                            present.join(", ")
                        ),
                    });
                }
            }
            if let Some(name) = ours.iter().find(|name| crate::files::is_input(&dir.join(name))) {
                return Err(SweepError::Folder {
                    dir: dir.to_path_buf(),
                    message: format!("{name} is an input of this run (the reference, or a shard being merged): give another --out"),
                });
            }
            remove_ours(dir, &ours)?;
            write(&dir.join(MANIFEST), &manifest_text(manifest)?)?;
            Ok(Vec::new())
        }
    }
}

/// Whether `found` is the same sweep as `wanted` but for designs added, removed or edited (an
/// unsharded sweep: a shard's pairs would move between shards).
fn only_designs_differ(found: &Manifest, wanted: &Manifest) -> bool {
    let rest = |m: &Manifest| Manifest {
        designs: Vec::new(),
        ..m.clone()
    };
    found.shard.is_none() && wanted.shard.is_none() && rest(found) == rest(wanted)
}

/// Takes over a folder whose sweep differs from `manifest` only in its designs: the records of
/// the designs both have unchanged (same id, same file and model hashes) are kept, as the new
/// sweep's finished pairs, and the rest computed again. The partial log is written before the
/// old results and manifest go, so an interruption anywhere leaves a folder this reads again.
fn changed_designs(dir: &Path, found: &Manifest, manifest: &Manifest) -> Result<Vec<Record>, SweepError> {
    let unchanged: std::collections::HashSet<&str> = manifest
        .designs
        .iter()
        .filter(|d| found.designs.contains(d))
        .map(|d| d.id.as_str())
        .collect();
    let previous = if dir.join(RESULTS).exists() {
        read_records(&dir.join(RESULTS))?
    } else if dir.join(PARTIAL).exists() {
        read_partial(&dir.join(PARTIAL))?
    } else {
        Vec::new()
    };
    let kept: Vec<Record> = previous.into_iter().filter(|r| unchanged.contains(r.design.as_str())).collect();
    let mut text = String::new();
    for record in &kept {
        text.push_str(&record_line(record)?);
    }
    rewrite_log(&dir.join(PARTIAL), &text)?;
    remove_ours(dir, &[RESULTS, CSV, TABLE])?;
    write(&dir.join(MANIFEST), &manifest_text(manifest)?)?;
    Ok(kept)
}

/// Removes those of this tool's files `names` that are in `dir`.
fn remove_ours(dir: &Path, names: &[&str]) -> Result<(), SweepError> {
    for name in names {
        let path = dir.join(name);
        if path.exists() {
            std::fs::remove_file(&path).map_err(|e| SweepError::Write {
                path: path.clone(),
                message: e.to_string(),
            })?;
        }
    }
    Ok(())
}

fn manifest_text(manifest: &Manifest) -> Result<String, SweepError> {
    serde_json::to_string_pretty(manifest)
        .map(|t| t + "\n")
        .map_err(|e| SweepError::Folder {
            dir: PathBuf::new(),
            message: e.to_string(),
        })
}

fn difference(found: &Manifest, wanted: &Manifest) -> String {
    if found.format != wanted.format {
        return format!("format {} instead of {}", found.format, wanted.format);
    }
    if found.mode != wanted.mode || found.engines != wanted.engines {
        return format!("mode {} instead of {}", found.mode, wanted.mode);
    }
    if (found.seed, found.ik_seeds) != (wanted.seed, wanted.ik_seeds) {
        return format!(
            "seed {} and {} IK seeds instead of {} and {}",
            found.seed, found.ik_seeds, wanted.seed, wanted.ik_seeds
        );
    }
    if found.designs.len() != wanted.designs.len() {
        return format!("{} designs instead of {}", found.designs.len(), wanted.designs.len());
    }
    if let Some((old, new)) = found.designs.iter().zip(&wanted.designs).find(|(a, b)| a != b) {
        return if old.id == new.id {
            format!("design `{}` has changed since", new.id)
        } else {
            format!("design `{}` where this sweep has `{}`", old.id, new.id)
        };
    }
    if found.reference != wanted.reference {
        return "another --reference".into();
    }
    if found.scenarios != wanted.scenarios {
        return "other scenarios, or the same files changed".into();
    }
    format!(
        "shard {} instead of {}",
        found.shard.as_deref().unwrap_or("none"),
        wanted.shard.as_deref().unwrap_or("none")
    )
}

/// Replaces the sweep's own partial log (never an input: the folder was checked to be this
/// sweep's) through a temporary file beside it, so an interruption leaves the old or the new.
fn rewrite_log(path: &Path, text: &str) -> Result<(), SweepError> {
    let error = |e: std::io::Error| SweepError::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let temporary = path.with_extension("jsonl.rewrite");
    std::fs::write(&temporary, text).map_err(error)?;
    std::fs::rename(&temporary, path).map_err(error)
}

/// How often the partial log is synced to disk while records are written as they finish.
const SYNC_EVERY: std::time::Duration = std::time::Duration::from_secs(1);

/// The partial log of a running sweep: each record is one `write` of its whole line as it
/// finishes, so a killed sweep loses only the pairs still running; synced to disk at most once a
/// second (and when the log is closed) so that a quick sweep does not wait on the disk per pair.
pub struct Log {
    path: PathBuf,
    file: std::fs::File,
    synced: std::time::Instant,
}

impl Log {
    /// Opens `dir`'s partial log for appending.
    ///
    /// # Errors
    /// [`SweepError::Write`].
    pub fn open(dir: &Path) -> Result<Self, SweepError> {
        let path = dir.join(PARTIAL);
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .map_err(|e| SweepError::Write {
                path: path.clone(),
                message: e.to_string(),
            })?;
        Ok(Self {
            path,
            file,
            synced: std::time::Instant::now(),
        })
    }

    /// Appends `record`'s line.
    ///
    /// # Errors
    /// [`SweepError::Write`].
    pub fn write(&mut self, record: &Record) -> Result<(), SweepError> {
        self.file.write_all(record_line(record)?.as_bytes()).map_err(|e| self.error(&e))?;
        if self.synced.elapsed() >= SYNC_EVERY {
            self.sync()?;
        }
        Ok(())
    }

    /// Syncs what was written to disk.
    ///
    /// # Errors
    /// [`SweepError::Write`].
    pub fn sync(&mut self) -> Result<(), SweepError> {
        self.file.sync_data().map_err(|e| self.error(&e))?;
        self.synced = std::time::Instant::now();
        Ok(())
    }

    fn error(&self, e: &std::io::Error) -> SweepError {
        SweepError::Write {
            path: self.path.clone(),
            message: e.to_string(),
        }
    }
}

fn record_line(record: &Record) -> Result<String, SweepError> {
    serde_json::to_string(record).map(|t| t + "\n").map_err(|e| SweepError::Folder {
        dir: PathBuf::new(),
        message: e.to_string(),
    })
}

/// Reads a sweep's own results file: every line a record.
///
/// # Errors
/// [`SweepError::Folder`] naming the line that is not a record.
pub fn read_records(path: &Path) -> Result<Vec<Record>, SweepError> {
    parse_records(&read_text(path)?).map_err(|message| SweepError::Folder {
        dir: path.to_path_buf(),
        message,
    })
}

/// Reads another sweep's results (a reference, a shard): an input of this run, never overwritten
/// by it; with the SHA-256 of the file.
///
/// # Errors
/// As [`read_records`].
pub fn read_input_records(path: &Path) -> Result<(Vec<Record>, String), SweepError> {
    let text = crate::files::read_text(path, MAX_RESULTS_BYTES).map_err(|source| SweepError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let records = parse_records(&text).map_err(|message| SweepError::Reference {
        dir: path.to_path_buf(),
        message,
    })?;
    Ok((records, sha256_hex(text.as_bytes())))
}

/// Every line a record; else the message naming the first line that is not.
fn parse_records(text: &str) -> Result<Vec<Record>, String> {
    text.lines()
        .enumerate()
        .map(|(index, line)| serde_json::from_str(line).map_err(|e| format!("line {}: not a sweep record: {e}", index + 1)))
        .collect()
}

/// Reads the partial log; a last line cut short by an interruption is dropped (its pair runs
/// again).
fn read_partial(path: &Path) -> Result<Vec<Record>, SweepError> {
    let text = read_text(path)?;
    let lines: Vec<&str> = text.split_inclusive('\n').collect();
    let mut records = Vec::with_capacity(lines.len());
    for (index, line) in lines.iter().enumerate() {
        match serde_json::from_str::<Record>(line.trim_end()) {
            Ok(record) => records.push(record),
            Err(_) if index + 1 == lines.len() && !line.ends_with('\n') => {}
            Err(e) => {
                return Err(SweepError::Folder {
                    dir: path.to_path_buf(),
                    message: format!("line {}: not a sweep record: {e}", index + 1),
                })
            }
        }
    }
    Ok(records)
}

/// Writes the finished sweep: records in canonical order, the CSV and the tables; removes the
/// partial log.
///
/// # Errors
/// [`SweepError::Write`].
pub fn finish(dir: &Path, records: &[Record], csv: &str, table: &str) -> Result<(), SweepError> {
    let mut text = String::new();
    for record in records {
        text.push_str(&record_line(record)?);
    }
    write(&dir.join(RESULTS), &text)?;
    write(&dir.join(CSV), csv)?;
    write(&dir.join(TABLE), table)?;
    let partial = dir.join(PARTIAL);
    if partial.exists() {
        std::fs::remove_file(&partial).map_err(|e| SweepError::Write {
            path: partial,
            message: e.to_string(),
        })?;
    }
    Ok(())
}

/// Writes `manifest` (for a merged sweep, whose folder is new).
///
/// # Errors
/// [`SweepError::Write`].
pub fn write_manifest(dir: &Path, manifest: &Manifest) -> Result<(), SweepError> {
    write(&dir.join(MANIFEST), &manifest_text(manifest)?)
}

/// The shards in `dirs`, checked to be the `N` shards of one sweep, each finished: their common
/// manifest without the shard, and every record.
///
/// # Errors
/// [`SweepError::Merge`] naming the folder that does not fit.
pub fn read_shards(dirs: &[PathBuf]) -> Result<(Manifest, Vec<Record>), SweepError> {
    let mut common: Option<Manifest> = None;
    let mut seen: Vec<usize> = Vec::new();
    let mut count = None;
    let mut records = Vec::new();
    for dir in dirs {
        let merge_error = |message: String| SweepError::Merge { dir: dir.clone(), message };
        let manifest = read_manifest(dir)?.ok_or_else(|| merge_error(format!("no {MANIFEST}: not a sweep folder")))?;
        let shard = manifest
            .shard
            .clone()
            .ok_or_else(|| merge_error("holds a whole sweep, not a shard".into()))?;
        let (k, n) = super::Shard::parse(&shard).map_err(merge_error)?.parts();
        if *count.get_or_insert(n) != n {
            return Err(merge_error(format!("is shard {k}/{n}, the others are of {}", count.unwrap_or(n))));
        }
        if seen.contains(&k) {
            return Err(merge_error(format!("shard {k}/{n} is given twice")));
        }
        seen.push(k);
        let whole = Manifest { shard: None, ..manifest };
        match &common {
            Some(first) if first != &whole => {
                return Err(merge_error(format!("is a shard of another sweep ({})", difference(&whole, first))))
            }
            Some(_) => {}
            None => common = Some(whole),
        }
        let results = dir.join(RESULTS);
        if !results.exists() {
            return Err(merge_error(
                "is not finished (no results.jsonl): run its sweep again to resume it".into(),
            ));
        }
        // Read as inputs: the merge's --out may then not replace them.
        records.extend(read_input_records(&results).map_err(|e| merge_error(e.to_string()))?.0);
    }
    let n = count.unwrap_or(0);
    let missing: Vec<String> = (1..=n).filter(|k| !seen.contains(k)).map(|k| format!("{k}/{n}")).collect();
    if !missing.is_empty() {
        return Err(SweepError::Merge {
            dir: dirs.first().cloned().unwrap_or_default(),
            message: format!("shards missing: {}", missing.join(", ")),
        });
    }
    let manifest = common.ok_or_else(|| SweepError::Merge {
        dir: PathBuf::new(),
        message: "no shard folders given".into(),
    })?;
    Ok((manifest, records))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(design: &str) -> Record {
        Record {
            design: design.into(),
            scenario: "t".into(),
            goals: 1,
            goals_solved: 1,
            goals_proven_unreachable: 0,
            goals_undecided: 0,
            task_solved: true,
            position_error_mm: Some(0.0),
            orientation_error_deg: Some(0.0),
            hardware_cost_m: None,
            task_loss: Some(1.0),
            verdict: None,
        }
    }

    fn manifest() -> Manifest {
        Manifest {
            format: FORMAT,
            mode: "reach_only".into(),
            engines: None,
            seed: 0,
            ik_seeds: 4,
            designs: ["a", "b", "c"]
                .into_iter()
                .map(|id| DesignRef {
                    id: id.into(),
                    sha256: None,
                })
                .collect(),
            scenarios: vec![],
            shard: None,
            reference: None,
        }
    }

    #[test]
    fn a_resumed_partial_log_loses_its_cut_line_so_the_next_batch_appends_after_whole_lines() {
        let dir = tempfile::tempdir().expect("temp dir");
        assert!(open(dir.path(), &manifest(), false).expect("new folder").is_empty());
        let mut log = Log::open(dir.path()).expect("log");
        log.write(&record("a")).expect("append");
        log.write(&record("b")).expect("append");
        drop(log);
        let partial = dir.path().join(PARTIAL);
        let mut text = std::fs::read_to_string(&partial).expect("read");
        text.push_str("{\"design\":\"c\",\"sce");
        std::fs::write(&partial, &text).expect("write");
        assert_eq!(open(dir.path(), &manifest(), false).expect("resumed").len(), 2);
        Log::open(dir.path()).expect("log").write(&record("c")).expect("append");
        assert_eq!(open(dir.path(), &manifest(), false).expect("resumed again").len(), 3);
    }

    #[test]
    fn a_folder_without_a_sweep_is_refused_even_when_its_files_have_our_names() {
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::write(dir.path().join(CSV), "mine").expect("write");
        for force in [false, true] {
            let error = open(dir.path(), &manifest(), force).expect_err("refused").to_string();
            assert!(error.contains("is not empty and holds no sweep (results.csv)"), "{error}");
        }
        assert_eq!(std::fs::read_to_string(dir.path().join(CSV)).expect("kept"), "mine");
    }
}
