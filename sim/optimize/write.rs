//! A design back to the design JSON that `design::parse` reads to the same design (every f64
//! written in its shortest round-trip form).

use crate::design::{Design, DesignMode};
use serde_json::{json, Value};

/// The design file of `design`, pretty-printed with a trailing newline; `description` is written
/// as the file's `description`.
pub fn design_json(design: &Design, description: &str) -> String {
    let mut file = serde_json::Map::new();
    file.insert("name".into(), json!(design.name));
    file.insert("mode".into(), json!(design.mode.name()));
    file.insert("description".into(), json!(description));
    match design.mode {
        DesignMode::Free | DesignMode::Economic => {
            let joints: Vec<Value> = design
                .joints
                .iter()
                .map(|j| {
                    let mut row = json!({
                        "d": j.d,
                        "a": j.a,
                        "alpha": j.alpha,
                        "limits": j.limits,
                        "max_velocity": j.max_velocity,
                    });
                    if let Some(torque) = j.rated_torque {
                        row["rated_torque"] = json!(torque);
                    }
                    row
                })
                .collect();
            file.insert("joints".into(), Value::Array(joints));
        }
        DesignMode::Modular => {
            file.insert("modules".into(), json!(design.modules));
        }
        DesignMode::Preset => {
            file.insert("preset".into(), json!(design.preset));
        }
    }
    file.insert("base".into(), json!(design.base));
    file.insert("tool".into(), json!(design.tool));
    let mut text = serde_json::to_string_pretty(&Value::Object(file)).expect("a JSON value always serializes");
    text.push('\n');
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn every_shipped_design_reads_back_to_the_same_design() {
        for entry in std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("designs")).expect("designs/") {
            let path = entry.expect("entry").path();
            if path.extension().is_none_or(|e| e != "json") {
                continue;
            }
            let design = crate::design::load(&path).expect("a shipped design loads");
            let text = design_json(&design, "round trip");
            let back = crate::design::parse(&text, &path).unwrap_or_else(|e| panic!("{}: {e}\n{text}", path.display()));
            assert_eq!(back.joints, design.joints, "{}", path.display());
            assert_eq!(
                (back.name.as_str(), back.mode),
                (design.name.as_str(), design.mode),
                "{}",
                path.display()
            );
            assert_eq!((back.base, back.tool), (design.base, design.tool), "{}", path.display());
        }
    }
}
