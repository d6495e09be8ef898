//! A course for the paper's real-world robot ("Transfer to the Real World": three obstacles and
//! 36 target poses distributed evenly between them, tolerance of rotational symmetry about the
//! tool z axis), built so that this robot can pass it.
//!
//! Construction: three obstacles stand in front of the robot (a box, a post, a ball). Each has a
//! region of 12 goals arching over it: the tool starts low beside the obstacle, rises over it
//! and comes down on its other side, its z axis pointing at the obstacle. The goal
//! configurations lie on a smooth curve in joint space through three keyframes per region (the
//! quadratic through them, sampled at 12 evenly spaced parameters); joint 5, which only spins
//! the tool about the last tube, turns the tool z axis towards the obstacle. The tour is home,
//! then the regions in order; a careless path (straight across a region, or low between
//! regions) runs through an obstacle.
//!
//! Every goal configuration and every straight joint-space segment of the tour keeps
//! [`COURSE_CLEARANCE_M`] from the obstacles under the conservative model of `clearance.rs`,
//! stays above the floor, and every goal configuration is free of self-collision; the generator
//! checks this and panics otherwise (a bug in the constants, caught by the tests).

use super::clearance::CapsuleRobot;
use super::{modular_model, provenance, unit, FLOOR_HEIGHT_M};
use crate::design::catalog::SlotOption;
use crate::model::{Model, Shape};
use crate::scenario::{Floor, Goal, Obstacle, Scenario, Tolerance};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{FRAC_PI_2, PI};

/// The paper's real-world robot, `designs/paper-real-world.json`.
pub const COURSE_MODULES: [SlotOption; 5] = [
    SlotOption::Direct,
    SlotOption::LShort,
    SlotOption::Direct,
    SlotOption::Direct,
    SlotOption::ILong,
];
/// Seed of the committed course. It only spins each goal about its tool z axis (uniformly), which
/// the `z_symmetric` tolerance ignores, so every seed gives an equally passable course.
pub const COURSE_SEED: u64 = 3;
/// Goals per obstacle region (paper: 36 goals distributed evenly between 3 obstacles).
pub const COURSE_GOALS_PER_REGION: usize = 12;
/// Clearance kept between the robot and every obstacle (m), at the goal configurations and along
/// the straight joint-space segments between consecutive ones.
pub const COURSE_CLEARANCE_M: f64 = 0.05;
/// Largest joint change between two checked samples of a tour segment (rad). Between samples a
/// point of the robot moves at most half a step times the joint's reach, summed over the joints
/// (`CapsuleRobot::motion_bound`); that bound is subtracted from the sampled clearance.
pub const COURSE_PATH_STEP_RAD: f64 = 0.01;
/// Start of the tour (rad). Not all zeros: at `q = 0` the paper robot folds its 0.4 m tube back
/// across its second link (tool at (0.2, 0.2, 0)), which is a self-collision under both the exact
/// and the capsule geometry. This is the arm upright (elbow up, tube pointing forward), clear of
/// itself and the floor.
pub const COURSE_HOME: [f64; 5] = [0.0, 1.2, -1.2, FRAC_PI_2, 0.0];

/// One obstacle of the course: name, pose, shape. Sizes in metres.
fn obstacle(name: &str, position: [f64; 3], shape: Shape) -> Obstacle {
    Obstacle {
        name: name.into(),
        world_from_shape: Isometry3::from_parts(Translation3::new(position[0], position[1], position[2]), UnitQuaternion::identity()),
        shape,
    }
}

/// The three obstacles, in tour order.
pub fn course_obstacles() -> Vec<Obstacle> {
    vec![
        obstacle(
            "box",
            [0.1035, 0.386, 0.0],
            Shape::Box {
                half_extents: [0.06, 0.06, 0.1],
            },
        ),
        obstacle(
            "post",
            [0.45, 0.0, 0.025],
            Shape::Cylinder {
                radius: 0.05,
                length: 0.25,
            },
        ),
        obstacle("ball", [0.144, -0.395, 0.1], Shape::Sphere { radius: 0.08 }),
    ]
}

/// Per region, three keyframes of joints 1 to 4 (rad): beside the obstacle, over it, beside it
/// on the other side.
const KEYFRAMES: [[[f64; 4]; 3]; 3] = [
    [
        [1.2, 0.3, -0.9, FRAC_PI_2],
        [0.8, 0.9, -1.5, FRAC_PI_2],
        [0.4, 0.3, -0.9, FRAC_PI_2],
    ],
    [
        [0.2, 0.3, -0.9, FRAC_PI_2],
        [-0.2, 0.9, -1.5, FRAC_PI_2],
        [-0.6, 0.3, -0.9, FRAC_PI_2],
    ],
    [
        [-0.8, 0.3, -0.9, FRAC_PI_2],
        [-1.2, 0.9, -1.5, FRAC_PI_2],
        [-1.6, 0.3, -0.9, FRAC_PI_2],
    ],
];

/// The joint configurations (rad) the course's goals are the tool poses of, in goal order: the
/// generator's own construction, for checks. Seed-independent.
pub fn course_configurations() -> Vec<Vec<f64>> {
    let model = modular_model(&COURSE_MODULES);
    let obstacles = course_obstacles();
    let mut configurations = Vec::with_capacity(3 * COURSE_GOALS_PER_REGION);
    for (region, keyframes) in KEYFRAMES.iter().enumerate() {
        let target = obstacles[region].world_from_shape.translation.vector;
        for i in 0..COURSE_GOALS_PER_REGION {
            let t = i as f64 / (COURSE_GOALS_PER_REGION - 1) as f64;
            // Quadratic through the keyframes at t = 0, 1/2, 1 (Lagrange form).
            let weights = [2.0 * (t - 0.5) * (t - 1.0), -4.0 * t * (t - 1.0), 2.0 * t * (t - 0.5)];
            let mut q: Vec<f64> = (0..4).map(|j| (0..3).map(|k| weights[k] * keyframes[k][j]).sum()).collect();
            q.push(0.0);
            q[4] = pointing_spin(&model, &q, &target);
            configurations.push(q);
        }
    }
    configurations
}

/// Joint 5 angle (rad) that turns the tool z axis as close as it gets to the direction from the
/// tool to `target`. The tool z axis is `sin(q5) a - cos(q5) b` with `a`, `b` its directions at
/// `q5 = pi/2` and `q5 = 0` (negated), so the best angle is `atan2(a.d, -b.d)`.
fn pointing_spin(model: &Model, q: &[f64], target: &Vector3<f64>) -> f64 {
    let mut probe = q.to_vec();
    probe[4] = 0.0;
    let at_zero = model.tool_pose(&probe);
    probe[4] = PI / 2.0;
    let at_quarter = model.tool_pose(&probe);
    let direction = (target - at_zero.translation.vector).normalize();
    let a = at_quarter.rotation * Vector3::z();
    let b = -(at_zero.rotation * Vector3::z());
    a.dot(&direction).atan2(-b.dot(&direction))
}

/// What the generator measured on its own tour (m): the worst clearance to the obstacles over
/// the goal configurations and the tour's segments (after subtracting the motion bound), the
/// lowest height of the robot above the floor, and the worst self-clearance at the goals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CourseMargins {
    /// Smallest robot-obstacle clearance, goals and segments (m).
    pub obstacles_m: f64,
    /// Smallest robot-floor clearance, goals and segments (m).
    pub floor_m: f64,
    /// Smallest self-clearance of non-adjacent links at the goal configurations (m).
    pub self_m: f64,
    /// Number of configurations checked along the tour.
    pub samples: usize,
}

/// Measures the tour of [`course_configurations`] from [`COURSE_HOME`] against
/// [`course_obstacles`] with the generator's conservative model.
pub fn course_margins() -> CourseMargins {
    let model = modular_model(&COURSE_MODULES);
    let mut robot = CapsuleRobot::new(&model);
    let obstacles = course_obstacles();
    let mut margins = CourseMargins {
        obstacles_m: f64::INFINITY,
        floor_m: f64::INFINITY,
        self_m: f64::INFINITY,
        samples: 0,
    };
    let goals = course_configurations();
    for q in &goals {
        robot.set(q);
        margins.self_m = margins.self_m.min(robot.self_clearance());
    }
    let mut previous = COURSE_HOME.to_vec();
    for q in &goals {
        let delta: Vec<f64> = q.iter().zip(&previous).map(|(b, a)| b - a).collect();
        let largest = delta.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
        let steps = (largest / COURSE_PATH_STEP_RAD).ceil().max(1.0) as usize;
        // Any configuration on the segment is within half a step of a sample.
        let half_step: Vec<f64> = delta.iter().map(|d| d / steps as f64 / 2.0).collect();
        let slack = robot.motion_bounds(&half_step);
        for i in 0..=steps {
            let s = i as f64 / steps as f64;
            let sample: Vec<f64> = previous.iter().zip(&delta).map(|(a, d)| a + d * s).collect();
            robot.set(&sample);
            margins.obstacles_m = margins.obstacles_m.min(robot.obstacle_clearance(&obstacles, &slack));
            margins.floor_m = margins.floor_m.min(robot.floor_clearance(FLOOR_HEIGHT_M, &slack));
            margins.samples += 1;
        }
        previous = q.clone();
    }
    margins
}

/// The course for the paper's real-world robot: [`course_obstacles`], 36 goals (12 per obstacle
/// region) with tolerance `z_symmetric`, home [`COURSE_HOME`], floor at
/// [`super::FLOOR_HEIGHT_M`]. `seed` spins each goal about its tool z axis.
///
/// # Panics
/// When the built-in tour breaks its own clearance guarantees (see the module docs); the tests
/// make sure it does not.
pub fn course(seed: u64) -> Scenario {
    let margins = course_margins();
    assert!(
        margins.obstacles_m >= COURSE_CLEARANCE_M && margins.floor_m > 0.0 && margins.self_m > 0.0,
        "the course tour breaks its clearance guarantees: {margins:?}"
    );
    let model = modular_model(&COURSE_MODULES);
    let obstacles = course_obstacles();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let goals = course_configurations()
        .iter()
        .enumerate()
        .map(|(index, q)| {
            let tool = model.tool_pose(q);
            let spin = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), rng.random_range(-PI..PI));
            let region = &obstacles[index / COURSE_GOALS_PER_REGION].name;
            Goal {
                name: format!("{region} {}", index % COURSE_GOALS_PER_REGION + 1),
                position: tool.translation.vector.map(|v| v + 0.0),
                rotation: unit(*(tool.rotation * spin).quaternion()),
                tolerance: Tolerance::ZSymmetric,
            }
        })
        .collect();
    Scenario {
        name: "course".into(),
        world_from_base: Isometry3::identity(),
        floor: Some(Floor { height: FLOOR_HEIGHT_M }),
        obstacles,
        goals,
        home: Some(COURSE_HOME.to_vec()),
        provenance: Some(provenance("course", seed, &[("robot", "designs/paper-real-world.json".into())])),
    }
}
