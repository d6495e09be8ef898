//! The paper's cluttered benchmark ("Manipulators for Cluttered Environments"): 36 tasks, each
//! with 8 goal poses and 8 sphere obstacles within a maximum distance of the robot base.
//!
//! Goals are tool poses of one random 6-slot robot of the reference modular catalog at random
//! joint angles (as the paper builds goals: forward kinematics of random parameters), so at least
//! that catalog robot reaches every goal when obstacles are ignored. Obstacles are spheres placed
//! uniformly, resampled when they touch a goal's neighbourhood, the base keep-out or the floor
//! (the paper "discards all that intersect with any goals").

use super::clearance::CapsuleRobot;
use super::{dh_tool_pose, modular_model, provenance, unit, FLOOR_HEIGHT_M};
use crate::design::catalog::SlotOption;
use crate::model::PAPER_CAPSULE_RADIUS_M;
use crate::scenario::{Floor, Goal, Obstacle, Scenario, Tolerance};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

/// Number of tasks in the benchmark (paper: 36).
pub const CLUTTERED_TASKS: usize = 36;
/// Master seed of the committed tasks `scenarios/cluttered/task-NN.json`; task `k` uses stream
/// `k` of the ChaCha8 generator seeded with it. Arbitrary, fixed once: changing it changes every
/// committed task.
pub const CLUTTERED_MASTER_SEED: u64 = 2025;
/// Goal poses per task (paper: 8).
pub const CLUTTERED_GOALS: usize = 8;
/// Sphere obstacles per task (paper: 8).
pub const CLUTTERED_OBSTACLES: usize = 8;
/// Connection slots of the random catalog robot that makes the goals: 6, the paper's 6-dof robots.
pub const CLUTTERED_SLOTS: usize = 6;
/// Maximum distance of goal positions and obstacle centres from the base origin (m). The paper
/// does not give its value; 1.0 m is the reach of its real-world robot (hardware cost 1.0 m) and
/// within reach of most 6-slot catalog robots (0.6 m to 2.4 m of modules).
pub const CLUTTERED_MAX_DISTANCE_M: f64 = 1.0;
/// Obstacle radius range (m): uniform in [0.05, 0.15].
pub const CLUTTERED_OBSTACLE_RADIUS_M: [f64; 2] = [0.05, 0.15];
/// Radius of the tool link around a goal (m): the paper's capsule radius.
pub const TOOL_LINK_RADIUS_M: f64 = PAPER_CAPSULE_RADIUS_M;
/// Free space kept around the tool link at a goal (m), so that a goal is not wedged against an
/// obstacle (the paper's collision loss starts at 0.12 m; 0.05 m leaves room to approach).
pub const GOAL_MARGIN_M: f64 = 0.05;
/// Radius of the ball around each goal position that obstacles must not touch (m).
pub const GOAL_NEIGHBOURHOOD_M: f64 = TOOL_LINK_RADIUS_M + GOAL_MARGIN_M;
/// Radius of the keep-out ball around the base origin (m) that obstacles must not touch and goal
/// neighbourhoods must stay out of: it holds the first joint module (bounding radius 0.085 m) and
/// the second one's housing on the shortest first link, 0.1 m up (0.185 m), plus 0.06 m.
pub const BASE_KEEP_OUT_RADIUS_M: f64 = 0.25;

/// Goal samples tried for one random robot before another robot is drawn (a robot whose reach
/// mostly lies beyond the maximum distance).
const ATTEMPTS_PER_ROBOT: usize = 20_000;

/// How a cluttered task's goals were made: the robot and its joint angles, one per goal.
#[derive(Debug, Clone, PartialEq)]
pub struct ClutteredWitness {
    /// The 6 catalog slot options of the robot that made the goals.
    pub modules: Vec<SlotOption>,
    /// Joint angles (rad) at which that robot's tool frame is each goal, in goal order.
    pub configurations: Vec<Vec<f64>>,
}

/// Cluttered benchmark task number `task` from master seed `seed` (the committed tasks use
/// [`CLUTTERED_MASTER_SEED`]): [`CLUTTERED_GOALS`] goals with tolerance `pose` and
/// [`CLUTTERED_OBSTACLES`] spheres, floor at [`super::FLOOR_HEIGHT_M`].
pub fn cluttered(task: usize, seed: u64) -> Scenario {
    generate(task, seed).0
}

/// The robot and joint angles task `task` of master seed `seed` was built from, as
/// [`cluttered`] builds them: a check that every goal is reachable by a catalog robot.
pub fn cluttered_witness(task: usize, seed: u64) -> ClutteredWitness {
    generate(task, seed).1
}

fn generate(task: usize, seed: u64) -> (Scenario, ClutteredWitness) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(task as u64);

    let (witness, goals) = loop {
        let modules: Vec<SlotOption> = (0..CLUTTERED_SLOTS)
            .map(|_| SlotOption::ALL[rng.random_range(0..SlotOption::ALL.len())])
            .collect();
        if let Some(found) = goals_of(&modules, &mut rng) {
            break found;
        }
    };

    let goal_positions: Vec<Vector3<f64>> = goals.iter().map(|g| g.position).collect();
    let mut obstacles = Vec::with_capacity(CLUTTERED_OBSTACLES);
    while obstacles.len() < CLUTTERED_OBSTACLES {
        let [low, high] = CLUTTERED_OBSTACLE_RADIUS_M;
        let radius = rng.random_range(low..high);
        let reach = CLUTTERED_MAX_DISTANCE_M;
        let centre = Vector3::new(
            rng.random_range(-reach..reach),
            rng.random_range(-reach..reach),
            rng.random_range(FLOOR_HEIGHT_M..reach),
        );
        if obstacle_allowed(&centre, radius, &goal_positions) {
            obstacles.push(Obstacle {
                name: format!("obstacle {}", obstacles.len()),
                world_from_shape: Isometry3::from_parts(Translation3::from(centre), UnitQuaternion::identity()),
                shape: crate::model::Shape::Sphere { radius },
            });
        }
    }

    let scenario = Scenario {
        name: format!("cluttered-task-{task:02}"),
        world_from_base: Isometry3::identity(),
        floor: Some(Floor { height: FLOOR_HEIGHT_M }),
        obstacles,
        goals,
        home: None,
        provenance: Some(provenance("cluttered", seed, &[("task", task.into())])),
        notes: Vec::new(),
    };
    (scenario, witness)
}

/// Whether a sphere obstacle may stand at `centre`: within the maximum distance, clear of the
/// floor, the base keep-out and every goal's neighbourhood.
fn obstacle_allowed(centre: &Vector3<f64>, radius: f64, goals: &[Vector3<f64>]) -> bool {
    centre.norm() <= CLUTTERED_MAX_DISTANCE_M
        && centre.z - radius > FLOOR_HEIGHT_M
        && centre.norm() - radius > BASE_KEEP_OUT_RADIUS_M
        && goals.iter().all(|g| (centre - g).norm() - radius > GOAL_NEIGHBOURHOOD_M)
}

/// Draws goal poses for the robot made of `modules`, or `None` when too few samples qualify.
fn goals_of(modules: &[SlotOption], rng: &mut ChaCha8Rng) -> Option<(ClutteredWitness, Vec<Goal>)> {
    let model = modular_model(modules);
    let mut robot = CapsuleRobot::new(&model);
    let mut configurations = Vec::with_capacity(CLUTTERED_GOALS);
    let mut goals = Vec::with_capacity(CLUTTERED_GOALS);
    for _ in 0..ATTEMPTS_PER_ROBOT {
        // Uniform over the circle per joint; the modules' +-2 pi limits hold every angle twice.
        let q: Vec<f64> = (0..model.dof()).map(|_| rng.random_range(-PI..PI)).collect();
        let tool = dh_tool_pose(modules, &q);
        let position = tool.translation.vector;
        let distance = position.norm();
        // A goal must lie within the maximum distance, keep its neighbourhood out of the base
        // keep-out and above the floor, and come from a pose of the robot that is neither in
        // self-collision (paper capsules and exact colliders) nor through the floor.
        let placed = distance <= CLUTTERED_MAX_DISTANCE_M
            && distance - GOAL_NEIGHBOURHOOD_M >= BASE_KEEP_OUT_RADIUS_M
            && position.z - GOAL_NEIGHBOURHOOD_M >= FLOOR_HEIGHT_M;
        if !placed {
            continue;
        }
        robot.set(&q);
        let clear = robot.floor_clearance(FLOOR_HEIGHT_M, &robot.exact()) > 0.0
            && robot.self_clearance() > 0.0
            && robot.exact_self_clearance() > 0.0;
        if !clear {
            continue;
        }
        goals.push(Goal {
            name: format!("goal {}", goals.len()),
            position: position.map(|v| v + 0.0),
            rotation: unit(*tool.rotation.quaternion()),
            tolerance: Tolerance::Pose,
            task: None,
        });
        configurations.push(q);
        if goals.len() == CLUTTERED_GOALS {
            let witness = ClutteredWitness {
                modules: modules.to_vec(),
                configurations,
            };
            return Some((witness, goals));
        }
    }
    None
}
