//! Scenario files: the JSON schema and its validation (`load`, `parse`). Writing is in `write.rs`.

use super::{Floor, Goal, Obstacle, Provenance, Scenario, ScenarioError, TaskTolerance, Tolerance, TolerancePart};
use crate::limits;
use crate::model::{load_mesh, Shape};
use nalgebra::{Isometry3, Matrix3, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// How far a given quaternion's norm may be from 1, and how far `R^T R` of a given rotation
/// matrix may be from the identity (largest absolute entry). 1e-6 accepts numbers written with 7
/// significant digits and rejects typos.
pub const ORIENTATION_TOLERANCE: f64 = 1e-6;

/// A quaternion whose norm is this close to 1 is kept bit for bit instead of being divided by its
/// norm, so that `parse(to_json(s))` gives back exactly `s`: a normalised quaternion is unit only
/// to within a few units in the last place, and dividing again could change its last bits.
const UNIT_NORM_ROUNDING: f64 = 4.0 * f64::EPSILON;

/// The obstacle types a file may name, as written.
const OBSTACLE_TYPES: &str = "sphere, capsule, box, cylinder, mesh";

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ScenarioFile {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) name: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) provenance: Option<Provenance>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) base: Option<PoseFile>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) floor: Option<FloorFile>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) tolerance: Option<Tolerance>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) home: Option<Vec<f64>>,
    #[serde(default)]
    pub(super) obstacles: Vec<ObstacleFile>,
    pub(super) goals: Vec<GoalFile>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PoseFile {
    #[serde(default)]
    pub(super) position: [f64; 3],
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) rpy: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) quaternion: Option<[f64; 4]>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FloorFile {
    pub(super) height: f64,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ObstacleFile {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) name: Option<String>,
    #[serde(rename = "type")]
    pub(super) kind: String,
    pub(super) position: [f64; 3],
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) quaternion: Option<[f64; 4]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) rpy: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) radius: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) length: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) size: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) file: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) scale: Option<Scale>,
}

/// A mesh scale: one number for every axis, or one per axis.
#[derive(Deserialize, Serialize)]
#[serde(untagged)]
pub(super) enum Scale {
    Uniform(f64),
    PerAxis([f64; 3]),
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct GoalFile {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) name: Option<String>,
    pub(super) position: [f64; 3],
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) quaternion: Option<[f64; 4]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) rotation: Option<[[f64; 3]; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) tolerance: Option<Tolerance>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) task_tolerance: Option<TaskToleranceFile>,
}

/// A goal's own tolerance ([`TaskTolerance`]); a missing bound is unbounded.
#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TaskToleranceFile {
    pub(super) parts: Vec<TolerancePart>,
    pub(super) inner_m: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) inner_rad: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) outer_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) outer_rad: Option<f64>,
}

impl TaskToleranceFile {
    pub(super) fn of(task: &TaskTolerance) -> Self {
        let finite = |v: f64| v.is_finite().then_some(v);
        TaskToleranceFile {
            parts: task.parts.clone(),
            inner_m: task.inner_m,
            inner_rad: finite(task.inner_rad),
            outer_m: finite(task.outer_m),
            outer_rad: finite(task.outer_rad),
        }
    }

    /// The tolerance, or why the numbers are not one: each bound non-negative, the inner ball
    /// within the outer.
    fn checked(&self) -> Result<TaskTolerance, String> {
        let task = TaskTolerance {
            parts: self.parts.clone(),
            inner_m: self.inner_m,
            inner_rad: self.inner_rad.unwrap_or(f64::INFINITY),
            outer_m: self.outer_m.unwrap_or(f64::INFINITY),
            outer_rad: self.outer_rad.unwrap_or(f64::INFINITY),
        };
        let ordered = |inner: f64, outer: f64| inner >= 0.0 && inner <= outer && !inner.is_nan() && !outer.is_nan();
        if ordered(task.inner_m, task.outer_m) && ordered(task.inner_rad, task.outer_rad) && task.inner_m.is_finite() {
            Ok(task)
        } else {
            Err(format!(
                "inner_m {}, outer_m {:?}, inner_rad {:?}, outer_rad {:?}: expected 0 <= inner <= outer (a missing outer bound is unbounded)",
                self.inner_m, self.outer_m, self.inner_rad, self.outer_rad
            ))
        }
    }
}

/// Reads and validates a scenario file.
///
/// # Errors
/// [`ScenarioError`] naming the file and the field: unreadable file, malformed JSON (with line
/// and column), unknown fields or obstacle types, non-finite or non-positive sizes, quaternions
/// that are not unit, rotation matrices that are not rotations, both or neither goal orientation,
/// missing or unreadable mesh files, an empty goal list.
pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
    let text = crate::files::read_text(path, limits::MAX_TEXT_BYTES).map_err(|source| ScenarioError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text, path)
}

/// Validates a scenario given as JSON text. `path` names the file in messages, gives the default
/// name (its stem) and the folder mesh files are relative to.
///
/// # Errors
/// As [`load`].
pub fn parse(text: &str, path: &Path) -> Result<Scenario, ScenarioError> {
    if super::timor::is_timor_task(text) {
        return super::timor::parse_timor_task(text, path);
    }
    let file: ScenarioFile = serde_json::from_str(text).map_err(|e| ScenarioError::Parse {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let check = Checker { path };

    let name = match file.name {
        Some(name) if name.trim().is_empty() => return Err(check.invalid("name", "is empty".into())),
        Some(name) => name,
        None => path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scenario".into()),
    };
    let world_from_base = match &file.base {
        Some(base) => check.pose("base", base.position, base.quaternion, base.rpy)?,
        None => Isometry3::identity(),
    };
    let floor = match file.floor {
        Some(floor) => Some(Floor {
            height: check.finite("floor.height", floor.height)?,
        }),
        None => None,
    };
    if let Some(home) = &file.home {
        for (index, &value) in home.iter().enumerate() {
            check.finite(&format!("home[{index}]"), value)?;
        }
    }

    for (field, count, limit) in [
        ("obstacles", file.obstacles.len(), limits::MAX_OBSTACLES),
        ("goals", file.goals.len(), limits::MAX_GOALS),
    ] {
        if count > limit {
            return Err(check.invalid(field, format!("has {count} entries; the limit is {limit}")));
        }
    }
    let mut obstacles = Vec::with_capacity(file.obstacles.len());
    for (index, obstacle) in file.obstacles.iter().enumerate() {
        let obstacle = check.obstacle(index, obstacle)?;
        // Reports, engines and exclusions name obstacles: a name must say which one.
        if obstacle.name == "floor" || obstacles.iter().any(|o: &Obstacle| o.name == obstacle.name) {
            return Err(check.invalid(
                &format!("obstacles[{index}].name"),
                format!(
                    "`{}` is already the name of {}; obstacle names must be unique",
                    obstacle.name,
                    if obstacle.name == "floor" {
                        "the floor"
                    } else {
                        "another obstacle"
                    }
                ),
            ));
        }
        obstacles.push(obstacle);
    }

    if file.goals.is_empty() {
        return Err(check.invalid("goals", "is empty; a scenario needs at least one goal".into()));
    }
    let default_tolerance = file.tolerance.unwrap_or(Tolerance::Pose);
    let mut goals = Vec::with_capacity(file.goals.len());
    for (index, goal) in file.goals.iter().enumerate() {
        let field = format!("goals[{index}]");
        let position = check.position(&format!("{field}.position"), goal.position)?;
        let rotation = match (goal.quaternion, goal.rotation) {
            (Some(q), None) => check.quaternion(&format!("{field}.quaternion"), q)?,
            (None, Some(r)) => check.rotation_matrix(&format!("{field}.rotation"), r)?,
            (Some(_), Some(_)) => {
                return Err(check.invalid(
                    &field,
                    "gives both `quaternion` and `rotation`; give exactly one orientation".into(),
                ))
            }
            (None, None) => {
                return Err(check.invalid(
                    &field,
                    "gives neither `quaternion` nor `rotation`; give exactly one orientation".into(),
                ))
            }
        };
        goals.push(Goal {
            name: check.name(&field, goal.name.as_deref(), || default_goal_name(index))?,
            position,
            rotation,
            tolerance: goal.tolerance.unwrap_or(default_tolerance),
            task: match &goal.task_tolerance {
                None => None,
                Some(task) => Some(task.checked().map_err(|m| check.invalid(&format!("{field}.task_tolerance"), m))?),
            },
        });
    }

    Ok(Scenario {
        name,
        world_from_base,
        floor,
        obstacles,
        goals,
        home: file.home,
        provenance: file.provenance,
        notes: Vec::new(),
    })
}

/// The name a goal gets when the file gives none.
pub(crate) fn default_goal_name(index: usize) -> String {
    format!("goal {index}")
}

/// The name an obstacle gets when the file gives none.
pub(crate) fn default_obstacle_name(index: usize) -> String {
    format!("obstacle {index}")
}

/// A number for a message: plain when short, scientific when huge.
fn short(value: f64) -> String {
    if value.abs() >= 1e6 {
        format!("{value:e}")
    } else {
        format!("{value}")
    }
}

/// Validation helpers that know the file they report about.
struct Checker<'a> {
    path: &'a Path,
}

impl Checker<'_> {
    fn invalid(&self, field: &str, message: String) -> ScenarioError {
        ScenarioError::Invalid {
            path: self.path.to_path_buf(),
            field: field.to_string(),
            message,
        }
    }

    /// A finite number within +-[`limits::MAX_LENGTH_M`] (a height, a home joint position).
    fn finite(&self, field: &str, value: f64) -> Result<f64, ScenarioError> {
        if !value.is_finite() {
            Err(self.invalid(field, format!("{value} is not a finite number")))
        } else if value.abs() > limits::MAX_LENGTH_M {
            Err(self.invalid(
                field,
                format!("{value:e}: expected at most {} in absolute value", limits::MAX_LENGTH_M),
            ))
        } else {
            Ok(value)
        }
    }

    /// A length that must be finite and strictly positive (m, or a unitless scale factor).
    fn positive(&self, field: &str, value: f64, unit: &str) -> Result<f64, ScenarioError> {
        if value.is_finite() && value > 0.0 && value <= limits::MAX_LENGTH_M {
            Ok(value)
        } else {
            Err(self.invalid(
                field,
                format!(
                    "{}{unit}: expected a finite number > 0 and at most {}",
                    short(value),
                    limits::MAX_LENGTH_M
                ),
            ))
        }
    }

    fn position(&self, field: &str, xyz: [f64; 3]) -> Result<Vector3<f64>, ScenarioError> {
        for (axis, value) in ["x", "y", "z"].iter().zip(xyz) {
            if !value.is_finite() {
                return Err(self.invalid(field, format!("{axis} = {value} is not a finite number")));
            }
            if value.abs() > limits::MAX_LENGTH_M {
                return Err(self.invalid(
                    field,
                    format!(
                        "{axis} = {value:e} m: expected at most {} m in absolute value",
                        limits::MAX_LENGTH_M
                    ),
                ));
            }
        }
        Ok(Vector3::from(xyz))
    }

    fn name(&self, field: &str, given: Option<&str>, default: impl FnOnce() -> String) -> Result<String, ScenarioError> {
        match given {
            Some(name) if name.trim().is_empty() => Err(self.invalid(&format!("{field}.name"), "is empty".into())),
            Some(name) => Ok(name.to_string()),
            None => Ok(default()),
        }
    }

    /// `[w, x, y, z]` with norm 1 within [`ORIENTATION_TOLERANCE`], normalised.
    fn quaternion(&self, field: &str, wxyz: [f64; 4]) -> Result<UnitQuaternion<f64>, ScenarioError> {
        if wxyz.iter().any(|v| !v.is_finite()) {
            return Err(self.invalid(field, format!("{wxyz:?} has a non-finite number")));
        }
        let [w, x, y, z] = wxyz;
        let quaternion = Quaternion::new(w, x, y, z);
        let norm = quaternion.norm();
        if (norm - 1.0).abs() > ORIENTATION_TOLERANCE {
            return Err(self.invalid(
                field,
                format!("[w, x, y, z] = {wxyz:?} has norm {norm}; expected a unit quaternion (norm 1 within {ORIENTATION_TOLERANCE})"),
            ));
        }
        Ok(unit_quaternion(quaternion))
    }

    /// Row-major 3x3 rotation matrix: orthonormal within [`ORIENTATION_TOLERANCE`], det > 0.
    fn rotation_matrix(&self, field: &str, rows: [[f64; 3]; 3]) -> Result<UnitQuaternion<f64>, ScenarioError> {
        if rows.iter().flatten().any(|v| !v.is_finite()) {
            return Err(self.invalid(field, format!("{rows:?} has a non-finite number")));
        }
        let matrix = Matrix3::from_fn(|row, column| rows[row][column]);
        let deviation = (matrix.transpose() * matrix - Matrix3::identity()).abs().max();
        if deviation > ORIENTATION_TOLERANCE {
            return Err(self.invalid(
                field,
                format!("{rows:?} is not orthonormal: R^T R differs from the identity by {deviation:e} (allowed {ORIENTATION_TOLERANCE})"),
            ));
        }
        let determinant = matrix.determinant();
        if determinant < 0.0 {
            return Err(self.invalid(
                field,
                format!("{rows:?} has determinant {determinant}; a reflection is not a rotation"),
            ));
        }
        let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(matrix));
        Ok(unit_quaternion(rotation.into_inner()))
    }

    /// A pose from a position and at most one of `quaternion` and `rpy` (default identity).
    fn pose(
        &self,
        field: &str,
        position: [f64; 3],
        quaternion: Option<[f64; 4]>,
        rpy: Option<[f64; 3]>,
    ) -> Result<Isometry3<f64>, ScenarioError> {
        let translation = Translation3::from(self.position(&format!("{field}.position"), position)?);
        let rotation = match (quaternion, rpy) {
            (Some(q), None) => self.quaternion(&format!("{field}.quaternion"), q)?,
            (None, Some(rpy)) => {
                if rpy.iter().any(|v| !v.is_finite()) {
                    return Err(self.invalid(&format!("{field}.rpy"), format!("{rpy:?} has a non-finite number")));
                }
                UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2])
            }
            (None, None) => UnitQuaternion::identity(),
            (Some(_), Some(_)) => return Err(self.invalid(field, "gives both `quaternion` and `rpy`; give at most one orientation".into())),
        };
        Ok(Isometry3::from_parts(translation, rotation))
    }

    fn obstacle(&self, index: usize, file: &ObstacleFile) -> Result<Obstacle, ScenarioError> {
        let field = format!("obstacles[{index}]");
        let at = |name: &str| format!("{field}.{name}");
        let world_from_shape = self.pose(&field, file.position, file.quaternion, file.rpy)?;
        // Which size fields each type takes; any other one given is a mistake worth reporting.
        let takes: &[&str] = match file.kind.as_str() {
            "sphere" => &["radius"],
            "capsule" | "cylinder" => &["radius", "length"],
            "box" => &["size"],
            "mesh" => &["file", "scale"],
            other => {
                return Err(self.invalid(
                    &at("type"),
                    format!("unknown obstacle type `{other}`; expected one of {OBSTACLE_TYPES}"),
                ))
            }
        };
        let given = [
            ("radius", file.radius.is_some()),
            ("length", file.length.is_some()),
            ("size", file.size.is_some()),
            ("file", file.file.is_some()),
            ("scale", file.scale.is_some()),
        ];
        for (name, present) in given {
            if present && !takes.contains(&name) {
                return Err(self.invalid(&at(name), format!("a {} takes {}, not `{name}`", file.kind, takes.join(" and "))));
            }
        }
        let required = |name: &str, value: Option<f64>| -> Result<f64, ScenarioError> {
            let value = value.ok_or_else(|| self.invalid(&at(name), format!("is missing; a {} needs it", file.kind)))?;
            self.positive(&at(name), value, " m")
        };
        let shape = match file.kind.as_str() {
            "sphere" => Shape::Sphere {
                radius: required("radius", file.radius)?,
            },
            "capsule" => Shape::Capsule {
                radius: required("radius", file.radius)?,
                length: required("length", file.length)?,
            },
            "cylinder" => Shape::Cylinder {
                radius: required("radius", file.radius)?,
                length: required("length", file.length)?,
            },
            "box" => {
                let size = file
                    .size
                    .ok_or_else(|| self.invalid(&at("size"), "is missing; a box needs its edge lengths [x, y, z]".into()))?;
                let mut half_extents = [0.0; 3];
                for (axis, (half, full)) in half_extents.iter_mut().zip(size).enumerate() {
                    *half = self.positive(&format!("{field}.size[{axis}]"), full, " m")? / 2.0;
                }
                Shape::Box { half_extents }
            }
            _ => self.mesh(&field, file)?,
        };
        Ok(Obstacle {
            name: self.name(&field, file.name.as_deref(), || default_obstacle_name(index))?,
            world_from_shape,
            shape,
        })
    }

    fn mesh(&self, field: &str, file: &ObstacleFile) -> Result<Shape, ScenarioError> {
        let file_field = format!("{field}.file");
        let uri = file.file.as_deref().ok_or_else(|| {
            self.invalid(
                &file_field,
                "is missing; a mesh needs a file (relative to the scenario file)".into(),
            )
        })?;
        let scale = match file.scale {
            None => [1.0; 3],
            Some(Scale::Uniform(s)) => [self.positive(&format!("{field}.scale"), s, "")?; 3],
            Some(Scale::PerAxis(s)) => {
                let mut scale = [0.0; 3];
                for (axis, (out, value)) in scale.iter_mut().zip(s).enumerate() {
                    *out = self.positive(&format!("{field}.scale[{axis}]"), value, "")?;
                }
                scale
            }
        };
        let folder = self.path.parent().unwrap_or_else(|| Path::new(""));
        let resolved = folder.join(uri);
        let mesh_error = |message: String| ScenarioError::Mesh {
            path: self.path.to_path_buf(),
            field: file_field.clone(),
            mesh: resolved.clone(),
            message,
        };
        if !resolved.exists() {
            return Err(mesh_error("not found (mesh paths are relative to the scenario file)".into()));
        }
        Ok(Shape::Mesh(load_mesh(uri, &resolved, scale).map_err(mesh_error)?))
    }
}

/// The unit quaternion of `quaternion`, keeping it bit for bit when it is unit to within rounding.
pub(crate) fn unit_quaternion(quaternion: Quaternion<f64>) -> UnitQuaternion<f64> {
    if (quaternion.norm() - 1.0).abs() <= UNIT_NORM_ROUNDING {
        UnitQuaternion::new_unchecked(quaternion)
    } else {
        UnitQuaternion::new_normalize(quaternion)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_str(text: &str) -> Result<Scenario, ScenarioError> {
        parse(text, Path::new("inline.json"))
    }

    fn error(text: &str) -> String {
        match parse_str(text) {
            Ok(_) => panic!("expected an error for {text}"),
            Err(e) => e.to_string(),
        }
    }

    const GOAL: &str = r#"{"position": [0.5, 0, 0.3], "quaternion": [1, 0, 0, 0]}"#;

    #[test]
    fn minimal_scenario_gets_defaults() {
        let scenario = parse_str(&format!(r#"{{"goals": [{GOAL}]}}"#)).expect("valid");
        assert_eq!(scenario.name, "inline");
        assert_eq!(scenario.goals[0].name, "goal 0");
        assert_eq!(scenario.goals[0].tolerance, Tolerance::Pose);
        assert!(scenario.floor.is_none() && scenario.obstacles.is_empty() && scenario.home.is_none());
        assert_eq!(scenario.world_from_base, Isometry3::identity());
    }

    #[test]
    fn rotation_matrix_and_quaternion_agree() {
        // 90 degrees about z: x -> y.
        let text = r#"{"goals": [
            {"position": [0, 0, 0], "rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]]},
            {"position": [0, 0, 0], "quaternion": [0.7071067811865476, 0, 0, 0.7071067811865476], "tolerance": "position"}],
            "tolerance": "z_symmetric"}"#;
        let scenario = parse_str(text).expect("valid");
        assert!(scenario.goals[0].rotation.angle_to(&scenario.goals[1].rotation) < 1e-15);
        assert_eq!(scenario.goals[0].tolerance, Tolerance::ZSymmetric);
        assert_eq!(scenario.goals[1].tolerance, Tolerance::Position);
    }

    #[test]
    fn rejects_non_unit_quaternion_naming_field_and_norm() {
        let err = error(r#"{"goals": [{"position": [0, 0, 0], "quaternion": [1, 0, 0, 0.1]}]}"#);
        assert!(err.contains("goals[0].quaternion") && err.contains("norm 1.004987"), "{err}");
    }

    #[test]
    fn rejects_reflection() {
        let err = error(r#"{"goals": [{"position": [0, 0, 0], "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, -1]]}]}"#);
        assert!(err.contains("goals[0].rotation") && err.contains("determinant -1"), "{err}");
    }

    #[test]
    fn rejects_sizes_that_are_not_positive() {
        for (obstacle, field) in [
            (r#"{"type": "sphere", "position": [0, 0, 0], "radius": 0}"#, "obstacles[0].radius"),
            (
                r#"{"type": "capsule", "position": [0, 0, 0], "radius": 0.1, "length": -1}"#,
                "obstacles[0].length",
            ),
            (
                r#"{"type": "box", "position": [0, 0, 0], "size": [0.1, 0, 0.1]}"#,
                "obstacles[0].size[1]",
            ),
            (
                r#"{"type": "cylinder", "position": [0, 0, 0], "radius": 0.1}"#,
                "obstacles[0].length",
            ),
            (
                r#"{"type": "sphere", "position": [0, 0, 0], "radius": 0.1, "size": [1, 1, 1]}"#,
                "obstacles[0].size",
            ),
        ] {
            let err = error(&format!(r#"{{"obstacles": [{obstacle}], "goals": [{GOAL}]}}"#));
            assert!(err.starts_with(&format!("inline.json: {field}: ")), "{err}");
        }
    }

    #[test]
    fn rejects_unknown_fields_with_line() {
        let err = error(&format!("{{\"goals\": [{GOAL}],\n \"obstacle\": []}}"));
        assert!(err.contains("unknown field `obstacle`") && err.contains("line 2"), "{err}");
    }

    #[test]
    fn base_takes_rpy_or_quaternion_but_not_both() {
        let scenario = parse_str(&format!(
            r#"{{"base": {{"position": [1, 2, 3], "rpy": [0, 0, 0.5]}}, "goals": [{GOAL}]}}"#
        ))
        .expect("valid");
        assert!((scenario.world_from_base.rotation.angle() - 0.5).abs() < 1e-15);
        let err = error(&format!(
            r#"{{"base": {{"position": [1, 2, 3], "rpy": [0, 0, 0.5], "quaternion": [1, 0, 0, 0]}}, "goals": [{GOAL}]}}"#
        ));
        assert!(err.contains("base: gives both"), "{err}");
    }
}
