//! MuJoCo as the physics engine: the robot of our MJCF export, in its scenario, following a
//! [`TimedPath`] under gravity ([`run_mujoco`]), replaying configurations kinematically
//! ([`replay_mujoco`]); the static load check ([`static_load`](super::static_load)) loads the
//! model the same way.
//!
//! # The world
//!
//! The exported model ([`to_mjcf`]) with the scenario's obstacles as world geoms (named as the
//! obstacles), the floor as a plane `floor`, and `<exclude>` for every link pair the collision
//! world does not check (adjacent links, [`CollisionWorld::excluded`], links without geometry).
//! A link-obstacle or link-floor pair the world does not check is still simulated by MuJoCo
//! (an `<exclude>` names bodies, and obstacles are all in the world body) but not recorded; the
//! only such pair by default is the base against the floor, and the base never moves. MuJoCo
//! never collides two bodies fixed to the world, so a base-obstacle contact is not reported.
//! MuJoCo collides cylinders approximately (docs/collision.md): depths involving a
//! cylinder are MuJoCo's, not the exact ones. Meshes are written as their convex pieces
//! ([`crate::convex`], the pieces rapier collides), geoms `<link>/<k>/<p>` and `<obstacle>/<p>`,
//! each attributed to its link or obstacle, so a contact names the pair as before.
//!
//! # Control
//!
//! One MuJoCo position actuator per joint with `kp` = [`Gains::stiffness`] and `kv` =
//! [`Gains::damping`], and `ctrl = q_ref + (kd / kp) qd_ref`, so the actuator force is exactly
//! `kp (q_ref - q) + kd (qd_ref - qd)`, the law the rapier run uses. Actuators rather than an
//! explicit law in `qfrc_applied`: with the `implicitfast` integrator MuJoCo integrates the
//! actuators' velocity gain implicitly, so the large damping of stiff joints cannot destabilise
//! the 1 ms step (see [`gains`](fn@super::gains)). No gravity feedforward: the sag is what the gains
//! are sized for. Force and control ranges are not limited; the peak effort is recorded and
//! judged against the rating separately.
//!
//! # Stepping and recording
//!
//! Each step is split: `mj_step1` (positions, velocities, collision at time `t`), record the
//! state at `t` against the reference at `t`, set the controls from the reference at `t`,
//! `mj_step2` (forces and integration to `t + h`). So every record (errors, contacts) belongs
//! to one time. A goal hold is judged at the record closest to its `end_s`.

use super::{ContactRecorder, EngineError, EngineRun, Gains, GoalHold, RunOptions};
use crate::collide::{Body, CollisionWorld};
use crate::export::{to_mjcf, MjcfOptions};
use crate::frames::pose_difference;
use crate::model::{Collider, Model};
use crate::plan::TimedPath;
use crate::scenario::Scenario;
use mujoco_rs::prelude::*;
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion};
use std::collections::HashMap;

/// MuJoCo integrator of the runs: implicit in velocity-dependent forces, no Coriolis
/// derivatives (cheaper than `implicit`, and our damping is all in the actuators).
const INTEGRATOR: &str = "implicitfast";

/// A MuJoCo model of the robot in its scenario with our elements located.
pub(super) struct Loaded {
    pub(super) model: MjModel,
    qpos_address: Vec<usize>,
    pub(super) dof_address: Vec<usize>,
    actuator: Vec<usize>,
    tool_site: usize,
    /// Per geom id: the body of the collision world it belongs to, if any.
    geom_body: Vec<Option<Body>>,
    /// Checked pairs, keyed by the bodies ordered by [`order`], with the names as the
    /// collision world writes them (`a_name`, `b_name`), so both engines report the same.
    checked: HashMap<(Body, Body), (String, String)>,
}

impl Loaded {
    /// Exports and loads `model` in `scenario`. `gains` `None` writes no actuators.
    pub(super) fn new(
        model: &Model,
        scenario: Option<&Scenario>,
        world: Option<&CollisionWorld>,
        gains: Option<&Gains>,
        opts: &RunOptions,
    ) -> Result<Self, EngineError> {
        super::check_version()?;
        let checked: HashMap<(Body, Body), (String, String)> = world
            .map(|w| {
                w.pairs()
                    .iter()
                    .filter(|p| w.engines_collide(p))
                    .map(|p| (order(p.a, p.b), (p.a_name.clone(), p.b_name.clone())))
                    .collect()
            })
            .unwrap_or_default();
        // Every link pair the collision world does not check is excluded, so MuJoCo does not
        // push apart what our collision model deliberately leaves touching; a checked pair with
        // shape pairs left out is excluded as bodies and its other geom pairs collided explicitly.
        let mut excluded_body_pairs = Vec::new();
        let mut explicit_geom_pairs = Vec::new();
        if let Some(world) = world {
            for a in 0..model.links.len() {
                for b in a + 1..model.links.len() {
                    let names = (model.links[a].name.clone(), model.links[b].name.clone());
                    if !checked.contains_key(&(Body::Link(a), Body::Link(b))) {
                        excluded_body_pairs.push(names);
                        continue;
                    }
                    let shapes = |link: usize| 0..model.links[link].colliders.len();
                    let all = shapes(a).flat_map(|x| shapes(b).map(move |y| (x, y)));
                    if all.clone().all(|(x, y)| world.shape_pair_checked((a, x), (b, y))) {
                        continue;
                    }
                    explicit_geom_pairs.extend(
                        all.filter(|&(x, y)| world.shape_pair_checked((a, x), (b, y)))
                            .map(|(x, y)| (format!("{}/{x}", names.0), format!("{}/{y}", names.1))),
                    );
                    excluded_body_pairs.push(names);
                }
            }
        }
        let world_colliders = scenario
            .map(|s| {
                s.obstacles
                    .iter()
                    .map(|o| Collider {
                        link_from_shape: o.world_from_shape,
                        shape: o.shape.clone(),
                        label: o.name.clone(),
                    })
                    .collect()
            })
            .unwrap_or_default();
        let mjcf_options = MjcfOptions {
            timestep: opts.timestep_s,
            kp: gains.map(|g| g.stiffness.clone()),
            kv: gains.map(|g| g.damping.clone()),
            include_actuators: gains.is_some(),
            world_colliders,
            floor_height: scenario.and_then(|s| s.floor).map(|f| f.height),
            world_sites: Vec::new(),
            excluded_body_pairs,
            explicit_geom_pairs,
            gravity_m_s2: opts.gravity_m_s2,
            integrator: Some(INTEGRATOR.into()),
            // The pieces, not the hull MuJoCo would make of a whole mesh: the same shapes rapier
            // collides, and no phantom contact inside a mesh's concavity.
            convex_pieces: true,
            ..Default::default()
        };
        let xml = to_mjcf(model, &mjcf_options).map_err(|source| EngineError::Export {
            robot: model.name.clone(),
            source,
        })?;
        let source_name = format!("the MJCF export of `{}`", model.name);
        let mj = MjModel::from_xml_string(&xml).map_err(|e| EngineError::MujocoLoad {
            source_name: source_name.clone(),
            message: e.to_string(),
        })?;
        let find = |kind: MjtObjBase, label: &'static str, name: &str| {
            mj.name_to_id(kind, name).ok_or_else(|| EngineError::MissingElement {
                source_name: source_name.clone(),
                kind: label,
                name: name.to_string(),
            })
        };
        let mut qpos_address = Vec::with_capacity(model.dof());
        let mut dof_address = Vec::with_capacity(model.dof());
        let mut actuator = Vec::with_capacity(model.dof());
        for joint in &model.joints {
            let id = find(MjtObjBase::mjOBJ_JOINT, "joint", &joint.name)?;
            qpos_address.push(mj.jnt_qposadr()[id] as usize);
            dof_address.push(mj.jnt_dofadr()[id] as usize);
            if gains.is_some() {
                actuator.push(find(MjtObjBase::mjOBJ_ACTUATOR, "actuator", &joint.name)?);
            }
        }
        let tool_site = find(MjtObjBase::mjOBJ_SITE, "site", "tool")?;
        let link_names: Vec<String> = model.links.iter().map(|l| l.name.clone()).collect();
        let obstacle_names: Vec<String> = scenario
            .map(|s| s.obstacles.iter().map(|o| o.name.clone()).collect())
            .unwrap_or_default();
        let geom_body = (0..mj.ffi().ngeom as usize)
            .map(|geom| {
                let body = mj.geom_bodyid()[geom] as usize;
                let geom_name = mj.id_to_name(MjtObjBase::mjOBJ_GEOM, geom).unwrap_or_default();
                if body != 0 {
                    let body_name = mj.id_to_name(MjtObjBase::mjOBJ_BODY, body).unwrap_or_default();
                    return link_names.iter().position(|n| n == body_name).map(Body::Link);
                }
                // World body: the floor, an obstacle (a mesh's convex pieces `<name>/<p>`), or
                // the geoms of a base named `world` (`world/<k>`, pieces `world/<k>/<p>`).
                let piece_of = |name: &str| {
                    let (whole, piece) = name.rsplit_once('/')?;
                    piece.parse::<usize>().is_ok().then(|| whole.to_string())
                };
                if scenario.is_some_and(|s| s.floor.is_some()) && geom_name == "floor" {
                    Some(Body::Floor)
                } else if let Some(k) = obstacle_names.iter().position(|n| n == geom_name) {
                    Some(Body::Obstacle(k))
                } else if let Some(k) = piece_of(geom_name).and_then(|whole| obstacle_names.iter().position(|n| *n == whole)) {
                    Some(Body::Obstacle(k))
                } else {
                    let rest = geom_name.strip_prefix(link_names[0].as_str())?.strip_prefix('/')?;
                    let is_geom = rest.split('/').take(2).all(|part| part.parse::<usize>().is_ok());
                    is_geom.then_some(Body::Link(0))
                }
            })
            .collect();
        Ok(Self {
            model: mj,
            qpos_address,
            dof_address,
            actuator,
            tool_site,
            geom_body,
            checked,
        })
    }

    /// Records the contacts of `data` (after collision) at `time_s`: checked pairs only, depth
    /// at least `min_depth_m` (and never negative: MuJoCo also lists contacts within a margin).
    fn record_contacts(&self, data: &MjData<&MjModel>, recorder: &mut ContactRecorder, time_s: f64, min_depth_m: f64) {
        recorder.begin_step();
        let mut q: Option<Vec<f64>> = None;
        for contact in data.contact() {
            let depth = -contact.dist;
            // Strictly deeper than the tolerance counts, as in the rapier run.
            if depth <= min_depth_m.max(0.0) {
                continue;
            }
            let body = |geom: i32| usize::try_from(geom).ok().and_then(|g| self.geom_body.get(g).copied().flatten());
            let (Some(a), Some(b)) = (body(contact.geom1), body(contact.geom2)) else {
                continue;
            };
            if let Some((a_name, b_name)) = self.checked.get(&order(a, b)) {
                let q = q.get_or_insert_with(|| self.qpos_address.iter().map(|&address| data.qpos()[address]).collect());
                recorder.contact(a_name, b_name, time_s, depth, q);
            }
        }
        recorder.end_step();
    }

    /// World pose of the tool site (after kinematics).
    fn tool_pose(&self, data: &MjData<&MjModel>) -> Isometry3<f64> {
        let position = data.site_xpos()[self.tool_site];
        let matrix = Matrix3::from_row_slice(&data.site_xmat()[self.tool_site]);
        Isometry3::from_parts(
            Translation3::new(position[0], position[1], position[2]),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(matrix)),
        )
    }

    pub(super) fn set_configuration(&self, data: &mut MjData<&MjModel>, q: &[f64]) {
        for (&address, &value) in self.qpos_address.iter().zip(q) {
            data.qpos_mut()[address] = value;
        }
    }
}

/// Pair order: links before obstacles before the floor, lower index first.
fn order(a: Body, b: Body) -> (Body, Body) {
    let rank = |body: Body| match body {
        Body::Link(i) => (0, i),
        Body::Obstacle(k) => (1, k),
        Body::Floor => (2, 0),
    };
    if rank(a) <= rank(b) {
        (a, b)
    } else {
        (b, a)
    }
}

/// Per-run maxima of tracking errors.
struct Tracking {
    max_joint_error: Vec<f64>,
    max_position_m: f64,
    max_orientation_rad: f64,
}

/// Runs the robot along `path` in MuJoCo (see the module docs): `model` is the placed model the
/// collision `world` was built for, started at rest at the path's first configuration, driven
/// by position actuators with `gains`, for the path's duration (rounded up to whole steps).
///
/// # Errors
/// [`EngineError::InvalidTimestep`] for a step that is not positive, [`EngineError::Export`]
/// when the model cannot be exported (including gains not matching the joints),
/// [`EngineError::MujocoLoad`] / [`EngineError::Mujoco`] from MuJoCo,
/// [`EngineError::ConfigurationLength`] for a path whose configurations do not fit the model.
pub fn run_mujoco(
    model: &Model,
    scenario: &Scenario,
    world: &CollisionWorld,
    path: &TimedPath,
    gains: &Gains,
    opts: &RunOptions,
) -> Result<EngineRun, EngineError> {
    super::inputs::check_run(model, path, gains, opts)?;
    let dof = model.dof();
    let loaded = Loaded::new(model, Some(scenario), Some(world), Some(gains), opts)?;
    let mut data = loaded.model.make_data();
    let h = opts.timestep_s;
    let (mut q_ref, mut qd_ref) = (vec![0.0; dof], vec![0.0; dof]);
    path.sample(0.0, &mut q_ref, &mut qd_ref);
    loaded.set_configuration(&mut data, &q_ref);
    let steps = (path.duration_s() / h).ceil() as usize;
    let holds = path.holds();
    let hold_steps: Vec<usize> = holds.iter().map(|hold| ((hold.end_s / h).round() as usize).min(steps)).collect();

    let mut tracking = Tracking {
        max_joint_error: vec![0.0; dof],
        max_position_m: 0.0,
        max_orientation_rad: 0.0,
    };
    let mut peak_effort = vec![0.0_f64; dof];
    let mut goal_holds = Vec::with_capacity(holds.len());
    let mut recorder = ContactRecorder::new();
    let mut joint_error = vec![0.0; dof];
    for k in 0..=steps {
        // Times as multiples of the step, not accumulated sums: no drift over long runs.
        let t = k as f64 * h;
        data.step1();
        path.sample(t, &mut q_ref, &mut qd_ref);
        for j in 0..dof {
            joint_error[j] = (data.qpos()[loaded.qpos_address[j]] - q_ref[j]).abs();
            tracking.max_joint_error[j] = tracking.max_joint_error[j].max(joint_error[j]);
        }
        let (position_error, orientation_error) = pose_difference(&loaded.tool_pose(&data), &model.tool_pose(&q_ref));
        tracking.max_position_m = tracking.max_position_m.max(position_error);
        tracking.max_orientation_rad = tracking.max_orientation_rad.max(orientation_error);
        for (hold, _) in holds.iter().zip(&hold_steps).filter(|(_, &step)| step == k) {
            goal_holds.push(GoalHold {
                goal: hold.goal,
                time_s: t,
                position_error_m: position_error,
                orientation_error_rad: orientation_error,
                joint_error: joint_error.iter().fold(0.0, |a, &b| a.max(b)),
            });
        }
        loaded.record_contacts(&data, &mut recorder, t, opts.contact_depth_m);
        if k == steps {
            break;
        }
        for j in 0..dof {
            // The position actuator applies kp (ctrl - q) - kv qd; this ctrl adds kv qd_ref.
            let kp = gains.stiffness[j];
            let feedforward = if kp > 0.0 { gains.damping[j] / kp * qd_ref[j] } else { 0.0 };
            data.ctrl_mut()[loaded.actuator[j]] = q_ref[j] + feedforward;
        }
        data.step2();
        for (peak, &dof_address) in peak_effort.iter_mut().zip(&loaded.dof_address) {
            *peak = peak.max(data.qfrc_actuator()[dof_address].abs());
        }
    }
    Ok(EngineRun {
        engine: "mujoco",
        mode: "dynamic",
        steps,
        timestep_s: h,
        max_joint_error: tracking.max_joint_error,
        max_tool_position_error_m: tracking.max_position_m,
        max_tool_orientation_error_rad: tracking.max_orientation_rad,
        holds: goal_holds,
        contacts: recorder.finish(),
        peak_effort,
    })
}

/// Sets each configuration of `samples` (time in s, configuration in rad or m) directly in
/// MuJoCo (`qpos`, then `mj_fwdPosition`: kinematics and collision) and records the contacts as
/// [`run_mujoco`] does. Joint errors and efforts are zero (nothing is driven), there are no
/// holds, the tool error is MuJoCo's tool site against our FK of the same configuration, and
/// `steps` is the number of samples; `opts.timestep_s` is reported as the step.
///
/// # Errors
/// As [`run_mujoco`]; [`EngineError::ConfigurationLength`] for a sample of the wrong length.
pub fn replay_mujoco(
    model: &Model,
    scenario: &Scenario,
    world: &CollisionWorld,
    samples: &[(f64, Vec<f64>)],
    opts: &RunOptions,
) -> Result<EngineRun, EngineError> {
    super::inputs::check_replay(model, samples, opts)?;
    let loaded = Loaded::new(model, Some(scenario), Some(world), None, opts)?;
    let mut data = loaded.model.make_data();
    let mut recorder = ContactRecorder::new();
    let (mut max_position_m, mut max_orientation_rad) = (0.0_f64, 0.0_f64);
    for (time_s, q) in samples {
        loaded.set_configuration(&mut data, q);
        data.fwd_position();
        let (position, orientation) = pose_difference(&loaded.tool_pose(&data), &model.tool_pose(q));
        max_position_m = max_position_m.max(position);
        max_orientation_rad = max_orientation_rad.max(orientation);
        loaded.record_contacts(&data, &mut recorder, *time_s, opts.contact_depth_m);
    }
    Ok(EngineRun {
        engine: "mujoco",
        mode: "kinematic",
        steps: samples.len(),
        timestep_s: opts.timestep_s,
        max_joint_error: vec![0.0; model.dof()],
        max_tool_position_error_m: max_position_m,
        max_tool_orientation_error_rad: max_orientation_rad,
        holds: Vec::new(),
        contacts: recorder.finish(),
        peak_effort: vec![0.0; model.dof()],
    })
}
