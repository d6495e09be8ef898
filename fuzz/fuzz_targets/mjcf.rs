//! MJCF files, loaded by MuJoCo from a scratch file (MuJoCo reads files only). MuJoCo may print
//! its own errors to stderr; an `Err` is fine.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = proving_ground_fuzz::scratch_file("fuzz.xml", data);
    let _ = proving_ground::model::from_mjcf(&path);
});
