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
/// This tool's files in a sweep folder (the lock and interrupted writes' temporaries aside).
const OURS: [&str; 5] = [MANIFEST, PARTIAL, RESULTS, CSV, TABLE];

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

/// Takes `dir` (created if missing) for this process's writes: held until the returned lock is
/// dropped (see [`crate::files::lock_folder`]).
///
/// # Errors
/// [`SweepError::Folder`] when another process holds it (naming its pid) or the file system
/// cannot lock.
pub fn lock(dir: &Path) -> Result<crate::files::FolderLock, SweepError> {
    crate::files::lock_folder(dir).map_err(|e| SweepError::Folder {
        dir: dir.to_path_buf(),
        message: e.to_string(),
    })
}

/// The manifest's identity, carried by every line of the partial log: the start of the SHA-256
/// of its text.
fn identity(manifest: &Manifest) -> Result<String, SweepError> {
    let hex = sha256_hex(manifest_text(manifest)?.as_bytes());
    Ok(hex[..16].to_string())
}

/// One line of the partial log: a record and the sweep it belongs to.
#[derive(Deserialize)]
struct Line {
    sweep: String,
    record: Record,
}

/// [`Line`] as written, borrowing what it holds.
#[derive(Serialize)]
struct LineRef<'a> {
    sweep: &'a str,
    record: &'a Record,
}

/// What a folder held for this sweep when it was opened.
#[derive(Debug, Default)]
pub struct Resumed {
    /// Finished pairs of this very sweep.
    pub records: Vec<Record>,
    /// Lines of the partial log that another sweep wrote: ignored, their pairs computed.
    pub foreign: usize,
    /// Lines that are not records (cut short or damaged by a crash): ignored likewise.
    pub damaged: usize,
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

/// What a folder's manifest is.
enum Found {
    /// No `sweep.json`.
    Nothing,
    /// A readable one.
    Manifest(Manifest),
    /// One that does not parse (a crash while it was first written, on a file system that does
    /// not order a rename after the data): why not.
    Damaged(String),
}

/// Prepares `dir` for `manifest`: a new or empty folder gets the manifest; a folder holding the
/// same sweep is resumed (its finished records returned); anything else is refused unless
/// `force`, which removes this tool's files there (and nothing else) and starts over. The caller
/// holds the folder ([`lock`]): temporaries that killed writes left are removed first, and a
/// damaged manifest is rewritten when the partial log's lines prove the folder is this sweep's.
///
/// # Errors
/// [`SweepError::Folder`] naming the first difference, or a file that is not ours.
pub fn open(dir: &Path, manifest: &Manifest, force: bool) -> Result<Resumed, SweepError> {
    let folder_error = |message: String| SweepError::Folder {
        dir: dir.to_path_buf(),
        message,
    };
    let write_error = |path: &Path, e: std::io::Error| SweepError::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    std::fs::create_dir_all(dir).map_err(|e| write_error(dir, e))?;
    crate::files::remove_temporaries(dir, &OURS).map_err(|e| write_error(dir, e))?;
    // The partial log's temporary before it was written through `write_atomic`.
    remove_ours(dir, &[LEGACY_REWRITE])?;
    let id = identity(manifest)?;
    let found = match read_manifest(dir) {
        Ok(Some(found)) => Found::Manifest(found),
        Ok(None) => Found::Nothing,
        Err(e) => Found::Damaged(e.to_string()),
    };
    if let Found::Damaged(why) = &found {
        if !force && !dir.join(RESULTS).exists() && dir.join(PARTIAL).exists() {
            let partial = read_partial(&dir.join(PARTIAL), &id)?;
            if !partial.records.is_empty() {
                // Lines stamped with this manifest's identity: the folder is this sweep's.
                write(&dir.join(MANIFEST), &manifest_text(manifest)?)?;
                return resume_partial(dir, partial, &id);
            }
        }
        if !force {
            return Err(folder_error(format!(
                "{why}; its partial log holds no pair of this sweep: `--force` starts the sweep over in this folder (replacing this tool's files only)"
            )));
        }
    }
    match found {
        Found::Manifest(found) if &found == manifest && !force => {
            if dir.join(RESULTS).exists() {
                let records = read_records(&dir.join(RESULTS))
                    .map_err(|e| folder_error(format!("{e}; `--force` computes the sweep again in this folder")))?;
                return Ok(Resumed {
                    records,
                    ..Resumed::default()
                });
            }
            let partial = dir.join(PARTIAL);
            if partial.exists() {
                return resume_partial(dir, read_partial(&partial, &id)?, &id);
            }
            Ok(Resumed::default())
        }
        Found::Manifest(found) if !force && only_designs_differ(&found, manifest) => changed_designs(dir, &found, manifest),
        Found::Manifest(found) if !force => Err(folder_error(format!(
            "holds another sweep ({}); pass --force to replace it, or another --out",
            difference(&found, manifest)
        ))),
        found => {
            let entries = std::fs::read_dir(dir).map_err(|e| write_error(dir, e))?;
            let foreign: Vec<String> = entries
                .filter_map(Result::ok)
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|name| !OURS.contains(&name.as_str()) && name != crate::files::LOCK)
                .collect();
            if matches!(found, Found::Nothing) {
                let mut present: Vec<String> = OURS
                    .iter()
                    .filter(|name| dir.join(name).exists())
                    .map(|name| (*name).to_string())
                    .collect();
                present.extend(foreign);
                if !present.is_empty() {
                    return Err(folder_error(format!(
                        "is not empty and holds no sweep ({}): give a new or empty folder",
                        present.join(", ")
                    )));
                }
            }
            if let Some(name) = OURS.iter().find(|name| crate::files::is_input(&dir.join(name))) {
                return Err(folder_error(format!(
                    "{name} is an input of this run (the reference, or a shard being merged): give another --out"
                )));
            }
            remove_ours(dir, &OURS)?;
            write(&dir.join(MANIFEST), &manifest_text(manifest)?)?;
            Ok(Resumed::default())
        }
    }
}

/// Where an older version rewrote the partial log through (removed when found).
const LEGACY_REWRITE: &str = "pairs.partial.jsonl.rewrite";

/// Resumes from the partial log as read: when lines were ignored (another sweep's, or cut short
/// by an interruption) the log is rewritten without them, so the next lines follow whole ones.
fn resume_partial(dir: &Path, partial: Resumed, id: &str) -> Result<Resumed, SweepError> {
    if partial.foreign + partial.damaged > 0 {
        rewrite_log(&dir.join(PARTIAL), &partial.records, id)?;
    }
    Ok(partial)
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
fn changed_designs(dir: &Path, found: &Manifest, manifest: &Manifest) -> Result<Resumed, SweepError> {
    let unchanged: std::collections::HashSet<&str> = manifest
        .designs
        .iter()
        .filter(|d| found.designs.contains(d))
        .map(|d| d.id.as_str())
        .collect();
    let previous = if dir.join(RESULTS).exists() {
        Resumed {
            records: read_records(&dir.join(RESULTS))?,
            ..Resumed::default()
        }
    } else if dir.join(PARTIAL).exists() {
        read_partial(&dir.join(PARTIAL), &identity(found)?)?
    } else {
        Resumed::default()
    };
    let kept: Vec<Record> = previous
        .records
        .into_iter()
        .filter(|r| unchanged.contains(r.design.as_str()))
        .collect();
    rewrite_log(&dir.join(PARTIAL), &kept, &identity(manifest)?)?;
    remove_ours(dir, &[RESULTS, CSV, TABLE])?;
    write(&dir.join(MANIFEST), &manifest_text(manifest)?)?;
    Ok(Resumed { records: kept, ..previous })
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
            crate::files::crash_point();
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
/// sweep's) with `records`, atomically and synced, so an interruption leaves the old or the new.
fn rewrite_log(path: &Path, records: &[Record], id: &str) -> Result<(), SweepError> {
    let mut text = String::new();
    for record in records {
        text.push_str(&line_text(record, id)?);
    }
    write(path, &text)
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
    /// The manifest's identity, stamped on every line.
    id: String,
}

impl Log {
    /// Opens `dir`'s partial log for appending the records of `manifest`'s sweep.
    ///
    /// # Errors
    /// [`SweepError::Write`].
    pub fn open(dir: &Path, manifest: &Manifest) -> Result<Self, SweepError> {
        let id = identity(manifest)?;
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
            id,
        })
    }

    /// Appends `record`'s line.
    ///
    /// # Errors
    /// [`SweepError::Write`].
    pub fn write(&mut self, record: &Record) -> Result<(), SweepError> {
        crate::files::crash_point();
        self.file
            .write_all(line_text(record, &self.id)?.as_bytes())
            .map_err(|e| self.error(&e))?;
        crate::files::crash_point();
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

/// A partial log's line: `record` stamped with its sweep's identity.
fn line_text(record: &Record, id: &str) -> Result<String, SweepError> {
    let line = LineRef { sweep: id, record };
    serde_json::to_string(&line).map(|t| t + "\n").map_err(|e| SweepError::Folder {
        dir: PathBuf::new(),
        message: e.to_string(),
    })
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

/// Reads the partial log: the records stamped with `id`; lines of another sweep (or of a
/// version that did not stamp them) and lines that are not records (cut short by a kill, or
/// zero-filled by a power loss) are counted and left out, their pairs run again.
fn read_partial(path: &Path, id: &str) -> Result<Resumed, SweepError> {
    let text = read_text(path)?;
    let mut resumed = Resumed::default();
    for line in text.split_inclusive('\n') {
        if !line.ends_with('\n') {
            // Cut short, even where what came through parses: the next line would join it.
            resumed.damaged += 1;
            continue;
        }
        match serde_json::from_str::<Line>(line.trim_end()) {
            Ok(line) if line.sweep == id => resumed.records.push(line.record),
            Ok(_) => resumed.foreign += 1,
            Err(_) if serde_json::from_str::<Record>(line.trim_end()).is_ok() => resumed.foreign += 1,
            Err(_) => resumed.damaged += 1,
        }
    }
    Ok(resumed)
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
    remove_ours(dir, &[PARTIAL])?;
    crate::files::sync_folder(dir);
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
        assert!(open(dir.path(), &manifest(), false).expect("new folder").records.is_empty());
        let mut log = Log::open(dir.path(), &manifest()).expect("log");
        log.write(&record("a")).expect("append");
        log.write(&record("b")).expect("append");
        drop(log);
        let partial = dir.path().join(PARTIAL);
        let mut text = std::fs::read_to_string(&partial).expect("read");
        text.push_str("{\"sweep\":\"0123\",\"rec");
        std::fs::write(&partial, &text).expect("write");
        let resumed = open(dir.path(), &manifest(), false).expect("resumed");
        assert_eq!((resumed.records.len(), resumed.damaged), (2, 1));
        Log::open(dir.path(), &manifest())
            .expect("log")
            .write(&record("c"))
            .expect("append");
        let resumed = open(dir.path(), &manifest(), false).expect("resumed again");
        assert_eq!((resumed.records.len(), resumed.damaged), (3, 0));
    }

    #[test]
    fn lines_of_another_sweep_and_damaged_lines_are_left_out_and_counted() {
        let dir = tempfile::tempdir().expect("temp dir");
        open(dir.path(), &manifest(), false).expect("new folder");
        let other = Manifest { seed: 1, ..manifest() };
        Log::open(dir.path(), &manifest())
            .expect("log")
            .write(&record("a"))
            .expect("append");
        Log::open(dir.path(), &other).expect("log").write(&record("b")).expect("append");
        let partial = dir.path().join(PARTIAL);
        let mut text = std::fs::read_to_string(&partial).expect("read");
        // What a power loss leaves: a run of zero bytes where a line was.
        text.push_str(&"\0".repeat(40));
        text.push('\n');
        text.push_str(&record_line(&record("c")).expect("line"));
        std::fs::write(&partial, &text).expect("write");
        Log::open(dir.path(), &manifest())
            .expect("log")
            .write(&record("c"))
            .expect("append");
        let resumed = open(dir.path(), &manifest(), false).expect("resumed");
        let designs: Vec<&str> = resumed.records.iter().map(|r| r.design.as_str()).collect();
        assert_eq!(designs, ["a", "c"]);
        assert_eq!((resumed.foreign, resumed.damaged), (2, 1));
        let resumed = open(dir.path(), &manifest(), false).expect("resumed again");
        assert_eq!((resumed.records.len(), resumed.foreign, resumed.damaged), (2, 0, 0));
    }

    #[test]
    fn temporaries_of_killed_writes_never_block_a_folder() {
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::write(dir.path().join(".sweep.json.4242.0.tmp"), "{\"form").expect("write");
        open(dir.path(), &manifest(), false).expect("taken");
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .expect("list")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, [MANIFEST]);
    }

    #[test]
    fn a_damaged_manifest_is_repaired_from_its_own_lines_or_replaced_with_force() {
        let dir = tempfile::tempdir().expect("temp dir");
        open(dir.path(), &manifest(), false).expect("new folder");
        Log::open(dir.path(), &manifest())
            .expect("log")
            .write(&record("a"))
            .expect("append");
        std::fs::write(dir.path().join(MANIFEST), "\0\0\0").expect("damage");
        let resumed = open(dir.path(), &manifest(), false).expect("repaired");
        assert_eq!(resumed.records.len(), 1);
        assert_eq!(read_manifest(dir.path()).expect("readable"), Some(manifest()));
        // Another sweep's folder with a damaged manifest: refused, then replaced with --force.
        let other = Manifest { seed: 1, ..manifest() };
        std::fs::write(dir.path().join(MANIFEST), "{").expect("damage");
        let error = open(dir.path(), &other, false).expect_err("not provably ours").to_string();
        assert!(error.contains("`--force` starts the sweep over"), "{error}");
        assert!(open(dir.path(), &other, true).expect("forced").records.is_empty());
        assert_eq!(read_manifest(dir.path()).expect("readable"), Some(other));
    }

    #[test]
    fn a_second_lock_on_a_folder_is_refused_with_the_holders_pid() {
        let dir = tempfile::tempdir().expect("temp dir");
        let held = lock(dir.path()).expect("first");
        let error = lock(dir.path()).expect_err("second").to_string();
        assert!(
            error.contains(&format!("in use by another validate-design (pid {})", std::process::id())),
            "{error}"
        );
        drop(held);
        lock(dir.path()).expect("free again");
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
