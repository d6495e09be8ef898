//! STL mesh files (the format is taken from the file name's extension).
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = proving_ground::model::load_mesh_bytes("fuzz.stl", data, Path::new("fuzz.stl"), [1.0, 1.0, 1.0]);
});
