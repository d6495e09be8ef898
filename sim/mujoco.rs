//! The MuJoCo library, below every stage that uses it (the MJCF reader, the engines, the
//! kinematic oracle): loaded at first use, and its version checked against the pin.
//!
//! Loaded at first use, so that everything that does not need MuJoCo (help,
//! `generate`, `--engines rapier`, designs and URDFs without the kinematics check) runs on a
//! machine without it, and a run that needs it says what to install.
//!
//! How (see build.rs): the binaries have no `DT_NEEDED` entry on libmujoco; rustc is told to call
//! foreign functions through the PLT (`-C relro-level=partial` in `.cargo/config.toml`), whose
//! slots the dynamic loader binds at the first call. [`ensure`] opens the library with
//! `RTLD_GLOBAL` before any MuJoCo function runs, so those first calls find it. No MuJoCo global
//! variable may be referenced directly: data is bound at start-up, and the binary would not start.

use std::ffi::{CStr, CString};
use std::sync::OnceLock;

/// The library's file name, as the loader looks it up (rpath to `.mujoco/lib`, then the system).
pub const SONAME: &str = env!("MUJOCO_SONAME");

/// Environment variable naming the MuJoCo library file to load instead of [`SONAME`] (then the
/// only one tried).
pub const LIBRARY_ENV: &str = "MUJOCO_LIBRARY";

static LOADED: OnceLock<Result<(), String>> = OnceLock::new();

/// Makes MuJoCo callable, loading it on the first call.
///
/// # Errors
/// What could not be loaded and what to install.
pub fn ensure() -> Result<(), String> {
    LOADED.get_or_init(load).clone()
}

fn last_dl_error() -> String {
    // SAFETY: dlerror returns null or a NUL-terminated string owned by the C library.
    let message = unsafe { libc::dlerror() };
    if message.is_null() {
        "no reason given".into()
    } else {
        // SAFETY: not null, NUL-terminated, read before any other dl call.
        unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
    }
}

fn load() -> Result<(), String> {
    let version = MUJOCO_VERSION;
    // A file named by the user is the only one tried: loading another one instead would hide
    // the mistake.
    let names = match std::env::var(LIBRARY_ENV) {
        Ok(file) => vec![file],
        Err(_) => vec![SONAME.to_string()],
    };
    let mut failures = Vec::new();
    for name in &names {
        let c_name = CString::new(name.as_str()).map_err(|_| format!("{name}: a path with a NUL byte"))?;
        // Local first: a library that is not the right MuJoCo never enters the global scope.
        // SAFETY: a NUL-terminated name; the handle is checked for null.
        let handle = unsafe { libc::dlopen(c_name.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL) };
        if handle.is_null() {
            failures.push(last_dl_error());
            continue;
        }
        // SAFETY: a live handle and a NUL-terminated symbol name.
        let symbol = unsafe { libc::dlsym(handle, c"mj_version".as_ptr()) };
        if symbol.is_null() {
            return Err(format!("{name} is not a MuJoCo library (it has no mj_version)"));
        }
        // SAFETY: MuJoCo declares `int mj_version(void)`.
        let mj_version: extern "C" fn() -> std::os::raw::c_int = unsafe { std::mem::transmute(symbol) };
        let found = mj_version();
        let expected = mujoco_rs::mujoco_c::mjVERSION_HEADER;
        if u32::try_from(found).ok() != Some(expected) {
            return Err(format!(
                "{name} is MuJoCo version {found}; proving-ground needs MuJoCo {version} (version number {expected})"
            ));
        }
        // SAFETY: the library is already loaded (RTLD_NOLOAD); this only makes it global.
        let global = unsafe { libc::dlopen(c_name.as_ptr(), libc::RTLD_NOW | libc::RTLD_NOLOAD | libc::RTLD_GLOBAL) };
        if global.is_null() {
            return Err(format!("cannot make {name} visible to the program: {}", last_dl_error()));
        }
        // The handles stay open: MuJoCo stays loaded for the life of the process.
        return Ok(());
    }
    Err(format!(
        "this needs MuJoCo {version}, but {} could not be loaded ({}). Build from the repository \
         (`cargo build --release` fetches it into .mujoco/lib), or `pip install mujoco=={version}` and set \
         {LIBRARY_ENV} to the path of its {SONAME}",
        names.join(", "),
        failures.join("; ")
    ))
}

/// The MuJoCo version the project pins (`mujoco/PIN`) and was verified against.
pub const MUJOCO_VERSION: &str = "3.17.0";

/// Why MuJoCo cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MujocoError {
    /// The MuJoCo library could not be loaded.
    #[error("{message}")]
    Unavailable {
        /// What was tried and what to install.
        message: String,
    },
    /// The linked MuJoCo is not the version the project pins.
    #[error("linked MuJoCo is {found}, proving-ground was built and verified against {expected} (mujoco/PIN)")]
    Version {
        /// Version reported by the library.
        found: String,
        /// Version pinned.
        expected: &'static str,
    },
}

/// Loads MuJoCo if needed and checks that it is the pinned version (mujoco-rs panics on a
/// mismatch, so this comes before any model is loaded).
///
/// # Errors
/// [`MujocoError::Unavailable`] or [`MujocoError::Version`].
pub fn check_version() -> Result<(), MujocoError> {
    ensure().map_err(|message| MujocoError::Unavailable { message })?;
    // SAFETY: mj_versionString returns a pointer to a static NUL-terminated string.
    let found = unsafe { CStr::from_ptr(mujoco_rs::mujoco_c::mj_versionString()) }
        .to_string_lossy()
        .into_owned();
    if found != MUJOCO_VERSION {
        return Err(MujocoError::Version {
            found,
            expected: MUJOCO_VERSION,
        });
    }
    Ok(())
}
