//! Design files (JSON): parsing, and for a design that parses, building its model.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(design) = proving_ground::design::parse(text, Path::new("fuzz.json")) {
        let _ = proving_ground::model::from_design(&design);
    }
});
