//! Scenario -> JSON text with deterministic bytes, the inverse of `file::parse`.
//!
//! Keys come in a fixed order (the schema's order, provenance parameters sorted), numbers in
//! serde_json's shortest round-trip form (ryu), objects indented by two spaces, arrays of numbers
//! on one line, and the text ends with a newline. Nothing depends on hash order or on serde_json's
//! `preserve_order` feature.

use super::file::{default_goal_name, default_obstacle_name};
use super::{Scenario, ScenarioError, Tolerance};
use crate::model::Shape;
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use std::path::Path;

/// One JSON value under construction: scalars already formatted.
enum Node {
    Scalar(String),
    Array(Vec<Node>),
    Object(Vec<(String, Node)>),
}

impl Node {
    fn number(value: f64) -> Node {
        // serde_json writes every finite f64 in its shortest round-trip form; a validated or
        // generated scenario holds only finite numbers.
        Node::Scalar(serde_json::to_string(&value).expect("an f64 always serialises"))
    }

    fn string(value: &str) -> Node {
        Node::Scalar(serde_json::to_string(value).expect("a string always serialises"))
    }

    fn numbers(values: &[f64]) -> Node {
        Node::Array(values.iter().map(|&v| Node::number(v)).collect())
    }

    fn from_value(value: &serde_json::Value) -> Node {
        match value {
            serde_json::Value::Array(items) => Node::Array(items.iter().map(Node::from_value).collect()),
            serde_json::Value::Object(map) => {
                let mut entries: Vec<(String, Node)> = map.iter().map(|(k, v)| (k.clone(), Node::from_value(v))).collect();
                entries.sort_by(|a, b| a.0.cmp(&b.0));
                Node::Object(entries)
            }
            scalar => Node::Scalar(scalar.to_string()),
        }
    }

    fn write(&self, out: &mut String, indent: usize) {
        match self {
            Node::Scalar(text) => out.push_str(text),
            Node::Array(items) if items.is_empty() => out.push_str("[]"),
            Node::Array(items) if items.iter().all(|i| matches!(i, Node::Scalar(_))) => {
                out.push('[');
                for (i, item) in items.iter().enumerate() {
                    if i > 0 {
                        out.push_str(", ");
                    }
                    item.write(out, indent);
                }
                out.push(']');
            }
            Node::Array(items) => {
                out.push('[');
                for (i, item) in items.iter().enumerate() {
                    out.push_str(if i > 0 { ",\n" } else { "\n" });
                    push_indent(out, indent + 1);
                    item.write(out, indent + 1);
                }
                out.push('\n');
                push_indent(out, indent);
                out.push(']');
            }
            Node::Object(entries) if entries.is_empty() => out.push_str("{}"),
            Node::Object(entries) => {
                out.push('{');
                for (i, (key, value)) in entries.iter().enumerate() {
                    out.push_str(if i > 0 { ",\n" } else { "\n" });
                    push_indent(out, indent + 1);
                    out.push_str(&serde_json::to_string(key).expect("a string always serialises"));
                    out.push_str(": ");
                    value.write(out, indent + 1);
                }
                out.push('\n');
                push_indent(out, indent);
                out.push('}');
            }
        }
    }
}

fn push_indent(out: &mut String, level: usize) {
    for _ in 0..level {
        out.push_str("  ");
    }
}

fn quaternion(rotation: &UnitQuaternion<f64>) -> Node {
    Node::numbers(&crate::frames::wxyz(rotation))
}

fn vector(v: &Vector3<f64>) -> Node {
    Node::numbers(&crate::frames::xyz(v))
}

fn pose_entries(pose: &Isometry3<f64>, entries: &mut Vec<(String, Node)>, always_rotation: bool) {
    entries.push(("position".into(), vector(&pose.translation.vector)));
    if always_rotation || pose.rotation != UnitQuaternion::identity() {
        entries.push(("quaternion".into(), quaternion(&pose.rotation)));
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
    let mut root: Vec<(String, Node)> = vec![("name".into(), Node::string(&scenario.name))];
    if let Some(provenance) = &scenario.provenance {
        let parameters = provenance
            .parameters
            .iter()
            .map(|(k, v)| (k.clone(), Node::from_value(v)))
            .collect();
        root.push((
            "provenance".into(),
            Node::Object(vec![
                ("generator".into(), Node::string(&provenance.generator)),
                ("seed".into(), Node::Scalar(provenance.seed.to_string())),
                ("parameters".into(), Node::Object(parameters)),
            ]),
        ));
    }
    let mut base = Vec::new();
    pose_entries(&scenario.world_from_base, &mut base, true);
    root.push(("base".into(), Node::Object(base)));
    if let Some(floor) = &scenario.floor {
        root.push(("floor".into(), Node::Object(vec![("height".into(), Node::number(floor.height))])));
    }
    let tolerance = common_tolerance(scenario);
    root.push(("tolerance".into(), Node::string(tolerance.name())));
    if let Some(home) = &scenario.home {
        root.push(("home".into(), Node::numbers(home)));
    }

    let obstacles = scenario
        .obstacles
        .iter()
        .enumerate()
        .map(|(index, obstacle)| {
            let mut entries = Vec::new();
            if obstacle.name != default_obstacle_name(index) {
                entries.push(("name".into(), Node::string(&obstacle.name)));
            }
            entries.push(("type".into(), Node::string(obstacle.shape.kind())));
            pose_entries(&obstacle.world_from_shape, &mut entries, false);
            match &obstacle.shape {
                Shape::Sphere { radius } => entries.push(("radius".into(), Node::number(*radius))),
                Shape::Capsule { radius, length } | Shape::Cylinder { radius, length } => {
                    entries.push(("radius".into(), Node::number(*radius)));
                    entries.push(("length".into(), Node::number(*length)));
                }
                // Doubling is exact in binary floating point, so the halves read back unchanged.
                Shape::Box { half_extents } => entries.push(("size".into(), Node::numbers(&half_extents.map(|h| 2.0 * h)))),
                Shape::Mesh(mesh) => {
                    entries.push(("file".into(), Node::string(&mesh.uri)));
                    if mesh.scale != [1.0; 3] {
                        entries.push(("scale".into(), Node::numbers(&mesh.scale)));
                    }
                }
            }
            Node::Object(entries)
        })
        .collect();
    root.push(("obstacles".into(), Node::Array(obstacles)));

    let goals = scenario
        .goals
        .iter()
        .enumerate()
        .map(|(index, goal)| {
            let mut entries = Vec::new();
            if goal.name != default_goal_name(index) {
                entries.push(("name".into(), Node::string(&goal.name)));
            }
            entries.push(("position".into(), vector(&goal.position)));
            entries.push(("quaternion".into(), quaternion(&goal.rotation)));
            if goal.tolerance != tolerance {
                entries.push(("tolerance".into(), Node::string(goal.tolerance.name())));
            }
            Node::Object(entries)
        })
        .collect();
    root.push(("goals".into(), Node::Array(goals)));

    let mut out = String::new();
    Node::Object(root).write(&mut out, 0);
    out.push('\n');
    out
}

/// Writes [`to_json`] of `scenario` to `path`, creating missing parent folders. An existing file
/// is replaced only when `overwrite` is true.
///
/// # Errors
/// [`ScenarioError::Write`] when the file exists (and `overwrite` is false) or cannot be written.
pub fn save(scenario: &Scenario, path: &Path, overwrite: bool) -> Result<(), ScenarioError> {
    let write_error = |source: std::io::Error| ScenarioError::Write {
        path: path.to_path_buf(),
        source,
    };
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(write_error)?;
    }
    crate::files::write_atomic(path, to_json(scenario).as_bytes(), overwrite).map_err(|error| match error {
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
