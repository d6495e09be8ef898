//! Consumes a design JSON file (`free`, `economic`, `modular` or `preset` mode).
//! Produces a validated, immutable [`Design`]: one standard-DH row per joint plus limits,
//! ratings, base pose and tool offset. Fails with [`DesignError`] naming the file and field.

pub mod catalog;
mod write;

pub use write::to_json;

use crate::frames::PoseSpec;
use crate::limits;
use catalog::{Preset, SlotOption};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A validated design.
#[derive(Debug, Clone, Serialize)]
pub struct Design {
    /// Design name (file field `name`, else the file stem).
    pub name: String,
    /// Design mode.
    pub mode: DesignMode,
    /// One standard-DH joint per row.
    pub joints: Vec<DhJoint>,
    /// Modular slot options, for modular designs.
    pub modules: Option<Vec<SlotOption>>,
    /// The preset expanded, for preset designs.
    pub preset: Option<Preset>,
    /// Pose of frame 0 in the world.
    pub base: PoseSpec,
    /// Tool offset relative to frame n.
    pub tool: PoseSpec,
    /// Economic values read as the named value of their set they lie next to (float32 rounding,
    /// see [`catalog::FLOAT32_SNAP`]); `joints` holds the values used.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub snapped: Vec<SnappedValue>,
}

/// An economic value read as a named value of its set: `-1.5707963705062866` (float32's
/// `-pi/2`) as `-pi/2`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SnappedValue {
    /// The field (`joints[2].alpha`).
    pub field: String,
    /// The value as written in the file (m or rad).
    pub written: f64,
    /// The value used (m or rad).
    pub used: f64,
    /// How the value used is named (`-pi/2`, `0.1`).
    pub name: &'static str,
}

impl std::fmt::Display for SnappedValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} = {} snapped to {}", self.field, self.written, self.name)?;
        // A symbolic name (pi/2) gets its number too; a length is its own number.
        if self.name != self.used.to_string() {
            write!(f, " ({})", self.used)?;
        }
        write!(f, " (within {:e}; a float32 generator's rounding)", catalog::FLOAT32_SNAP)
    }
}

/// Design mode, as in the paper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DesignMode {
    /// Any finite DH parameters.
    Free,
    /// DH parameters restricted to the economic sets.
    Economic,
    /// A sequence of catalog modules.
    Modular,
    /// A published industrial robot.
    Preset,
}

impl DesignMode {
    /// The name used in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Free => "free",
            Self::Economic => "economic",
            Self::Modular => "modular",
            Self::Preset => "preset",
        }
    }
}

/// One joint: `T(q) = Rot_z(q) Trans_z(d) Trans_x(a) Rot_x(alpha)`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DhJoint {
    /// Offset along the previous z axis (m).
    pub d: f64,
    /// Offset along the new x axis (m).
    pub a: f64,
    /// Twist about the new x axis (rad).
    pub alpha: f64,
    /// Position limits (rad).
    pub limits: [f64; 2],
    /// Maximum speed (rad/s).
    pub max_velocity: f64,
    /// Rated torque (N m), when known.
    pub rated_torque: Option<f64>,
}

impl Design {
    /// A modular design of catalog `slots`, named `name`, at the origin without a tool offset.
    pub fn modular(name: &str, slots: &[SlotOption]) -> Design {
        Design {
            name: name.to_string(),
            mode: DesignMode::Modular,
            joints: slots
                .iter()
                .map(|m| module_joint(m.dh(), Some(catalog::JOINT_MODULE_RATED_TORQUE_NM)))
                .collect(),
            modules: Some(slots.to_vec()),
            preset: None,
            base: PoseSpec::default(),
            tool: PoseSpec::default(),
            snapped: vec![],
        }
    }

    /// The robot a catalog id names (`modular6/D-Ls-Il-D-Is-Ll`, `preset/UR20`), named by the
    /// id; `Ok(None)` for text that is not a catalog id.
    ///
    /// # Errors
    /// The message for text that looks like an id and names no robot.
    pub fn from_catalog_id(text: &str) -> Result<Option<Design>, String> {
        Ok(catalog::parse_id(text)?.map(|id| match id {
            catalog::CatalogId::Modular(slots) => Design::modular(text, &slots),
            catalog::CatalogId::Preset(preset) => Design::preset(text, preset),
        }))
    }

    /// An industrial preset, named `name`, at the origin without a tool offset.
    pub fn preset(name: &str, preset: Preset) -> Design {
        // The paper ignores preset joint limits and publishes no ratings in its tables.
        Design {
            name: name.to_string(),
            mode: DesignMode::Preset,
            joints: preset.dh().into_iter().map(|row| module_joint(row, None)).collect(),
            modules: None,
            preset: Some(preset),
            base: PoseSpec::default(),
            tool: PoseSpec::default(),
            snapped: vec![],
        }
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The paper's hardware cost `c_h = sum |a_i| + sum |d_i|` (m).
    pub fn hardware_cost(&self) -> f64 {
        self.joints.iter().map(|j| j.a.abs() + j.d.abs()).sum()
    }
}

/// Why a design file could not be used.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// The file could not be read.
    #[error("cannot read design {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The JSON is malformed or does not match the schema.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// serde's message, with line and column.
        message: String,
    },
    /// A field has a value outside what it allows.
    #[error("{path}: {field}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The field (`joints[2].a`).
        field: String,
        /// The value and what was expected.
        message: String,
    },
    /// An economic design breaks the economic constraints.
    #[error("{path}: joint {joint} (joints[{index}]): {parameter} = {value} is not economic; allowed {allowed}")]
    NotEconomic {
        /// The file.
        path: PathBuf,
        /// Joint number, 1-based.
        joint: usize,
        /// Index into `joints`.
        index: usize,
        /// `d`, `a` or `alpha`.
        parameter: &'static str,
        /// The value given.
        value: f64,
        /// The allowed set.
        allowed: &'static str,
    },
}

#[derive(Deserialize)]
struct ModeOnly {
    mode: String,
}

// The file schema, read by `parse` and written by `write::to_json`: one type per mode.

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct DhFile {
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    mode: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    description: Option<String>,
    joints: Vec<DhJointFile>,
    #[serde(skip_serializing_if = "Option::is_none")]
    base: Option<PoseSpec>,
    #[serde(skip_serializing_if = "Option::is_none")]
    tool: Option<PoseSpec>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct DhJointFile {
    d: f64,
    a: f64,
    alpha: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    limits: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    max_velocity: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rated_torque: Option<f64>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct ModularFile {
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    mode: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    description: Option<String>,
    modules: Vec<SlotOption>,
    #[serde(skip_serializing_if = "Option::is_none")]
    base: Option<PoseSpec>,
    #[serde(skip_serializing_if = "Option::is_none")]
    tool: Option<PoseSpec>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct PresetFile {
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    mode: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    description: Option<String>,
    preset: Preset,
    #[serde(skip_serializing_if = "Option::is_none")]
    base: Option<PoseSpec>,
    #[serde(skip_serializing_if = "Option::is_none")]
    tool: Option<PoseSpec>,
}

/// Reads and validates a design file.
///
/// # Errors
/// [`DesignError`] naming the file and the field: unreadable file, malformed JSON, unknown mode or
/// field, non-finite or out-of-range numbers, economic violations (an economic value within
/// [`catalog::FLOAT32_SNAP`] of a named value of its set is not one: it is read as that value and
/// listed in [`Design::snapped`]).
pub fn load(path: &Path) -> Result<Design, DesignError> {
    let text = crate::files::read_text(path, crate::limits::MAX_TEXT_BYTES).map_err(|source| DesignError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text, path)
}

/// Validates a design given as JSON text; `path` is used in messages and for the default name.
///
/// # Errors
/// As [`load`].
pub fn parse(text: &str, path: &Path) -> Result<Design, DesignError> {
    let parse_error = |e: serde_json::Error| DesignError::Parse {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    // Two passes so that schema errors keep serde's line and column: the mode picks the type, then
    // the text is read again as exactly that type.
    let mode: ModeOnly = serde_json::from_str(text).map_err(parse_error)?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "design".into());
    let mut design = match mode.mode.as_str() {
        "free" | "economic" => {
            let file: DhFile = serde_json::from_str(text).map_err(parse_error)?;
            let joints = file
                .joints
                .iter()
                .map(|j| DhJoint {
                    d: j.d,
                    a: j.a,
                    alpha: j.alpha,
                    limits: j.limits.unwrap_or([-catalog::JOINT_MODULE_LIMIT, catalog::JOINT_MODULE_LIMIT]),
                    max_velocity: j.max_velocity.unwrap_or(catalog::JOINT_MODULE_MAX_SPEED),
                    rated_torque: Some(j.rated_torque.unwrap_or(catalog::JOINT_MODULE_RATED_TORQUE_NM)),
                })
                .collect();
            let mode = if mode.mode == "free" {
                DesignMode::Free
            } else {
                DesignMode::Economic
            };
            Design {
                name: file.name.unwrap_or(stem),
                mode,
                joints,
                modules: None,
                preset: None,
                base: file.base.unwrap_or_default(),
                tool: file.tool.unwrap_or_default(),
                snapped: vec![],
            }
        }
        "modular" => {
            let file: ModularFile = serde_json::from_str(text).map_err(parse_error)?;
            Design {
                base: file.base.unwrap_or_default(),
                tool: file.tool.unwrap_or_default(),
                ..Design::modular(&file.name.unwrap_or(stem), &file.modules)
            }
        }
        "preset" => {
            let file: PresetFile = serde_json::from_str(text).map_err(parse_error)?;
            Design {
                base: file.base.unwrap_or_default(),
                tool: file.tool.unwrap_or_default(),
                ..Design::preset(&file.name.unwrap_or(stem), file.preset)
            }
        }
        other => {
            return Err(DesignError::Invalid {
                path: path.to_path_buf(),
                field: "mode".into(),
                message: format!("unknown mode `{other}`; expected one of free, economic, modular, preset"),
            })
        }
    };
    validate(&design, path)?;
    if design.mode == DesignMode::Economic {
        design.snapped = economic(&mut design.joints, path)?;
    }
    Ok(design)
}

/// Checks the DH values of an economic design against the economic sets. A value within
/// [`catalog::FLOAT32_SNAP`] of a named value of its set is set to that value and listed.
fn economic(joints: &mut [DhJoint], path: &Path) -> Result<Vec<SnappedValue>, DesignError> {
    let mut snapped = Vec::new();
    for (index, joint) in joints.iter_mut().enumerate() {
        for (parameter, value) in [("d", &mut joint.d), ("a", &mut joint.a), ("alpha", &mut joint.alpha)] {
            if let Some(snap) = catalog::economic_snap(parameter, *value) {
                snapped.push(SnappedValue {
                    field: format!("joints[{index}].{parameter}"),
                    written: *value,
                    used: snap.value,
                    name: snap.name,
                });
                *value = snap.value;
            } else if let Some(allowed) = catalog::economic_violation(parameter, *value) {
                return Err(DesignError::NotEconomic {
                    path: path.to_path_buf(),
                    joint: index + 1,
                    index,
                    parameter,
                    value: *value,
                    allowed,
                });
            }
        }
    }
    Ok(snapped)
}

fn module_joint(row: [f64; 3], rated_torque: Option<f64>) -> DhJoint {
    DhJoint {
        d: row[0],
        a: row[1],
        alpha: row[2],
        limits: [-catalog::JOINT_MODULE_LIMIT, catalog::JOINT_MODULE_LIMIT],
        max_velocity: catalog::JOINT_MODULE_MAX_SPEED,
        rated_torque,
    }
}

/// Largest rated torque (N m) a design may state; beyond it the number is a typo, not a rating.
const MAX_RATING: f64 = 1e6;

fn validate(design: &Design, path: &Path) -> Result<(), DesignError> {
    let invalid = |field: String, message: String| DesignError::Invalid {
        path: path.to_path_buf(),
        field,
        message,
    };
    let list = if design.mode == DesignMode::Modular { "modules" } else { "joints" };
    if design.joints.is_empty() {
        return Err(invalid(list.into(), "is empty; a design needs at least one joint".into()));
    }
    if design.joints.len() > limits::MAX_JOINTS {
        return Err(invalid(
            list.into(),
            format!("has {} joints; the limit is {}", design.joints.len(), limits::MAX_JOINTS),
        ));
    }
    if design.name.trim().is_empty() {
        return Err(invalid("name".into(), "is empty".into()));
    }
    for (field, pose) in [("base", &design.base), ("tool", &design.tool)] {
        if !pose.is_finite() {
            return Err(invalid(field.into(), "has a non-finite number".into()));
        }
        if pose.position.iter().chain(&pose.rpy).any(|v| v.abs() > limits::MAX_LENGTH_M) {
            return Err(invalid(field.into(), format!("has a number beyond +-{}", limits::MAX_LENGTH_M)));
        }
    }
    for (index, joint) in design.joints.iter().enumerate() {
        for (name, value) in [
            ("d", joint.d),
            ("a", joint.a),
            ("alpha", joint.alpha),
            ("max_velocity", joint.max_velocity),
        ] {
            if !value.is_finite() {
                return Err(invalid(
                    format!("joints[{index}].{name}"),
                    format!("{value} is not a finite number"),
                ));
            }
            if value.abs() > limits::MAX_LENGTH_M {
                return Err(invalid(
                    format!("joints[{index}].{name}"),
                    format!("{value:e}: expected at most {} in absolute value", limits::MAX_LENGTH_M),
                ));
            }
        }
        let [lower, upper] = joint.limits;
        if !(lower.is_finite() && upper.is_finite() && lower < upper) {
            return Err(invalid(
                format!("joints[{index}].limits"),
                format!("[{lower}, {upper}] rad: expected finite lower < upper"),
            ));
        }
        if lower.abs().max(upper.abs()) > limits::MAX_JOINT_LIMIT {
            return Err(invalid(
                format!("joints[{index}].limits"),
                format!(
                    "[{lower:e}, {upper:e}] rad: expected limits within +-{} rad",
                    limits::MAX_JOINT_LIMIT
                ),
            ));
        }
        if joint.max_velocity <= 0.0 {
            return Err(invalid(
                format!("joints[{index}].max_velocity"),
                format!("{} rad/s: expected > 0", joint.max_velocity),
            ));
        }
        if let Some(torque) = joint.rated_torque {
            if !(torque.is_finite() && torque > 0.0 && torque <= MAX_RATING) {
                return Err(invalid(
                    format!("joints[{index}].rated_torque"),
                    format!("{torque} N m: expected > 0 and at most {MAX_RATING}"),
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_str(text: &str) -> Result<Design, DesignError> {
        parse(text, Path::new("inline.json"))
    }

    #[test]
    fn modular_design_expands_catalog_rows() {
        let design = parse_str(r#"{"mode": "modular", "modules": ["direct", "L-short", "direct", "direct", "I-long"]}"#).expect("valid");
        assert_eq!(design.dof(), 5);
        assert_eq!(design.joints[1].a, 0.20);
        assert!((design.hardware_cost() - 1.0).abs() < 1e-12);
        assert_eq!(design.name, "inline");
    }

    #[test]
    fn rejects_unknown_mode() {
        let err = parse_str(r#"{"mode": "magic", "joints": []}"#).unwrap_err().to_string();
        assert!(err.contains("unknown mode `magic`"), "{err}");
    }

    #[test]
    fn rejects_unknown_field_with_line() {
        let err = parse_str("{\"mode\": \"free\",\n \"joints\": [{\"d\": 0.1, \"a\": 0, \"alpha\": 0, \"lenght\": 1}]}")
            .unwrap_err()
            .to_string();
        assert!(err.contains("lenght") && err.contains("line 2"), "{err}");
    }

    #[test]
    fn rejects_economic_violation_naming_joint_and_parameter() {
        let err = parse_str(r#"{"mode": "economic", "joints": [{"d": 0.1, "a": 0, "alpha": 0}, {"d": 0.05, "a": 0, "alpha": 0}]}"#)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("joint 2") && err.contains("d = 0.05") && err.contains("[0.1, 0.4]"),
            "{err}"
        );
    }

    #[test]
    fn rejects_inverted_limits() {
        let err = parse_str(r#"{"mode": "free", "joints": [{"d": 0.1, "a": 0, "alpha": 0, "limits": [1, -1]}]}"#)
            .unwrap_err()
            .to_string();
        assert!(err.contains("joints[0].limits"), "{err}");
    }

    #[test]
    fn rejects_empty_design() {
        let err = parse_str(r#"{"mode": "modular", "modules": []}"#).unwrap_err().to_string();
        assert!(err.contains("modules: is empty"), "{err}");
    }
}
