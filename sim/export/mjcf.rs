//! Model -> MJCF text, written through quick-xml ([`crate::xml::Doc`]).
//!
//! One body per link, nested along the chain: the base body at `world_from_base` (static, no
//! joint), every other body at its joint's `parent_from_joint` with a hinge or slide joint, its
//! inertial, and its colliders as geoms. The tool frame is a site `tool` in the last body. Meshes
//! are written inline as assets (vertices already scaled), so no mesh file is read and any format
//! the model loader understood works. One position actuator per joint, and contact exclusions for
//! the body pairs one joint connects.
//!
//! For a physics run, [`MjcfOptions`] also adds the world around the robot: static geoms in the
//! world body (a scenario's obstacles, named as given), a floor plane `floor`, contact
//! exclusions for further body pairs (the pairs a collision world does not check), gravity and
//! the integrator. MuJoCo collides cylinders approximately (see docs/collision.md, "Collision
//! checking"); the geometry written is still the exact one.
//!
//! Numbers are written with `{}` (shortest text that parses back to the same f64) and angles in
//! radians, declared in `<compiler>`. MuJoCo re-centres and re-orients mesh geoms at their
//! centroid and collides with their convex hull; the body frames and sites stay as written. So
//! for the engine runs ([`MjcfOptions::convex_pieces`]) a mesh is written as its convex pieces
//! ([`crate::convex`]), each piece its own hull.

use super::numbers;
use super::{check_chain, check_unique, ExportError};
use crate::convex::ConvexPiece;
use crate::frames::{wxyz, xyz};
use crate::model::{Collider, JointKind, Model, Shape};
use crate::xml::{Attributes, Doc, NO_ATTRIBUTES};
use nalgebra::Isometry3;
use std::sync::Arc;

/// Name of MuJoCo's world body; no other body may use it.
const WORLD_BODY: &str = "world";
/// Position gain used when [`MjcfOptions::kp`] is `None` (N m/rad for hinges, N/m for slides).
const DEFAULT_KP: f64 = 100.0;
/// Velocity gain used when [`MjcfOptions::kv`] is `None` (N m s/rad for hinges, N s/m for slides).
const DEFAULT_KV: f64 = 10.0;
/// Name of the floor plane geom.
const FLOOR_GEOM: &str = "floor";
/// The default class of a scene's obstacles.
const OBSTACLE_CLASS: &str = "obstacle";
/// Scene colours (`rgba`): a viewer tells robot, obstacles, floor and goal frames apart.
const ROBOT_RGBA: &str = "0.62 0.64 0.68 1";
const OBSTACLE_RGBA: &str = "0.85 0.5 0.25 0.6";
const FLOOR_RGBA: &str = "0.9 0.9 0.88 1";
const SITE_RGBA: &str = "0.2 0.7 0.3 0.8";
/// Prefix of the mesh assets of world colliders (`mesh_world_<k>`, `k` the collider's index).
const WORLD_MESH_PREFIX: &str = "mesh_world_";

/// Options for [`to_mjcf`].
#[derive(Debug, Clone)]
pub struct MjcfOptions {
    /// Simulation time step in seconds; default 0.001 s.
    pub timestep: f64,
    /// Position-actuator stiffness per joint, chain order (N m/rad for hinges, N/m for slides);
    /// default `None`: 100 for every joint.
    pub kp: Option<Vec<f64>>,
    /// Position-actuator damping per joint, chain order (N m s/rad for hinges, N s/m for
    /// slides); default `None`: 10 for every joint.
    pub kv: Option<Vec<f64>>,
    /// Write one `<position>` actuator per joint; default `true`.
    pub include_actuators: bool,
    /// Static geoms in the world body, each at `link_from_shape` in the world, named by its
    /// `label` (a scenario's obstacles); default none.
    pub world_colliders: Vec<Collider>,
    /// Height (m) of a floor plane geom `floor` covering everything below it; default `None`.
    pub floor_height: Option<f64>,
    /// Sites in the world body, `(name, world_from_site)` (a scenario's goal frames, for a
    /// viewer: sites take no part in contacts); default none.
    pub world_sites: Vec<(String, Isometry3<f64>)>,
    /// Body pairs (body names) whose contacts MuJoCo ignores, beyond the pairs one joint
    /// connects (always excluded); default none. A pair given twice is written once.
    pub excluded_body_pairs: Vec<(String, String)>,
    /// Geom pairs (geom names, `link/k`) MuJoCo collides explicitly (`<pair>`), whatever the
    /// body exclusions: the shape pairs still checked of a link pair whose other shape pairs
    /// overlap by construction; default none.
    pub explicit_geom_pairs: Vec<(String, String)>,
    /// Gravity along world -z (m/s^2); default 9.81.
    pub gravity_m_s2: f64,
    /// MuJoCo `integrator` option (`Euler`, `implicitfast`, `implicit`, `RK4`); default `None`:
    /// not written, MuJoCo's default (Euler).
    pub integrator: Option<String>,
    /// Write each mesh as its convex pieces ([`crate::convex`]), one asset and one geom per
    /// piece, rather than the whole mesh, which MuJoCo collides as its convex hull; a mesh VHACD
    /// cannot decompose is written whole. Default `false`: the file then describes the model
    /// exactly (read back, it is the same model, meshes and all); the engine runs set it.
    pub convex_pieces: bool,
    /// Colours for a viewer (`<default>` classes: the robot grey, obstacles orange and
    /// translucent, the floor light, sites green); default `false` (MuJoCo's own grey).
    pub colours: bool,
    /// `<keyframe>` keys, `(name, q)` with `q` in chain order (and the position actuators' `ctrl`
    /// set to it, so a viewer holds the pose); default none.
    pub keyframes: Vec<(String, Vec<f64>)>,
}

impl Default for MjcfOptions {
    fn default() -> Self {
        Self {
            timestep: 0.001,
            kp: None,
            kv: None,
            include_actuators: true,
            world_colliders: Vec::new(),
            floor_height: None,
            world_sites: Vec::new(),
            excluded_body_pairs: Vec::new(),
            explicit_geom_pairs: Vec::new(),
            gravity_m_s2: 9.81,
            integrator: None,
            convex_pieces: false,
            colours: false,
            keyframes: Vec::new(),
        }
    }
}

/// Writes a model as MJCF text.
///
/// Body, joint and actuator names are the model's link and joint names; geoms are named
/// `<link>/<k>` and mesh assets `mesh_<link>_<k>` after the collider's index `k` in its link. A
/// mesh written as convex pieces (see [`MjcfOptions::convex_pieces`]) has geoms `<link>/<k>/<p>`
/// and assets `mesh_<link>_<k>_<p>` for its pieces `p` (a world collider `<label>/<p>` and
/// `mesh_world_<k>_<p>`), preceded by a comment naming the mesh; explicit pairs naming such a
/// collider are written for each of its pieces. A
/// base link called `world` is MuJoCo's world body itself: its geoms go straight into
/// `<worldbody>` (inside a `<frame>` when `world_from_base` is not the identity) and its inertial,
/// which a static body does not need, is left out.
///
/// # Errors
/// [`ExportError::ChainShape`] for a model that is not a serial chain,
/// [`ExportError::MissingInertial`] for a moving link without mass properties,
/// [`ExportError::GainCount`] when `opts.kp` or `opts.kv` does not have one value per joint,
/// [`ExportError::DuplicateName`] when two bodies or two joints would share a name (including a
/// link other than the base called `world`), or two geoms (a world collider named like a link
/// geom, another world collider, or `floor`).
pub fn to_mjcf(model: &Model, opts: &MjcfOptions) -> Result<String, ExportError> {
    check_chain(model)?;
    // Without an inertial MuJoCo would derive the mass from the geoms at water density, or
    // make it zero; neither is the robot.
    if let Some((joint, link)) = model.massless_link() {
        return Err(ExportError::MissingInertial {
            robot: model.name.clone(),
            link: link.name.clone(),
            joint: joint.name.clone(),
        });
    }
    let kp = gains(model, "kp", opts.kp.as_deref(), DEFAULT_KP)?;
    let kv = gains(model, "kv", opts.kv.as_deref(), DEFAULT_KV)?;
    let base_is_world = model.links[0].name == WORLD_BODY;
    let body_names = model.links.iter().map(|l| l.name.as_str());
    let reserved = (!base_is_world).then_some(WORLD_BODY);
    check_unique(model, "MJCF", "body", reserved.into_iter().chain(body_names))?;
    check_unique(model, "MJCF", "joint", model.joints.iter().map(|j| j.name.as_str()))?;
    let pieces = Pieces::of(model, opts);
    let link_geoms: Vec<String> = model
        .links
        .iter()
        .enumerate()
        .flat_map(|(i, link)| (0..link.colliders.len()).map(move |k| (i, k, format!("{}/{k}", link.name))))
        .flat_map(|(i, k, name)| piece_names(&name, pieces.link(i, k)))
        .collect();
    let world_geoms: Vec<String> = opts
        .world_colliders
        .iter()
        .enumerate()
        .flat_map(|(k, c)| piece_names(&c.label, pieces.world(k)))
        .collect();
    let floor = opts.floor_height.map(|_| FLOOR_GEOM);
    check_unique(
        model,
        "MJCF",
        "site",
        std::iter::once("tool").chain(opts.world_sites.iter().map(|(name, _)| name.as_str())),
    )?;
    check_unique(
        model,
        "MJCF",
        "geom",
        link_geoms.iter().chain(&world_geoms).map(String::as_str).chain(floor),
    )?;

    let mut doc = Doc::new(2);
    doc.open("mujoco", [("model", model.name.as_str())]);
    doc.empty("compiler", [("angle", "radian"), ("autolimits", "true")]);
    let mut option = vec![
        ("timestep", super::number(opts.timestep)),
        ("gravity", numbers([0.0, 0.0, -opts.gravity_m_s2])),
    ];
    if let Some(name) = &opts.integrator {
        option.push(("integrator", name.clone()));
    }
    doc.empty("option", option);
    if opts.colours {
        doc.open("default", NO_ATTRIBUTES);
        doc.empty("geom", [("rgba", ROBOT_RGBA)]);
        doc.empty("site", [("rgba", SITE_RGBA)]);
        for (class, rgba) in [(OBSTACLE_CLASS, OBSTACLE_RGBA), (FLOOR_GEOM, FLOOR_RGBA)] {
            doc.open("default", [("class", class)]);
            doc.empty("geom", [("rgba", rgba)]);
            doc.close("default");
        }
        doc.close("default");
    }
    write_assets(&mut doc, model, &opts.world_colliders, &pieces);
    write_bodies(&mut doc, model, base_is_world, opts, &pieces);
    if opts.include_actuators && !model.joints.is_empty() {
        doc.open("actuator", NO_ATTRIBUTES);
        for ((joint, kp), kv) in model.joints.iter().zip(&kp).zip(&kv) {
            let name = joint.name.as_str();
            let (kp, kv) = (super::number(*kp), super::number(*kv));
            doc.empty("position", [("name", name), ("joint", name), ("kp", &kp), ("kv", &kv)]);
        }
        doc.close("actuator");
    }
    // Adjacent pairs first, then the extra ones not already written (either order).
    let mut pairs: Vec<(&str, &str)> = model
        .adjacent_link_pairs()
        .into_iter()
        .map(|(a, b)| (model.links[a].name.as_str(), model.links[b].name.as_str()))
        .collect();
    for (a, b) in &opts.excluded_body_pairs {
        let (a, b) = (a.as_str(), b.as_str());
        if !pairs.iter().any(|&(x, y)| (x, y) == (a, b) || (x, y) == (b, a)) {
            pairs.push((a, b));
        }
    }
    if !pairs.is_empty() || !opts.explicit_geom_pairs.is_empty() {
        doc.open("contact", NO_ATTRIBUTES);
        for (a, b) in &opts.explicit_geom_pairs {
            for geom1 in pieces.geoms_of(model, a) {
                for geom2 in pieces.geoms_of(model, b) {
                    doc.empty("pair", [("geom1", &geom1), ("geom2", &geom2)]);
                }
            }
        }
        for (body1, body2) in pairs {
            doc.empty("exclude", [("body1", body1), ("body2", body2)]);
        }
        doc.close("contact");
    }
    if !opts.keyframes.is_empty() {
        doc.open("keyframe", NO_ATTRIBUTES);
        for (name, q) in &opts.keyframes {
            if q.len() != model.dof() {
                return Err(ExportError::GainCount {
                    robot: model.name.clone(),
                    gain: "keyframe",
                    given: q.len(),
                    joints: model.dof(),
                });
            }
            let qpos = numbers(q.iter().copied());
            let mut key = vec![("name", name.as_str()), ("qpos", qpos.as_str())];
            if opts.include_actuators {
                key.push(("ctrl", qpos.as_str()));
            }
            doc.empty("key", key);
        }
        doc.close("keyframe");
    }
    doc.close("mujoco");
    Ok(doc.finish())
}

/// One gain per joint: the given ones (checked for length) or the default for all.
fn gains(model: &Model, gain: &'static str, given: Option<&[f64]>, default: f64) -> Result<Vec<f64>, ExportError> {
    match given {
        None => Ok(vec![default; model.dof()]),
        Some(values) if values.len() == model.dof() => Ok(values.to_vec()),
        Some(values) => Err(ExportError::GainCount {
            robot: model.name.clone(),
            gain,
            given: values.len(),
            joints: model.dof(),
        }),
    }
}

/// The convex pieces of every mesh collider written as pieces; `None` for the others.
struct Pieces {
    links: Vec<Vec<Option<Arc<Vec<ConvexPiece>>>>>,
    world: Vec<Option<Arc<Vec<ConvexPiece>>>>,
}

impl Pieces {
    fn of(model: &Model, opts: &MjcfOptions) -> Self {
        let all = || model.links.iter().flat_map(|l| &l.colliders).chain(&opts.world_colliders);
        let of = |collider: &Collider| match (&collider.shape, opts.convex_pieces) {
            (Shape::Mesh(mesh), true) => crate::convex::pieces(mesh),
            _ => None,
        };
        if opts.convex_pieces {
            crate::convex::prepare(all().filter_map(|c| match &c.shape {
                Shape::Mesh(mesh) => Some(mesh),
                _ => None,
            }));
        }
        Self {
            links: model.links.iter().map(|l| l.colliders.iter().map(of).collect()).collect(),
            world: opts.world_colliders.iter().map(of).collect(),
        }
    }

    fn link(&self, link: usize, k: usize) -> Option<&[ConvexPiece]> {
        self.links.get(link)?.get(k)?.as_deref().map(Vec::as_slice)
    }

    fn world(&self, k: usize) -> Option<&[ConvexPiece]> {
        self.world.get(k)?.as_deref().map(Vec::as_slice)
    }

    /// The geoms written for the link geom named `name` (`<link>/<k>`): its pieces', or itself.
    fn geoms_of(&self, model: &Model, name: &str) -> Vec<String> {
        let found = model.links.iter().enumerate().find_map(|(i, link)| {
            let k: usize = name.strip_prefix(link.name.as_str())?.strip_prefix('/')?.parse().ok()?;
            (k < link.colliders.len()).then(|| self.link(i, k))
        });
        piece_names(name, found.flatten())
    }
}

/// The geom (or asset) names of a collider named `name`: one per piece, `<name>/<p>` (or
/// `<name>_<p>`), or `name` itself when it is written whole.
fn piece_names(name: &str, pieces: Option<&[ConvexPiece]>) -> Vec<String> {
    piece_names_with(name, '/', pieces)
}

fn piece_names_with(name: &str, separator: char, pieces: Option<&[ConvexPiece]>) -> Vec<String> {
    match pieces {
        Some(pieces) => (0..pieces.len()).map(|p| format!("{name}{separator}{p}")).collect(),
        None => vec![name.to_string()],
    }
}

fn write_assets(doc: &mut Doc, model: &Model, world_colliders: &[Collider], pieces: &Pieces) {
    // (asset name, collider, its pieces) of every mesh collider, links first.
    let link_meshes = model.links.iter().enumerate().flat_map(|(i, link)| {
        link.colliders
            .iter()
            .enumerate()
            .map(move |(k, collider)| (mesh_name(&link.name, k), collider, pieces.link(i, k)))
    });
    let world_meshes = world_colliders
        .iter()
        .enumerate()
        .map(|(k, collider)| (format!("{WORLD_MESH_PREFIX}{k}"), collider, pieces.world(k)));
    let meshes: Vec<_> = link_meshes
        .chain(world_meshes)
        .filter(|(_, collider, _)| matches!(collider.shape, Shape::Mesh(_)))
        .collect();
    if meshes.is_empty() {
        return;
    }
    let asset = |doc: &mut Doc, name: &str, vertices: &[[f64; 3]], triangles: &[[u32; 3]]| {
        // MuJoCo reads mesh vertices as f32 and refuses one below its smallest normal number
        // ("number is too large": the ROBOTIS Open Manipulator's STLs hold 1.5e-40 m, noise
        // about 0): those are written as 0.
        let flushed = vertices
            .iter()
            .flatten()
            .map(|&v| if v.abs() < f64::from(f32::MIN_POSITIVE) { 0.0 } else { v });
        let vertex = numbers(flushed);
        let face = triangles.iter().flatten().map(u32::to_string).collect::<Vec<_>>().join(" ");
        doc.empty("mesh", [("name", name), ("vertex", &vertex), ("face", &face)]);
    };
    doc.open("asset", NO_ATTRIBUTES);
    for (name, collider, pieces) in meshes {
        let Shape::Mesh(mesh) = &collider.shape else {
            continue;
        };
        match pieces {
            None => asset(doc, &name, &mesh.vertices, &mesh.triangles),
            Some(pieces) => {
                doc.comment(&format!("{}: convex pieces of {}", collider.label, mesh.uri));
                for (piece_name, piece) in piece_names_with(&name, '_', Some(pieces)).iter().zip(pieces) {
                    asset(doc, piece_name, &piece.vertices, &piece.triangles);
                }
            }
        }
    }
    doc.close("asset");
}

/// The bodies, nested: each link's body is opened inside its parent's and all are closed at the
/// end, innermost first.
fn write_bodies(doc: &mut Doc, model: &Model, base_is_world: bool, opts: &MjcfOptions, pieces: &Pieces) {
    doc.open("worldbody", NO_ATTRIBUTES);
    // The world's own geoms come first, outside any base frame: their poses are world poses.
    if let Some(height) = opts.floor_height {
        let pos = numbers([0.0, 0.0, height]);
        let mut floor = vec![("name", FLOOR_GEOM), ("type", "plane"), ("pos", &pos), ("size", "0 0 1")];
        if opts.colours {
            floor.push(("class", FLOOR_GEOM));
        }
        doc.empty("geom", floor);
    }
    let class = opts.colours.then_some(OBSTACLE_CLASS);
    for (k, collider) in opts.world_colliders.iter().enumerate() {
        let mesh = format!("{WORLD_MESH_PREFIX}{k}");
        write_geoms(doc, &collider.label, &mesh, collider, pieces.world(k), class);
    }
    for (name, world_from_site) in &opts.world_sites {
        let mut site = vec![("name", name.clone())];
        site.extend(pose(world_from_site));
        site.push(("size", "0.01".into()));
        doc.empty("site", site);
    }
    let mut closing = Vec::with_capacity(model.links.len());
    for (i, link) in model.links.iter().enumerate() {
        let parent_from_body = match i {
            0 => &model.world_from_base,
            _ => &model.joints[i - 1].parent_from_joint,
        };
        let is_world = i == 0 && base_is_world;
        if is_world {
            if *parent_from_body != Isometry3::identity() {
                doc.open("frame", pose(parent_from_body));
                closing.push("frame");
            }
        } else {
            let mut body = vec![("name", link.name.clone())];
            body.extend(pose(parent_from_body));
            doc.open("body", body);
            closing.push("body");
        }

        if i > 0 {
            let joint = &model.joints[i - 1];
            let kind = match joint.kind {
                JointKind::Revolute | JointKind::Continuous => "hinge",
                JointKind::Prismatic => "slide",
            };
            let limits = match (joint.kind, joint.limits) {
                (JointKind::Continuous, _) | (_, None) => ("limited", "false".to_string()),
                (_, Some([lower, upper])) => ("range", numbers([lower, upper])),
            };
            let axis = numbers(joint.axis.iter().copied());
            doc.empty(
                "joint",
                [
                    ("name", joint.name.as_str()),
                    ("type", kind),
                    ("axis", &axis),
                    (limits.0, &limits.1),
                ],
            );
        }
        if let (Some(inertial), false) = (&link.inertial, is_world) {
            let i = &inertial.inertia;
            let full = numbers([i[(0, 0)], i[(1, 1)], i[(2, 2)], i[(0, 1)], i[(0, 2)], i[(1, 2)]]);
            let (pos, mass) = (numbers(xyz(&inertial.com)), super::number(inertial.mass));
            doc.empty("inertial", [("pos", &pos), ("mass", &mass), ("fullinertia", &full)]);
        }
        for (k, collider) in link.colliders.iter().enumerate() {
            let (name, mesh) = (format!("{}/{k}", link.name), mesh_name(&link.name, k));
            write_geoms(doc, &name, &mesh, collider, pieces.link(i, k), None);
        }
        if i == model.links.len() - 1 {
            let mut site = vec![("name", "tool".to_string())];
            site.extend(pose(&model.last_from_tool));
            doc.empty("site", site);
        }
    }
    while let Some(tag) = closing.pop() {
        doc.close(tag);
    }
    doc.close("worldbody");
}

/// The geoms of one collider: itself, or one per convex piece (each on its own asset, all at
/// the collider's pose: the pieces are in the mesh's frame).
fn write_geoms(doc: &mut Doc, name: &str, mesh: &str, collider: &Collider, pieces: Option<&[ConvexPiece]>, class: Option<&str>) {
    let names = piece_names(name, pieces);
    let meshes = piece_names_with(mesh, '_', pieces);
    for (name, mesh) in names.iter().zip(&meshes) {
        let mut attributes = geom_attributes(name, mesh, collider);
        if let Some(class) = class {
            attributes.push(("class", class.to_string()));
        }
        doc.empty("geom", attributes);
    }
}

/// A `<geom>` named `name` at the collider's pose; a mesh refers to the asset `mesh`.
fn geom_attributes(name: &str, mesh: &str, collider: &Collider) -> Attributes {
    let (kind, shape) = match &collider.shape {
        Shape::Sphere { radius } => ("sphere", ("size", super::number(*radius))),
        Shape::Cylinder { radius, length } => ("cylinder", ("size", numbers([*radius, length / 2.0]))),
        Shape::Capsule { radius, length } => ("capsule", ("size", numbers([*radius, length / 2.0]))),
        Shape::Box { half_extents } => ("box", ("size", numbers(*half_extents))),
        Shape::Mesh(_) => ("mesh", ("mesh", mesh.to_string())),
    };
    let mut attributes = vec![("name", name.to_string()), ("type", kind.to_string()), shape];
    attributes.extend(pose(&collider.link_from_shape));
    attributes
}

fn mesh_name(link: &str, k: usize) -> String {
    format!("mesh_{link}_{k}")
}

/// `pos="x y z" quat="w x y z"` of a pose in its parent frame.
fn pose(parent_from_child: &Isometry3<f64>) -> [(&'static str, String); 2] {
    [
        ("pos", numbers(xyz(&parent_from_child.translation.vector))),
        ("quat", numbers(wxyz(&parent_from_child.rotation))),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{from_design, TriMesh};
    use std::path::{Path, PathBuf};

    fn modular_model() -> Model {
        let text = r#"{"mode": "modular", "modules": ["direct", "L-short", "direct", "direct", "I-long"]}"#;
        let design = crate::design::parse(text, Path::new("modular.json")).expect("valid design");
        from_design(&design)
    }

    fn body_block<'a>(text: &'a str, name: &str) -> &'a str {
        let start = text.find(&format!(r#"<body name="{name}""#)).expect("body written");
        &text[start..]
    }

    #[test]
    fn modular_design_has_tool_site_actuators_and_exclusions() {
        let model = modular_model();
        let text = to_mjcf(&model, &MjcfOptions::default()).expect("exports");
        assert!(text.starts_with(&format!(r#"<mujoco model="{}">"#, model.name)), "{text}");
        assert!(text.contains(r#"<compiler angle="radian" autolimits="true"/>"#));
        assert!(text.contains(r#"<option timestep="0.001" gravity="0 0 -9.81"/>"#));
        assert_eq!(text.matches(r#"<site name="tool""#).count(), 1, "{text}");
        assert_eq!(text.matches("<position ").count(), model.dof(), "{text}");
        assert_eq!(text.matches("<joint ").count(), model.dof(), "{text}");
        assert_eq!(text.matches(r#"type="hinge""#).count(), model.dof(), "{text}");
        for joint in &model.joints {
            let actuator = format!(r#"<position name="{0}" joint="{0}" kp="100" kv="10"/>"#, joint.name);
            assert!(text.contains(&actuator), "{actuator} not in\n{text}");
        }
        for (a, b) in model.adjacent_link_pairs() {
            let exclude = format!(r#"<exclude body1="{}" body2="{}"/>"#, model.links[a].name, model.links[b].name);
            assert!(text.contains(&exclude), "{exclude} not in\n{text}");
        }
        assert_eq!(text.matches("<exclude ").count(), model.dof());
        assert_eq!(text.matches("<body ").count(), model.links.len());
        assert_eq!(text.matches("</body>").count(), model.links.len());
        assert!(!text.contains("<asset>"));
    }

    #[test]
    fn base_body_is_static_and_the_site_is_in_the_last_body() {
        let model = modular_model();
        let text = to_mjcf(&model, &MjcfOptions::default()).expect("exports");
        let base = body_block(&text, "base");
        let first_child = base.find(r#"<body name="link1""#).expect("link1 nested in base");
        assert!(!base[..first_child].contains("<joint"), "{text}");
        let last = body_block(&text, "link5");
        assert!(last.contains(r#"<site name="tool""#));
        assert!(!last[1..].contains("<body "), "the last body has no child");
        assert!(last.contains(r#"<joint name="joint5" type="hinge""#));
        assert!(last.contains("fullinertia="));
    }

    #[test]
    fn geoms_are_named_after_link_and_index() {
        let model = modular_model();
        let text = to_mjcf(&model, &MjcfOptions::default()).expect("exports");
        for link in &model.links {
            for k in 0..link.colliders.len() {
                assert!(text.contains(&format!(r#"<geom name="{}/{k}" "#, link.name)), "{}/{k}", link.name);
            }
        }
        // The joint module housing: a 0.12 m x 0.12 m cylinder.
        assert!(text.contains(r#"<geom name="link1/0" type="cylinder" size="0.06 0.06""#), "{text}");
    }

    #[test]
    fn floats_keep_full_precision() {
        let mut model = modular_model();
        model.last_from_tool = Isometry3::translation(0.1 + 0.2, -1.0 / 3.0, 0.0);
        model.joints[0].limits = Some([-2.0 / 3.0, 1e-20]);
        let text = to_mjcf(&model, &MjcfOptions::default()).expect("exports");
        assert!(
            text.contains(r#"<site name="tool" pos="0.30000000000000004 -0.3333333333333333 0" quat="1 0 0 0"/>"#),
            "{text}"
        );
        // Tiny magnitudes in exponent form (MuJoCo refuses a number written with every zero).
        let range = format!(r#"range="{} 1e-20""#, -2.0 / 3.0);
        assert!(text.contains(&range), "{range} not in\n{text}");
        let parsed: Vec<f64> = range[7..range.len() - 1].split(' ').map(|v| v.parse().expect("number")).collect();
        assert_eq!(parsed, [-2.0 / 3.0, 1e-20]);
    }

    #[test]
    fn rejects_moving_link_without_inertial() {
        let mut model = modular_model();
        model.links[3].inertial = None;
        let error = to_mjcf(&model, &MjcfOptions::default()).expect_err("massless link");
        assert!(
            matches!(&error, ExportError::MissingInertial { link, joint, .. } if link == "link3" && joint == "joint3"),
            "{error}"
        );
        assert!(error.to_string().contains("link `link3`"), "{error}");
    }

    #[test]
    fn continuous_joint_is_unlimited_and_prismatic_is_a_slide() {
        let mut model = modular_model();
        model.joints[0].kind = JointKind::Continuous;
        model.joints[0].limits = None;
        model.joints[1].kind = JointKind::Prismatic;
        model.joints[1].limits = Some([0.0, 0.5]);
        let text = to_mjcf(&model, &MjcfOptions::default()).expect("exports");
        let axis = numbers(model.joints[0].axis.iter().copied());
        assert!(
            text.contains(&format!(r#"<joint name="joint1" type="hinge" axis="{axis}" limited="false"/>"#)),
            "{text}"
        );
        assert!(
            text.contains(r#"<joint name="joint2" type="slide" axis="0 0 1" range="0 0.5"/>"#),
            "{text}"
        );
    }

    fn with_tetrahedron(model: &mut Model) -> usize {
        let vertices = vec![[0.0; 3], [0.001, 0.0, 0.0], [0.0, 0.002, 0.0], [0.0, 0.0, 0.001]];
        model.links[2].colliders.push(Collider {
            link_from_shape: Isometry3::translation(0.0, 0.0, 0.1),
            shape: Shape::Mesh(TriMesh {
                uri: "meshes/part.dae".into(),
                file: PathBuf::from("/nonexistent/part.dae"),
                scale: [0.001, 0.002, 0.001],
                vertices,
                triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            }),
            label: "part".into(),
        });
        model.links[2].colliders.len() - 1
    }

    #[test]
    fn mesh_collider_is_written_inline() {
        let mut model = modular_model();
        let k = with_tetrahedron(&mut model);
        let text = to_mjcf(&model, &MjcfOptions::default()).expect("exports");
        let asset = format!(r#"<mesh name="mesh_link2_{k}" vertex="0 0 0 0.001 0 0 0 0.002 0 0 0 0.001" face="0 2 1 0 1 3 0 3 2 1 2 3"/>"#);
        assert!(text.contains(&asset), "{asset} not in\n{text}");
        assert!(
            text.contains(&format!(r#"<geom name="link2/{k}" type="mesh" mesh="mesh_link2_{k}""#)),
            "{text}"
        );
        assert!(!text.contains("part.dae"), "no file is referenced");
    }

    #[test]
    fn mesh_collider_is_written_as_convex_pieces() {
        let mut model = modular_model();
        let k = with_tetrahedron(&mut model);
        let opts = MjcfOptions {
            explicit_geom_pairs: vec![(format!("link2/{k}"), "link4/0".into())],
            convex_pieces: true,
            ..MjcfOptions::default()
        };
        let text = to_mjcf(&model, &opts).expect("exports");
        assert!(text.contains("<!-- part: convex pieces of meshes/part.dae -->"), "{text}");
        assert!(
            !text.contains(&format!(r#"name="mesh_link2_{k}""#)),
            "the whole mesh is not written"
        );
        // VHACD cuts even a tetrahedron (it splits by voxels); every piece has its asset, its
        // geom at the collider's pose and its explicit pair.
        let pieces = text.matches(&format!(r#"<mesh name="mesh_link2_{k}_"#)).count();
        assert!(pieces >= 1, "{text}");
        for p in 0..pieces {
            let geom = format!(r#"<geom name="link2/{k}/{p}" type="mesh" mesh="mesh_link2_{k}_{p}" pos="0 0 0.1""#);
            assert!(text.contains(&geom), "{geom} not in\n{text}");
            let pair = format!(r#"<pair geom1="link2/{k}/{p}" geom2="link4/0"/>"#);
            assert!(text.contains(&pair), "{pair} not in\n{text}");
        }
        assert_eq!(text.matches("<pair ").count(), pieces, "{text}");
        assert!(!text.contains(&format!(r#"name="link2/{k}" "#)), "{text}");
    }

    #[test]
    fn gains_come_from_options_and_must_match_the_joints() {
        let model = modular_model();
        let opts = MjcfOptions {
            kp: Some(vec![1.0, 2.0, 3.0, 4.0, 5.5]),
            timestep: 0.002,
            ..MjcfOptions::default()
        };
        let text = to_mjcf(&model, &opts).expect("exports");
        assert!(
            text.contains(r#"<position name="joint5" joint="joint5" kp="5.5" kv="10"/>"#),
            "{text}"
        );
        assert!(text.contains(r#"timestep="0.002""#));

        let opts = MjcfOptions {
            kv: Some(vec![1.0; 3]),
            ..MjcfOptions::default()
        };
        let error = to_mjcf(&model, &opts).expect_err("3 gains for 5 joints");
        assert!(
            matches!(
                error,
                ExportError::GainCount {
                    gain: "kv",
                    given: 3,
                    joints: 5,
                    ..
                }
            ),
            "{error}"
        );
    }

    #[test]
    fn actuators_can_be_left_out() {
        let opts = MjcfOptions {
            include_actuators: false,
            ..MjcfOptions::default()
        };
        let text = to_mjcf(&modular_model(), &opts).expect("exports");
        assert!(!text.contains("<actuator>"), "{text}");
        assert!(text.contains("<contact>"));
    }

    #[test]
    fn base_named_world_is_the_world_body() {
        let mut model = modular_model();
        model.links[0].name = "world".into();
        model.world_from_base = Isometry3::translation(0.0, 0.0, 0.5);
        let text = to_mjcf(&model, &MjcfOptions::default()).expect("exports");
        assert!(!text.contains(r#"<body name="world""#), "{text}");
        assert!(text.contains(r#"<frame pos="0 0 0.5" quat="1 0 0 0">"#), "{text}");
        assert!(text.contains(r#"<exclude body1="world" body2="link1"/>"#), "{text}");
        assert_eq!(text.matches("</frame>").count(), 1);

        model.links[2].name = "world".into();
        let error = to_mjcf(&model, &MjcfOptions::default()).expect_err("two world bodies");
        assert!(
            matches!(&error, ExportError::DuplicateName { kind: "body", name, .. } if name == "world"),
            "{error}"
        );
    }

    #[test]
    fn world_geoms_floor_exclusions_gravity_and_integrator_are_written() {
        let model = modular_model();
        let opts = MjcfOptions {
            world_colliders: vec![Collider {
                link_from_shape: Isometry3::translation(0.5, 0.0, 0.25),
                shape: Shape::Box {
                    half_extents: [0.1, 0.2, 0.25],
                },
                label: "shelf".into(),
            }],
            floor_height: Some(-0.01),
            excluded_body_pairs: vec![("link3".into(), "link1".into()), ("link1".into(), "link2".into())],
            gravity_m_s2: 3.5,
            integrator: Some("implicitfast".into()),
            ..MjcfOptions::default()
        };
        let text = to_mjcf(&model, &opts).expect("exports");
        assert!(
            text.contains(r#"<option timestep="0.001" gravity="0 0 -3.5" integrator="implicitfast"/>"#),
            "{text}"
        );
        assert!(
            text.contains(r#"<geom name="floor" type="plane" pos="0 0 -0.01" size="0 0 1"/>"#),
            "{text}"
        );
        assert!(
            text.contains(r#"<geom name="shelf" type="box" size="0.1 0.2 0.25" pos="0.5 0 0.25" quat="1 0 0 0"/>"#),
            "{text}"
        );
        assert!(text.contains(r#"<exclude body1="link3" body2="link1"/>"#), "{text}");
        // link1-link2 is adjacent and already excluded: written once.
        assert_eq!(text.matches("<exclude ").count(), model.dof() + 1, "{text}");

        let opts = MjcfOptions {
            floor_height: Some(0.0),
            world_colliders: vec![Collider {
                link_from_shape: Isometry3::identity(),
                shape: Shape::Sphere { radius: 0.1 },
                label: "floor".into(),
            }],
            ..MjcfOptions::default()
        };
        let error = to_mjcf(&model, &opts).expect_err("two geoms named floor");
        assert!(
            matches!(&error, ExportError::DuplicateName { kind: "geom", name, .. } if name == "floor"),
            "{error}"
        );
    }

    #[test]
    fn names_are_escaped() {
        let mut model = modular_model();
        model.name = "arm \"A\" & <B>".into();
        let text = to_mjcf(&model, &MjcfOptions::default()).expect("exports");
        assert!(text.starts_with(r#"<mujoco model="arm &quot;A&quot; &amp; &lt;B&gt;">"#), "{text}");
    }
}
