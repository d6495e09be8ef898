//! MJCF -> Model, through MuJoCo.
//!
//! MuJoCo (mujoco-rs) loads and compiles the file, so every MJCF feature MuJoCo understands
//! (defaults, `<frame>`, `fromto`, `<include>`, degrees, Euler conventions, mesh files) is
//! resolved by MuJoCo itself; this module reads the compiled `mjModel`, whose arrays give each
//! body, joint, geom and inertia in one canonical form (radians, quaternions, principal inertia).
//!
//! Chain: by default the arm, the longest chain of bodies carrying a joint that is not a gripper
//! joint; with `--tip` the bodies carrying a joint above the tip's body (see `chain`). Each
//! carries exactly one hinge or slide joint. Jointless bodies, and moving bodies off the chain
//! (held at their joints' reference position), are merged into the nearest chain body above
//! them, or into the base. The base link is the body holding the first chain body (the world
//! body when that body hangs from `<worldbody>` directly). A link frame is its body frame moved
//! to the joint's `pos`, so the joint axis passes through the link origin as the model requires;
//! geoms, inertia and sites move with it. The tool frame is the `--tip` body's or site's frame;
//! by default the site named `tool` when there is one (on the last chain body or a jointless
//! body below it), else the body or site rigidly on the last chain body named like a tool frame,
//! else the last chain body's frame. Every default is said in `ModelSource::Mjcf::choices`.

mod chain;
mod checks;
mod geoms;
mod joint;

use chain::Tool;

use super::{Diagnostic, Inertial, Joint, Link, Model, ModelError, ModelSource};
use mujoco_rs::mujoco_c::{mj_deleteModel, mj_loadXML, mjtJoint};
use mujoco_rs::prelude::*;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use std::path::Path;

/// Name of the site that marks the tool frame.
pub const TOOL_SITE: &str = "tool";

/// Reads an MJCF file into a model (see the module docs for how bodies become links).
///
/// # Errors
/// [`ModelError::MjcfLoad`] with MuJoCo's own message when MuJoCo cannot load the file (bad XML,
/// unknown element, missing mesh file, a linked MuJoCo of another version);
/// [`ModelError::UnsupportedMjcf`] naming the body, joint, geom or site for what a serial model
/// cannot hold: free or ball joints, two joints in one chain body, longest chains that tie, an unlimited
/// slide joint, a joint `ref`, a plane, height field or SDF geom on a moving body, a `tool` site
/// the last joint does not move, or no joint at all; [`ModelError::BadInertia`] for a moving link
/// without usable mass.
pub fn from_mjcf(path: &Path) -> Result<Model, ModelError> {
    from_mjcf_to(path, None)
}

/// [`from_mjcf`] with the chain ending at `tip`: a body (the tool frame is its frame) or a site
/// (the site's frame); the chain is the moving bodies above it, and moving bodies off it are held
/// at their joints' reference position like jointless ones. `None` is [`from_mjcf`]'s default.
///
/// # Errors
/// As [`from_mjcf`]; [`ModelError::UnsupportedMjcf`] for a `tip` that names no body or site, or
/// one no joint moves.
pub fn from_mjcf_to(path: &Path, tip: Option<&str>) -> Result<Model, ModelError> {
    // Loads MuJoCo, and checks its version first: mujoco-rs panics on a mismatch.
    crate::mujoco::check_version().map_err(|e| ModelError::MjcfLoad {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    checks::before_load(path)?;
    let mj = MjModel::from_xml(path).map_err(|e| ModelError::MjcfLoad {
        path: path.to_path_buf(),
        message: {
            let message = full_load_error(path).unwrap_or_else(|| e.to_string());
            // MuJoCo names a missing asset as written; say where relative names are looked up.
            match (message.contains("Error opening file"), path.parent()) {
                (true, Some(dir)) => format!(
                    "{message} (relative asset paths are resolved against {} and its <compiler meshdir/assetdir>)",
                    dir.display()
                ),
                _ => message,
            }
        },
    })?;
    Reader { path, mj: &mj }.build(tip)
}

/// MuJoCo's whole load error for `path`: mujoco-rs keeps only its first 99 characters, which
/// cuts off the element and line MuJoCo names at the end. `None` when the file loads after all.
fn full_load_error(path: &Path) -> Option<String> {
    let text = path.to_str()?;
    let file = std::ffi::CString::new(text).ok()?;
    let mut buffer = vec![0 as std::os::raw::c_char; 4096];
    // SAFETY: `file` is NUL-terminated, no VFS is passed, and `buffer` is writable for the
    // length given; MuJoCo NUL-terminates what it writes.
    let model = unsafe { mj_loadXML(file.as_ptr(), std::ptr::null(), buffer.as_mut_ptr(), buffer.len() as i32) };
    if !model.is_null() {
        // SAFETY: `model` was just returned by mj_loadXML and is not used afterwards.
        unsafe { mj_deleteModel(model) };
        return None;
    }
    // SAFETY: zero-initialised, and MuJoCo writes a NUL-terminated message within the buffer.
    let message = unsafe { std::ffi::CStr::from_ptr(buffer.as_ptr()) };
    Some(message.to_string_lossy().trim().to_string()).filter(|m| !m.is_empty())
}

/// Reads one compiled model; `path` names it in messages.
pub(super) struct Reader<'a> {
    pub(super) path: &'a Path,
    pub(super) mj: &'a MjModel,
}

/// Where every body ended up.
pub(super) struct Layout {
    /// Chain index of the link each body is merged into (0: the base).
    pub(super) owner: Vec<usize>,
    /// Each body's frame in its owner link's frame.
    pub(super) link_from_body: Vec<Isometry3<f64>>,
}

impl Reader<'_> {
    /// Name of an object, or `#id` for an unnamed one.
    pub(super) fn name(&self, kind: MjtObjBase, id: usize) -> String {
        match self.mj.id_to_name(kind, id) {
            Some(name) if !name.is_empty() => name.to_string(),
            _ => format!("#{id}"),
        }
    }

    pub(super) fn body(&self, id: usize) -> String {
        format!("body `{}`", self.name(MjtObjBase::mjOBJ_BODY, id))
    }

    pub(super) fn joint_element(&self, joint: usize) -> String {
        let body = self.mj.jnt_bodyid()[joint] as usize;
        format!("joint `{}` of {}", self.name(MjtObjBase::mjOBJ_JOINT, joint), self.body(body))
    }

    pub(super) fn unsupported(&self, element: String, problem: String) -> ModelError {
        ModelError::UnsupportedMjcf {
            path: self.path.to_path_buf(),
            element,
            problem,
        }
    }

    fn build(&self, tip: Option<&str>) -> Result<Model, ModelError> {
        self.check_numbers()?;
        let mj = self.mj;
        let body_count = mj.ffi().nbody as usize;
        let parent = |b: usize| mj.body_parentid()[b] as usize;

        // Joint types first: a ball or free joint is the clearest message for a floating robot.
        for (joint, kind) in mj.jnt_type().iter().enumerate() {
            let what = match kind {
                mjtJoint::mjJNT_FREE => "a free joint (a floating body)",
                mjtJoint::mjJNT_BALL => "a ball joint",
                _ => continue,
            };
            return Err(self.unsupported(
                self.joint_element(joint),
                format!("is {what}; only hinge and slide joints can be on a serial chain"),
            ));
        }
        let all_moving: Vec<usize> = (1..body_count).filter(|&b| mj.body_jntnum()[b] > 0).collect();
        if all_moving.is_empty() {
            return Err(self.unsupported("<worldbody>".into(), "has no hinge or slide joint: nothing moves".into()));
        }
        let mut choices = Vec::new();
        let (moving, tool) = match tip {
            Some(name) => self.chain_to(name, &mut choices)?,
            None => self.default_chain(&all_moving, &mut choices)?,
        };
        for &body in &moving {
            let count = mj.body_jntnum()[body];
            if count > 1 {
                let first = mj.body_jntadr()[body] as usize;
                let names: Vec<String> = (first..first + count as usize)
                    .map(|j| format!("`{}`", self.name(MjtObjBase::mjOBJ_JOINT, j)))
                    .collect();
                return Err(self.unsupported(
                    self.body(body),
                    format!(
                        "has {count} joints ({}); each body of a serial chain has one hinge or slide joint (split it into one body per joint)",
                        names.join(", ")
                    ),
                ));
            }
        }
        let first = moving[0];
        let layout = self.layout(&moving);
        let joints = moving
            .iter()
            .enumerate()
            .map(|(k, &body)| self.joint(body, &layout, k))
            .collect::<Result<Vec<_>, _>>()?;
        let mut diagnostics = Vec::new();
        let mut links = self.links(&moving, &layout, &joints, &mut diagnostics)?;
        for joint in &joints {
            if let Some([lower, upper]) = joint.limits {
                if lower == upper {
                    diagnostics.push(Diagnostic {
                        path: self.path.to_path_buf(),
                        element: format!("joint `{}` range", joint.name),
                        message: format!("lower = upper = {lower}: the joint cannot move"),
                    });
                }
            }
        }
        let last_from_tool = self.tool(tool, &moving, &layout)?;

        // The paper's capsule approximation, as for every robot read from a file.
        super::add_bones(&mut links, &joints, &last_from_tool);

        let base_body = parent(first);
        let world_from_base = self.world_from_body(base_body);
        let model_name = self.model_name();
        Ok(Model {
            name: model_name,
            source: ModelSource::Mjcf {
                path: self.path.to_path_buf(),
                base_body: self.name(MjtObjBase::mjOBJ_BODY, base_body),
                tip_body: self.name(MjtObjBase::mjOBJ_BODY, moving[moving.len() - 1]),
                choices,
            },
            world_from_base,
            joints,
            links,
            last_from_tool,
            diagnostics,
        })
    }

    /// `<mujoco model="...">`, stored by MuJoCo as the first name; else the file stem.
    fn model_name(&self) -> String {
        let names = self.mj.names();
        let bytes: Vec<u8> = names.iter().take_while(|&&c| c != 0).map(|&c| c as u8).collect();
        match String::from_utf8(bytes) {
            Ok(name) if !name.is_empty() => name,
            _ => self
                .path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "robot".into()),
        }
    }

    /// Body frame in its parent body's frame, as compiled.
    pub(super) fn parent_from_body(&self, body: usize) -> Isometry3<f64> {
        pose(&self.mj.body_pos()[body], &self.mj.body_quat()[body])
    }

    /// Body frame in the world at the reference configuration (every joint at 0).
    fn world_from_body(&self, body: usize) -> Isometry3<f64> {
        let mut world_from_body = Isometry3::identity();
        let mut at = body;
        while at != 0 {
            world_from_body = self.parent_from_body(at) * world_from_body;
            at = self.mj.body_parentid()[at] as usize;
        }
        world_from_body
    }

    /// Owner link and link-relative frame of every body.
    fn layout(&self, moving: &[usize]) -> Layout {
        let mj = self.mj;
        let body_count = mj.ffi().nbody as usize;
        let base_body = mj.body_parentid()[moving[0]] as usize;
        let mut owner = vec![0usize; body_count];
        let mut link_from_body = vec![Isometry3::identity(); body_count];
        // The base link frame is the base body's frame; the world body sits at its inverse.
        link_from_body[0] = self.world_from_body(base_body).inverse();
        for body in 1..body_count {
            if let Some(k) = moving.iter().position(|&m| m == body) {
                owner[body] = k + 1;
                // The link frame sits at the joint anchor, axes as the body's.
                let anchor = Vector3::from(mj.jnt_pos()[mj.body_jntadr()[body] as usize]);
                link_from_body[body] = Isometry3::translation(-anchor.x, -anchor.y, -anchor.z);
            } else {
                let above = mj.body_parentid()[body] as usize;
                owner[body] = owner[above];
                link_from_body[body] = link_from_body[above] * self.parent_from_body(body);
            }
        }
        Layout { owner, link_from_body }
    }

    /// The links: the base and one per moving body, with the geoms and mass of every body merged
    /// into each.
    fn links(
        &self,
        moving: &[usize],
        layout: &Layout,
        joints: &[Joint],
        diagnostics: &mut Vec<Diagnostic>,
    ) -> Result<Vec<Link>, ModelError> {
        let base_body = self.mj.body_parentid()[moving[0]] as usize;
        let chain_bodies: Vec<usize> = std::iter::once(base_body).chain(moving.iter().copied()).collect();
        let mut links = Vec::with_capacity(chain_bodies.len());
        for (index, &chain_body) in chain_bodies.iter().enumerate() {
            let members: Vec<usize> = (0..layout.owner.len())
                .filter(|&b| layout.owner[b] == index && b != chain_body)
                .collect();
            let mut colliders = Vec::new();
            let mut masses: Vec<Inertial> = Vec::new();
            for &body in std::iter::once(&chain_body).chain(&members) {
                colliders.extend(self.colliders(body, index, layout, diagnostics)?);
                masses.extend(self.inertial(body, layout));
            }
            let inertial = Inertial::combine(&masses);
            if index > 0 {
                let bad = |problem: String| ModelError::BadInertia {
                    path: self.path.to_path_buf(),
                    link: self.name(MjtObjBase::mjOBJ_BODY, chain_body),
                    joint: joints[index - 1].name.clone(),
                    problem,
                };
                let inertial = inertial.as_ref().ok_or_else(|| bad("its mass is 0".into()))?;
                inertial.check().map_err(bad)?;
            }
            links.push(Link {
                name: self.name(MjtObjBase::mjOBJ_BODY, chain_body),
                // The world body is not a part of the robot; it is only named as the base.
                merged: members
                    .iter()
                    .filter(|&&b| b != 0)
                    .map(|&b| self.name(MjtObjBase::mjOBJ_BODY, b))
                    .collect(),
                colliders,
                inertial,
                segments: vec![],
            });
        }
        Ok(links)
    }

    /// Mass properties of one body in its owner link's frame; `None` for a massless body.
    fn inertial(&self, body: usize, layout: &Layout) -> Option<Inertial> {
        let mj = self.mj;
        let mass = mj.body_mass()[body];
        if mass <= 0.0 {
            return None;
        }
        let principal = pose(&mj.body_ipos()[body], &mj.body_iquat()[body]);
        let body_from_principal = Inertial {
            mass,
            com: Vector3::zeros(),
            inertia: nalgebra::Matrix3::from_diagonal(&Vector3::from(mj.body_inertia()[body])),
        };
        Some(
            body_from_principal
                .transformed(&principal)
                .transformed(&layout.link_from_body[body]),
        )
    }

    /// The tool frame in the last link's frame.
    fn tool(&self, tool: Tool, moving: &[usize], layout: &Layout) -> Result<Isometry3<f64>, ModelError> {
        let mj = self.mj;
        let last = moving[moving.len() - 1];
        let (body, body_from_tool, element) = match tool {
            Tool::LastBody => return Ok(layout.link_from_body[last]),
            Tool::Body(body) => (body, Isometry3::identity(), self.body(body)),
            Tool::Site(site) => (
                mj.site_bodyid()[site] as usize,
                pose(&mj.site_pos()[site], &mj.site_quat()[site]),
                format!("site `{}`", self.name(MjtObjBase::mjOBJ_SITE, site)),
            ),
        };
        if layout.owner[body] != moving.len() {
            return Err(self.unsupported(
                element,
                format!(
                    "is on {}, which the last joint (of {}) does not carry; the tool site must move with the end of the chain",
                    self.body(body),
                    self.body(last)
                ),
            ));
        }
        Ok(layout.link_from_body[body] * body_from_tool)
    }
}

/// A MuJoCo position and `w x y z` quaternion as a pose.
pub(super) fn pose(position: &[f64; 3], quaternion: &[f64; 4]) -> Isometry3<f64> {
    let [w, x, y, z] = *quaternion;
    Isometry3::from_parts(
        Translation3::new(position[0], position[1], position[2]),
        UnitQuaternion::new_normalize(Quaternion::new(w, x, y, z)),
    )
}
