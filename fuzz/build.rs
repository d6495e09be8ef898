//! Link settings for the fuzz binaries, mirroring the ones proving-ground's build.rs gives its own
//! binaries: `cargo::rustc-link-arg` of a dependency does not reach its dependents.
//!
//! MuJoCo is loaded at first use (sim/mujoco.rs): its symbols are left undefined and bound
//! lazily (with `-C relro-level=partial`, which fuzz/run adds to RUSTFLAGS, because cargo-fuzz's
//! RUSTFLAGS replace the flags of .cargo/config.toml), and the library is found through the rpath.
fn main() {
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    let dir = match std::env::var("MUJOCO_DYNAMIC_LINK_DIR") {
        Ok(dir) => dir,
        Err(_) => {
            let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
            println!("cargo::rustc-link-arg=-Wl,--unresolved-symbols=ignore-all");
            println!("cargo::rustc-link-arg=-Wl,-z,lazy");
            format!("{manifest}/../.mujoco/lib")
        }
    };
    println!("cargo::rustc-link-arg=-Wl,-rpath,{dir}");
}
