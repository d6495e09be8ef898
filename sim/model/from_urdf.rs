//! URDF -> Model.
//!
//! urdf-rs parses the file; roxmltree reads it a second time only to learn what urdf-rs hides:
//! whether `<inertial>` and `<limit>` were written at all (urdf-rs fills both with zeros), and the
//! line of each element for messages.
//!
//! The chain runs from the base link (default: the root) to the tip link. The default tip: the arm
//! is the longest chain of movable joints that are not gripper joints (a tie is an error); the tip
//! is the link below its last joint, or the link fixed below that one named like a tool frame
//! (see `names`). Gripper joints end the tree and have a `<mimic>`, are mimicked from another
//! branch, carry a gripper word, or branch as a pair from one moving body. Every default is said
//! in `ModelSource::Urdf::choices`. Fixed joints are folded into their parent; links off the chain
//! (gripper parts too) are attached to the chain link they hang from, at their joints' zero
//! position.

use super::inertia::BALANCE_LIMIT;
use super::mesh::{load_mesh, package_paths_from_env, resolve_mesh_uri};
use super::{arm, names};
use super::{Collider, Diagnostic, Inertial, Joint, JointKind, Link, Model, ModelError, ModelSource, Shape};
use crate::frames::isometry_from_xyz_rpy;
use nalgebra::{Isometry3, Matrix3, Unit, Vector3};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// Options for reading a URDF.
#[derive(Debug, Clone, Default)]
pub struct UrdfOptions {
    /// First link of the chain; default the root link.
    pub base_link: Option<String>,
    /// Last link of the chain; default the arm's tool frame (see the module docs).
    pub tip_link: Option<String>,
    /// Roots searched for `package://NAME/...` meshes before `ROS_PACKAGE_PATH` and the folders
    /// holding the URDF.
    pub package_paths: Vec<PathBuf>,
}

/// Environment variable with extra `:`-separated package roots, as in ROS.
pub const PACKAGE_PATH_ENV: &str = "ROS_PACKAGE_PATH";

/// Reads a URDF file into a model.
///
/// # Errors
/// [`ModelError`] naming the file and the element: unreadable or malformed file, unknown links,
/// a graph that is not a tree, an ambiguous tip, unsupported joints on the chain, missing limits,
/// missing or unreadable meshes, non-physical or missing mass on a moving link.
pub fn from_urdf(path: &Path, opts: &UrdfOptions) -> Result<Model, ModelError> {
    let text = crate::files::read_text(path, crate::limits::MAX_TEXT_BYTES).map_err(|source| ModelError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    from_urdf_str(&text, path, opts)
}

/// Reads URDF text; `path` names it in messages and anchors relative mesh paths.
///
/// # Errors
/// As [`from_urdf`].
pub fn from_urdf_str(text: &str, path: &Path, opts: &UrdfOptions) -> Result<Model, ModelError> {
    // Our own XML pass first: limits, lines, names and numbers; urdf-rs then reads a file that
    // only its own schema can still reject.
    let doc = crate::limits::parse_xml(text).map_err(|message| ModelError::UrdfParse {
        path: path.to_path_buf(),
        message,
    })?;
    super::urdf_xml::check(&doc, path)?;
    let robot = urdf_rs::read_from_string(&without_visuals(text, &doc)).map_err(|e| ModelError::UrdfParse {
        path: path.to_path_buf(),
        message: format!("{e} (urdf-rs, which gives no line)"),
    })?;
    let facts = XmlFacts::read(&doc);
    let mut package_paths = opts.package_paths.clone();
    package_paths.extend(package_paths_from_env(std::env::var(PACKAGE_PATH_ENV).ok().as_deref()));
    Builder {
        path,
        robot: &robot,
        facts,
        package_paths,
        diagnostics: vec![],
    }
    .build(opts)
}

/// The text without its links' `<visual>` elements: nothing here reads them, and urdf-rs
/// refuses some that ROS's own parser reads (two `<material>` in one `<visual>`, as in the xacro
/// output of ROS-Industrial's ABB IRB 4600 support package).
fn without_visuals<'t>(text: &'t str, doc: &roxmltree::Document) -> std::borrow::Cow<'t, str> {
    let visuals: Vec<std::ops::Range<usize>> = doc
        .descendants()
        .filter(|node| node.has_tag_name("visual") && node.parent().is_some_and(|parent| parent.has_tag_name("link")))
        .map(|node| node.range())
        .collect();
    if visuals.is_empty() {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut kept = String::with_capacity(text.len());
    let mut at = 0;
    // In document order, never nested: each cut starts after the last one ended.
    for range in visuals {
        kept.push_str(&text[at..range.start]);
        at = range.end;
    }
    kept.push_str(&text[at..]);
    std::borrow::Cow::Owned(kept)
}

/// What urdf-rs does not tell: presence of elements and their lines.
struct XmlFacts {
    link_has_inertial: HashMap<String, bool>,
    joint_has_limit: HashMap<String, bool>,
    line: HashMap<(&'static str, String), u32>,
}

impl XmlFacts {
    fn read(doc: &roxmltree::Document) -> Self {
        let mut facts = XmlFacts {
            link_has_inertial: HashMap::new(),
            joint_has_limit: HashMap::new(),
            line: HashMap::new(),
        };
        for node in doc.root_element().children().filter(|n| n.is_element()) {
            let Some(name) = node.attribute("name") else { continue };
            let has = |tag: &str| node.children().any(|c| c.has_tag_name(tag));
            let line = doc.text_pos_at(node.range().start).row;
            match node.tag_name().name() {
                "link" => {
                    facts.link_has_inertial.insert(name.to_string(), has("inertial"));
                    facts.line.insert(("link", name.to_string()), line);
                }
                "joint" => {
                    facts.joint_has_limit.insert(name.to_string(), has("limit"));
                    facts.line.insert(("joint", name.to_string()), line);
                }
                _ => {}
            }
        }
        facts
    }
}

struct Builder<'a> {
    path: &'a Path,
    robot: &'a urdf_rs::Robot,
    facts: XmlFacts,
    package_paths: Vec<PathBuf>,
    diagnostics: Vec<Diagnostic>,
}

fn is_movable(kind: &urdf_rs::JointType) -> bool {
    !matches!(kind, urdf_rs::JointType::Fixed)
}

impl<'a> Builder<'a> {
    fn element(&self, kind: &'static str, name: &str) -> String {
        match self.facts.line.get(&(kind, name.to_string())) {
            Some(line) => format!("{kind} `{name}` (line {line})"),
            None => format!("{kind} `{name}`"),
        }
    }

    fn invalid(&self, element: String, message: String) -> ModelError {
        ModelError::InvalidValue {
            path: self.path.to_path_buf(),
            element,
            message,
        }
    }

    fn build(mut self, opts: &UrdfOptions) -> Result<Model, ModelError> {
        let robot = self.robot;
        let links: BTreeMap<&str, &urdf_rs::Link> = robot.links.iter().map(|l| (l.name.as_str(), l)).collect();
        let known = || links.keys().copied().collect::<Vec<_>>().join(", ");
        if links.is_empty() {
            return Err(self.invalid("robot".into(), "has no <link>".into()));
        }

        // Parent joint of every link; a second parent means the graph is not a tree.
        let mut parent_joint: HashMap<&str, &urdf_rs::Joint> = HashMap::new();
        let mut children: BTreeMap<&str, Vec<&urdf_rs::Joint>> = BTreeMap::new();
        for joint in &robot.joints {
            for (role, link) in [("<parent>", &joint.parent.link), ("<child>", &joint.child.link)] {
                if !links.contains_key(link.as_str()) {
                    return Err(ModelError::UnknownLink {
                        path: self.path.to_path_buf(),
                        context: format!("{} {role}", self.element("joint", &joint.name)),
                        link: link.clone(),
                        known: known(),
                    });
                }
            }
            if let Some(previous) = parent_joint.insert(joint.child.link.as_str(), joint) {
                return Err(ModelError::NotATree {
                    path: self.path.to_path_buf(),
                    message: format!(
                        "link `{}` is the child of two joints, `{}` and `{}`; a URDF must be a tree",
                        joint.child.link, previous.name, joint.name
                    ),
                });
            }
            children.entry(joint.parent.link.as_str()).or_default().push(joint);
        }
        let roots: Vec<&str> = links.keys().copied().filter(|l| !parent_joint.contains_key(l)).collect();
        let root = match roots.as_slice() {
            [one] => *one,
            [] => {
                return Err(ModelError::NotATree {
                    path: self.path.to_path_buf(),
                    message: "every link has a parent joint: the joints form a cycle".into(),
                })
            }
            many => {
                return Err(ModelError::NotATree {
                    path: self.path.to_path_buf(),
                    message: format!(
                        "{} links have no parent joint ({}); a URDF has exactly one root",
                        many.len(),
                        many.join(", ")
                    ),
                })
            }
        };

        // One root does not make a tree: joints can also close a cycle among the other links.
        let mut reached = std::collections::HashSet::from([root]);
        let mut stack = vec![root];
        while let Some(link) = stack.pop() {
            for joint in children.get(link).map(Vec::as_slice).unwrap_or(&[]) {
                if reached.insert(joint.child.link.as_str()) {
                    stack.push(joint.child.link.as_str());
                }
            }
        }
        if reached.len() < links.len() {
            let detached: Vec<&str> = links.keys().copied().filter(|l| !reached.contains(l)).collect();
            return Err(ModelError::NotATree {
                path: self.path.to_path_buf(),
                message: format!(
                    "links {} cannot be reached from the root `{root}`: their joints form a cycle",
                    detached.join(", ")
                ),
            });
        }

        let base = match &opts.base_link {
            Some(name) if !links.contains_key(name.as_str()) => {
                return Err(ModelError::UnknownLink {
                    path: self.path.to_path_buf(),
                    context: "--base".into(),
                    link: name.clone(),
                    known: known(),
                })
            }
            Some(name) => name.as_str(),
            None => root,
        };
        let tip = match &opts.tip_link {
            Some(name) if !links.contains_key(name.as_str()) => {
                return Err(ModelError::UnknownLink {
                    path: self.path.to_path_buf(),
                    context: "--tip".into(),
                    link: name.clone(),
                    known: known(),
                })
            }
            Some(name) => (name.clone(), vec![]),
            None => self.default_tip(base, &children)?,
        };
        let (tip, mut choices) = tip;
        if self.path.extension().is_some_and(|e| !e.eq_ignore_ascii_case("urdf")) {
            choices.insert(0, "read as a URDF: its root element is <robot>".to_string());
        }

        // Walk up from the tip to the base.
        let mut path_joints: Vec<&urdf_rs::Joint> = Vec::new();
        let mut at = tip.as_str();
        while at != base {
            match parent_joint.get(at) {
                Some(joint) => {
                    path_joints.push(joint);
                    at = joint.parent.link.as_str();
                }
                None => {
                    return Err(ModelError::TipNotBelowBase {
                        path: self.path.to_path_buf(),
                        base: base.into(),
                        tip: tip.clone(),
                    })
                }
            }
        }
        path_joints.reverse();

        for joint in &path_joints {
            let unsupported = match joint.joint_type {
                _ if joint.mimic.is_some() && is_movable(&joint.joint_type) => Some("a mimic joint"),
                urdf_rs::JointType::Floating => Some("floating"),
                urdf_rs::JointType::Planar => Some("planar"),
                urdf_rs::JointType::Spherical => Some("spherical"),
                _ => None,
            };
            if let Some(kind) = unsupported {
                return Err(ModelError::UnsupportedJoint {
                    path: self.path.to_path_buf(),
                    joint: joint.name.clone(),
                    kind: kind.into(),
                    base: base.into(),
                    tip: tip.clone(),
                });
            }
        }

        // Chain links: the base and the child of every movable joint on the path. Fixed offsets in
        // between accumulate into the next joint's origin; the ones after the last movable joint
        // become the tool offset.
        let mut chain_links: Vec<&str> = vec![base];
        let mut joints = Vec::new();
        let mut pending = Isometry3::identity();
        for joint in &path_joints {
            let origin = self.origin(&joint.origin, self.element("joint", &joint.name))?;
            if is_movable(&joint.joint_type) {
                joints.push(self.joint(joint, pending * origin)?);
                chain_links.push(joint.child.link.as_str());
                pending = Isometry3::identity();
            } else {
                pending *= origin;
            }
        }
        if joints.len() > crate::limits::MAX_JOINTS {
            return Err(self.invalid(
                format!("the chain from `{base}` to `{tip}`"),
                format!("has {} movable joints; the limit is {}", joints.len(), crate::limits::MAX_JOINTS),
            ));
        }
        if joints.is_empty() {
            return Err(ModelError::NoMovableJoint {
                path: self.path.to_path_buf(),
                base: base.into(),
                tip: tip.clone(),
            });
        }
        let last_from_tool = pending;

        // Everything below the base hangs from the nearest chain link above it.
        let mut owned: Vec<Vec<(&str, Isometry3<f64>)>> = chain_links.iter().map(|l| vec![(*l, Isometry3::identity())]).collect();
        let chain_index: HashMap<&str, usize> = chain_links.iter().enumerate().map(|(i, l)| (*l, i)).collect();
        let mut stack: Vec<(&str, usize, Isometry3<f64>)> = vec![(base, 0, Isometry3::identity())];
        while let Some((link, owner, owner_from_link)) = stack.pop() {
            for joint in children.get(link).map(Vec::as_slice).unwrap_or(&[]) {
                let child = joint.child.link.as_str();
                if let Some(&index) = chain_index.get(child) {
                    if index > 0 && joints[index - 1].name == joint.name {
                        stack.push((child, index, Isometry3::identity()));
                        continue;
                    }
                }
                // Off the chain, or fixed: attached to the owner at the joint's zero position.
                let origin = self.origin(&joint.origin, self.element("joint", &joint.name))?;
                let owner_from_child = owner_from_link * origin;
                owned[owner].push((child, owner_from_child));
                stack.push((child, owner, owner_from_child));
            }
        }

        let mut model_links = Vec::with_capacity(chain_links.len());
        for (index, group) in owned.iter().enumerate() {
            model_links.push(self.link(index, group, &links, &joints)?);
        }
        let massless: Vec<String> = model_links[1..]
            .iter()
            .filter(|link| link.inertial.is_none())
            .map(|link| self.element("link", &link.name))
            .collect();
        if let Some((first, others)) = massless.split_first() {
            // Kinematics-only files (ROS-Industrial's support packages among them) leave mass
            // out: reach, IK and collisions need none; the engines and the torque check refuse
            // the model in the pipeline (`Error::NoMass`). One warning for all such links.
            let also = if others.is_empty() {
                String::new()
            } else {
                format!(" (nor have {})", others.join(", "))
            };
            self.diagnostics.push(Diagnostic {
                path: self.path.to_path_buf(),
                element: first.clone(),
                message: format!(
                    "moved by a joint but has no <inertial>{also}: reach, IK and collisions are checked, the engines and the torque check need the mass (run with --reach-only)"
                ),
            });
        }
        if model_links.iter().skip(1).all(|link| link.colliders.is_empty()) {
            // Every configuration then counts as free: a user reading PASS must know why.
            self.diagnostics.push(Diagnostic {
                path: self.path.to_path_buf(),
                element: format!("robot `{}`", robot.name),
                message: "no link the joints move has <collision> geometry (<visual> is never used for collisions): contacts, clearances and collision proofs have nothing to check, so every configuration counts as free".into(),
            });
        }
        // The paper's capsule approximation, as for every robot read from a file.
        super::add_bones(&mut model_links, &joints, &last_from_tool);
        Ok(Model {
            name: if robot.name.is_empty() {
                "robot".into()
            } else {
                robot.name.clone()
            },
            source: ModelSource::Urdf {
                path: self.path.to_path_buf(),
                base_link: base.into(),
                tip_link: tip,
                choices,
            },
            world_from_base: Isometry3::identity(),
            joints,
            links: model_links,
            last_from_tool,
            diagnostics: self.diagnostics,
        })
    }

    /// The default tip below `base` and the sentences that say why: the arm is the longest
    /// chain of movable joints that are not gripper joints (the rule of [`arm`]); the
    /// tip is the link below the arm's last joint, followed down fixed joints to the link named
    /// like a tool frame ([`names::TOOL_NAMES`]) when exactly one name ranks first.
    fn default_tip(&self, base: &str, children: &BTreeMap<&str, Vec<&urdf_rs::Joint>>) -> Result<(String, Vec<String>), ModelError> {
        let mut choices = Vec::new();
        let (movers, joints) = self.movers(base, children);
        let by_index = arm::grippers(&movers);
        let grippers = Self::gripper_joints(&movers, &joints, &by_index);
        for (name, reason) in &grippers {
            choices.push(format!(
                "{} is a gripper joint, not an arm joint: {reason}; it is held at 0 and what it moves is rigid geometry of the link it hangs from",
                self.element("joint", name)
            ));
        }
        for (m, word) in arm::named_but_kept(&movers, &by_index) {
            choices.push(format!(
                "{} (link `{}`) is named like a gripper's (`{word}`) but kept as an arm joint: it turns, its own name has no gripper word, no joint mimics it and no finger hangs beside it; if it is the gripper's, end the arm above it with --tip",
                self.element("joint", &joints[m].name),
                movers[m].part
            ));
        }
        let (arm_end, length) = match arm::arm_end(&movers, &by_index) {
            Ok((end, length)) => (movers[end].part.as_str(), length),
            Err(arm::NoArmEnd::Nothing) => {
                return Err(ModelError::NoMovableJoint {
                    path: self.path.to_path_buf(),
                    base: base.into(),
                    tip: base.into(),
                })
            }
            Err(arm::NoArmEnd::Tie { ends, length }) => {
                let mut candidates: Vec<&str> = ends.iter().map(|&m| movers[m].part.as_str()).collect();
                candidates.sort_unstable();
                return Err(ModelError::AmbiguousTip {
                    path: self.path.to_path_buf(),
                    base: base.into(),
                    length,
                    candidates: candidates.join(", "),
                });
            }
        };

        // The tool frame: the arm's last link or a link rigidly below it, never past a movable
        // (gripper) joint.
        let mut rigid = vec![arm_end];
        let mut at = 0;
        while at < rigid.len() {
            for joint in children.get(rigid[at]).map(Vec::as_slice).unwrap_or(&[]) {
                if !is_movable(&joint.joint_type) {
                    rigid.push(joint.child.link.as_str());
                }
            }
            at += 1;
        }
        let arm = format!(
            "the arm is the longest chain of movable joints from `{base}` that are not gripper joints ({length} joints, to link `{arm_end}`)"
        );
        let tip = match names::pick_tool(&rigid) {
            Ok(Some(tool)) if tool == arm_end => {
                choices.push(format!(
                    "tip `{tool}` (no --tip): {arm}, whose last link is named like a tool frame"
                ));
                tool
            }
            Ok(Some(tool)) => {
                choices.push(format!(
                    "tip `{tool}` (no --tip): {arm}; `{tool}` is fixed below it and named like a tool frame ({})",
                    names::tool_rule()
                ));
                tool
            }
            Ok(None) => {
                choices.push(format!(
                    "tip `{arm_end}` (no --tip): {arm}; no link fixed below it is named like a tool frame ({})",
                    names::tool_rule()
                ));
                arm_end
            }
            Err(tied) => {
                choices.push(format!(
                    "tip `{arm_end}` (no --tip): {arm}; the links fixed below it named like a tool frame tie ({}): choose one with --tip",
                    tied.join(", ")
                ));
                arm_end
            }
        };
        Ok((tip.to_string(), choices))
    }

    /// The movable joints below `base` as [`arm::Mover`]s (parents first), with their joints.
    /// A `<mimic>` couples a joint to the one it names whatever that is; a joint that mimics it
    /// couples it to that joint (a joint its own descendant mimics is a linkage of the arm).
    fn movers<'r>(&'r self, base: &str, children: &BTreeMap<&str, Vec<&'r urdf_rs::Joint>>) -> (Vec<arm::Mover>, Vec<&'r urdf_rs::Joint>) {
        let mut joints: Vec<&urdf_rs::Joint> = Vec::new();
        let mut above: Vec<Option<usize>> = Vec::new();
        let mut stack: Vec<(&str, Option<usize>)> = vec![(base, None)];
        while let Some((link, up)) = stack.pop() {
            for joint in children.get(link).map(Vec::as_slice).unwrap_or(&[]) {
                if is_movable(&joint.joint_type) {
                    joints.push(joint);
                    above.push(up);
                    stack.push((joint.child.link.as_str(), Some(joints.len() - 1)));
                } else {
                    stack.push((joint.child.link.as_str(), up));
                }
            }
        }
        let index: HashMap<&str, usize> = joints.iter().enumerate().map(|(k, j)| (j.name.as_str(), k)).collect();
        let movers = joints
            .iter()
            .zip(above)
            .map(|(joint, above)| {
                let mut couplings = Vec::new();
                if let Some(mimic) = &joint.mimic {
                    couplings.push((None, format!("it has <mimic joint=\"{}\">", mimic.joint)));
                }
                for other in self
                    .robot
                    .joints
                    .iter()
                    .filter(|o| o.mimic.as_ref().is_some_and(|m| m.joint == joint.name))
                {
                    couplings.push((index.get(other.name.as_str()).copied(), format!("joint `{}` mimics it", other.name)));
                }
                arm::Mover {
                    above,
                    joints: vec![joint.name.clone()],
                    part: joint.child.link.clone(),
                    couplings,
                    slides: matches!(joint.joint_type, urdf_rs::JointType::Prismatic),
                }
            })
            .collect();
        (movers, joints)
    }

    /// The gripper joints among `movers` (by joint name), each with the sentence that says why.
    fn gripper_joints(
        movers: &[arm::Mover],
        joints: &[&urdf_rs::Joint],
        found: &BTreeMap<usize, arm::GripperReason>,
    ) -> BTreeMap<String, String> {
        found
            .iter()
            .map(|(m, reason)| {
                let sentence = match reason {
                    arm::GripperReason::Coupled(sentence) => sentence.clone(),
                    arm::GripperReason::JointWord(word) => format!("its name has `{word}`"),
                    arm::GripperReason::PartWord(word) => {
                        format!("its link `{}` is named like a gripper part (`{word}`)", movers[*m].part)
                    }
                    arm::GripperReason::Sibling { other, above } => format!(
                        "it and joint `{}` branch from the body joint `{}` moves and nothing moves below them (fingers)",
                        joints[*other].name, joints[*above].name
                    ),
                };
                (joints[*m].name.clone(), sentence)
            })
            .collect()
    }

    fn origin(&self, pose: &urdf_rs::Pose, element: String) -> Result<Isometry3<f64>, ModelError> {
        if pose.xyz.0.iter().chain(pose.rpy.0.iter()).any(|v| !v.is_finite()) {
            return Err(self.invalid(
                element,
                format!("<origin xyz=\"{:?}\" rpy=\"{:?}\"> has a non-finite number", pose.xyz.0, pose.rpy.0),
            ));
        }
        Ok(isometry_from_xyz_rpy(pose.xyz.0, pose.rpy.0))
    }

    fn joint(&mut self, joint: &urdf_rs::Joint, parent_from_joint: Isometry3<f64>) -> Result<Joint, ModelError> {
        let element = self.element("joint", &joint.name);
        let axis = Vector3::from(joint.axis.xyz.0);
        if !axis.iter().all(|v| v.is_finite()) || axis.norm() < 1e-9 {
            return Err(self.invalid(
                element,
                format!("<axis xyz=\"{:?}\"> must be a finite non-zero vector", joint.axis.xyz.0),
            ));
        }
        let kind = match joint.joint_type {
            urdf_rs::JointType::Revolute => JointKind::Revolute,
            urdf_rs::JointType::Continuous => JointKind::Continuous,
            _ => JointKind::Prismatic,
        };
        let has_limit = self.facts.joint_has_limit.get(&joint.name).copied().unwrap_or(false);
        let limit = &joint.limit;
        let limits = if kind == JointKind::Continuous {
            None
        } else {
            if !has_limit {
                return Err(self.invalid(
                    element,
                    "has no <limit>; a revolute or prismatic joint needs lower and upper limits (urdf-rs would read [0, 0])".into(),
                ));
            }
            if !(limit.lower.is_finite() && limit.upper.is_finite()) || limit.lower > limit.upper {
                return Err(self.invalid(
                    format!("{element} <limit>"),
                    format!("lower {} and upper {}: expected finite lower <= upper", limit.lower, limit.upper),
                ));
            }
            if limit.lower == limit.upper {
                self.diagnostics.push(Diagnostic {
                    path: self.path.to_path_buf(),
                    element: format!("{element} <limit>"),
                    message: format!("lower = upper = {}: the joint cannot move", limit.lower),
                });
            }
            Some([limit.lower, limit.upper])
        };
        // URDF requires effort and velocity; 0 is the common way of writing "not specified".
        for (what, value) in [("effort", limit.effort), ("velocity", limit.velocity)] {
            if value < 0.0 {
                return Err(self.invalid(
                    format!("{element} <limit>"),
                    format!("{what} {value}: expected a positive rating (0 means not specified)"),
                ));
            }
        }
        let positive = |value: f64, what: &str, diagnostics: &mut Vec<Diagnostic>| {
            if value.is_finite() && value > 0.0 {
                Some(value)
            } else {
                if has_limit && value != 0.0 {
                    diagnostics.push(Diagnostic {
                        path: self.path.to_path_buf(),
                        element: format!("{element} <limit>"),
                        message: format!("{what} {value} is not positive; treated as unknown"),
                    });
                }
                None
            }
        };
        let max_effort = positive(limit.effort, "effort", &mut self.diagnostics);
        let max_velocity = positive(limit.velocity, "velocity", &mut self.diagnostics);
        Ok(Joint {
            name: joint.name.clone(),
            kind,
            parent_from_joint,
            axis: Unit::new_normalize(axis),
            limits,
            max_velocity,
            max_effort,
        })
    }

    fn link(
        &mut self,
        index: usize,
        group: &[(&str, Isometry3<f64>)],
        links: &BTreeMap<&str, &urdf_rs::Link>,
        joints: &[Joint],
    ) -> Result<Link, ModelError> {
        let mut colliders = Vec::new();
        let mut masses = Vec::new();
        let (chain_name, _) = group[0];
        for (name, owner_from_link) in group {
            let Some(link) = links.get(name) else { continue };
            let element = self.element("link", name);
            for (k, collision) in link.collision.iter().enumerate() {
                let origin = self.origin(&collision.origin, format!("{element} <collision> {k}"))?;
                let label = match &collision.name {
                    Some(n) if !n.is_empty() => format!("{name}/{n}"),
                    _ => format!("{name}/collision {k}"),
                };
                if is_placeholder(&collision.geometry) {
                    self.diagnostics.push(Diagnostic {
                        path: self.path.to_path_buf(),
                        element: format!("{element} <collision> {k}"),
                        message: "every size is 0 (a placeholder): ignored, it has nothing to collide with".into(),
                    });
                    continue;
                }
                for (pose, shape) in self.shapes(&collision.geometry, name, &format!("{element} <collision> {k}"))? {
                    colliders.push(Collider {
                        link_from_shape: owner_from_link * origin * pose,
                        shape,
                        label: label.clone(),
                    });
                }
            }
            if self.facts.link_has_inertial.get(*name).copied().unwrap_or(false) {
                let inertial = self.inertial(&link.inertial, &element)?;
                if inertial.mass > 0.0 {
                    // A single part may be odd (a point mass) while the merged body is fine; the
                    // merged body is checked below and is what simulators see (a link of one
                    // part only there).
                    if let (Err(problem), true) = (inertial.check(), group.len() > 1) {
                        self.diagnostics.push(Diagnostic {
                            path: self.path.to_path_buf(),
                            element: format!("{element} <inertial>"),
                            message: problem,
                        });
                    }
                    masses.push(inertial.transformed(owner_from_link));
                } else if index > 0 && !link.collision.is_empty() {
                    self.diagnostics.push(Diagnostic {
                        path: self.path.to_path_buf(),
                        element: format!("{element} <inertial>"),
                        message: "mass is 0 although the link has collision geometry".into(),
                    });
                }
            }
        }
        let link = |inertial: Option<Inertial>| Link {
            name: chain_name.into(),
            merged: group[1..].iter().map(|(n, _)| n.to_string()).collect(),
            colliders,
            inertial,
            segments: vec![],
        };
        if index == 0 {
            return Ok(link(Inertial::combine(&masses)));
        }
        let joint = &joints[index - 1].name;
        // Where to fix it: the links whose <inertial> were combined, with their lines.
        let sources: Vec<String> = group
            .iter()
            .filter(|(n, _)| self.facts.link_has_inertial.get(*n).copied().unwrap_or(false))
            .map(|(n, _)| self.element("link", n))
            .collect();
        let bad = |problem: String| ModelError::BadInertia {
            path: self.path.to_path_buf(),
            link: chain_name.into(),
            joint: joint.clone(),
            problem: if sources.is_empty() {
                problem
            } else {
                format!("{problem}; the <inertial> of {}", sources.join(", "))
            },
        };
        if sources.is_empty() {
            // No mass at all: warned about once for every such link (see `build`).
            return Ok(link(None));
        }
        let inertial = Inertial::combine(&masses).ok_or_else(|| bad("its <inertial> mass is 0".into()))?;
        let inertial = match inertial.check() {
            Ok(()) => inertial,
            Err(problem) => {
                let (fixed, shortfall) = inertial.balanced().ok_or_else(|| {
                    let shortfall = inertial.triangle_shortfall();
                    bad(if shortfall > 0.0 {
                        format!(
                            "{problem}, short by {:.1} % (up to {:.0} % is balanced with a warning)",
                            shortfall * 100.0,
                            BALANCE_LIMIT * 100.0
                        )
                    } else {
                        problem.clone()
                    })
                })?;
                self.diagnostics.push(Diagnostic {
                    path: self.path.to_path_buf(),
                    element: format!("link `{chain_name}` <inertial>"),
                    message: format!(
                        "{problem}, short by {:.2} %: its two smaller principal moments are each raised by half of that (the least change that meets it; MuJoCo's balanceinertia would make all three equal)",
                        shortfall * 100.0
                    ),
                });
                fixed
            }
        };
        Ok(link(Some(inertial)))
    }

    fn inertial(&self, inertial: &urdf_rs::Inertial, element: &str) -> Result<Inertial, ModelError> {
        let i = &inertial.inertia;
        let values = [inertial.mass.value, i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz];
        if values.iter().any(|v| !v.is_finite()) || inertial.mass.value < 0.0 {
            return Err(self.invalid(
                format!("{element} <inertial>"),
                format!(
                    "mass {} and inertia {:?}: expected finite numbers, mass >= 0",
                    inertial.mass.value,
                    &values[1..]
                ),
            ));
        }
        let frame = self.origin(&inertial.origin, format!("{element} <inertial>"))?;
        let tensor = Matrix3::new(i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz);
        Ok(Inertial {
            mass: inertial.mass.value,
            com: Vector3::zeros(),
            inertia: tensor,
        }
        .transformed(&frame))
    }

    fn shapes(&self, geometry: &urdf_rs::Geometry, link: &str, element: &str) -> Result<Vec<(Isometry3<f64>, Shape)>, ModelError> {
        let positive = |values: &[f64], what: &str| -> Result<(), ModelError> {
            if values.iter().all(|v| v.is_finite() && *v > 0.0) {
                Ok(())
            } else {
                Err(self.invalid(element.to_string(), format!("{what} {values:?}: expected positive finite numbers")))
            }
        };
        Ok(match geometry {
            urdf_rs::Geometry::Sphere { radius } => {
                positive(&[*radius], "<sphere radius>")?;
                vec![(Isometry3::identity(), Shape::Sphere { radius: *radius })]
            }
            urdf_rs::Geometry::Cylinder { radius, length } => {
                positive(&[*radius, *length], "<cylinder radius length>")?;
                vec![(
                    Isometry3::identity(),
                    Shape::Cylinder {
                        radius: *radius,
                        length: *length,
                    },
                )]
            }
            urdf_rs::Geometry::Capsule { radius, length } => {
                positive(&[*radius, *length], "<capsule radius length>")?;
                vec![(
                    Isometry3::identity(),
                    Shape::Capsule {
                        radius: *radius,
                        length: *length,
                    },
                )]
            }
            urdf_rs::Geometry::Box { size } => {
                positive(&size.0, "<box size>")?;
                vec![(
                    Isometry3::identity(),
                    Shape::Box {
                        half_extents: [size.0[0] / 2.0, size.0[1] / 2.0, size.0[2] / 2.0],
                    },
                )]
            }
            urdf_rs::Geometry::Mesh { filename, scale } => {
                let scale = scale.as_ref().map(|s| s.0).unwrap_or([1.0; 3]);
                if scale.iter().any(|v| !v.is_finite() || *v == 0.0) {
                    return Err(self.invalid(
                        element.to_string(),
                        format!("<mesh scale=\"{scale:?}\">: expected finite non-zero factors"),
                    ));
                }
                let dir = self.path.parent().unwrap_or(Path::new("."));
                let file = resolve_mesh_uri(filename, dir, &self.package_paths).map_err(|searched| ModelError::MissingMesh {
                    path: self.path.to_path_buf(),
                    link: link.into(),
                    uri: filename.clone(),
                    searched: searched.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "),
                    hint: super::mesh::missing_mesh_hint(filename),
                })?;
                let mesh = load_mesh(filename, &file, scale).map_err(|message| ModelError::BadMesh {
                    path: self.path.to_path_buf(),
                    link: link.into(),
                    mesh: file.clone(),
                    message,
                })?;
                vec![(Isometry3::identity(), Shape::Mesh(mesh))]
            }
        })
    }
}

/// Whether a box, cylinder or capsule has every size zero: the placeholder some vendors write
/// (Kinova's Jaco and Mico URDFs give their `root` a `<box size="0 0 0">`). A shape with some
/// sizes zero and others not, a negative size, or a sphere of radius 0 (one number: a typo as
/// likely as a placeholder) is still an error.
fn is_placeholder(geometry: &urdf_rs::Geometry) -> bool {
    match geometry {
        urdf_rs::Geometry::Sphere { .. } => false,
        urdf_rs::Geometry::Cylinder { radius, length } | urdf_rs::Geometry::Capsule { radius, length } => *radius == 0.0 && *length == 0.0,
        urdf_rs::Geometry::Box { size } => size.0.iter().all(|v| *v == 0.0),
        urdf_rs::Geometry::Mesh { .. } => false,
    }
}
