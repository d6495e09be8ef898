//! Writing a run's outputs: atomically, never over a file the run read.

use crate::error::Error;
use std::path::{Path, PathBuf};

/// Writes text to `path` atomically (see [`crate::files::write_atomic`]), replacing an existing
/// output but never a file this process has read (the design, the scenario, a mesh, a file an
/// MJCF includes, or a link to any of them).
///
/// # Errors
/// [`Error::WouldOverwriteInput`] or [`Error::Write`] (the old file is then intact).
pub fn write_output(path: &Path, text: &str) -> Result<(), Error> {
    write_output_bytes(path, text.as_bytes())
}

/// [`write_output`] for bytes (a PNG).
///
/// # Errors
/// As [`write_output`].
pub fn write_output_bytes(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    crate::files::write_atomic(path, bytes, true).map_err(|error| write_error(path, error))
}

/// Writes `files` (file name, bytes) into the folder `dir`, creating it: only these names are
/// written (a file of the same name is replaced, never an input of this run); anything else in
/// the folder is left alone. All of them or none (see [`OutputSet`]). Returns the paths written,
/// in order.
///
/// # Errors
/// [`Error::PictureFolder`] when `dir` is not a folder or a name in it is a folder,
/// [`Error::WouldOverwriteInput`] or [`Error::Write`] as [`write_output`].
pub fn write_files_into(dir: &Path, files: &[(String, Vec<u8>)]) -> Result<Vec<PathBuf>, Error> {
    let mut set = OutputSet::default();
    let written = set.add_into(dir, files)?;
    set.commit()?;
    Ok(written)
}

/// A run's outputs written as one set: either every file is new, or (a full disk, a size
/// limit, a refused target) every old file is as it was, with the error.
#[derive(Debug, Default)]
pub struct OutputSet {
    staged: crate::files::Staged,
}

fn write_error(path: &Path, error: crate::files::WriteError) -> Error {
    match error {
        crate::files::WriteError::Input => Error::WouldOverwriteInput { path: path.to_path_buf() },
        other => Error::Write {
            path: path.to_path_buf(),
            source: std::io::Error::other(other.to_string()),
        },
    }
}

impl OutputSet {
    /// Adds a file to the set (written to a temporary now, in place at [`Self::commit`]).
    ///
    /// # Errors
    /// As [`write_output`].
    pub fn add(&mut self, path: &Path, bytes: &[u8]) -> Result<(), Error> {
        self.staged.add(path, bytes).map_err(|e| write_error(path, e))
    }

    /// Adds `files` (file name, bytes) in the folder `dir`, creating it (see
    /// [`write_files_into`]); returns their paths.
    ///
    /// # Errors
    /// As [`write_files_into`].
    pub fn add_into(&mut self, dir: &Path, files: &[(String, Vec<u8>)]) -> Result<Vec<PathBuf>, Error> {
        let folder_error = |message: String| Error::PictureFolder {
            path: dir.to_path_buf(),
            message,
        };
        if dir.exists() && !dir.is_dir() {
            return Err(folder_error("it exists and is not a folder".into()));
        }
        std::fs::create_dir_all(dir).map_err(|e| folder_error(format!("cannot create it: {e}")))?;
        let mut paths = Vec::with_capacity(files.len());
        for (name, bytes) in files {
            let path = dir.join(name);
            if path.is_dir() {
                return Err(folder_error(format!("{name} in it is a folder")));
            }
            self.add(&path, bytes)?;
            paths.push(path);
        }
        Ok(paths)
    }

    /// Puts every file of the set in place.
    ///
    /// # Errors
    /// [`Error::Write`] naming the file whose rename failed.
    pub fn commit(self) -> Result<(), Error> {
        self.staged.commit().map_err(|(path, e)| write_error(&path, e))
    }
}
