//! The robot in rapier (`rapier3d` 0.36, f32): a dynamic run that drives a multibody along a
//! [`TimedPath`] with joint motors ([`run_rapier`]), and a kinematic replay that only runs the
//! collision detection at given configurations ([`replay_rapier`]). Both fill an [`EngineRun`].
//!
//! # The model in rapier
//!
//! - One rigid body per link, its frame the model's link frame. The base is fixed; the moving
//!   links carry the model's mass, centre of mass and inertia (principal moments and frame found
//!   in f64, then rounded), and their colliders have density 0 so the geometry adds no mass.
//! - The joints form one multibody (reduced coordinates, so the chain cannot drift apart): each
//!   joint's rapier x axis is turned onto the model's axis, contacts between the two links it
//!   joins are off, and rapier's default joint damping (0.1 N m s/rad) is removed. Joint limits
//!   are not given to rapier: the reference stays within them.
//! - Colliders are the exact shapes: balls, cuboids, `capsule_z`, and cylinders turned by +90
//!   degrees about x (parry's cylinder axis is y, ours z). A mesh is a compound of its convex
//!   pieces ([`crate::convex`], the same pieces MuJoCo gets): solid, and far cheaper to collide
//!   than two non-convex trimeshes; a mesh VHACD cannot decompose (flat) stays a trimesh. Our
//!   parry check keeps the mesh itself, and re-measures every engine contact in it. Obstacles are
//!   parentless fixed colliders; the floor is a half-space whose top is at the floor height.
//!   Gravity is along -z.
//! - Everything is f32: positions near 1 m are resolved to about 1e-7 m, joint angles to 1e-7 rad.
//!
//! # Control: how rapier's motor maps to `tau = kp (q_ref - q) + kd (qd_ref - qd)`
//!
//! Each joint has a rapier motor in [`MotorModel::ForceBased`](rapier3d::prelude::MotorModel)
//! mode with `stiffness = kp` and `damping = kd` from [`Gains`] (the default, acceleration-based
//! mode would scale both by the joint's effective inertia). rapier solves the motor as a soft
//! velocity constraint at every solver substep (4 per step, `h = dt / 4`): the impulse `lambda`
//! it finds satisfies
//! `lambda / h = kp (q_target - q) + (kd + h kp) (qd_target - qd⁺)`, that is, with
//! `q⁺ = q + h qd⁺`, `lambda / h = kp (q_target + h qd_target - q⁺) + kd (qd_target - qd⁺)`:
//! exactly our law, evaluated implicitly at the end of the substep (backward Euler), so stiff
//! gains stay stable. The motor's target is the reference at the end of the step, `q_ref(t + dt)`
//! and `qd_ref(t + dt)`. The torque is unlimited (rated torques are judged from
//! [`EngineRun::peak_effort`], not enforced). `tests/rapier.rs` checks the mapping on a pendulum
//! that must settle where `kp` balances the gravity torque.
//!
//! rapier does not write the impulses of a multibody's own motors back (0.36: "we don't support
//! impulse writeback for internal constraints yet"), so the effort is the control law evaluated
//! on the state after each step, `kp (q_ref - q) + kd (qd_ref - qd)` at `t + dt`.
//!
//! # Contacts
//!
//! Contacts stay on: a collision is a physical event and pushes the robot like it would push the
//! real one; every contact is also recorded. A collider pair is only computed when its two bodies
//! form a pair [`CollisionWorld::pairs`] checks (a contact-pair hook), so adjacent links,
//! structurally overlapping links, excluded pairs and the mounted base on the floor are neither
//! simulated nor reported, exactly as in the parry check. The base is fixed, but its contacts
//! with obstacles are computed and reported too.
//!
//! rapier reports *predictive* contacts: every collider pair within the prediction distance
//! (`IntegrationParameters::prediction_distance`, 0.02 m by default) gets contact points with
//! `dist > 0` before the shapes touch. A pair is recorded only when its deepest point has
//! `dist < -RunOptions::contact_depth_m` (a penetration deeper than the option, strictly positive
//! with the default 0), with depth `-dist`. Collider skins are 0, so `dist` is the shapes' own
//! signed distance; contact recycling is off, so depths are never stale. The narrow phase runs at
//! the start of each step, so a dynamic step's contacts are recorded at the step's start time.
//!
//! # Recording
//!
//! After each step (time `t + dt`): per joint the tracking error against the reference, the tool
//! pose (last link body times `Model::last_from_tool`) against our forward kinematics of the
//! reference, and the effort. A goal hold is measured at the step nearest the end of its dwell.

mod scene;

use super::{ContactRecorder, EngineError, EngineRun, Gains, GoalHold, RunOptions};
use crate::collide::CollisionWorld;
use crate::model::{JointKind, Model};
use crate::plan::TimedPath;
use crate::scenario::Scenario;
use nalgebra::Isometry3;
use rapier3d::prelude as rp;
use scene::{build, isometry_of, motor_axis, multibody_of, Drive, PairFilter, Scene};

/// Runs `model` (already placed in the scenario) along `path` in rapier, joint motors with
/// `gains`, from the path's first configuration at rest until the path's end, and records
/// tracking, effort, goal holds and contacts (see the module docs).
///
/// # Errors
/// [`EngineError::Rapier`] when the path, the gains and the model disagree on the number of
/// joints, the step is not positive, a moving link has no mass or rapier rejects a mesh.
pub fn run_rapier(
    model: &Model,
    scenario: &Scenario,
    world: &CollisionWorld,
    path: &TimedPath,
    gains: &Gains,
    opts: &RunOptions,
) -> Result<EngineRun, EngineError> {
    super::inputs::check_run(model, path, gains, opts)?;
    let dof = model.dof();
    let Some(first) = path.segments.first() else {
        return Err(EngineError::EmptyPath { robot: model.name.clone() });
    };
    let mut scene = build(
        model,
        scenario,
        world,
        &first.from,
        Drive::Motors,
        opts.timestep_s,
        opts.gravity_m_s2,
    )?;
    let multibody = multibody_of(&scene.world, &scene.links);
    let dt = opts.timestep_s;
    let duration = path.duration_s();
    // A duration a rounding error above a whole number of steps takes no extra step.
    let steps = ((duration / dt) * (1.0 - 1e-12)).ceil().max(0.0) as usize;
    let hold_steps: Vec<(usize, usize, &[f64])> = path
        .holds()
        .iter()
        .map(|h| (h.goal, ((h.end_s / dt).round() as usize).clamp(1, steps.max(1)), h.q))
        .collect();

    let mut run = EngineRun {
        engine: "rapier",
        mode: "dynamic",
        steps,
        timestep_s: dt,
        max_joint_error: vec![0.0; dof],
        max_tool_position_error_m: 0.0,
        max_tool_orientation_error_rad: 0.0,
        holds: Vec::with_capacity(hold_steps.len()),
        contacts: Vec::new(),
        peak_effort: vec![0.0; dof],
    };
    let mut recorder = ContactRecorder::new();
    let mut kinematics = model.workspace();
    let mut q_ref = vec![0.0; dof];
    let mut qd_ref = vec![0.0; dof];
    let mut q = vec![0.0; dof];
    let mut qd = vec![0.0; dof];
    let mut q_before = first.from.clone();
    for step in 1..=steps {
        let t = step as f64 * dt;
        path.sample(t, &mut q_ref, &mut qd_ref);
        if let Some(index) = multibody {
            set_motor_targets(&mut scene.world, index, model, gains, &q_ref, &qd_ref);
        }
        scene.world.step_with_events(&scene.filter, &());
        // The narrow phase ran on the state at the step's start: the joints read after the
        // previous step.
        record_contacts(&scene, &mut recorder, t - dt, opts.contact_depth_m, &q_before);
        if let Some(index) = multibody {
            read_joints(&scene.world, index, model, &mut q, &mut qd);
        }
        q_before.copy_from_slice(&q);

        for j in 0..dof {
            run.max_joint_error[j] = run.max_joint_error[j].max((q[j] - q_ref[j]).abs());
            let effort = gains.stiffness[j] * (q_ref[j] - q[j]) + gains.damping[j] * (qd_ref[j] - qd[j]);
            run.peak_effort[j] = run.peak_effort[j].max(effort.abs());
        }
        let (position_error, orientation_error) = tool_error(model, &scene, &q_ref, &mut kinematics);
        run.max_tool_position_error_m = run.max_tool_position_error_m.max(position_error);
        run.max_tool_orientation_error_rad = run.max_tool_orientation_error_rad.max(orientation_error);
        for &(goal, _, held) in hold_steps.iter().filter(|h| h.1 == step) {
            let (position_error_m, orientation_error_rad) = tool_error(model, &scene, held, &mut kinematics);
            run.holds.push(GoalHold {
                goal,
                time_s: t,
                position_error_m,
                orientation_error_rad,
                joint_error: q.iter().zip(held).fold(0.0, |m, (a, b)| m.max((a - b).abs())),
            });
        }
    }
    run.contacts = recorder.finish();
    Ok(run)
}

/// Places the robot at each sample's configuration (time in s, joint values) and records the
/// contacts rapier's collision detection reports there, as [`run_rapier`] does; no dynamics.
/// The run has mode `kinematic`, one step per sample, zero tracking errors and efforts, and no
/// goal holds; `timestep_s` is `opts.timestep_s`.
///
/// # Errors
/// [`EngineError::Rapier`] when a sample does not have one value per joint or rapier rejects a
/// mesh.
pub fn replay_rapier(
    model: &Model,
    scenario: &Scenario,
    world: &CollisionWorld,
    samples: &[(f64, Vec<f64>)],
    opts: &RunOptions,
) -> Result<EngineRun, EngineError> {
    let dof = model.dof();
    super::inputs::check_replay(model, samples, opts)?;
    let start = samples.first().map_or_else(|| vec![0.0; dof], |(_, q)| q.clone());
    let mut scene = build(model, scenario, world, &start, Drive::Placed, opts.timestep_s, opts.gravity_m_s2)?;
    let mut recorder = ContactRecorder::new();
    let mut kinematics = model.workspace();
    for (t, q) in samples {
        model.forward(q, &mut kinematics);
        for (handle, pose) in scene.links.iter().zip(&kinematics.link_in_world) {
            if let Some(body) = scene.world.bodies.get_mut(*handle) {
                body.set_position(scene::pose_of(pose), true);
            }
        }
        scene.world.detect_collisions(&scene.filter, &());
        record_contacts(&scene, &mut recorder, *t, opts.contact_depth_m, q);
    }
    Ok(EngineRun {
        engine: "rapier",
        mode: "kinematic",
        steps: samples.len(),
        timestep_s: opts.timestep_s,
        max_joint_error: vec![0.0; dof],
        max_tool_position_error_m: 0.0,
        max_tool_orientation_error_rad: 0.0,
        holds: Vec::new(),
        contacts: recorder.finish(),
        peak_effort: vec![0.0; dof],
    })
}

/// Joint `j`'s multibody link: the base is link 0 and the joints were added in chain order.
fn joint_link(j: usize) -> usize {
    j + 1
}

fn set_motor_targets(world: &mut rp::PhysicsWorld, index: rp::MultibodyIndex, model: &Model, gains: &Gains, q: &[f64], qd: &[f64]) {
    let Some(multibody) = world.multibody_joints.get_multibody_mut(index) else {
        return;
    };
    for (j, joint) in model.joints.iter().enumerate() {
        if let Some(link) = multibody.link_mut(joint_link(j)) {
            link.joint.data.set_motor(
                motor_axis(joint.kind),
                q[j] as f32,
                qd[j] as f32,
                gains.stiffness[j] as f32,
                gains.damping[j] as f32,
            );
        }
    }
}

fn read_joints(world: &rp::PhysicsWorld, index: rp::MultibodyIndex, model: &Model, q: &mut [f64], qd: &mut [f64]) {
    let Some(multibody) = world.multibody_joints.get_multibody(index) else {
        return;
    };
    for (j, joint) in model.joints.iter().enumerate() {
        if let Some(link) = multibody.link(joint_link(j)) {
            // Generalized coordinates are laid out linear x y z, then angular x y z.
            let coordinate = match joint.kind {
                JointKind::Prismatic => 0,
                JointKind::Revolute | JointKind::Continuous => 3,
            };
            q[j] = link.joint().coords()[coordinate] as f64;
            qd[j] = multibody.joint_velocity(link)[0] as f64;
        }
    }
}

/// Tool position and orientation error (m, rad) of the simulated robot against our forward
/// kinematics of `q_ref`.
fn tool_error(model: &Model, scene: &Scene, q_ref: &[f64], kinematics: &mut crate::model::KinematicsWorkspace) -> (f64, f64) {
    let Some(last) = scene.links.last().and_then(|&h| scene.world.bodies.get(h)) else {
        return (0.0, 0.0);
    };
    let tool: Isometry3<f64> = isometry_of(last.position()) * model.last_from_tool;
    model.forward(q_ref, kinematics);
    let reference = &kinematics.tool_in_world;
    (
        (tool.translation.vector - reference.translation.vector).norm(),
        reference.rotation.angle_to(&tool.rotation),
    )
}

/// Records every checked pair whose deepest contact penetrates deeper than `depth_m`.
fn record_contacts(scene: &Scene, recorder: &mut ContactRecorder, time_s: f64, depth_m: f64, q: &[f64]) {
    recorder.begin_step();
    for pair in scene.world.narrow_phase.contact_pairs() {
        let Some((_, contact)) = pair.find_deepest_contact() else {
            continue;
        };
        let depth = -(contact.dist as f64);
        if depth <= depth_m {
            continue;
        }
        let colliders = &scene.world.colliders;
        let (Some(a), Some(b)) = (colliders.get(pair.collider1), colliders.get(pair.collider2)) else {
            continue;
        };
        if let Some((a_name, b_name)) = filter_names(&scene.filter, a.user_data, b.user_data) {
            recorder.contact(a_name, b_name, time_s, depth, q);
        }
    }
    recorder.end_step();
}

fn filter_names(filter: &PairFilter, a: u128, b: u128) -> Option<(&str, &str)> {
    filter.names(a, b).map(|(x, y)| (x.as_str(), y.as_str()))
}
