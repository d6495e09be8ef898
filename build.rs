//! Puts the MuJoCo shared library where the linker and the binaries find it.
//!
//! mujoco-rs links `-lmujoco` from the directory named in `mujoco/mujoco.pc` (or from
//! `MUJOCO_DYNAMIC_LINK_DIR`). This script makes sure that library exists before anything links,
//! and embeds its directory as an rpath so that no `LD_LIBRARY_PATH` is needed at run time.
//!
//! Order, first that applies wins:
//! 1. `MUJOCO_DYNAMIC_LINK_DIR` is set: mujoco-rs links from there; we only add the rpath.
//! 2. `.mujoco/lib/libmujoco.so.<version>` exists with the pinned hash: reused.
//! 3. An importable Python `mujoco` of the pinned version: its library is copied (hash checked).
//! 4. The official wheel is fetched with `python3 -m pip download`, hash checked, and unpacked.
//!
//! Except with 1, the binaries do not depend on the library at start-up: it is loaded at first
//! use (see `sim/mujoco.rs`).
//!
//! Failures end the build with one message saying what to install or set.

use sha2::{Digest, Sha256};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

struct Pin {
    version: String,
    lib_sha256: String,
    wheel: String,
    wheel_sha256: String,
}

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let pin_path = manifest.join("mujoco/PIN");
    println!("cargo::rerun-if-changed={}", pin_path.display());
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");

    // `cargo::error` fails the build with just this message; exiting non-zero as well would make
    // cargo dump the script's whole output around it.
    if let Err(message) = run(&manifest, &pin_path) {
        println!("cargo::error={}", message.replace('\n', " "));
    }
}

fn run(manifest: &Path, pin_path: &Path) -> Result<(), String> {
    if let Ok(dir) = std::env::var("MUJOCO_DYNAMIC_LINK_DIR") {
        // mujoco-rs links the real library from there: a start-up dependency, not lazy.
        println!("cargo::rustc-link-arg=-Wl,-rpath,{dir}");
        let version = read_pin(pin_path, "x86_64").map(|p| p.version).unwrap_or_default();
        println!("cargo::rustc-env=MUJOCO_SONAME=libmujoco.so.{version}");
        return Ok(());
    }
    let arch = std::env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let pin = read_pin(pin_path, &arch)?;
    if os != "linux" || arch != "x86_64" {
        return Err(format!(
            "proving-ground fetches MuJoCo {} automatically only on x86_64 Linux (this is {arch} {os}); \
             install MuJoCo {} and set MUJOCO_DYNAMIC_LINK_DIR to the directory holding libmujoco",
            pin.version, pin.version
        ));
    }

    let lib_dir = manifest.join(".mujoco/lib");
    let lib_name = format!("libmujoco.so.{}", pin.version);
    let lib_path = lib_dir.join(&lib_name);
    println!("cargo::rerun-if-changed={}", lib_path.display());

    if !(lib_path.is_file() && sha256_file(&lib_path)? == pin.lib_sha256) {
        fs::create_dir_all(&lib_dir).map_err(|e| format!("cannot create {}: {e}", lib_dir.display()))?;
        match python_mujoco_lib(&pin.version, &lib_name) {
            Some(installed) => install_from(&installed, &lib_path, &pin)?,
            None => fetch_wheel(manifest, &lib_path, &lib_name, &pin)?,
        }
    }

    // MuJoCo is loaded at first use (sim/mujoco.rs), so a binary without it still runs
    // everything else. mujoco-rs links `-lmujoco` from this folder: an empty linker script of that
    // name satisfies it without a DT_NEEDED entry; the MuJoCo symbols stay undefined and are bound
    // lazily through the PLT, which needs `-C relro-level=partial` (.cargo/config.toml).
    lazy_flags_present()?;
    let link = lib_dir.join("libmujoco.so");
    let _ = fs::remove_file(&link);
    fs::write(
        &link,
        "/* MuJoCo is loaded at run time (sim/mujoco.rs); -lmujoco links nothing. */\n",
    )
    .map_err(|e| format!("cannot write {}: {e}", link.display()))?;
    println!("cargo::rustc-link-arg=-Wl,--unresolved-symbols=ignore-all");
    println!("cargo::rustc-link-arg=-Wl,-z,lazy");
    // dlopen of the soname searches the binary's RUNPATH.
    println!("cargo::rustc-link-arg=-Wl,-rpath,{}", lib_dir.display());
    println!("cargo::rustc-env=MUJOCO_SONAME={lib_name}");
    Ok(())
}

/// Without partial RELRO rustc calls foreign functions through GOT slots bound at start-up, and a
/// binary with unresolved MuJoCo symbols would not start. A `RUSTFLAGS` variable replaces the
/// flags of `.cargo/config.toml`, so say so instead of building such a binary.
fn lazy_flags_present() -> Result<(), String> {
    let flags = std::env::var("CARGO_ENCODED_RUSTFLAGS").unwrap_or_default();
    let flags: Vec<&str> = flags.split('\x1f').collect();
    let wanted = |f: &str| f == "relro-level=partial" || f == "relro-level=off";
    let found = flags.windows(2).any(|w| w[0] == "-C" && wanted(w[1])) || flags.iter().any(|f| f.strip_prefix("-C").is_some_and(wanted));
    if found {
        Ok(())
    } else {
        Err(
            "MuJoCo is loaded at first use and needs `-C relro-level=partial` in the rust flags (.cargo/config.toml sets it); \
             a RUSTFLAGS environment variable replaces that setting: add `-C relro-level=partial` to it"
                .into(),
        )
    }
}

fn read_pin(path: &Path, arch: &str) -> Result<Pin, String> {
    let text = fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let field = |key: &str| -> Result<String, String> {
        text.lines()
            .filter_map(|line| line.split_once('='))
            .find(|(k, _)| k.trim() == key)
            .map(|(_, v)| v.trim().to_string())
            .ok_or_else(|| format!("{}: missing `{key}`", path.display()))
    };
    let arch_key = |base: &str| format!("{base}_{}", if arch.is_empty() { "x86_64" } else { arch });
    Ok(Pin {
        version: field("version")?,
        lib_sha256: field(&arch_key("lib_sha256")).unwrap_or_default(),
        wheel: field(&arch_key("wheel")).unwrap_or_default(),
        wheel_sha256: field(&arch_key("wheel_sha256")).unwrap_or_default(),
    })
}

fn sha256_file(path: &Path) -> Result<String, String> {
    let bytes = fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    Ok(Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect())
}

/// The library of an importable Python `mujoco` of exactly the pinned version, if any.
fn python_mujoco_lib(version: &str, lib_name: &str) -> Option<PathBuf> {
    let out = Command::new("python3")
        .args([
            "-c",
            "import os, mujoco; print(mujoco.__version__); print(os.path.dirname(mujoco.__file__))",
        ])
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let mut lines = text.lines();
    let found_version = lines.next()?.trim();
    let dir = PathBuf::from(lines.next()?.trim());
    if found_version != version {
        println!("cargo::warning=ignoring Python mujoco {found_version}: proving-ground needs {version}");
        return None;
    }
    let lib = dir.join(lib_name);
    lib.is_file().then_some(lib)
}

fn install_from(source: &Path, dest: &Path, pin: &Pin) -> Result<(), String> {
    let hash = sha256_file(source)?;
    if hash != pin.lib_sha256 {
        return Err(format!(
            "{} has sha256 {hash}, not the pinned {} (mujoco/PIN); reinstall mujoco=={} or set MUJOCO_DYNAMIC_LINK_DIR",
            source.display(),
            pin.lib_sha256,
            pin.version
        ));
    }
    fs::copy(source, dest).map_err(|e| format!("cannot copy {} to {}: {e}", source.display(), dest.display()))?;
    Ok(())
}

fn fetch_wheel(manifest: &Path, dest: &Path, lib_name: &str, pin: &Pin) -> Result<(), String> {
    let download = manifest.join(".mujoco/download");
    let wheel = download.join(&pin.wheel);
    let offline_help = format!(
        "MuJoCo {v} is needed and could not be fetched. Either let `python3 -m pip download mujoco=={v}` reach PyPI, \
         or `pip install mujoco=={v}`, or set MUJOCO_DYNAMIC_LINK_DIR to a directory holding libmujoco.so (MuJoCo {v})",
        v = pin.version
    );
    if !wheel.is_file() {
        let output = Command::new("python3")
            .args(["-m", "pip", "download", "--quiet", "--no-deps", "--only-binary=:all:"])
            .args(["--platform", "manylinux_2_28_x86_64", "--python-version", "3.11"])
            .args(["--implementation", "cp", "--abi", "cp311", "--dest"])
            .arg(&download)
            .arg(format!("mujoco=={}", pin.version))
            .output();
        match output {
            Ok(out) if out.status.success() && wheel.is_file() => {}
            Ok(out) => {
                let said = String::from_utf8_lossy(&out.stderr);
                let last = said.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("no message");
                return Err(format!("{offline_help} (pip said: {})", last.trim()));
            }
            Err(e) => return Err(format!("cannot run python3 ({e}). {offline_help}")),
        }
    }
    let hash = sha256_file(&wheel)?;
    if hash != pin.wheel_sha256 {
        let _ = fs::remove_file(&wheel);
        return Err(format!(
            "{} has sha256 {hash}, not the pinned {} (mujoco/PIN); removed it, build again to refetch",
            wheel.display(),
            pin.wheel_sha256
        ));
    }
    // A wheel is a zip file; python3 is already required for pip, so its zipfile does the unpacking.
    let script = "import sys, zipfile\nz = zipfile.ZipFile(sys.argv[1])\nopen(sys.argv[3], 'wb').write(z.read('mujoco/' + sys.argv[2]))";
    let status = Command::new("python3")
        .args(["-c", script])
        .arg(&wheel)
        .arg(lib_name)
        .arg(dest)
        .status();
    if !matches!(status, Ok(s) if s.success()) {
        return Err(format!("cannot unpack {lib_name} from {}", wheel.display()));
    }
    let hash = sha256_file(dest)?;
    if hash != pin.lib_sha256 {
        let _ = fs::remove_file(dest);
        return Err(format!("{} has sha256 {hash}, not the pinned {}", dest.display(), pin.lib_sha256));
    }
    Ok(())
}
