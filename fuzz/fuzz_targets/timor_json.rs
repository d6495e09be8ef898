//! Timor files: a module set and an assembly of it (the input split at its first NUL byte),
//! assembled into a model; and the whole input as a Timor / CoBRA task.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let _ = proving_ground::scenario::parse_timor_task(text, Path::new("fuzz/task.json"));
    if let Some((set, assembly)) = text.split_once('\0') {
        let _ = proving_ground::model::from_timor_text(set, assembly, Path::new("fuzz/assembly.json"));
    }
});
