//! Helpers shared by the integration tests.
#![allow(dead_code, unreachable_pub)]

use proving_ground::model::Model;
use proving_ground::pipeline::{self, LoadOptions};
use std::path::{Path, PathBuf};

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The real-world URDF shipped in designs/ (Franka Panda, STL collision meshes).
pub fn panda_urdf() -> PathBuf {
    repo().join("designs/urdf/example-robot-data/robots/panda_description/urdf/panda.urdf")
}

/// Every design JSON in designs/, sorted.
pub fn design_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(repo().join("designs"))
        .expect("designs/ exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    files
}

/// Every shipped robot as `(id, model)`: the designs and the Panda URDF (chain to panda_hand).
pub fn shipped_models() -> Vec<(String, Model)> {
    let mut models: Vec<(String, Model)> = design_files()
        .iter()
        .map(|path| {
            let model = pipeline::load_model(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            (stem(path), model)
        })
        .collect();
    let opts = LoadOptions {
        tip_link: Some("panda_hand".into()),
        ..LoadOptions::default()
    };
    models.push((
        "panda".into(),
        pipeline::load_model(&panda_urdf(), &opts).expect("the Panda URDF loads"),
    ));
    models
}

/// File stem as a string.
pub fn stem(path: &Path) -> String {
    path.file_stem().expect("file has a stem").to_string_lossy().into_owned()
}

/// A fixture under tests/fixtures/.
pub fn fixture(name: &str) -> PathBuf {
    repo().join("tests/fixtures").join(name)
}
