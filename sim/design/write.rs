//! A design back to the design file that `design::parse` reads to the same design, written from
//! the schema's own serde types in the layout of [`crate::json`].

use super::{Design, DesignMode, DhFile, DhJointFile, ModularFile, PresetFile};

/// The design file of `design`, with a trailing newline; `description` is written as the file's
/// `description`. Every joint's limits and speed are written (a file without them would read
/// the catalog's defaults), so the text reads back to the same joints.
pub fn to_json(design: &Design, description: &str) -> String {
    let name = Some(design.name.clone());
    let mode = design.mode.name().to_string();
    let description = Some(description.to_string());
    let (base, tool) = (Some(design.base), Some(design.tool));
    let text = match (design.mode, &design.modules, design.preset) {
        (DesignMode::Modular, Some(modules), _) => crate::json::to_text(&ModularFile {
            name,
            mode,
            description,
            modules: modules.clone(),
            base,
            tool,
        }),
        (DesignMode::Preset, _, Some(preset)) => crate::json::to_text(&PresetFile {
            name,
            mode,
            description,
            preset,
            base,
            tool,
        }),
        // A modular or preset design without its modules or preset is still its DH rows.
        _ => crate::json::to_text(&DhFile {
            name,
            mode: if design.mode == DesignMode::Economic { "economic" } else { "free" }.to_string(),
            description,
            joints: design
                .joints
                .iter()
                .map(|j| DhJointFile {
                    d: j.d,
                    a: j.a,
                    alpha: j.alpha,
                    limits: Some(j.limits),
                    max_velocity: Some(j.max_velocity),
                    rated_torque: j.rated_torque,
                })
                .collect(),
            base,
            tool,
        }),
    };
    // A validated design holds only finite numbers, all that serde_json could refuse.
    text.expect("a design file always serialises")
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
            let text = to_json(&design, "round trip");
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
