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
    /// The designs, in order, by id.
    pub designs: Vec<String>,
    /// The scenarios, in order: id and SHA-256 of the file.
    pub scenarios: Vec<ScenarioRef>,
    /// `K/N` when this folder holds one shard of the sweep.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<String>,
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
                return read_partial(&partial);
            }
            Ok(Vec::new())
        }
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
            if !foreign.is_empty() && existing.is_none() {
                return Err(SweepError::Folder {
                    dir: dir.to_path_buf(),
                    message: format!(
                        "is not empty and holds no sweep ({}): give a new or empty folder",
                        foreign.join(", ")
                    ),
                });
            }
            for name in ours {
                let path = dir.join(name);
                if path.exists() {
                    std::fs::remove_file(&path).map_err(|e| SweepError::Write {
                        path: path.clone(),
                        message: e.to_string(),
                    })?;
                }
            }
            write(&dir.join(MANIFEST), &manifest_text(manifest)?)?;
            Ok(Vec::new())
        }
    }
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
    if found.designs != wanted.designs {
        return format!("{} designs, not the same {}", found.designs.len(), wanted.designs.len());
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

/// Appends finished records to the partial log, flushed: an interrupted sweep keeps them.
///
/// # Errors
/// [`SweepError::Write`].
pub fn append(dir: &Path, records: &[Record]) -> Result<(), SweepError> {
    let path = dir.join(PARTIAL);
    let error = |e: std::io::Error| SweepError::Write {
        path: path.clone(),
        message: e.to_string(),
    };
    let mut file = std::fs::OpenOptions::new().create(true).append(true).open(&path).map_err(error)?;
    let mut text = String::new();
    for record in records {
        text.push_str(&record_line(record)?);
    }
    file.write_all(text.as_bytes()).map_err(error)?;
    file.sync_data().map_err(error)
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
    parse_records(path, &read_text(path)?)
}

/// Reads another sweep's results (a reference): an input of this run, never overwritten by it.
///
/// # Errors
/// As [`read_records`].
pub fn read_input_records(path: &Path) -> Result<Vec<Record>, SweepError> {
    let text = crate::files::read_text(path, MAX_RESULTS_BYTES).map_err(|source| SweepError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_records(path, &text)
}

fn parse_records(path: &Path, text: &str) -> Result<Vec<Record>, SweepError> {
    text.lines()
        .enumerate()
        .map(|(index, line)| {
            serde_json::from_str(line).map_err(|e| SweepError::Folder {
                dir: path.to_path_buf(),
                message: format!("line {}: not a sweep record: {e}", index + 1),
            })
        })
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
        records.extend(read_records(&results)?);
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
