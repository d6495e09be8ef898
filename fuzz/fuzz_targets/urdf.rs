//! URDF text. The path is in a folder that does not exist, so mesh references do not resolve
//! next to it (`package://` URIs are still looked up under its ancestors and ROS_PACKAGE_PATH).
#![no_main]

use libfuzzer_sys::fuzz_target;
use proving_ground::model::{from_urdf_str, UrdfOptions};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let _ = from_urdf_str(text, Path::new("/nonexistent-fuzz/robot.urdf"), &UrdfOptions::default());
});
