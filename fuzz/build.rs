//! The fuzz binaries link libmujoco through proving-ground, but the rpath that proving-ground's
//! build script sets reaches only proving-ground's own binaries (`cargo::rustc-link-arg` does not
//! propagate to dependents). Set the same rpath here so no `LD_LIBRARY_PATH` is needed.
fn main() {
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    let dir = match std::env::var("MUJOCO_DYNAMIC_LINK_DIR") {
        Ok(dir) => dir,
        Err(_) => {
            let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
            format!("{manifest}/../.mujoco/lib")
        }
    };
    println!("cargo::rustc-link-arg=-Wl,-rpath,{dir}");
}
