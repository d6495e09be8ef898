//! DAE mesh files (the format is taken from the file name's extension).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // load_mesh_bytes does not exist yet: load_mesh reads the same bytes from a scratch file.
    let path = proving_ground_fuzz::scratch_file("fuzz.dae", data);
    let _ = proving_ground::model::load_mesh("fuzz.dae", &path, [1.0, 1.0, 1.0]);
});
