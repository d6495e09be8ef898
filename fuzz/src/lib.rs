//! Helpers shared by the fuzz targets.

use std::path::PathBuf;
use std::sync::OnceLock;

/// A scratch file `name` in a folder of this process's own (`$TMPDIR/proving-ground-fuzz-PID`),
/// written anew with `bytes` on every call.
///
/// # Panics
/// When the scratch folder or file cannot be written: that is the harness failing, not a finding.
pub fn scratch_file(name: &str, bytes: &[u8]) -> PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    let dir = DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("proving-ground-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("fuzz harness: cannot create its scratch folder");
        dir
    });
    let path = dir.join(name);
    // A new file each time: on ext4, rewriting a file truncated to zero flushes it to disk at close
    // (auto_da_alloc), which made every run take milliseconds.
    let _ = std::fs::remove_file(&path);
    std::fs::write(&path, bytes).expect("fuzz harness: cannot write its scratch file");
    path
}
