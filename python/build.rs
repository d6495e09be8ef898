//! Link settings for the extension module, as proving-ground's build.rs gives its own binaries
//! (`cargo::rustc-link-arg` of a dependency does not reach its dependents): MuJoCo is loaded at
//! first use, its symbols bound lazily and found through the rpath to the repo's `.mujoco/lib`.
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
