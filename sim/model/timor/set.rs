//! A Timor module set (`modules.json`): modules made of bodies, joints between them and
//! connectors on them. Read into checked values; assembling them is `assembly`'s job.
//!
//! Conventions (timor-python 1.1, `Bodies.py`, `Joints.py`, `Geometry.py`): a connector's pose is
//! the body-to-connector transformation, its z axis pointing away from the body; a joint moves
//! about (or along) the z axis of its joint frame, which sits at `poseParent` in the parent body,
//! and the child body sits at `poseChild` in the joint frame; a body's inertia is about its centre
//! of mass `r_com`, in body axes. Boxes have full edge lengths `x, y, z`, cylinders radius `r`
//! and full length `z` along their z axis, both centred on their pose. Mesh files are relative
//! to the folder of `modules.json` (`package://` stripped).

use super::json::{isometry, Id, Matrix4Rows, Num, OneOrMany};
use crate::model::{Collider, Inertial, JointKind, Shape};
use nalgebra::{Isometry3, Matrix3, Vector3};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The file as Timor writes it.
#[derive(Debug, Deserialize)]
pub(super) struct SetFile {
    pub modules: Vec<ModuleFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ModuleFile {
    header: Header,
    #[serde(default)]
    bodies: OneOrMany<BodyFile>,
    #[serde(default)]
    joints: OneOrMany<JointFile>,
}

#[derive(Debug, Deserialize)]
struct Header {
    #[serde(rename = "ID")]
    id: Id,
    #[serde(default)]
    name: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BodyFile {
    #[serde(rename = "ID")]
    id: Id,
    mass: Num,
    inertia: [[Num; 3]; 3],
    r_com: [Num; 3],
    #[serde(default)]
    connectors: OneOrMany<ConnectorFile>,
    #[serde(default)]
    collision: Option<OneOrMany<GeometryFile>>,
    /// Visual geometry is not read: collision geometry is what is checked.
    #[serde(default)]
    #[allow(dead_code)]
    visual: Option<serde::de::IgnoredAny>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ConnectorFile {
    #[serde(rename = "ID")]
    id: Id,
    #[serde(default)]
    pose: Option<Matrix4Rows>,
    #[serde(default)]
    gender: Option<String>,
    #[serde(default, rename = "type")]
    kind: Option<String>,
    #[serde(default)]
    size: Option<OneOrMany<Num>>,
}

/// One collision geometry as Timor writes it, in modules and in tasks alike.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct GeometryFile {
    #[serde(rename = "type")]
    kind: String,
    #[serde(default)]
    parameters: BTreeMap<String, serde_json::Value>,
    #[serde(default)]
    pose: Option<Matrix4Rows>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "camelCase")]
struct JointFile {
    #[serde(rename = "ID")]
    id: Id,
    parent: Id,
    child: Id,
    #[serde(rename = "type")]
    kind: String,
    #[serde(default)]
    passive: Option<serde_json::Value>,
    #[serde(default)]
    pose_parent: Option<Matrix4Rows>,
    #[serde(default)]
    pose_child: Option<Matrix4Rows>,
    limits: LimitsFile,
    #[serde(default)]
    #[allow(dead_code)]
    gear_ratio: Option<Num>,
    #[serde(default)]
    #[allow(dead_code)]
    motor_inertia: Option<Num>,
    #[serde(default)]
    #[allow(dead_code)]
    friction_coulomb: Option<Num>,
    #[serde(default)]
    #[allow(dead_code)]
    friction_viscous: Option<Num>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "camelCase")]
struct LimitsFile {
    #[serde(alias = "lower")]
    position_lower: Option<Num>,
    #[serde(alias = "upper")]
    position_upper: Option<Num>,
    #[serde(default)]
    peak_torque: Option<Num>,
    #[serde(default)]
    velocity: Option<Num>,
    #[serde(default)]
    #[allow(dead_code)]
    acceleration: Option<Num>,
}

/// Connector gender: male and female connect, hermaphroditic connects hermaphroditic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Gender {
    Female,
    Male,
    Hermaphroditic,
}

impl Gender {
    fn parse(text: &str) -> Option<Gender> {
        match text {
            "f" | "female" => Some(Gender::Female),
            "m" | "male" => Some(Gender::Male),
            "h" | "hermaphroditic" => Some(Gender::Hermaphroditic),
            _ => None,
        }
    }

    pub(crate) fn letter(self) -> &'static str {
        match self {
            Gender::Female => "f",
            Gender::Male => "m",
            Gender::Hermaphroditic => "h",
        }
    }

    fn connects(self, other: Gender) -> bool {
        match (self, other) {
            (Gender::Hermaphroditic, Gender::Hermaphroditic) => true,
            (Gender::Hermaphroditic, _) | (_, Gender::Hermaphroditic) => false,
            (a, b) => a != b,
        }
    }
}

/// Where two modules meet.
#[derive(Debug, Clone)]
pub(crate) struct Connector {
    pub id: String,
    /// Index of the body it sits on, in its module.
    pub body: usize,
    /// The connector frame in the body frame.
    pub body_from_connector: Isometry3<f64>,
    pub gender: Gender,
    pub kind: String,
    pub size: Vec<f64>,
}

impl Connector {
    /// Why `self` cannot meet `other`, if it cannot (Timor's rule: same type and size, matching
    /// genders).
    pub(crate) fn mismatch(&self, other: &Connector) -> Option<String> {
        let describe = |c: &Connector| format!("`{}` ({}, type `{}`, size {:?})", c.id, c.gender.letter(), c.kind, c.size);
        let why = if self.kind != other.kind {
            "their types differ"
        } else if self.size != other.size {
            "their sizes differ"
        } else if !self.gender.connects(other.gender) {
            "their genders do not mate (m with f, h with h)"
        } else {
            return None;
        };
        Some(format!("{} and {}: {why}", describe(self), describe(other)))
    }
}

/// A rigid body of a module.
#[derive(Debug, Clone)]
pub(crate) struct Body {
    pub id: String,
    /// Mass properties in the body frame; `None` when the mass is 0.
    pub inertial: Option<Inertial>,
    /// Collision geometry in the body frame.
    pub colliders: Vec<Collider>,
}

/// A joint between two bodies of one module.
#[derive(Debug, Clone)]
pub(crate) struct ModuleJoint {
    pub id: String,
    pub parent: usize,
    pub child: usize,
    /// `None` for a fixed joint.
    pub kind: Option<JointKind>,
    pub parent_from_joint: Isometry3<f64>,
    pub joint_from_child: Isometry3<f64>,
    pub limits: Option<[f64; 2]>,
    pub max_velocity: Option<f64>,
    pub max_effort: Option<f64>,
}

/// One module of the set.
#[derive(Debug, Clone)]
pub(crate) struct Module {
    pub id: String,
    pub name: Option<String>,
    pub bodies: Vec<Body>,
    pub joints: Vec<ModuleJoint>,
    pub connectors: Vec<Connector>,
}

/// A module set, checked.
#[derive(Debug, Clone)]
pub(crate) struct ModuleSet {
    /// The `modules.json` read.
    pub path: PathBuf,
    pub modules: Vec<Module>,
}

impl ModuleSet {
    pub(crate) fn module(&self, id: &str) -> Option<&Module> {
        self.modules.iter().find(|m| m.id == id)
    }

    /// Every module ID, in file order, for messages.
    pub(crate) fn ids(&self) -> String {
        self.modules.iter().map(|m| m.id.as_str()).collect::<Vec<_>>().join(", ")
    }
}

/// What went wrong, and where: the element (`module `J2`, joint `Revolute``) and the problem.
pub(crate) type Problem = (String, String);

/// Checks a parsed set; `dir` anchors mesh paths.
pub(super) fn check(file: SetFile, path: &Path) -> Result<ModuleSet, Problem> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut modules: Vec<Module> = Vec::with_capacity(file.modules.len());
    for (k, module) in file.modules.into_iter().enumerate() {
        let id = module.header.id.0.clone();
        if modules.iter().any(|m| m.id == id) {
            return Err((
                format!("modules[{k}] header ID"),
                format!("`{id}` is used by two modules; IDs must be unique"),
            ));
        }
        modules.push(check_module(module, dir)?);
    }
    if modules.is_empty() {
        return Err(("modules".into(), "is empty; expected at least one module".into()));
    }
    Ok(ModuleSet {
        path: path.to_path_buf(),
        modules,
    })
}

fn check_module(module: ModuleFile, dir: &Path) -> Result<Module, Problem> {
    let id = module.header.id.0.clone();
    let at = |what: String| format!("module `{id}`, {what}");
    let mut bodies = Vec::new();
    let mut connectors = Vec::new();
    for body in module.bodies.into_vec() {
        let body_id = body.id.0.clone();
        if bodies.iter().any(|b: &Body| b.id == body_id) {
            return Err((at(format!("body `{body_id}`")), "the body ID is used twice in this module".into()));
        }
        let element = at(format!("body `{body_id}`"));
        let index = bodies.len();
        let inertial = inertial(&body, &element)?;
        for connector in body.connectors.into_vec() {
            let cid = connector.id.0.clone();
            let element = format!("{element}, connector `{cid}`");
            if connectors.iter().any(|c: &Connector| c.id == cid) {
                return Err((element, "the connector ID is used twice in this module".into()));
            }
            let gender_text = connector.gender.as_deref().unwrap_or("h");
            let gender =
                Gender::parse(gender_text).ok_or_else(|| (format!("{element} gender"), format!("`{gender_text}`; expected f, m or h")))?;
            let size = connector
                .size
                .map(OneOrMany::into_vec)
                .unwrap_or_default()
                .iter()
                .map(|n| n.0)
                .collect();
            connectors.push(Connector {
                id: cid,
                body: index,
                body_from_connector: pose(connector.pose.as_ref(), &format!("{element} pose"))?,
                gender,
                kind: connector.kind.unwrap_or_default(),
                size,
            });
        }
        let mut colliders = Vec::new();
        for (g, geometry) in body.collision.map(OneOrMany::into_vec).unwrap_or_default().into_iter().enumerate() {
            let element = format!("{element}, collision[{g}]");
            // Timor's geometry names, less the module: `<body>.c<k>`.
            colliders.extend(geometry_colliders(
                &geometry,
                &element,
                dir,
                &format!("{body_id}.c{g}"),
                "the folder of modules.json",
            )?);
        }
        bodies.push(Body {
            id: body_id,
            inertial,
            colliders,
        });
    }
    let mut joints = Vec::new();
    for joint in module.joints.into_vec() {
        let element = at(format!("joint `{}`", joint.id));
        let body = |name: &Id, role: &str| {
            bodies.iter().position(|b| b.id == name.0).ok_or_else(|| {
                let known: Vec<&str> = bodies.iter().map(|b| b.id.as_str()).collect();
                (
                    format!("{element} {role}"),
                    format!("no body `{name}` in this module (bodies: {})", known.join(", ")),
                )
            })
        };
        let (parent, child) = (body(&joint.parent, "parent")?, body(&joint.child, "child")?);
        if parent == child {
            return Err((element, "joins a body to itself".into()));
        }
        if joint
            .passive
            .as_ref()
            .is_some_and(|p| matches!(p, serde_json::Value::Bool(true)) || p.as_str().is_some_and(|s| s.eq_ignore_ascii_case("true")))
        {
            return Err((
                format!("{element} passive"),
                "passive joints are not supported (nor by Timor)".into(),
            ));
        }
        let kind = match joint.kind.as_str() {
            "revolute" | "revolute_active" | "continuous" | "JointModelRZ" => Some(JointKind::Revolute),
            "prismatic" | "prismatic_active" | "JointModelPZ" => Some(JointKind::Prismatic),
            "fixed" => None,
            other => {
                return Err((
                    format!("{element} type"),
                    format!("`{other}`; expected revolute, continuous, prismatic or fixed"),
                ))
            }
        };
        let finite_positive = |value: Option<Num>, what: &str| -> Result<Option<f64>, Problem> {
            match value.map(|n| n.0) {
                None => Ok(None),
                Some(v) if v == f64::INFINITY => Ok(None),
                Some(v) if v.is_finite() && v > 0.0 => Ok(Some(v)),
                Some(v) => Err((
                    format!("{element} limits {what}"),
                    format!("{v}; expected a positive number or Infinity"),
                )),
            }
        };
        let max_effort = finite_positive(joint.limits.peak_torque, "peakTorque")?;
        let max_velocity = finite_positive(joint.limits.velocity, "velocity")?;
        let lower = joint.limits.position_lower.map_or(f64::NEG_INFINITY, |n| n.0);
        let upper = joint.limits.position_upper.map_or(f64::INFINITY, |n| n.0);
        let (kind, limits) = match kind {
            None => (None, None),
            Some(kind) => joint_limits(kind, lower, upper, &element)?,
        };
        joints.push(ModuleJoint {
            id: joint.id.0.clone(),
            parent,
            child,
            kind,
            parent_from_joint: pose(joint.pose_parent.as_ref(), &format!("{element} poseParent"))?,
            joint_from_child: pose(joint.pose_child.as_ref(), &format!("{element} poseChild"))?,
            limits,
            max_velocity,
            max_effort,
        });
    }
    Ok(Module {
        id,
        name: module.header.name,
        bodies,
        joints,
        connectors,
    })
}

/// The joint kind and limits for `lower`..`upper`: a revolute joint unlimited both ways is
/// continuous; everything else needs finite limits, lower below upper.
fn joint_limits(kind: JointKind, lower: f64, upper: f64, element: &str) -> Result<(Option<JointKind>, Option<[f64; 2]>), Problem> {
    if kind == JointKind::Revolute && lower == f64::NEG_INFINITY && upper == f64::INFINITY {
        return Ok((Some(JointKind::Continuous), None));
    }
    let bound = crate::limits::MAX_JOINT_LIMIT;
    if !(lower.is_finite() && upper.is_finite() && lower < upper && lower.abs() <= bound && upper.abs() <= bound) {
        let unit = if kind == JointKind::Prismatic { "m" } else { "rad" };
        let allowed = if kind == JointKind::Prismatic {
            "a prismatic joint needs both limits"
        } else {
            "a revolute joint has both limits finite, or both infinite (continuous)"
        };
        return Err((
            format!("{element} limits"),
            format!("positionLower {lower} and positionUpper {upper} {unit}: expected lower < upper within +-{bound}; {allowed}"),
        ));
    }
    Ok((Some(kind), Some([lower, upper])))
}

fn pose(rows: Option<&Matrix4Rows>, element: &str) -> Result<Isometry3<f64>, Problem> {
    match rows {
        None => Ok(Isometry3::identity()),
        Some(rows) => isometry(rows).map_err(|problem| (element.to_string(), problem)),
    }
}

fn inertial(body: &BodyFile, element: &str) -> Result<Option<Inertial>, Problem> {
    let mass = body.mass.0;
    let inertia = Matrix3::from_fn(|r, c| body.inertia[r][c].0);
    let com = Vector3::from_fn(|r, _| body.r_com[r].0);
    if !(mass.is_finite() && mass >= 0.0) || inertia.iter().chain(com.iter()).any(|v| !v.is_finite()) {
        return Err((
            format!("{element} mass, inertia, r_com"),
            format!("mass {mass}: expected finite numbers and a mass >= 0"),
        ));
    }
    Ok((mass > 0.0).then_some(Inertial { mass, com, inertia }))
}

/// A number parameter of a geometry, under any of its names.
fn parameter(geometry: &GeometryFile, names: &[&str], element: &str) -> Result<f64, Problem> {
    let value = names.iter().find_map(|n| geometry.parameters.get(*n)).ok_or_else(|| {
        (
            format!("{element} parameters"),
            format!("a {} needs `{}`", geometry.kind, names.join("` or `")),
        )
    })?;
    let number = value
        .as_f64()
        .filter(|v| v.is_finite() && *v > 0.0 && *v <= crate::limits::MAX_LENGTH_M);
    number.ok_or_else(|| {
        (
            format!("{element} parameters {}", names[0]),
            format!("{value}; expected a positive length in metres"),
        )
    })
}

/// The colliders of one geometry, in the frame its pose is given in (a body's, or the world for
/// a task's obstacle); mesh files are relative to `dir`, which `anchor` names for messages.
pub(crate) fn geometry_colliders(
    geometry: &GeometryFile,
    element: &str,
    dir: &Path,
    label: &str,
    anchor: &str,
) -> Result<Vec<Collider>, Problem> {
    let body_from_shape = pose(geometry.pose.as_ref(), &format!("{element} pose"))?;
    let one = |shape: Shape| {
        Ok(vec![Collider {
            link_from_shape: body_from_shape,
            shape,
            label: label.to_string(),
        }])
    };
    match geometry.kind.as_str() {
        "box" => {
            let [x, y, z] = [
                parameter(geometry, &["x"], element)?,
                parameter(geometry, &["y"], element)?,
                parameter(geometry, &["z"], element)?,
            ];
            one(Shape::Box {
                half_extents: [x / 2.0, y / 2.0, z / 2.0],
            })
        }
        "cylinder" => one(Shape::Cylinder {
            radius: parameter(geometry, &["r", "radius"], element)?,
            length: parameter(geometry, &["z", "length"], element)?,
        }),
        "sphere" => one(Shape::Sphere {
            radius: parameter(geometry, &["r"], element)?,
        }),
        "empty" => Ok(vec![]),
        "mesh" => super::mesh::colliders(&geometry.parameters, element, dir, label, body_from_shape, anchor),
        other => Err((
            format!("{element} type"),
            format!("`{other}`; expected box, cylinder, sphere, mesh or empty"),
        )),
    }
}
