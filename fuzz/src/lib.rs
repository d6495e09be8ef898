//! Helpers shared by the fuzz targets.

use std::path::PathBuf;
use std::sync::OnceLock;

/// A scratch file `name` in a folder of this process's own (`$TMPDIR/proving-ground-fuzz-PID`),
/// created once and then overwritten with `bytes` on every call.
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
    std::fs::write(&path, bytes).expect("fuzz harness: cannot write its scratch file");
    path
}
