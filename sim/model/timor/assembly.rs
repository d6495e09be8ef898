//! A Timor assembly: modules of a set joined connector to connector, walked from the base
//! connector into the serial chain every later stage uses.
//!
//! Timor's rules (timor-python 1.1, `Module.py`, `ModuleAssembly`): two connectors meet with
//! their frames facing each other, the second turned by pi about the first's x axis; the world
//! sees the base connector turned by pi about x as well (a base pose of identity stands the robot
//! upright at the origin), then the assembly's `basePose`. Given only a `moduleOrder`, each module
//! is attached to the one before it through the one pair of connectors that mate (type, size and
//! gender); none, or several, is an error, as in Timor. Bodies joined rigidly (connectors, fixed
//! joints) are one link; each moving joint starts the next link.

use super::set::{Connector, Module, ModuleSet, Problem};
use crate::model::{Collider, Diagnostic, Inertial, Joint, Link, Model, ModelError, ModelSource};
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use std::path::Path;

/// A module placed in the assembly (`moduleOrder[k]`); copies of one module get `-1`, `-2`, ...
/// as Timor names them.
#[derive(Debug, Clone)]
pub(crate) struct Instance<'a> {
    pub name: String,
    pub module: &'a Module,
}

/// One connection: (instance, connector index) on either side.
pub(crate) type Connection = ((usize, usize), (usize, usize));

/// How the modules are joined.
#[derive(Debug, Clone)]
pub(crate) struct Assembly<'a> {
    pub instances: Vec<Instance<'a>>,
    pub connections: Vec<Connection>,
    pub base: (usize, usize),
}

/// The turn by pi about x between two mated connectors, and between the world and the base
/// connector.
fn flip() -> Isometry3<f64> {
    Isometry3::from_parts(
        Default::default(),
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI),
    )
}

/// The instances for a module order: each module looked up, copies numbered.
pub(crate) fn instances<'a>(set: &'a ModuleSet, order: &[String]) -> Result<Vec<Instance<'a>>, Problem> {
    let mut instances: Vec<Instance> = Vec::with_capacity(order.len());
    for (k, id) in order.iter().enumerate() {
        let module = set.module(id).ok_or_else(|| {
            (
                format!("moduleOrder[{k}]"),
                format!("no module `{id}` in {} (modules: {})", set.path.display(), set.ids()),
            )
        })?;
        let copies = instances.iter().filter(|i| i.module.id == *id).count();
        let name = if copies == 0 { id.clone() } else { format!("{id}-{copies}") };
        instances.push(Instance { name, module });
    }
    if instances.is_empty() {
        return Err(("moduleOrder".into(), "is empty; expected the modules from the base on".into()));
    }
    Ok(instances)
}

impl<'a> Assembly<'a> {
    /// The base connector of the first module: its one connector of type `base`.
    fn base_of_first(instances: &[Instance]) -> Result<(usize, usize), Problem> {
        let first = &instances[0];
        let bases: Vec<usize> = (0..first.module.connectors.len())
            .filter(|&c| first.module.connectors[c].kind == "base")
            .collect();
        match bases.as_slice() {
            [c] => Ok((0, *c)),
            _ => Err((
                "moduleOrder[0]".into(),
                format!(
                    "module `{}` has {} connectors of type `base`; the first module of a module order needs exactly one (a base module)",
                    first.name,
                    bases.len()
                ),
            )),
        }
    }

    /// Whether connector `c` of instance `i` is free.
    fn is_free(&self, i: usize, c: usize) -> bool {
        self.base != (i, c) && !self.connections.iter().any(|&(a, b)| a == (i, c) || b == (i, c))
    }

    /// Timor's `from_serial_modules`: each module attached to the one before it through the one
    /// pair of connectors that mate.
    pub(crate) fn serial(instances: Vec<Instance<'a>>) -> Result<Self, Problem> {
        let base = Self::base_of_first(&instances)?;
        let mut assembly = Assembly {
            instances: vec![instances[0].clone()],
            connections: vec![],
            base,
        };
        for (k, instance) in instances.into_iter().enumerate().skip(1) {
            let mut ways = Vec::new();
            for (c, connector) in instance.module.connectors.iter().enumerate() {
                for (i, placed) in assembly.instances.iter().enumerate() {
                    for (f, free) in placed.module.connectors.iter().enumerate() {
                        if assembly.is_free(i, f) && connector.mismatch(free).is_none() {
                            ways.push(((i, f), (k, c)));
                        }
                    }
                }
            }
            let describe = |a: &Assembly, ((i, f), (_, c)): Connection| {
                format!(
                    "its `{}` to `{}` of `{}`",
                    instance.module.connectors[c].id, a.instances[i].module.connectors[f].id, a.instances[i].name
                )
            };
            match ways.as_slice() {
                [way] if way.0 .0 == k - 1 => assembly.connections.push(*way),
                [way] => {
                    return Err((
                        format!("moduleOrder[{k}]"),
                        format!(
                            "module `{}` mates only with module `{}`, not with the module before it: a module order is a chain; give moduleConnection for other shapes",
                            instance.name, assembly.instances[way.0 .0].name
                        ),
                    ))
                }
                [] => {
                    let free: Vec<String> = assembly
                        .instances
                        .iter()
                        .enumerate()
                        .flat_map(|(i, p)| (0..p.module.connectors.len()).map(move |f| (i, p, f)))
                        .filter(|(i, _, f)| assembly.is_free(*i, *f))
                        .map(|(_, p, f)| describe_connector(&p.name, &p.module.connectors[f]))
                        .collect();
                    let own: Vec<String> = instance.module.connectors.iter().map(|c| describe_connector(&instance.name, c)).collect();
                    return Err((
                        format!("moduleOrder[{k}]"),
                        format!(
                            "module `{}` mates with no free connector of the modules before it (its connectors: {}; free: {}); connectors mate with the same type and size, m with f or h with h",
                            instance.name,
                            or_none(&own),
                            or_none(&free)
                        ),
                    ));
                }
                _ => {
                    let listed: Vec<String> = ways.iter().map(|w| describe(&assembly, *w)).collect();
                    return Err((
                        format!("moduleOrder[{k}]"),
                        format!(
                            "module `{}` can be attached in {} ways ({}); give moduleConnection to say which",
                            instance.name,
                            ways.len(),
                            listed.join("; ")
                        ),
                    ));
                }
            }
            assembly.instances.push(instance);
        }
        Ok(assembly)
    }

    /// An assembly given connection by connection (Timor's `moduleConnection`, `baseConnection`).
    pub(crate) fn connected(
        instances: Vec<Instance<'a>>,
        connections: &[(usize, String, usize, String)],
        base: Option<(usize, String)>,
    ) -> Result<Self, Problem> {
        let find = |k: usize, side: usize, i: usize, id: &str| -> Result<usize, Problem> {
            let instance = instances.get(i).ok_or_else(|| {
                (
                    format!("moduleConnection[{k}][{side}]"),
                    format!("module index {i}; moduleOrder has {} modules", instances.len()),
                )
            })?;
            instance.module.connectors.iter().position(|c| c.id == id).ok_or_else(|| {
                let known: Vec<&str> = instance.module.connectors.iter().map(|c| c.id.as_str()).collect();
                (
                    format!("moduleConnection[{k}][{}]", side + 1),
                    format!(
                        "module `{}` has no connector `{id}` (its connectors: {})",
                        instance.name,
                        or_none(&known)
                    ),
                )
            })
        };
        let mut assembly = Assembly {
            instances: instances.clone(),
            connections: vec![],
            base: (usize::MAX, usize::MAX),
        };
        for (k, (a, ca, b, cb)) in connections.iter().enumerate() {
            let (ia, ib) = (find(k, 0, *a, ca)?, find(k, 2, *b, cb)?);
            if a == b {
                return Err((format!("moduleConnection[{k}]"), format!("connects module {a} to itself")));
            }
            for (i, c) in [(*a, ia), (*b, ib)] {
                if !assembly.is_free(i, c) {
                    return Err((
                        format!("moduleConnection[{k}]"),
                        format!(
                            "connector `{}` of `{}` is already used",
                            instances[i].module.connectors[c].id, instances[i].name
                        ),
                    ));
                }
            }
            if let Some(why) = instances[*a].module.connectors[ia].mismatch(&instances[*b].module.connectors[ib]) {
                return Err((format!("moduleConnection[{k}]"), format!("the connectors do not mate: {why}")));
            }
            assembly.connections.push(((*a, ia), (*b, ib)));
        }
        assembly.base = match base {
            Some((i, id)) => {
                let instance = instances.get(i).ok_or_else(|| {
                    (
                        "baseConnection[0][0]".to_string(),
                        format!("module index {i}; moduleOrder has {} modules", instances.len()),
                    )
                })?;
                let c = instance.module.connectors.iter().position(|c| c.id == id).ok_or_else(|| {
                    (
                        "baseConnection[0][1]".to_string(),
                        format!("module `{}` has no connector `{id}`", instance.name),
                    )
                })?;
                if !assembly.is_free(i, c) {
                    return Err((
                        "baseConnection[0]".into(),
                        format!("connector `{id}` of `{}` is used by a connection", instance.name),
                    ));
                }
                (i, c)
            }
            None => {
                let free_bases: Vec<(usize, usize)> = (0..instances.len())
                    .flat_map(|i| (0..instances[i].module.connectors.len()).map(move |c| (i, c)))
                    .filter(|&(i, c)| assembly.is_free(i, c) && instances[i].module.connectors[c].kind == "base")
                    .collect();
                match free_bases.as_slice() {
                    [one] => *one,
                    _ => {
                        return Err((
                            "baseConnection".into(),
                            format!(
                                "not given, and the assembly has {} free connectors of type `base`; expected exactly one",
                                free_bases.len()
                            ),
                        ))
                    }
                }
            }
        };
        Ok(assembly)
    }

    /// The connector at the other side of connector `c` of instance `i`, if connected.
    fn mate(&self, i: usize, c: usize) -> Option<(usize, usize)> {
        self.connections.iter().find_map(|&(a, b)| {
            if a == (i, c) {
                Some(b)
            } else if b == (i, c) {
                Some(a)
            } else {
                None
            }
        })
    }
}

fn describe_connector(instance: &str, c: &Connector) -> String {
    format!(
        "`{}` of `{instance}` ({}, `{}`, size {:?})",
        c.id,
        c.gender.letter(),
        c.kind,
        c.size
    )
}

fn or_none<S: AsRef<str>>(items: &[S]) -> String {
    if items.is_empty() {
        "none".into()
    } else {
        items.iter().map(AsRef::as_ref).collect::<Vec<_>>().join(", ")
    }
}

/// A link under construction: its bodies and where each sits in the link frame.
struct LinkParts {
    bodies: Vec<((usize, usize), Isometry3<f64>)>,
    child_joint: bool,
}

/// The serial model of an assembly of the set read from `module_set`. `path` is the assembly file
/// (for messages), `world_from_pose` its `basePose`.
pub(crate) fn model(
    assembly: &Assembly,
    module_set: &Path,
    path: &Path,
    name: String,
    world_from_pose: Isometry3<f64>,
    mut diagnostics: Vec<Diagnostic>,
) -> Result<Model, ModelError> {
    let invalid = |element: String, message: String| ModelError::InvalidValue {
        path: path.to_path_buf(),
        element,
        message,
    };
    let (bi, bc) = assembly.base;
    let base_connector = &assembly.instances[bi].module.connectors[bc];
    let world_from_base = world_from_pose * flip() * base_connector.body_from_connector.inverse();

    let mut links = vec![LinkParts {
        bodies: vec![],
        child_joint: false,
    }];
    let mut joints: Vec<Joint> = Vec::new();
    let mut free: Vec<(usize, Isometry3<f64>, String, bool)> = Vec::new();
    let mut visited: Vec<(usize, usize)> = Vec::new();
    // (instance, body, link, link_from_body)
    let mut stack = vec![(bi, base_connector.body, 0usize, Isometry3::identity())];
    while let Some((i, b, link, link_from_body)) = stack.pop() {
        if visited.contains(&(i, b)) {
            return Err(invalid(
                format!(
                    "module `{}`, body `{}`",
                    assembly.instances[i].name, assembly.instances[i].module.bodies[b].id
                ),
                "is reached twice from the base: the assembly has a closed loop; only trees of modules are assemblies".into(),
            ));
        }
        visited.push((i, b));
        links[link].bodies.push(((i, b), link_from_body));
        let module = assembly.instances[i].module;
        for (c, connector) in module.connectors.iter().enumerate().filter(|(_, c)| c.body == b) {
            if (i, c) == assembly.base {
                continue;
            }
            let link_from_connector = link_from_body * connector.body_from_connector;
            match assembly.mate(i, c) {
                Some((j, d)) => {
                    let other = &assembly.instances[j].module.connectors[d];
                    if !visited.contains(&(j, other.body)) {
                        stack.push((
                            j,
                            other.body,
                            link,
                            link_from_connector * flip() * other.body_from_connector.inverse(),
                        ));
                    }
                }
                None => free.push((
                    link,
                    link_from_connector,
                    format!("{}.{}", assembly.instances[i].name, connector.id),
                    connector.kind == "eef",
                )),
            }
        }
        for joint in &module.joints {
            let forward = joint.parent == b;
            if !forward && joint.child != b {
                continue;
            }
            let other = if forward { joint.child } else { joint.parent };
            if visited.contains(&(i, other)) {
                continue;
            }
            let (to_joint, from_joint) = if forward {
                (joint.parent_from_joint, joint.joint_from_child)
            } else {
                (joint.joint_from_child.inverse(), joint.parent_from_joint.inverse())
            };
            let Some(kind) = joint.kind else {
                stack.push((i, other, link, link_from_body * to_joint * from_joint));
                continue;
            };
            let joint_name = format!("{}.{}", assembly.instances[i].name, joint.id);
            if links[link].child_joint {
                return Err(invalid(
                    format!("joint `{joint_name}`"),
                    "branches off a link that already has a moving joint below it: the assembly is a tree of joints, and proving-ground checks serial arms (one chain from the base to the tool)".into(),
                ));
            }
            links[link].child_joint = true;
            joints.push(Joint {
                name: joint_name,
                kind,
                parent_from_joint: link_from_body * to_joint,
                axis: Vector3::z_axis(),
                limits: joint.limits,
                max_velocity: joint.max_velocity,
                max_effort: joint.max_effort,
            });
            links.push(LinkParts {
                bodies: vec![],
                child_joint: false,
            });
            stack.push((i, other, links.len() - 1, from_joint));
        }
    }
    if joints.is_empty() {
        return Err(invalid("moduleOrder".into(), "the assembly has no moving joint".into()));
    }
    if joints.len() > crate::limits::MAX_JOINTS {
        return Err(invalid(
            "moduleOrder".into(),
            format!("{} moving joints; the limit is {}", joints.len(), crate::limits::MAX_JOINTS),
        ));
    }
    let tool = tool_connector(&free).map_err(|problem| invalid("the tool".into(), problem))?;
    let last = links.len() - 1;
    if tool.0 != last {
        return Err(invalid(
            format!("connector `{}`", tool.2),
            format!(
                "is the tool, but it sits on link {} and the chain goes on to joint {}: the tool is at the end of the chain",
                tool.0,
                joints.len()
            ),
        ));
    }
    let last_from_tool = tool.1;

    let mut model_links = Vec::with_capacity(links.len());
    for (index, parts) in links.iter().enumerate() {
        let names: Vec<String> = parts
            .bodies
            .iter()
            .map(|((i, b), _)| format!("{}.{}", assembly.instances[*i].name, assembly.instances[*i].module.bodies[*b].id))
            .collect();
        let mut colliders: Vec<Collider> = Vec::new();
        let mut masses: Vec<Inertial> = Vec::new();
        for ((i, b), link_from_body) in &parts.bodies {
            let body = &assembly.instances[*i].module.bodies[*b];
            for collider in &body.colliders {
                colliders.push(Collider {
                    link_from_shape: link_from_body * collider.link_from_shape,
                    shape: collider.shape.clone(),
                    label: format!("{}.{}", assembly.instances[*i].name, collider.label),
                });
            }
            if let Some(inertial) = &body.inertial {
                masses.push(inertial.transformed(link_from_body));
            }
        }
        let inertial = if index == 0 {
            Inertial::combine(&masses)
        } else {
            Some(moving_inertial(
                &masses,
                &names[0],
                &joints[index - 1].name,
                path,
                &mut diagnostics,
            )?)
        };
        if index > 0 && colliders.is_empty() {
            diagnostics.push(Diagnostic {
                path: path.to_path_buf(),
                element: format!("link `{}`", names[0]),
                message: "has no collision geometry: nothing it holds can be found in contact".into(),
            });
        }
        model_links.push(Link {
            name: names[0].clone(),
            merged: names[1..].to_vec(),
            colliders,
            inertial,
            segments: vec![],
        });
    }
    crate::model::add_bones(&mut model_links, &joints, &last_from_tool);
    Ok(Model {
        name,
        source: ModelSource::Timor {
            path: path.to_path_buf(),
            module_set: module_set.to_path_buf(),
            modules: assembly.instances.iter().map(|i| i.module.id.clone()).collect(),
            tool: tool.2.clone(),
            choices: vec![],
        },
        world_from_base,
        joints,
        links: model_links,
        last_from_tool,
        diagnostics,
    })
}

/// The tool: the one free connector other than the base, else the one of type `eef` among them.
fn tool_connector(free: &[(usize, Isometry3<f64>, String, bool)]) -> Result<&(usize, Isometry3<f64>, String, bool), String> {
    let eef: Vec<&(usize, Isometry3<f64>, String, bool)> = free.iter().filter(|f| f.3).collect();
    match (free, eef.as_slice()) {
        ([one], _) => Ok(one),
        (_, [one]) => Ok(one),
        ([], _) => Err("no free connector is left for the tool (every connector but the base is connected)".into()),
        _ => {
            let names: Vec<&str> = free.iter().map(|f| f.2.as_str()).collect();
            Err(format!(
                "{} free connectors could hold the tool ({}) and {} of them has type `eef`; expected one free connector, or one of type `eef`",
                free.len(),
                names.join(", "),
                eef.len()
            ))
        }
    }
}

/// The mass (kg) and radius (m) of the token body a massless moving link gets: negligible beside
/// any module (Timor's lightest carry 0.1 kg), enough for the engines' positive-mass checks.
const TOKEN_MASS_KG: f64 = 1e-3;
const TOKEN_RADIUS_M: f64 = 0.01;

/// A moving link's mass properties: physical, or balanced with a warning as for URDFs.
fn moving_inertial(
    masses: &[Inertial],
    link: &str,
    joint: &str,
    path: &Path,
    diagnostics: &mut Vec<Diagnostic>,
) -> Result<Inertial, ModelError> {
    let bad = |problem: String| ModelError::BadInertia {
        path: path.to_path_buf(),
        link: link.into(),
        joint: joint.into(),
        problem,
    };
    // Timor's modules give the bodies between two joints of one module (a pan-tilt's middle
    // body, its output flange) mass 0, which its rigid-body model allows and the engines do
    // not: such a link gets a token mass, said in a warning.
    let Some(inertial) = Inertial::combine(masses) else {
        diagnostics.push(Diagnostic {
            path: path.to_path_buf(),
            element: format!("link `{link}` inertia"),
            message: format!(
                "every body it holds has mass 0 (as Timor allows); the engines and the static load get {TOKEN_MASS_KG} kg, a sphere of {TOKEN_RADIUS_M} m radius, in its place"
            ),
        });
        return Ok(Inertial::solid_sphere(TOKEN_MASS_KG, TOKEN_RADIUS_M));
    };
    match inertial.check() {
        Ok(()) => Ok(inertial),
        Err(problem) => {
            let (fixed, shortfall) = inertial.balanced().ok_or_else(|| bad(problem.clone()))?;
            diagnostics.push(Diagnostic {
                path: path.to_path_buf(),
                element: format!("link `{link}` inertia"),
                message: format!(
                    "{problem}, short by {:.2} %: its two smaller principal moments are each raised by half of that",
                    shortfall * 100.0
                ),
            });
            Ok(fixed)
        }
    }
}
