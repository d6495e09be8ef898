//! The file boundary. Every input is read through [`read_text`] or [`read_bytes`]: regular files
//! only, within a size limit, and remembered; every output is written through [`write_atomic`]:
//! a temporary file in the target's folder, flushed, then renamed over the target, never over a
//! file this process has read (same canonical path or same inode, so hard and symbolic links to
//! an input are refused too).
//!
//! The set of files read is process-wide because inputs are read deep inside the stages (a URDF's
//! meshes, a scenario's meshes, the files an MJCF `<include>`s): whichever stage read a file,
//! no output of the same process may replace it.

use crate::limits;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// One file that was read: where it is and which inode it is.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Identity {
    device: u64,
    inode: u64,
    canonical: PathBuf,
}

static READ: Mutex<Vec<Identity>> = Mutex::new(Vec::new());

fn identity(path: &Path) -> Option<Identity> {
    use std::os::unix::fs::MetadataExt;
    let meta = std::fs::metadata(path).ok()?;
    Some(Identity {
        device: meta.dev(),
        inode: meta.ino(),
        canonical: path.canonicalize().ok()?,
    })
}

/// Remembers `path` as an input of this process (for files read by others, such as MuJoCo).
pub fn record_input(path: &Path) {
    if let Some(id) = identity(path) {
        let mut read = READ.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        if !read.contains(&id) {
            read.push(id);
        }
    }
}

/// Every file this process has read, by canonical path, in the order first read.
pub fn inputs_read() -> Vec<PathBuf> {
    let read = READ.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    read.iter().map(|id| id.canonical.clone()).collect()
}

/// Whether writing `path` would replace a file this process has read.
pub fn is_input(path: &Path) -> bool {
    let Some(target) = identity(path) else { return false };
    let read = READ.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    read.iter().any(|id| {
        // An inode only counts while the file read still holds it: once that file is deleted
        // the number is reused by new files, which were never read.
        let same_inode = (id.device, id.inode) == (target.device, target.inode) && identity(&id.canonical).as_ref() == Some(id);
        same_inode || id.canonical == target.canonical
    })
}

/// What a path is when it is not a regular file, for messages.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let kind = meta.file_type();
    if kind.is_dir() {
        "a directory"
    } else if kind.is_fifo() {
        "a FIFO"
    } else if kind.is_char_device() || kind.is_block_device() {
        "a device"
    } else if kind.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

fn other(message: String) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, message)
}

/// Checks that `path` is a regular file of at most `limit` bytes, without opening it (opening a
/// FIFO blocks until a writer comes).
///
/// # Errors
/// An I/O error saying what the path is instead, or how large it is.
pub fn check_regular(path: &Path, limit: u64) -> std::io::Result<u64> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(other(format!("{}: expected a regular file", kind_of(&meta))));
    }
    if meta.len() > limit {
        return Err(other(format!(
            "{} bytes: larger than the limit of {} for this kind of file",
            meta.len(),
            limits::bytes(limit)
        )));
    }
    Ok(meta.len())
}

/// Reads a regular file of at most `limit` bytes and remembers it as an input.
///
/// # Errors
/// An I/O error: missing or unreadable, not a regular file (directory, FIFO, device), or larger
/// than `limit`.
pub fn read_bytes(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let expected = check_regular(path, limit)?;
    let file = std::fs::File::open(path)?;
    // The file may have changed between the check and the open: check what was opened.
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(other(format!("{}: expected a regular file", kind_of(&meta))));
    }
    let mut bytes = Vec::with_capacity(usize::try_from(expected.min(limit)).unwrap_or(0));
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(other(format!(
            "larger than the limit of {} for this kind of file",
            limits::bytes(limit)
        )));
    }
    record_input(path);
    Ok(bytes)
}

/// Reads a regular UTF-8 text file of at most `limit` bytes and remembers it as an input.
///
/// # Errors
/// As [`read_bytes`], and invalid UTF-8 (naming the line and column).
pub fn read_text(path: &Path, limit: u64) -> std::io::Result<String> {
    let bytes = read_bytes(path, limit)?;
    String::from_utf8(bytes).map_err(|e| {
        let valid = e.utf8_error().valid_up_to();
        let before = &e.as_bytes()[..valid];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = valid - before.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1) + 1;
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("line {line}, column {column}: invalid UTF-8 (expected a UTF-8 text file)"),
        )
    })
}

/// Why an output was not written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The target is a file this process read.
    #[error("it is an input of this run (same file or a link to it)")]
    Input,
    /// The target exists and replacing was not asked for.
    #[error("the file exists")]
    Exists,
    /// The file system refused; the old file, if any, is intact.
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// Writes `bytes` to `path` atomically: a temporary file beside it, flushed to disk, then renamed
/// over it, so a failed write leaves the old file intact and no partial file. An existing file is
/// replaced only when `replace` is true (and never when it is an input of this process); a
/// replaced file keeps its permissions.
///
/// # Errors
/// [`WriteError`].
pub fn write_atomic(path: &Path, bytes: &[u8], replace: bool) -> Result<(), WriteError> {
    let (existing, dir) = target(path)?;
    if existing.is_some() && !replace {
        return Err(WriteError::Exists);
    }
    let temp = write_temporary(path, &dir, bytes, existing.as_ref())?;
    crash_point();
    let written = (|| -> std::io::Result<()> {
        if replace {
            std::fs::rename(&temp, path)
        } else {
            // A hard link fails when the name exists, so a file created meanwhile is not lost.
            std::fs::hard_link(&temp, path).map_err(|e| {
                if e.kind() == std::io::ErrorKind::AlreadyExists {
                    other("the file exists".into())
                } else {
                    e
                }
            })?;
            std::fs::remove_file(&temp)
        }
    })();
    if let Err(error) = written {
        let _ = std::fs::remove_file(&temp);
        return Err(error.into());
    }
    crash_point();
    sync_folder(&dir);
    Ok(())
}

/// The exit code of a run the crash-test hook ended (what a shell shows for SIGKILL).
pub const CRASH_EXIT: i32 = 137;

/// The environment variable of the crash-test hook (see [`crash_point`]).
pub const CRASH_AT: &str = "VALIDATE_DESIGN_CRASH_AT";

/// A step of a write sequence where a crash leaves the files in a state of their own (a
/// temporary written, a rename done, a line appended). With [`CRASH_AT`] set to `N` the process
/// exits with [`CRASH_EXIT`] at the `N`-th such step, as a kill would end it there (no
/// destructor, no cleanup; the kernel closes the files and releases the folder's lock):
/// the tests run sweeps, merges and suites with every `N` and check that a rerun repairs the
/// folder. Unset (what every user has), it only counts.
pub fn crash_point() {
    static AT: std::sync::OnceLock<Option<u64>> = std::sync::OnceLock::new();
    static STEPS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let at = AT.get_or_init(|| std::env::var(CRASH_AT).ok().and_then(|v| v.trim().parse().ok()));
    if let Some(at) = at {
        if STEPS.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1 == *at {
            std::process::exit(CRASH_EXIT);
        }
    }
}

/// The lock file of a folder this tool writes (sweeps, merges, snapshot suites).
pub const LOCK: &str = ".validate-design.lock";

/// A folder held by this process: no other validate-design writes it until this is dropped, or
/// the process ends however it ends (the kernel releases the lock, so a dead run's folder is
/// taken over without any cleanup). Dropped, it removes its lock file (a snapshot folder in a
/// user's repository keeps no stray file); a killed run's file stays until the next run.
#[derive(Debug)]
pub struct FolderLock {
    file: std::fs::File,
    path: PathBuf,
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        // Removed while still locked: a run that opened the file meanwhile finds, once it holds
        // the lock, that the name no longer leads to its file, and starts over.
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

/// Why a folder could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    /// Another process holds it.
    #[error("is in use by another validate-design{}: wait for it to finish or stop it; one run writes a folder at a time", holder.as_ref().map_or(String::new(), |pid| format!(" (pid {pid})")))]
    Held {
        /// The holder's pid, as it wrote it.
        holder: Option<String>,
    },
    /// The folder or its lock file cannot be made, or the file system cannot lock.
    #[error("cannot be locked ({0}): the file system must support flock, so that two runs never write one folder")]
    Io(#[from] std::io::Error),
}

/// Takes `dir` (created if missing) for this process's writes: an exclusive `flock` on its
/// [`LOCK`] file, which names the holder's pid.
///
/// # Errors
/// [`LockError`].
pub fn lock_folder(dir: &Path) -> Result<FolderLock, LockError> {
    use std::os::unix::fs::MetadataExt;
    std::fs::create_dir_all(dir)?;
    let path = dir.join(LOCK);
    loop {
        // Not truncated on open: the holder's pid stays readable until the lock is ours.
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                let mut holder = String::new();
                let _ = file.read_to_string(&mut holder);
                let holder = holder.trim();
                return Err(LockError::Held {
                    holder: (!holder.is_empty()).then(|| holder.to_string()),
                });
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(e.into()),
        }
        // The holder before may have removed the file between our open and our lock: then the
        // lock is on a file nobody else can find, and the name must be opened again.
        let held = file.metadata()?;
        let named = std::fs::metadata(&path).ok();
        if named.is_none_or(|m| (m.dev(), m.ino()) != (held.dev(), held.ino())) {
            continue;
        }
        file.set_len(0)?;
        std::io::Seek::rewind(&mut file)?;
        writeln!(file, "{}", std::process::id())?;
        return Ok(FolderLock { file, path });
    }
}

/// Syncs a folder's entries (a rename or a new name) to disk. Best effort: some file systems
/// refuse to sync a directory, and the file's own data is already synced.
pub fn sync_folder(dir: &Path) {
    if let Ok(folder) = std::fs::File::open(dir) {
        let _ = folder.sync_all();
    }
}

/// Whether `file_name` is a temporary [`write_atomic`] makes for one of `targets`
/// (`.NAME.PID.N.tmp`): left behind only by a process killed mid-write.
pub fn is_temporary_of(file_name: &str, targets: &[&str]) -> bool {
    let Some(rest) = file_name.strip_prefix('.').and_then(|r| r.strip_suffix(".tmp")) else {
        return false;
    };
    targets.iter().any(|target| {
        rest.strip_prefix(target)
            .and_then(|r| r.strip_prefix('.'))
            .and_then(|r| r.split_once('.'))
            .is_some_and(|(pid, n)| {
                let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
                digits(pid) && digits(n)
            })
    })
}

/// Removes from `dir` the temporaries of `targets` that killed writers left (see
/// [`is_temporary_of`]); returns how many. The caller must hold the folder (no live writer).
///
/// # Errors
/// The folder cannot be listed or a temporary cannot be removed.
pub fn remove_temporaries(dir: &Path, targets: &[&str]) -> std::io::Result<usize> {
    let mut removed = 0;
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        if entry.file_type()?.is_file() && is_temporary_of(&entry.file_name().to_string_lossy(), targets) {
            std::fs::remove_file(entry.path())?;
            removed += 1;
            crash_point();
        }
    }
    Ok(removed)
}

/// A write target checked: never an input of this run, a regular file or a new name; its
/// metadata when it exists, and its folder.
fn target(path: &Path) -> Result<(Option<std::fs::Metadata>, PathBuf), WriteError> {
    if is_input(path) {
        return Err(WriteError::Input);
    }
    let existing = std::fs::metadata(path).ok();
    if let Some(meta) = &existing {
        if !meta.is_file() {
            return Err(WriteError::Io(other(format!(
                "{}: expected a regular file or a new name",
                kind_of(meta)
            ))));
        }
    }
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok((existing, dir))
}

/// Writes `bytes` to a new temporary beside `path` in `dir`, with the permissions of the file it
/// will replace, synced to disk; returns its path (removed again on failure).
fn write_temporary(path: &Path, dir: &Path, bytes: &[u8], existing: Option<&std::fs::Metadata>) -> std::io::Result<PathBuf> {
    let name = path.file_name().ok_or_else(|| other("expected a file name".into()))?;
    let (temp, mut file) = create_temp(dir, &name.to_string_lossy())?;
    let written = (|| -> std::io::Result<()> {
        file.write_all(bytes)?;
        if let Some(meta) = existing {
            file.set_permissions(meta.permissions())?;
        }
        file.sync_all()
    })();
    if let Err(error) = written {
        let _ = std::fs::remove_file(&temp);
        return Err(error);
    }
    Ok(temp)
}

/// Files written as one set: each is written in full to a temporary beside its target first;
/// only when all of them are does [`Staged::commit`] rename them over their targets. A failure
/// before (a full disk, a size limit, a refused target) leaves every old file as it was and no
/// temporary behind.
#[derive(Debug, Default)]
pub struct Staged {
    /// Target and temporary of each file, in the order added.
    pending: Vec<(PathBuf, PathBuf)>,
}

impl Staged {
    /// Writes `bytes` for `path` to a temporary, with [`write_atomic`]'s checks (never over an
    /// input, a regular file or a new name only); existing files are replaced at commit.
    ///
    /// # Errors
    /// [`WriteError`]; the set is unchanged.
    pub fn add(&mut self, path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
        let (existing, dir) = target(path)?;
        let temp = write_temporary(path, &dir, bytes, existing.as_ref())?;
        self.pending.push((path.to_path_buf(), temp));
        crash_point();
        Ok(())
    }

    /// Renames every file of the set over its target, then syncs their folders.
    ///
    /// # Errors
    /// The target whose rename failed (those before it are replaced, the rest left as they were).
    pub fn commit(mut self) -> Result<(), (PathBuf, WriteError)> {
        let pending = std::mem::take(&mut self.pending);
        let mut folders: Vec<PathBuf> = Vec::new();
        for (index, (target, temp)) in pending.iter().enumerate() {
            if let Err(error) = std::fs::rename(temp, target) {
                for (_, left) in &pending[index..] {
                    let _ = std::fs::remove_file(left);
                }
                return Err((target.clone(), error.into()));
            }
            crash_point();
            let folder = temp.parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf);
            if !folders.contains(&folder) {
                folders.push(folder);
            }
        }
        for folder in &folders {
            sync_folder(folder);
        }
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        for (_, temp) in &self.pending {
            let _ = std::fs::remove_file(temp);
        }
    }
}

fn create_temp(dir: &Path, name: &str) -> std::io::Result<(PathBuf, std::fs::File)> {
    static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    loop {
        let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let temp = dir.join(format!(".{name}.{}.{n}.tmp", std::process::id()));
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&temp) {
            Ok(file) => return Ok((temp, file)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_our_temporaries_of_the_named_targets_are_temporaries() {
        let targets = ["sweep.json", "results.jsonl"];
        assert!(is_temporary_of(".sweep.json.4711.0.tmp", &targets));
        assert!(is_temporary_of(".results.jsonl.12.345.tmp", &targets));
        for name in [
            "sweep.json",
            ".sweep.json.tmp",
            ".sweep.json.x.0.tmp",
            ".sweep.json.1.0.1.tmp",
            ".notes.txt.1.0.tmp",
            "sweep.json.1.0.tmp",
            ".sweep.json.1..tmp",
        ] {
            assert!(!is_temporary_of(name, &targets), "{name}");
        }
    }

    #[test]
    fn reads_are_remembered_and_refused_as_outputs_through_links() {
        let dir = tempfile::tempdir().expect("temp dir");
        let input = dir.path().join("in.json");
        std::fs::write(&input, "{}").expect("write");
        let hard = dir.path().join("hard.json");
        std::fs::hard_link(&input, &hard).expect("hard link");
        let soft = dir.path().join("soft.json");
        std::os::unix::fs::symlink(&input, &soft).expect("symlink");
        read_text(&input, 100).expect("read");
        for target in [&input, &hard, &soft] {
            assert!(
                matches!(write_atomic(target, b"x", true), Err(WriteError::Input)),
                "{}",
                target.display()
            );
        }
        assert_eq!(std::fs::read_to_string(&input).expect("read"), "{}");
    }

    #[test]
    fn fifo_and_directory_are_refused_without_blocking() {
        let dir = tempfile::tempdir().expect("temp dir");
        let fifo = dir.path().join("pipe.stl");
        let status = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
        assert!(status.success());
        let error = read_bytes(&fifo, 100).expect_err("a FIFO is refused");
        assert!(error.to_string().contains("a FIFO"), "{error}");
        let error = read_bytes(dir.path(), 100).expect_err("a directory is refused");
        assert!(error.to_string().contains("a directory"), "{error}");
    }

    #[test]
    fn size_limit_and_invalid_utf8_are_named() {
        let dir = tempfile::tempdir().expect("temp dir");
        let big = dir.path().join("big.json");
        std::fs::write(&big, vec![b' '; 101]).expect("write");
        assert!(read_bytes(&big, 100).expect_err("too large").to_string().contains("101 bytes"));
        let bad = dir.path().join("bad.xml");
        std::fs::write(&bad, b"<a>\n<b name=\"\xff\"/>").expect("write");
        let error = read_text(&bad, 100).expect_err("not UTF-8");
        assert!(error.to_string().contains("line 2, column 10"), "{error}");
    }

    #[test]
    fn no_replace_keeps_an_existing_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().expect("temp dir");
        let out = dir.path().join("out.json");
        std::fs::write(&out, "old").expect("write");
        assert!(matches!(write_atomic(&out, b"new", false), Err(WriteError::Exists)));
        write_atomic(&out, b"new", true).expect("replace");
        assert_eq!(std::fs::read_to_string(&out).expect("read"), "new");
        let fresh = dir.path().join("fresh.json");
        write_atomic(&fresh, b"n", false).expect("create");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .expect("list")
            .map(|e| e.expect("entry").file_name())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
    }
}
