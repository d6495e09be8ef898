//! Builds the rapier world of one run: the robot (a multibody, or kinematic bodies for a replay),
//! the obstacles, the floor and the contact filter, and converts poses between nalgebra (f64)
//! and rapier's glam types (f32).

use crate::collide::{Body, CollisionWorld};
use crate::engine::EngineError;
use crate::model::{JointKind, Model, Shape, TriMesh};
use crate::scenario::Scenario;
use nalgebra::{Isometry3, Matrix3, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3};
use rapier3d::prelude as rp;
use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI};

/// Height above the floor (m) beyond which a collider's bounding box is left out of the floor's
/// narrow phase. A half-space's bounding box is all of space, so the broad phase pairs every
/// link with the floor at every step, and every convex piece of a mesh link was then collided
/// with it (a seventh of a mesh robot's run). rapier keeps contact points up to its prediction
/// distance (2 cm at its default length unit of 1 m) away; beyond that the manifold would be
/// empty, so skipping the pair changes nothing but the time.
const FLOOR_SKIP_CLEARANCE_M: f32 = 0.1;

/// How the robot moves in the world being built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Drive {
    /// A multibody on a fixed base, moved by joint motors.
    Motors,
    /// One kinematic body per link, placed by the caller.
    Placed,
}

/// The names of a contact, link first, keyed by the two bodies' collider codes.
type PairNames = HashMap<(u128, u128), (String, String)>;

/// A built world and what the run loop needs to read it.
pub(super) struct Scene {
    /// Everything rapier simulates.
    pub(super) world: rp::PhysicsWorld,
    /// Rigid body of each model link, chain order (`links[0]` the base).
    pub(super) links: Vec<rp::RigidBodyHandle>,
    /// Lets through exactly the checked pairs of the collision world.
    pub(super) filter: PairFilter,
}

/// Collider `user_data` of a body: the kind in the high 64 bits, the index in the low 32 (a
/// link collider's index in `Link::colliders` in bits 32 to 63, see [`shape_code`]).
fn body_code(body: Body) -> u128 {
    match body {
        Body::Link(i) => i as u128,
        Body::Obstacle(k) => (1u128 << 64) | k as u128,
        Body::Floor => 2u128 << 64,
    }
}

/// Collider `user_data` of collider `element` of link `link`.
fn shape_code(link: usize, element: usize) -> u128 {
    ((element as u128) << 32) | link as u128
}

/// The body code of a collider's `user_data` (its collider index dropped).
fn body_of(code: u128) -> u128 {
    code & !(0xFFFF_FFFFu128 << 32)
}

/// `(link, collider)` of a link collider's `user_data`; `None` for obstacles and the floor.
fn shape_of(code: u128) -> Option<(usize, usize)> {
    (code >> 64 == 0).then_some(((code & 0xFFFF_FFFF) as usize, ((code >> 32) & 0xFFFF_FFFF) as usize))
}

fn ordered(a: u128, b: u128) -> (u128, u128) {
    if a <= b {
        (a, b)
    } else {
        (b, a)
    }
}

/// The contact filter: a collider pair is computed (and solved) only when its two bodies form a
/// pair the collision world checks, so adjacent links, structurally overlapping links and the
/// mounted base on the floor stay out exactly as in the parry check.
pub(super) struct PairFilter {
    names: PairNames,
    /// Link collider pairs left out of checked link pairs, as `user_data` codes, ordered.
    skipped: std::collections::HashSet<(u128, u128)>,
    flags: rp::SolverFlags,
    /// The floor's height (m), when the scenario has a floor.
    floor_height: Option<f32>,
}

impl PairFilter {
    fn new(world: &CollisionWorld, flags: rp::SolverFlags, floor_height: Option<f32>) -> Self {
        let names = world
            .pairs()
            .iter()
            .filter(|pair| world.engines_collide(pair))
            .map(|pair| {
                (
                    ordered(body_code(pair.a), body_code(pair.b)),
                    (pair.a_name.clone(), pair.b_name.clone()),
                )
            })
            .collect();
        let skipped = world
            .excluded_shape_indices()
            .map(|((i, a), (j, b))| ordered(shape_code(i, a), shape_code(j, b)))
            .collect();
        Self {
            names,
            skipped,
            flags,
            floor_height,
        }
    }

    /// Names of the checked pair of two colliders' codes, link first.
    pub(super) fn names(&self, a: u128, b: u128) -> Option<&(String, String)> {
        if !self.lets_through(a, b) {
            return None;
        }
        self.names.get(&ordered(body_of(a), body_of(b)))
    }

    /// Whether two colliders' contacts count: their bodies' pair is checked and the shape pair
    /// is not left out.
    fn lets_through(&self, a: u128, b: u128) -> bool {
        self.names.contains_key(&ordered(body_of(a), body_of(b)))
            && (shape_of(a).is_none() || shape_of(b).is_none() || !self.skipped.contains(&ordered(a, b)))
    }
}

impl rp::PhysicsHooks for PairFilter {
    fn filter_contact_pair(&self, context: &rp::PairFilterContext) -> Option<rp::SolverFlags> {
        let first = context.colliders.get(context.collider1)?;
        let second = context.colliders.get(context.collider2)?;
        if !self.lets_through(first.user_data, second.user_data) {
            return None;
        }
        if let Some(height) = self.floor_height {
            let floor = body_code(Body::Floor);
            let other = match (first.user_data == floor, second.user_data == floor) {
                (true, _) => Some(second),
                (_, true) => Some(first),
                _ => None,
            };
            if other.is_some_and(|collider| collider.compute_aabb().mins.z > height + FLOOR_SKIP_CLEARANCE_M) {
                return None;
            }
        }
        Some(self.flags)
    }
}

/// A rapier pose (f32) from an nalgebra isometry.
pub(super) fn pose_of(iso: &Isometry3<f64>) -> rp::Pose {
    let t = iso.translation.vector;
    let q = iso.rotation.quaternion();
    rp::Pose::from_parts(
        rp::Vector::new(t.x as f32, t.y as f32, t.z as f32),
        rp::Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32).normalize(),
    )
}

/// An nalgebra isometry from a rapier pose.
pub(super) fn isometry_of(pose: &rp::Pose) -> Isometry3<f64> {
    let t = pose.translation;
    let q = pose.rotation;
    Isometry3::from_parts(
        Translation3::new(t.x as f64, t.y as f64, t.z as f64),
        UnitQuaternion::from_quaternion(Quaternion::new(q.w as f64, q.x as f64, q.y as f64, q.z as f64)),
    )
}

/// Rotation taking rapier's joint x axis onto the model's joint axis.
fn x_onto(axis: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(&Vector3::x(), axis)
        // Only an axis along -x has no unique shortest rotation; any half turn about z will do.
        .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), PI))
}

fn rapier_error(model: &Model, message: String) -> EngineError {
    EngineError::Rapier {
        model: model.name.clone(),
        message,
    }
}

/// A rapier collider builder for one exact shape placed at `parent_from_shape`.
fn collider(shape: &Shape, parent_from_shape: &Isometry3<f64>, what: &str, model: &Model) -> Result<rp::ColliderBuilder, EngineError> {
    // parry's cylinder axis is y, ours z: turn y onto z.
    let y_onto_z = Isometry3::rotation(Vector3::x() * FRAC_PI_2);
    let (builder, pose) = match shape {
        Shape::Sphere { radius } => (rp::ColliderBuilder::ball(*radius as f32), *parent_from_shape),
        Shape::Box { half_extents } => (
            rp::ColliderBuilder::cuboid(half_extents[0] as f32, half_extents[1] as f32, half_extents[2] as f32),
            *parent_from_shape,
        ),
        Shape::Capsule { radius, length } => (
            rp::ColliderBuilder::capsule_z((length / 2.0) as f32, *radius as f32),
            *parent_from_shape,
        ),
        Shape::Cylinder { radius, length } => (
            rp::ColliderBuilder::cylinder((length / 2.0) as f32, *radius as f32),
            parent_from_shape * y_onto_z,
        ),
        Shape::Mesh(mesh) => (mesh_collider(mesh, what, model)?, *parent_from_shape),
    };
    Ok(builder.position(pose_of(&pose)).density(0.0))
}

/// A mesh as the compound of its convex pieces ([`crate::convex`]): rapier collides two
/// non-convex trimeshes slowly, and the pieces are what MuJoCo collides too. A mesh without
/// pieces (VHACD found no volume) stays a trimesh.
fn mesh_collider(mesh: &TriMesh, what: &str, model: &Model) -> Result<rp::ColliderBuilder, EngineError> {
    let point = |v: &[f64; 3]| rp::Vector::new(v[0] as f32, v[1] as f32, v[2] as f32);
    if let Some(pieces) = crate::convex::pieces(mesh) {
        let parts: Vec<(rp::Pose, rp::SharedShape)> = pieces
            .iter()
            // A piece too thin for an f32 hull is left out: its neighbours cover its surface.
            .filter_map(|piece| {
                let points: Vec<rp::Vector> = piece.vertices.iter().map(point).collect();
                rp::SharedShape::convex_hull(&points).map(|shape| (rp::Pose::IDENTITY, shape))
            })
            .collect();
        if !parts.is_empty() {
            return Ok(rp::ColliderBuilder::compound(parts));
        }
    }
    let vertices = mesh.vertices.iter().map(point).collect();
    rp::ColliderBuilder::trimesh(vertices, mesh.triangles.clone())
        .map_err(|e| rapier_error(model, format!("{what}: mesh {}: {e}", mesh.file.display())))
}

/// Builds the world with the robot at configuration `q` (at rest), the scenario's obstacles and
/// floor, gravity along -z and the step `timestep_s`.
pub(super) fn build(
    model: &Model,
    scenario: &Scenario,
    collision: &CollisionWorld,
    q: &[f64],
    drive: Drive,
    timestep_s: f64,
    gravity_m_s2: f64,
) -> Result<Scene, EngineError> {
    let link_meshes = model.links.iter().flat_map(|l| &l.colliders).map(|c| &c.shape);
    let obstacle_meshes = scenario.obstacles.iter().map(|o| &o.shape);
    crate::convex::prepare(link_meshes.chain(obstacle_meshes).filter_map(|shape| match shape {
        Shape::Mesh(mesh) => Some(mesh),
        _ => None,
    }));
    let mut world = rp::PhysicsWorld::new();
    world.gravity = rp::Vector::new(0.0, 0.0, -gravity_m_s2 as f32);
    world.integration_parameters.dt = timestep_s as f32;
    // A recycled pair keeps contact depths up to 5 cm stale; depths are what we record.
    world.integration_parameters.contact_recycling = false;
    // No continuous collision detection: rapier sweeps a body it finds fast against every fixed
    // collider, and its thin convex pieces count as fast at arm speeds, which cost a fifth of a
    // mesh robot's run. At 1 ms steps a link moves millimetres, and a contact is something we
    // record and judge, not something the engine should clamp motion to avoid.
    world.integration_parameters.max_ccd_substeps = 0;

    let mut kinematics = model.workspace();
    model.forward(q, &mut kinematics);
    // Every robot pair with a body that is not dynamic (the base, kinematic links, obstacles)
    // is off by default; the filter decides instead.
    let robot_collider = |builder: rp::ColliderBuilder, link: usize, element: usize| {
        builder
            .user_data(shape_code(link, element))
            .active_hooks(rp::ActiveHooks::FILTER_CONTACT_PAIRS)
            .active_collision_types(rp::ActiveCollisionTypes::all())
    };

    let mut links = Vec::with_capacity(model.links.len());
    for (index, link) in model.links.iter().enumerate() {
        let pose = pose_of(&kinematics.link_in_world[index]);
        let body = match (drive, index) {
            (Drive::Placed, _) => rp::RigidBodyBuilder::kinematic_position_based(),
            (Drive::Motors, 0) => rp::RigidBodyBuilder::fixed(),
            (Drive::Motors, _) => {
                let inertial = link.inertial.as_ref().ok_or_else(|| {
                    rapier_error(
                        model,
                        format!(
                            "link `{}` is moved by joint `{}` but has no mass",
                            link.name,
                            model.joints[index - 1].name
                        ),
                    )
                })?;
                rp::RigidBodyBuilder::dynamic()
                    .additional_mass_properties(mass_properties(inertial.mass, &inertial.com, &inertial.inertia))
                    .can_sleep(false)
            }
        };
        let handle = world.insert_body(body.pose(pose));
        for (k, part) in link.colliders.iter().enumerate() {
            let what = format!("link `{}` collider {k} ({})", link.name, part.label);
            let builder = collider(&part.shape, &part.link_from_shape, &what, model)?;
            world.insert_collider(robot_collider(builder, index, k), Some(handle));
        }
        links.push(handle);
    }

    if drive == Drive::Motors {
        attach_joints(model, q, &mut world, &links)?;
    }

    for (k, obstacle) in scenario.obstacles.iter().enumerate() {
        let what = format!("obstacle `{}`", obstacle.name);
        let builder = collider(&obstacle.shape, &obstacle.world_from_shape, &what, model)?;
        world.insert_collider(builder.user_data(body_code(Body::Obstacle(k))), None);
    }
    if let Some(floor) = &scenario.floor {
        let builder = rp::ColliderBuilder::new(rp::SharedShape::halfspace(rp::Vector::Z))
            .position(rp::Pose::from_translation(rp::Vector::new(0.0, 0.0, floor.height as f32)))
            .user_data(body_code(Body::Floor));
        world.insert_collider(builder, None);
    }

    let flags = match drive {
        Drive::Motors => rp::SolverFlags::COMPUTE_RIGID_IMPULSES,
        Drive::Placed => rp::SolverFlags::empty(),
    };
    Ok(Scene {
        world,
        links,
        filter: PairFilter::new(collision, flags, scenario.floor.as_ref().map(|floor| floor.height as f32)),
    })
}

/// Mass properties from the model's inertial: rapier wants principal moments and their frame,
/// found here in f64 before rounding to f32.
fn mass_properties(mass: f64, com: &Vector3<f64>, inertia: &Matrix3<f64>) -> rp::MassProperties {
    let eigen = nalgebra::SymmetricEigen::new(*inertia);
    let mut axes = eigen.eigenvectors;
    if axes.determinant() < 0.0 {
        axes.set_column(2, &(-axes.column(2)));
    }
    let frame = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(axes));
    let q = frame.quaternion();
    let moments = eigen.eigenvalues.map(|m| m.max(0.0) as f32);
    rp::MassProperties::with_principal_inertia_frame(
        rp::Vector::new(com.x as f32, com.y as f32, com.z as f32),
        mass as f32,
        rp::Vector::new(moments[0], moments[1], moments[2]),
        rp::Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32).normalize(),
    )
}

/// The rapier axis a joint's motor drives.
pub(super) fn motor_axis(kind: JointKind) -> rp::JointAxis {
    match kind {
        JointKind::Prismatic => rp::JointAxis::LinX,
        JointKind::Revolute | JointKind::Continuous => rp::JointAxis::AngX,
    }
}

/// Chains the links into one multibody rooted at the fixed base, every joint with a force-based
/// motor (gains set by the run loop), and sets the joint coordinates to `q` at rest.
fn attach_joints(model: &Model, q: &[f64], world: &mut rp::PhysicsWorld, links: &[rp::RigidBodyHandle]) -> Result<(), EngineError> {
    for (j, joint) in model.joints.iter().enumerate() {
        let align = Isometry3::from_parts(Translation3::identity(), x_onto(&joint.axis));
        let locked = match joint.kind {
            JointKind::Prismatic => rp::JointAxesMask::LOCKED_PRISMATIC_AXES,
            JointKind::Revolute | JointKind::Continuous => rp::JointAxesMask::LOCKED_REVOLUTE_AXES,
        };
        let axis = motor_axis(joint.kind);
        let data = rp::GenericJointBuilder::new(locked)
            .local_frame1(pose_of(&(joint.parent_from_joint * align)))
            .local_frame2(pose_of(&align))
            .contacts_enabled(false)
            .motor_model(axis, rp::MotorModel::ForceBased)
            .set_motor(axis, 0.0, 0.0, 0.0, 0.0)
            .build();
        world
            .multibody_joints
            .insert(links[j], links[j + 1], data, true)
            .ok_or_else(|| rapier_error(model, format!("joint `{}` could not join the multibody", joint.name)))?;
    }
    let Some(multibody) = multibody_of(world, links) else {
        return Ok(());
    };
    let bodies = &mut world.bodies;
    let multibody = world
        .multibody_joints
        .get_multibody_mut(multibody)
        .expect("the index was just looked up");
    // The first kinematics pass turns the root into a fixed one; only then does the multibody
    // have one coordinate per model joint.
    multibody.forward_kinematics(bodies, true);
    if multibody.ndofs() != q.len() {
        return Err(rapier_error(
            model,
            format!("the multibody has {} degrees of freedom, the model {}", multibody.ndofs(), q.len()),
        ));
    }
    let displacement: Vec<f32> = q.iter().map(|&v| v as f32).collect();
    multibody.apply_displacements(&displacement);
    multibody.forward_kinematics(bodies, true);
    multibody.update_rigid_bodies(bodies, true);
    // rapier adds 0.1 N m s/rad of joint damping by default; the gains are the whole controller.
    multibody.damping_mut().fill(0.0);
    Ok(())
}

/// The multibody the robot's links form, if it has joints.
pub(super) fn multibody_of(world: &rp::PhysicsWorld, links: &[rp::RigidBodyHandle]) -> Option<rp::MultibodyIndex> {
    links
        .get(1)
        .and_then(|&h| world.multibody_joints.rigid_body_link(h))
        .map(|link| link.multibody)
}
