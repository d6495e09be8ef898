//! Scenario -> JSON text, the inverse of `file::parse`, written from the serde types that read
//! it: keys in the schema's order (provenance parameters sorted), the layout of [`crate::json`].

use super::file::{
    default_goal_name, default_obstacle_name, FloorFile, GoalFile, ObstacleFile, PoseFile, Scale, ScenarioFile, TaskToleranceFile,
};
use super::{Scenario, ScenarioError, Tolerance};
use crate::model::Shape;
use nalgebra::{Isometry3, UnitQuaternion};
use std::path::Path;

/// `pose` in the file schema; the quaternion is left out at identity unless `always_rotation`.
fn pose_file(pose: &Isometry3<f64>, always_rotation: bool) -> PoseFile {
    PoseFile {
        position: crate::frames::xyz(&pose.translation.vector),
        rpy: None,
        quaternion: (always_rotation || pose.rotation != UnitQuaternion::identity()).then(|| crate::frames::wxyz(&pose.rotation)),
    }
}

/// The tolerance most goals use (ties go to the stricter one): written once as the scenario
/// default, so only the goals that differ carry their own.
fn common_tolerance(scenario: &Scenario) -> Tolerance {
    let all = [Tolerance::Pose, Tolerance::ZSymmetric, Tolerance::Position];
    let count = |t: Tolerance| scenario.goals.iter().filter(|g| g.tolerance == t).count();
    let mut best = Tolerance::Pose;
    for t in all {
        if count(t) > count(best) {
            best = t;
        }
    }
    best
}

/// The scenario as JSON text in the file schema, with deterministic bytes: `parse` of the text
/// (with the same path, for mesh files) gives back the same scenario, bit for bit.
///
/// Goal orientations are written as `quaternion` `[w, x, y, z]`, obstacle orientations too (left
/// out when identity); names equal to the default (`goal 3`, `obstacle 1`) are left out.
pub fn to_json(scenario: &Scenario) -> String {
    let tolerance = common_tolerance(scenario);
    let obstacles = scenario
        .obstacles
        .iter()
        .enumerate()
        .map(|(index, obstacle)| {
            let pose = pose_file(&obstacle.world_from_shape, false);
            let mut file = ObstacleFile {
                name: (obstacle.name != default_obstacle_name(index)).then(|| obstacle.name.clone()),
                kind: obstacle.shape.kind().to_string(),
                position: pose.position,
                quaternion: pose.quaternion,
                rpy: None,
                radius: None,
                length: None,
                size: None,
                file: None,
                scale: None,
            };
            match &obstacle.shape {
                Shape::Sphere { radius } => file.radius = Some(*radius),
                Shape::Capsule { radius, length } | Shape::Cylinder { radius, length } => {
                    file.radius = Some(*radius);
                    file.length = Some(*length);
                }
                // Doubling is exact in binary floating point, so the halves read back unchanged.
                Shape::Box { half_extents } => file.size = Some(half_extents.map(|h| 2.0 * h)),
                Shape::Mesh(mesh) => {
                    file.file = Some(mesh.uri.clone());
                    file.scale = (mesh.scale != [1.0; 3]).then_some(Scale::PerAxis(mesh.scale));
                }
            }
            file
        })
        .collect();
    let goals = scenario
        .goals
        .iter()
        .enumerate()
        .map(|(index, goal)| GoalFile {
            name: (goal.name != default_goal_name(index)).then(|| goal.name.clone()),
            position: crate::frames::xyz(&goal.position),
            quaternion: Some(crate::frames::wxyz(&goal.rotation)),
            rotation: None,
            tolerance: (goal.tolerance != tolerance).then_some(goal.tolerance),
            task_tolerance: goal.task.as_ref().map(TaskToleranceFile::of),
        })
        .collect();
    let file = ScenarioFile {
        name: Some(scenario.name.clone()),
        provenance: scenario.provenance.clone(),
        base: Some(pose_file(&scenario.world_from_base, true)),
        floor: scenario.floor.as_ref().map(|floor| FloorFile { height: floor.height }),
        tolerance: Some(tolerance),
        home: scenario.home.clone(),
        obstacles,
        goals,
    };
    // A validated or generated scenario holds only finite numbers and string keys, all that
    // serde_json could refuse.
    crate::json::to_text(&file).expect("a scenario file always serialises")
}

/// Writes [`to_json`] of `scenario` to `path`, creating missing parent folders. An existing file
/// is replaced only when `overwrite` is true.
///
/// # Errors
/// [`ScenarioError::Write`] when the file exists (and `overwrite` is false) or cannot be written.
pub fn save(scenario: &Scenario, path: &Path, overwrite: bool) -> Result<(), ScenarioError> {
    write_file(path, to_json(scenario).as_bytes(), overwrite)
}

/// Writes a scenario's text to `path`, creating missing parent folders, replacing a file only
/// when `overwrite` is true and never one this run read.
pub(super) fn write_file(path: &Path, bytes: &[u8], overwrite: bool) -> Result<(), ScenarioError> {
    let write_error = |source: std::io::Error| ScenarioError::Write {
        path: path.to_path_buf(),
        source,
    };
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(write_error)?;
    }
    crate::files::write_atomic(path, bytes, overwrite).map_err(|error| match error {
        crate::files::WriteError::Exists => write_error(std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            "the file exists; pass --force to replace it",
        )),
        crate::files::WriteError::Input => write_error(std::io::Error::other("it is an input of this run")),
        crate::files::WriteError::Io(e) => write_error(e),
    })
}

#[cfg(test)]
mod tests {
    use super::super::parse;
    use super::*;

    #[test]
    fn round_trip_is_exact_and_layout_is_fixed() {
        let text = r#"{"name": "t", "provenance": {"generator": "hand", "seed": 7, "parameters": {"b": [1, 2.5], "a": {"y": 1, "x": "s"}}},
            "base": {"position": [0.1, 0, 0], "rpy": [0.1, 0.2, 0.3]}, "floor": {"height": -0.1}, "home": [0, 0.5],
            "obstacles": [{"type": "box", "position": [1, 0, 0], "size": [0.1, 0.2, 0.3], "rpy": [0, 0, 1]},
                          {"name": "ball", "type": "sphere", "position": [0, 1, 0], "radius": 0.1}],
            "goals": [{"position": [0.3, 0.1, 0.2], "rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]], "tolerance": "position"},
                      {"name": "b", "position": [0.3, 0.1, 0.2], "quaternion": [0.6, 0.8, 0, 0]}]}"#;
        let first = parse(text, Path::new("t.json")).expect("valid");
        let json = to_json(&first);
        let second = parse(&json, Path::new("t.json")).expect("round trip parses");
        assert_eq!(to_json(&second), json);
        assert_eq!(second.world_from_base, first.world_from_base);
        assert_eq!(second.goals[0].rotation, first.goals[0].rotation);
        assert!(json.ends_with("}\n"), "{json}");
        assert!(json.contains("\n  \"floor\": {\n    \"height\": -0.1\n  },\n"), "{json}");
        assert!(
            json.contains("\"parameters\": {\n      \"a\": {\n        \"x\": \"s\",\n        \"y\": 1\n      },\n      \"b\": [1, 2.5]\n"),
            "{json}"
        );
        assert!(
            json.contains("\"size\": [0.1, 0.2, 0.3]") && json.contains("\"tolerance\": \"position\""),
            "{json}"
        );
        assert!(!json.contains("obstacle 0") && json.contains("\"name\": \"ball\""), "{json}");
    }
}
