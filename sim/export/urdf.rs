//! Model -> URDF text, written through quick-xml ([`crate::xml::Doc`]).
//!
//! Layout: a link `world`, a fixed joint `world_to_<base>` carrying `world_from_base`, the chain's
//! links (collision geometry and inertial, no `<visual>`) and joints, and a fixed joint
//! `<last>_to_tool` to a link `tool` carrying `last_from_tool`. Links without mass properties
//! (`world`, `tool`, usually the base) get no `<inertial>` at all, not a zero one.
//!
//! Numbers are written with `{}` (the shortest text that parses back to the same bits), so
//! positions, inertia, limits and mesh scales survive a round trip exactly. Orientations go
//! through roll-pitch-yaw and come back within a few 1e-16 rad.

use super::numbers;
use super::{check_chain, check_unique, ExportError};
use crate::frames::{rpy_of, xyz};
use crate::model::{Collider, Joint, JointKind, Link, Model, Shape};
use crate::xml::{Attributes, Doc, NO_ATTRIBUTES};
use nalgebra::Isometry3;

/// Name of the root link the exporter adds.
const WORLD_LINK: &str = "world";
/// Name of the tool link the exporter adds.
const TOOL_LINK: &str = "tool";
/// Compiler settings for MuJoCo's own URDF importer: keep every link as a body, keep our
/// inertia as written, take angles in radians and mesh paths as they are.
const MUJOCO_COMPILER: [(&str, &str); 6] = [
    ("angle", "radian"),
    ("fusestatic", "false"),
    ("discardvisual", "true"),
    ("strippath", "false"),
    ("balanceinertia", "false"),
    ("autolimits", "true"),
];

/// Options for [`to_urdf`].
#[derive(Debug, Clone, Default)]
pub struct UrdfExportOptions {
    /// Write a `<mujoco><compiler .../></mujoco>` block first in `<robot>` so that MuJoCo's
    /// URDF importer keeps every link as a body and reads angles in radians; default `false`.
    pub mujoco_block: bool,
    /// The folder the URDF will be written into: mesh files are then named relative to it, so
    /// the file loads from any working folder and moves with its meshes; `None` names them by
    /// absolute path (text kept in memory, compared with other exports).
    pub mesh_base: Option<std::path::PathBuf>,
    /// Where meshes that no URDF reader loads (Timor's VRML convex pieces) are written as binary
    /// STL, `<link>-<k>.stl` after the collider ([`written_meshes`] gives the files); `None`
    /// refuses such meshes.
    pub mesh_folder: Option<std::path::PathBuf>,
}

/// Whether a URDF can name `mesh`'s own file: STL, OBJ and DAE are what URDF readers load.
fn loadable(mesh: &crate::model::TriMesh) -> bool {
    mesh.file
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["stl", "obj", "dae"].iter().any(|ok| e.eq_ignore_ascii_case(ok)))
}

/// The file a written mesh gets in `folder`.
fn written_name(folder: &std::path::Path, link: &Link, k: usize) -> std::path::PathBuf {
    folder.join(format!("{}-{k}.stl", link.name.replace(['/', '\\'], "_")))
}

/// The STL files [`to_urdf`] names for meshes no URDF reader loads, with their bytes (binary
/// STL of the model's vertices, scale applied); empty without [`UrdfExportOptions::mesh_folder`].
pub fn written_meshes(model: &Model, opts: &UrdfExportOptions) -> Vec<(std::path::PathBuf, Vec<u8>)> {
    let Some(folder) = &opts.mesh_folder else { return Vec::new() };
    let mut files = Vec::new();
    for link in &model.links {
        for (k, collider) in link.colliders.iter().enumerate() {
            if let Shape::Mesh(mesh) = &collider.shape {
                if !loadable(mesh) {
                    files.push((written_name(folder, link, k), binary_stl(mesh)));
                }
            }
        }
    }
    files
}

/// `mesh` as binary STL: 80-byte header, triangle count, per triangle its normal, corners and
/// a zero attribute count.
fn binary_stl(mesh: &crate::model::TriMesh) -> Vec<u8> {
    let mut out = Vec::with_capacity(84 + 50 * mesh.triangles.len());
    let mut header = [b' '; 80];
    let title = b"proving-ground: a convex piece of a robot's collision mesh";
    header[..title.len()].copy_from_slice(title);
    out.extend_from_slice(&header);
    out.extend_from_slice(&u32::try_from(mesh.triangles.len()).unwrap_or(u32::MAX).to_le_bytes());
    for triangle in &mesh.triangles {
        let corner = |i: u32| nalgebra::Vector3::from(mesh.vertices[i as usize]);
        let (a, b, c) = (corner(triangle[0]), corner(triangle[1]), corner(triangle[2]));
        let normal = (b - a).cross(&(c - a)).try_normalize(0.0).unwrap_or_else(nalgebra::Vector3::zeros);
        for v in [normal, a, b, c] {
            for x in v.iter() {
                out.extend_from_slice(&(*x as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&0u16.to_le_bytes());
    }
    out
}

/// Writes a model as URDF text.
///
/// A base link already called `world` and placed at the world origin is used as the root
/// itself, without an extra `world` link. Joints without known effort or velocity get `0` in
/// `<limit>`; continuous joints get a `<limit>` with effort and velocity only. Mesh colliders
/// refer to their file relative to [`UrdfExportOptions::mesh_base`] (by absolute path without
/// one, or where no relative path leads there), with the model's scale (the file holds unscaled
/// vertices).
///
/// # Errors
/// [`ExportError::ChainShape`] for a model that is not a serial chain,
/// [`ExportError::DuplicateName`] when a link or joint name would occur twice,
/// [`ExportError::MeshPath`] for a mesh without a file or with a non-UTF-8 path.
pub fn to_urdf(model: &Model, opts: &UrdfExportOptions) -> Result<String, ExportError> {
    check_chain(model)?;
    let base = &model.links[0];
    let last = &model.links[model.links.len() - 1];
    let base_is_world = base.name == WORLD_LINK && model.world_from_base == Isometry3::identity();
    let world_joint = (!base_is_world).then(|| format!("{WORLD_LINK}_to_{}", base.name));
    let tool_joint = format!("{}_to_{TOOL_LINK}", last.name);
    let link_names = (!base_is_world)
        .then_some(WORLD_LINK)
        .into_iter()
        .chain(model.links.iter().map(|l| l.name.as_str()))
        .chain([TOOL_LINK]);
    check_unique(model, "URDF", "link", link_names)?;
    let joint_names = world_joint
        .as_deref()
        .into_iter()
        .chain(model.joints.iter().map(|j| j.name.as_str()))
        .chain([tool_joint.as_str()]);
    check_unique(model, "URDF", "joint", joint_names)?;

    let mut doc = Doc::new(2);
    doc.open("robot", [("name", model.name.as_str())]);
    if opts.mujoco_block {
        doc.open("mujoco", NO_ATTRIBUTES);
        doc.empty("compiler", MUJOCO_COMPILER);
        doc.close("mujoco");
    }
    if !base_is_world {
        doc.empty("link", [("name", WORLD_LINK)]);
    }
    for link in &model.links {
        write_link(&mut doc, model, link, opts)?;
    }
    doc.empty("link", [("name", TOOL_LINK)]);
    if let Some(name) = &world_joint {
        write_fixed_joint(&mut doc, name, WORLD_LINK, &base.name, &model.world_from_base);
    }
    for (i, joint) in model.joints.iter().enumerate() {
        write_joint(&mut doc, joint, &model.links[i].name, &model.links[i + 1].name);
    }
    write_fixed_joint(&mut doc, &tool_joint, &last.name, TOOL_LINK, &model.last_from_tool);
    doc.close("robot");
    Ok(doc.finish())
}

fn write_link(doc: &mut Doc, model: &Model, link: &Link, opts: &UrdfExportOptions) -> Result<(), ExportError> {
    if link.inertial.is_none() && link.colliders.is_empty() {
        doc.empty("link", [("name", link.name.as_str())]);
        return Ok(());
    }
    // Every mesh is named before anything is written: a link fails whole.
    let shapes = link
        .colliders
        .iter()
        .enumerate()
        .map(|(k, collider)| shape(model, link, k, collider, opts))
        .collect::<Result<Vec<_>, ExportError>>()?;
    doc.open("link", [("name", link.name.as_str())]);
    if let Some(inertial) = &link.inertial {
        let i = &inertial.inertia;
        doc.open("inertial", NO_ATTRIBUTES);
        doc.empty("origin", [("xyz", numbers(xyz(&inertial.com))), ("rpy", numbers([0.0; 3]))]);
        doc.empty("mass", [("value", super::number(inertial.mass))]);
        let entries = [
            ("ixx", (0, 0)),
            ("ixy", (0, 1)),
            ("ixz", (0, 2)),
            ("iyy", (1, 1)),
            ("iyz", (1, 2)),
            ("izz", (2, 2)),
        ];
        doc.empty("inertia", entries.map(|(key, at)| (key, super::number(i[at]))));
        doc.close("inertial");
    }
    for (collider, (tag, attributes)) in link.colliders.iter().zip(&shapes) {
        doc.open("collision", [("name", collider.label.as_str())]);
        write_origin(doc, &collider.link_from_shape);
        doc.open("geometry", NO_ATTRIBUTES);
        doc.empty(tag, attributes.iter().map(|(k, v)| (*k, v.as_str())));
        doc.close("geometry");
        doc.close("collision");
    }
    doc.close("link");
    Ok(())
}

/// The `<geometry>` element of a collider: its tag and attributes.
fn shape(
    model: &Model,
    link: &Link,
    k: usize,
    collider: &Collider,
    opts: &UrdfExportOptions,
) -> Result<(&'static str, Attributes), ExportError> {
    Ok(match &collider.shape {
        Shape::Sphere { radius } => ("sphere", vec![("radius", super::number(*radius))]),
        Shape::Cylinder { radius, length } => (
            "cylinder",
            vec![("radius", super::number(*radius)), ("length", super::number(*length))],
        ),
        Shape::Capsule { radius, length } => (
            "capsule",
            vec![("radius", super::number(*radius)), ("length", super::number(*length))],
        ),
        Shape::Box { half_extents } => ("box", vec![("size", numbers(half_extents.map(|h| 2.0 * h)))]),
        Shape::Mesh(mesh) => {
            let mesh_error = |problem: &'static str| ExportError::MeshPath {
                robot: model.name.clone(),
                link: link.name.clone(),
                collider: k,
                label: collider.label.clone(),
                file: mesh.file.clone(),
                problem,
            };
            if mesh.file.as_os_str().is_empty() {
                return Err(mesh_error("the model records no file for it"));
            }
            let (file, scale) = if loadable(mesh) {
                (mesh.file.clone(), mesh.scale)
            } else {
                let folder = opts.mesh_folder.as_deref().ok_or_else(|| {
                    mesh_error("it is a VRML convex piece, which URDF readers do not load: exported to a file (--export-urdf), it is written as STL beside the URDF")
                })?;
                // Written with the scale applied.
                (written_name(folder, link, k), [1.0; 3])
            };
            // Fails only for an empty path (ruled out above) or an unknown current folder.
            let absolute = std::path::absolute(&file).map_err(|_| mesh_error("it cannot be made absolute"))?;
            // A mesh written with the URDF does not exist yet: named by the paths as they are.
            let relative = |base: &std::path::Path| match loadable(mesh) {
                true => relative_path(&absolute, base),
                false => pathdiff::diff_paths(&absolute, std::path::absolute(base).ok()?),
            };
            let named = opts.mesh_base.as_deref().and_then(relative).unwrap_or(absolute);
            let filename = named.to_str().ok_or_else(|| mesh_error("the path is not valid UTF-8"))?;
            ("mesh", vec![("filename", filename.to_string()), ("scale", numbers(scale))])
        }
    })
}

/// `file` as seen from the folder `base`, both with their links resolved (`..` from a linked
/// folder leads where the file system says, not where the text says); `None` when either does
/// not exist or no relative path leads there (another drive).
fn relative_path(file: &std::path::Path, base: &std::path::Path) -> Option<std::path::PathBuf> {
    let file = std::fs::canonicalize(file).ok()?;
    let base = std::fs::canonicalize(base).ok()?;
    pathdiff::diff_paths(file, base)
}

fn write_joint(doc: &mut Doc, joint: &Joint, parent: &str, child: &str) {
    let kind = match joint.kind {
        JointKind::Revolute => "revolute",
        JointKind::Continuous => "continuous",
        JointKind::Prismatic => "prismatic",
    };
    doc.open("joint", [("name", joint.name.as_str()), ("type", kind)]);
    write_origin(doc, &joint.parent_from_joint);
    doc.empty("parent", [("link", parent)]);
    doc.empty("child", [("link", child)]);
    doc.empty("axis", [("xyz", numbers(xyz(&joint.axis.into_inner())))]);
    let mut limit = Vec::with_capacity(4);
    // A continuous joint, and a joint without known bounds, get effort and velocity only.
    if let (Some([lower, upper]), false) = (joint.limits, joint.kind == JointKind::Continuous) {
        limit.push(("lower", super::number(lower)));
        limit.push(("upper", super::number(upper)));
    }
    limit.push(("effort", super::number(joint.max_effort.unwrap_or(0.0))));
    limit.push(("velocity", super::number(joint.max_velocity.unwrap_or(0.0))));
    doc.empty("limit", limit);
    doc.close("joint");
}

fn write_fixed_joint(doc: &mut Doc, name: &str, parent: &str, child: &str, parent_from_child: &Isometry3<f64>) {
    doc.open("joint", [("name", name), ("type", "fixed")]);
    write_origin(doc, parent_from_child);
    doc.empty("parent", [("link", parent)]);
    doc.empty("child", [("link", child)]);
    doc.close("joint");
}

fn write_origin(doc: &mut Doc, pose: &Isometry3<f64>) {
    doc.empty(
        "origin",
        [
            ("xyz", numbers(xyz(&pose.translation.vector))),
            ("rpy", numbers(rpy_of(&pose.rotation))),
        ],
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{from_design, Inertial, TriMesh};
    use nalgebra::{Matrix3, Translation3, Unit, UnitQuaternion, Vector3};
    use std::f64::consts::FRAC_PI_2;
    use std::path::{Path, PathBuf};

    /// Rotation error allowed after an rpy round trip (rad); measured worst 7e-16 on 200 000
    /// random rotations, half of them within 1e-16..1 rad of gimbal lock.
    const RPY_ROUND_TRIP_RAD: f64 = 1e-14;

    fn modular_model() -> Model {
        let text = r#"{"mode": "modular", "modules": ["direct", "L-short", "direct", "direct", "I-long"]}"#;
        let design = crate::design::parse(text, Path::new("modular.json")).expect("valid design");
        from_design(&design)
    }

    fn parse(text: &str) -> urdf_rs::Robot {
        urdf_rs::read_from_string(text).unwrap_or_else(|e| panic!("{e}\n{text}"))
    }

    fn rotation_of(rpy: &urdf_rs::Vec3) -> UnitQuaternion<f64> {
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2])
    }

    fn link_block<'a>(text: &'a str, name: &str) -> &'a str {
        let start = text.find(&format!(r#"<link name="{name}""#)).expect("link written");
        let tag_end = start + text[start..].find('>').expect("tag closed");
        if text[..tag_end].ends_with('/') {
            return &text[start..tag_end];
        }
        let end = start + text[start..].find("</link>").expect("link closed");
        &text[start..end]
    }

    #[test]
    fn modular_design_has_world_chain_and_tool() {
        let model = modular_model();
        let text = to_urdf(&model, &UrdfExportOptions::default()).expect("exports");
        let robot = parse(&text);
        assert_eq!(robot.links.len(), model.links.len() + 2, "{text}");
        assert_eq!(robot.joints.len(), model.joints.len() + 2, "{text}");
        assert_eq!(robot.links[0].name, "world");
        assert_eq!(robot.links.last().map(|l| l.name.as_str()), Some("tool"));
        assert_eq!(robot.joints[0].name, "world_to_base");
        assert_eq!(robot.joints[0].joint_type, urdf_rs::JointType::Fixed);
        let last = robot.joints.last().expect("tool joint");
        assert_eq!(last.name, "link5_to_tool");
        assert_eq!((last.parent.link.as_str(), last.child.link.as_str()), ("link5", "tool"));
        for (i, joint) in model.joints.iter().enumerate() {
            let written = &robot.joints[i + 1];
            assert_eq!(written.name, joint.name);
            assert_eq!(written.joint_type, urdf_rs::JointType::Revolute);
            assert_eq!(written.parent.link, model.links[i].name);
            assert_eq!(written.child.link, model.links[i + 1].name);
        }
        for (link, written) in model.links.iter().zip(&robot.links[1..]) {
            assert_eq!(written.collision.len(), link.colliders.len(), "{}", link.name);
        }
        assert!(!text.contains("<mujoco>"));
    }

    #[test]
    fn numbers_read_back_bit_identical() {
        let mut model = modular_model();
        model.world_from_base = Isometry3::from_parts(
            Translation3::new(0.1 + 0.2, -1.0 / 3.0, 1e-300),
            UnitQuaternion::from_euler_angles(0.3, -FRAC_PI_2, 0.4),
        );
        model.last_from_tool = Isometry3::from_parts(
            Translation3::new(2.0 / 3.0, 0.0, 0.07),
            UnitQuaternion::from_euler_angles(-2.0, FRAC_PI_2 - 1e-9, 1.0),
        );
        model.links[2].inertial = Some(Inertial {
            mass: 1.0 / 7.0,
            com: Vector3::new(0.1, 1.0 / 3.0, -5e-17),
            inertia: Matrix3::new(0.3, 1e-5, -2e-6, 1e-5, 0.2, 1.0 / 11.0, -2e-6, 1.0 / 11.0, 0.25),
        });
        model.joints[1].limits = Some([-2.0 / 3.0, 1.0 / 3.0]);
        model.joints[1].max_effort = Some(1.0 / 9.0);
        let text = to_urdf(&model, &UrdfExportOptions::default()).expect("exports");
        let robot = parse(&text);

        let same_pose = |written: &urdf_rs::Pose, expected: &Isometry3<f64>, what: &str| {
            let t = expected.translation.vector;
            assert_eq!(written.xyz.0, [t.x, t.y, t.z], "{what}");
            let angle = rotation_of(&written.rpy).angle_to(&expected.rotation);
            assert!(angle < RPY_ROUND_TRIP_RAD, "{what}: {angle} rad");
        };
        same_pose(&robot.joints[0].origin, &model.world_from_base, "world_from_base");
        same_pose(&robot.joints[6].origin, &model.last_from_tool, "last_from_tool");
        for (i, joint) in model.joints.iter().enumerate() {
            same_pose(&robot.joints[i + 1].origin, &joint.parent_from_joint, &joint.name);
            let axis = joint.axis.into_inner();
            assert_eq!(robot.joints[i + 1].axis.xyz.0, [axis.x, axis.y, axis.z]);
        }
        for (link, written) in model.links.iter().zip(&robot.links[1..]) {
            for (collider, collision) in link.colliders.iter().zip(&written.collision) {
                same_pose(&collision.origin, &collider.link_from_shape, &collider.label);
                assert_eq!(collision.name.as_deref(), Some(collider.label.as_str()));
            }
        }

        let inertial = model.links[2].inertial.as_ref().expect("set above");
        let written = &robot.links[3].inertial;
        assert_eq!(written.mass.value.to_bits(), inertial.mass.to_bits());
        assert_eq!(written.origin.xyz.0, [inertial.com.x, inertial.com.y, inertial.com.z]);
        let i = &written.inertia;
        let m = &inertial.inertia;
        assert_eq!(
            [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz],
            [m[(0, 0)], m[(0, 1)], m[(0, 2)], m[(1, 1)], m[(1, 2)], m[(2, 2)]]
        );
        let limit = &robot.joints[2].limit;
        assert_eq!([limit.lower, limit.upper], [-2.0 / 3.0, 1.0 / 3.0]);
        assert_eq!(limit.effort, 1.0 / 9.0);
        assert_eq!(Some(limit.velocity), model.joints[1].max_velocity);
    }

    #[test]
    fn rpy_is_exact_near_and_at_gimbal_lock() {
        for pitch in [FRAC_PI_2, -FRAC_PI_2, FRAC_PI_2 - 1e-7, -FRAC_PI_2 + 1e-12, 0.4, -3.0] {
            for (roll, yaw) in [(0.0, 0.0), (0.3, 0.4), (-2.5, 1.9), (3.1, -3.1)] {
                let rotation = UnitQuaternion::from_euler_angles(roll, pitch, yaw);
                let rpy = rpy_of(&rotation);
                let back = UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]);
                let angle = back.angle_to(&rotation);
                assert!(angle < RPY_ROUND_TRIP_RAD, "rpy ({roll}, {pitch}, {yaw}) -> {rpy:?}: {angle} rad");
            }
        }
    }

    #[test]
    fn only_links_with_mass_get_an_inertial() {
        let model = modular_model();
        assert!(model.links[0].inertial.is_none());
        let text = to_urdf(&model, &UrdfExportOptions::default()).expect("exports");
        for name in ["world", "base", "tool"] {
            assert!(!link_block(&text, name).contains("<inertial"), "{name}:\n{text}");
        }
        for link in &model.links[1..] {
            assert!(link_block(&text, &link.name).contains("<inertial>"), "{}:\n{text}", link.name);
        }
        assert_eq!(parse(&text).links.len(), model.links.len() + 2);
    }

    #[test]
    fn continuous_joint_limit_has_only_effort_and_velocity() {
        let mut model = modular_model();
        model.joints[0].kind = JointKind::Continuous;
        model.joints[0].limits = None;
        model.joints[0].max_effort = None;
        let text = to_urdf(&model, &UrdfExportOptions::default()).expect("exports");
        let robot = parse(&text);
        assert_eq!(robot.joints[1].joint_type, urdf_rs::JointType::Continuous);
        let velocity = model.joints[0].max_velocity.expect("design joints have a speed");
        let expected = format!(r#"<limit effort="0" velocity="{velocity}"/>"#);
        assert!(text.contains(&expected), "{expected} not in\n{text}");
    }

    #[test]
    fn mujoco_block_follows_the_robot_tag() {
        let model = modular_model();
        let opts = UrdfExportOptions {
            mujoco_block: true,
            ..Default::default()
        };
        let text = to_urdf(&model, &opts).expect("exports");
        let robot_tag_end = text.find('>').expect("robot tag");
        let after = text[robot_tag_end + 1..].trim_start();
        assert!(
            after.starts_with("<mujoco>\n    <compiler angle=\"radian\" fusestatic=\"false\""),
            "{text}"
        );
        assert_eq!(parse(&text).links.len(), model.links.len() + 2);
    }

    fn tetrahedron(file: PathBuf) -> Collider {
        let scale = [0.001, 0.002, 0.001];
        Collider {
            link_from_shape: Isometry3::translation(0.0, 0.0, 0.1),
            shape: Shape::Mesh(TriMesh {
                uri: "package://arm/meshes/part.stl".into(),
                file,
                scale,
                vertices: vec![[0.0; 3], [scale[0], 0.0, 0.0], [0.0, scale[1], 0.0], [0.0, 0.0, scale[2]]],
                triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            }),
            label: "<collision> 0 of link part".into(),
        }
    }

    #[test]
    fn mesh_is_referenced_by_absolute_path_with_scale() {
        let mut model = modular_model();
        model.links[3].colliders.push(tetrahedron(PathBuf::from("meshes/part.stl")));
        let text = to_urdf(&model, &UrdfExportOptions::default()).expect("exports");
        let robot = parse(&text);
        let collision = robot.links[4].collision.last().expect("mesh collider");
        let urdf_rs::Geometry::Mesh { filename, scale } = &collision.geometry else {
            panic!("not a mesh: {:?}", collision.geometry);
        };
        assert!(Path::new(filename).is_absolute(), "{filename}");
        assert!(filename.ends_with("meshes/part.stl"), "{filename}");
        assert_eq!(scale.map(|s| s.0), Some([0.001, 0.002, 0.001]));
        assert!(text.contains(r#"<collision name="&lt;collision&gt; 0 of link part">"#), "{text}");
    }

    #[cfg(unix)]
    #[test]
    fn rejects_mesh_path_that_is_not_utf8() {
        use std::os::unix::ffi::OsStrExt;
        let mut model = modular_model();
        let file = PathBuf::from(std::ffi::OsStr::from_bytes(b"/meshes/\xff.stl"));
        model.links[2].colliders.push(tetrahedron(file));
        let k = model.links[2].colliders.len() - 1;
        let error = to_urdf(&model, &UrdfExportOptions::default()).expect_err("non-UTF-8 path");
        assert!(
            matches!(&error, ExportError::MeshPath { link, collider, .. } if link == "link2" && *collider == k),
            "{error}"
        );
        assert!(error.to_string().contains("UTF-8"), "{error}");
    }

    #[test]
    fn base_named_world_at_origin_is_the_root() {
        let mut model = modular_model();
        model.links[0].name = "world".into();
        let text = to_urdf(&model, &UrdfExportOptions::default()).expect("exports");
        let robot = parse(&text);
        assert_eq!(robot.links.len(), model.links.len() + 1);
        assert_eq!(robot.joints[0].parent.link, "world");
        assert_eq!(robot.joints[0].name, model.joints[0].name);
    }

    #[test]
    fn rejects_link_named_like_the_tool() {
        let mut model = modular_model();
        model.links[2].name = "tool".into();
        let error = to_urdf(&model, &UrdfExportOptions::default()).expect_err("clash");
        assert!(
            matches!(&error, ExportError::DuplicateName { kind: "link", name, .. } if name == "tool"),
            "{error}"
        );
    }

    #[test]
    fn unit_axis_survives() {
        let mut model = modular_model();
        let axis = Unit::new_normalize(Vector3::new(1.0, 2.0, 3.0));
        model.joints[2].axis = axis;
        let robot = parse(&to_urdf(&model, &UrdfExportOptions::default()).expect("exports"));
        assert_eq!(robot.joints[3].axis.xyz.0, [axis.x, axis.y, axis.z]);
    }
}
