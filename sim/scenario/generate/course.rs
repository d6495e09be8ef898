//! A course for the paper's real-world robot ("Transfer to the Real World": three obstacles and
//! 36 target poses distributed evenly between them, tolerance of rotational symmetry about the
//! tool z axis), built so that this robot can pass it.
//!
//! Layout (world = base frame, x forward, z up, floor at [`FLOOR_HEIGHT_M`]): a ball on the left,
//! a box in front, a post on the right, each about 0.42 to 0.45 m from the base axis. Each has a
//! region of 12 goals that arches over it in the vertical plane across the line from the base:
//! the tool starts beside the obstacle, rises over it and comes down on its other side, its z
//! axis pointing at the obstacle's nearest point. The tour is [`COURSE_HOME`], then the regions
//! in order (ball, box, post). The two low goals that open and close a region face each other
//! across the obstacle: moving the tool straight from one to the other runs it through the
//! obstacle, and for the box and the post so does the straight joint-space path between them.
//!
//! The goal configurations ([`course_configurations`]) are a table of joints 1 to 4, found once
//! by a position IK along the arches (0.16 to 0.2 m from the obstacle surfaces),
//! choosing among IK branches the tour with the least joint motion whose straight joint-space
//! segments keep the clearance, then rounded to 0.001 rad. Joint 5 only spins the tool about the
//! last tube; it is computed here to point the tool z axis at the obstacle. The table is kept
//! instead of the IK so that the course does not depend on a solver.
//!
//! Every goal configuration and every straight joint-space segment of the tour (from home)
//! keeps [`COURSE_CLEARANCE_M`] from the obstacles under the conservative model of
//! `clearance.rs`, stays above the floor, and every goal configuration is free of
//! self-collision (paper capsules and exact colliders); [`course`] checks this and panics
//! otherwise (the tests make sure it does not).

use super::clearance::CapsuleRobot;
use super::{dh_tool_pose, modular_model, provenance, unit, FLOOR_HEIGHT_M};
use crate::design::catalog::SlotOption;
use crate::model::Shape;
use crate::scenario::{Floor, Goal, Obstacle, Scenario, Tolerance};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{FRAC_PI_2, PI};

/// The paper's real-world robot, `designs/paper-real-world.json`: slots direct, L-short, direct,
/// direct, I-long.
pub const COURSE_MODULES: [SlotOption; 5] = [
    SlotOption::Direct,
    SlotOption::LShort,
    SlotOption::Direct,
    SlotOption::Direct,
    SlotOption::ILong,
];
/// Seed of the committed course. It only spins each goal about its tool z axis (uniformly), which
/// the `z_symmetric` tolerance ignores, so every seed gives an equally passable course; a full
/// pose match is then generally out of reach of the 5-joint robot, as in the paper.
pub const COURSE_SEED: u64 = 3;
/// Goals per obstacle region (paper: 36 goals distributed evenly between 3 obstacles).
pub const COURSE_GOALS_PER_REGION: usize = 12;
/// Clearance kept between the robot and every obstacle (m), at the goal configurations and along
/// the straight joint-space segments between consecutive ones (measured: 0.071 m).
pub const COURSE_CLEARANCE_M: f64 = 0.05;
/// Largest joint change between two checked samples of a tour segment (rad). Between samples a
/// capsule axis moves at most half a step times each joint's reach, summed over the joints before
/// its link; that bound is subtracted from the sampled clearances.
pub const COURSE_PATH_STEP_RAD: f64 = 0.01;
/// Start of the tour (rad): the arm straight up (upper arm vertical, 0.4 m tube vertical, tool
/// 0.7 m above the base). Not all zeros: at `q = 0` the paper robot folds its 0.4 m tube back
/// across its second link (tool at (0.2, 0.2, 0)), a self-collision under both the exact and the
/// capsule geometry.
pub const COURSE_HOME: [f64; 5] = [0.0, FRAC_PI_2, 0.0, FRAC_PI_2, 0.0];

/// Joints 1 to 4 (rad) of the 36 goal configurations, in tour order (see the module docs).
const TOUR: [[f64; 4]; 36] = [
    [-1.239, 2.726, 0.992, 0.854],
    [-1.255, 2.579, 0.989, 0.853],
    [-1.307, 2.437, 0.990, 0.853],
    [-1.393, 2.323, 0.980, 0.849],
    [-1.547, 2.172, 1.060, 0.886],
    [-1.687, 2.166, 1.003, 0.859],
    [0.985, 0.969, 2.148, -0.855],
    [0.898, 1.064, 1.962, -0.955],
    [0.890, 1.158, 1.747, -1.116],
    [0.945, 1.224, 1.545, -1.308],
    [1.092, 1.296, 1.308, -1.554],
    [1.250, 1.291, 1.109, -1.751],
    [1.233, 1.111, 1.069, -1.933],
    [1.203, 1.315, 1.074, -1.902],
    [1.096, 1.437, 1.161, -1.810],
    [0.948, 1.534, 1.224, -1.717],
    [0.799, 1.635, 1.216, -1.675],
    [0.654, 1.717, 1.159, -1.678],
    [0.486, 1.722, 1.154, -1.683],
    [0.357, 1.698, 1.154, -1.736],
    [0.244, 1.605, 1.147, -1.790],
    [0.171, 1.459, 1.135, -1.834],
    [0.227, 1.347, 1.027, -1.941],
    [0.366, 1.198, 0.883, -2.078],
    [0.116, 1.445, 0.828, -1.958],
    [0.101, 1.666, 0.816, -1.952],
    [0.041, 1.839, 0.842, -1.919],
    [-0.093, 1.923, 0.917, -1.849],
    [-0.213, 2.021, 0.936, -1.824],
    [-0.336, 2.105, 0.923, -1.831],
    [-0.429, 2.200, 0.853, -1.887],
    [-0.535, 2.230, 0.777, -1.946],
    [-0.621, 2.213, 0.682, -2.017],
    [-0.675, 2.139, 0.574, -2.089],
    [-0.675, 2.019, 0.446, -2.163],
    [-0.601, 1.851, 0.283, -2.239],
];

/// One obstacle of the course, upright at `position` (m).
fn obstacle(name: &str, position: [f64; 3], shape: Shape) -> Obstacle {
    Obstacle {
        name: name.into(),
        world_from_shape: Isometry3::from_parts(Translation3::new(position[0], position[1], position[2]), UnitQuaternion::identity()),
        shape,
    }
}

/// The three obstacles, in tour order: a ball (radius 0.08 m, centre 0.2 m above the floor) on
/// the left, a box (0.12 x 0.12 x 0.2 m, standing on the floor) in front, a post (cylinder of
/// radius 0.05 m, 0.25 m tall, standing on the floor) on the right.
pub fn course_obstacles() -> Vec<Obstacle> {
    vec![
        obstacle("ball", [0.144, 0.395, 0.1], Shape::Sphere { radius: 0.08 }),
        obstacle(
            "box",
            [0.45, 0.0, 0.0],
            Shape::Box {
                half_extents: [0.06, 0.06, 0.1],
            },
        ),
        obstacle(
            "post",
            [0.144, -0.395, 0.025],
            Shape::Cylinder {
                radius: 0.05,
                length: 0.25,
            },
        ),
    ]
}

/// The joint configurations (rad) whose tool poses are the course's goals, in goal order: the
/// generator's own construction, for checks. Seed-independent.
pub fn course_configurations() -> Vec<Vec<f64>> {
    let obstacles = course_obstacles();
    TOUR.iter()
        .enumerate()
        .map(|(index, joints)| {
            let mut q = joints.to_vec();
            q.push(0.0);
            let tool = dh_tool_pose(&COURSE_MODULES, &q).translation.vector;
            let target = nearest_point(&obstacles[index / COURSE_GOALS_PER_REGION], &tool);
            q[4] = pointing_spin(&q, &target);
            q
        })
        .collect()
}

/// The point of a course obstacle (sphere, box or cylinder) nearest to `p` (m, world).
fn nearest_point(obstacle: &Obstacle, p: &Vector3<f64>) -> Vector3<f64> {
    let pose = &obstacle.world_from_shape;
    let local = pose.inverse_transform_point(&Point3::from(*p)).coords;
    let nearest = match &obstacle.shape {
        Shape::Sphere { radius } => local.normalize() * *radius,
        Shape::Box { half_extents } => Vector3::from_fn(|axis, _| local[axis].clamp(-half_extents[axis], half_extents[axis])),
        Shape::Cylinder { radius, length } => {
            let radial = local.xy().norm();
            let scale = if radial > *radius { radius / radial } else { 1.0 };
            Vector3::new(local.x * scale, local.y * scale, local.z.clamp(-length / 2.0, length / 2.0))
        }
        _ => unreachable!("the course has spheres, boxes and cylinders only"),
    };
    pose.transform_point(&Point3::from(nearest)).coords
}

/// Joint 5 angle (rad) that turns the tool z axis as close as it gets to the direction from the
/// tool to `target`. The tool z axis is `sin(q5) a - cos(q5) b` with `a`, `b` its directions at
/// `q5 = pi/2` and `q5 = 0` (negated), so the best angle is `atan2(a.d, -b.d)`.
fn pointing_spin(q: &[f64], target: &Vector3<f64>) -> f64 {
    let mut probe = q.to_vec();
    probe[4] = 0.0;
    let at_zero = dh_tool_pose(&COURSE_MODULES, &probe);
    probe[4] = FRAC_PI_2;
    let at_quarter = dh_tool_pose(&COURSE_MODULES, &probe);
    let direction = (target - at_zero.translation.vector).normalize();
    let a = at_quarter.rotation * Vector3::z();
    let b = -(at_zero.rotation * Vector3::z());
    a.dot(&direction).atan2(-b.dot(&direction))
}

/// What the generator measures on its own tour (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CourseMargins {
    /// Smallest robot-obstacle clearance over the goal configurations and the tour's segments,
    /// after subtracting the motion between samples (m).
    pub obstacles_m: f64,
    /// Smallest height of the robot above the floor, goals and segments, same bound (m).
    pub floor_m: f64,
    /// Smallest self-clearance of the checked link pairs at the goal configurations, paper
    /// capsules (m).
    pub self_m: f64,
    /// The same with the exact colliders (tubes and joint module housings) (m).
    pub exact_self_m: f64,
    /// Number of configurations checked along the tour.
    pub samples: usize,
}

/// Measures the tour of [`course_configurations`] from [`COURSE_HOME`] against
/// [`course_obstacles`] with the generator's conservative capsule model.
pub fn course_margins() -> CourseMargins {
    let model = modular_model(&COURSE_MODULES);
    let mut robot = CapsuleRobot::new(&model);
    let obstacles = course_obstacles();
    let mut margins = CourseMargins {
        obstacles_m: f64::INFINITY,
        floor_m: f64::INFINITY,
        self_m: f64::INFINITY,
        exact_self_m: f64::INFINITY,
        samples: 0,
    };
    let mut previous = COURSE_HOME.to_vec();
    for q in course_configurations() {
        robot.set(&q);
        margins.self_m = margins.self_m.min(robot.self_clearance());
        margins.exact_self_m = margins.exact_self_m.min(robot.exact_self_clearance());
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
        previous = q;
    }
    margins
}

/// The course for the paper's real-world robot: [`course_obstacles`], 36 goals (12 per obstacle
/// region, named after it) with tolerance `z_symmetric`, home [`COURSE_HOME`], floor at
/// [`FLOOR_HEIGHT_M`]. `seed` spins each goal about its tool z axis.
///
/// # Panics
/// When the built-in tour breaks its own clearance guarantees (see the module docs); the tests
/// make sure it does not.
pub fn course(seed: u64) -> Scenario {
    let margins = course_margins();
    assert!(
        margins.obstacles_m >= COURSE_CLEARANCE_M && margins.floor_m > 0.0 && margins.self_m > 0.0 && margins.exact_self_m > 0.0,
        "the course tour breaks its clearance guarantees: {margins:?}"
    );
    let obstacles = course_obstacles();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let goals = course_configurations()
        .iter()
        .enumerate()
        .map(|(index, q)| {
            let tool = dh_tool_pose(&COURSE_MODULES, q);
            let spin = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), rng.random_range(-PI..PI));
            let region = &obstacles[index / COURSE_GOALS_PER_REGION].name;
            Goal {
                name: format!("{region} {}", index % COURSE_GOALS_PER_REGION + 1),
                position: tool.translation.vector.map(|v| v + 0.0),
                rotation: unit(*(tool.rotation * spin).quaternion()),
                tolerance: Tolerance::ZSymmetric,
                task: None,
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
        notes: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tour_keeps_its_clearances_with_room_to_spare() {
        let margins = course_margins();
        eprintln!("course margins: {margins:?}");
        assert!(margins.obstacles_m >= COURSE_CLEARANCE_M + 0.015, "{margins:?}");
        assert!(
            margins.floor_m > 0.0 && margins.self_m > 0.0 && margins.exact_self_m > 0.0,
            "{margins:?}"
        );
    }

    #[test]
    fn tool_z_points_at_the_obstacle() {
        let obstacles = course_obstacles();
        for (index, q) in course_configurations().iter().enumerate() {
            let tool = dh_tool_pose(&COURSE_MODULES, q);
            let target = nearest_point(&obstacles[index / COURSE_GOALS_PER_REGION], &tool.translation.vector);
            let toward = (target - tool.translation.vector).normalize();
            // The z axis is perpendicular to the last tube, so it points at the obstacle only up to
            // the tube's own direction; it must at least face it.
            assert!((tool.rotation * Vector3::z()).dot(&toward) > 0.5, "goal {index}");
        }
    }
}
