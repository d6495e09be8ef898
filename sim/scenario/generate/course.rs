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
use std::f64::consts::PI;

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
pub const COURSE_HOME: [f64; 5] = [0.0, 1.2, -1.2, 1.5708, 0.0];

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
    [[1.2, 0.3, -0.9, 1.5708], [0.8, 0.9, -1.5, 1.5708], [0.4, 0.3, -0.9, 1.5708]],
    [[0.2, 0.3, -0.9, 1.5708], [-0.2, 0.9, -1.5, 1.5708], [-0.6, 0.3, -0.9, 1.5708]],
    [[-0.8, 0.3, -0.9, 1.5708], [-1.2, 0.9, -1.5, 1.5708], [-1.6, 0.3, -0.9, 1.5708]],
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Position IK on joints 1-4 by damped least squares with a finite-difference Jacobian.
    fn ik(model: &Model, target: &Vector3<f64>, seed: &[f64]) -> Option<Vec<f64>> {
        let mut q = seed.to_vec();
        for _ in 0..200 {
            let p = model.tool_pose(&q).translation.vector;
            let e = target - p;
            if e.norm() < 1e-10 {
                return Some(q);
            }
            let mut jac = nalgebra::Matrix3x4::zeros();
            for j in 0..4 {
                let mut qq = q.clone();
                qq[j] += 1e-7;
                let d = (model.tool_pose(&qq).translation.vector - p) / 1e-7;
                jac.set_column(j, &d);
            }
            let jjt = jac * jac.transpose() + nalgebra::Matrix3::identity() * 1e-4;
            let dq = jac.transpose() * jjt.try_inverse()? * e;
            for j in 0..4 {
                q[j] += dq[j].clamp(-0.2, 0.2);
            }
        }
        None
    }

    fn score(robot: &mut CapsuleRobot<'_>, q: &[f64], obstacles: &[Obstacle]) -> (f64, f64, f64) {
        robot.set(q);
        let exact = robot.exact();
        (
            robot.obstacle_clearance(obstacles, &exact),
            robot.floor_clearance(FLOOR_HEIGHT_M, &exact),
            robot.self_clearance(),
        )
    }

    fn closest_point(obstacle: &Obstacle, p: &Vector3<f64>) -> Vector3<f64> {
        let pose = &obstacle.world_from_shape;
        let local = pose.inverse_transform_point(&nalgebra::Point3::from(*p)).coords;
        let near = match &obstacle.shape {
            Shape::Sphere { radius } => local.normalize() * *radius,
            Shape::Box { half_extents } => Vector3::new(
                local.x.clamp(-half_extents[0], half_extents[0]),
                local.y.clamp(-half_extents[1], half_extents[1]),
                local.z.clamp(-half_extents[2], half_extents[2]),
            ),
            Shape::Cylinder { radius, length } => {
                let radial = local.xy().norm();
                let scale = if radial > *radius { radius / radial } else { 1.0 };
                Vector3::new(local.x * scale, local.y * scale, local.z.clamp(-length / 2.0, length / 2.0))
            }
            _ => local,
        };
        pose.transform_point(&nalgebra::Point3::from(near)).coords
    }

    #[test]
    #[ignore = "exploration aid: searches keyframes"]
    fn explore_keyframes() {
        let model = modular_model(&COURSE_MODULES);
        let mut robot = CapsuleRobot::new(&model);
        let obstacles = course_obstacles();
        let mut obstacles = obstacles;
        if let Ok(b) = std::env::var("BOX") {
            let b: [f64; 6] = serde_json::from_str(&b).expect("json");
            obstacles[0] = obstacle(
                "box",
                [b[0], b[1], b[2]],
                Shape::Box {
                    half_extents: [b[3], b[4], b[5]],
                },
            );
        }
        // Per region: [cx, cy, half_width, top, z_low, offset]
        let arches: Vec<[f64; 6]> = serde_json::from_str(&std::env::var("ARCHES").expect("ARCHES")).expect("json");
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let value = |s: (f64, f64, f64)| if s.1 <= 0.0 { -1.0 } else { s.0.min(s.2 + 0.03) };
        let min_static: f64 = std::env::var("MIN_STATIC").ok().and_then(|v| v.parse().ok()).unwrap_or(0.065);
        let mut candidates: Vec<Vec<(Vec<f64>, f64)>> = Vec::new();
        for (region, arch) in arches.iter().enumerate() {
            let [cx, cy, w, top, z_low, d] = *arch;
            let phi = cy.atan2(cx);
            let tangential = Vector3::new(-phi.sin(), phi.cos(), 0.0);
            let side = top - z_low;
            let quarter = PI / 2.0 * d;
            let total = 2.0 * side + 2.0 * quarter + 2.0 * w;
            let points: Vec<Vector3<f64>> = (0..COURSE_GOALS_PER_REGION)
                .map(|i| {
                    let mut l = total * i as f64 / (COURSE_GOALS_PER_REGION - 1) as f64;
                    // (u along tangential, z)
                    let (u, z) = if l <= side {
                        (w + d, z_low + l)
                    } else if {
                        l -= side;
                        l <= quarter
                    } {
                        let a = l / d;
                        (w + d * a.cos(), top + d * a.sin())
                    } else if {
                        l -= quarter;
                        l <= 2.0 * w
                    } {
                        (w - l, top + d)
                    } else if {
                        l -= 2.0 * w;
                        l <= quarter
                    } {
                        let a = PI / 2.0 + l / d;
                        (-w + d * a.cos(), top + d * a.sin())
                    } else {
                        l -= quarter;
                        (-w - d, top - l)
                    };
                    Vector3::new(cx, cy, 0.0) + tangential * u + Vector3::z() * z
                })
                .collect();
            let obstacle = &obstacles[region];
            let mut list: Vec<Vec<(Vec<f64>, f64)>> = Vec::new();
            for p in &points {
                let mut found: Vec<(Vec<f64>, f64)> = Vec::new();
                for _ in 0..1000 {
                    let seed: Vec<f64> = (0..5).map(|j| if j < 4 { rng.random_range(-PI..PI) } else { 0.0 }).collect();
                    if let Some(mut q) = ik(&model, p, &seed) {
                        for v in q.iter_mut().take(4) {
                            *v = (*v + PI).rem_euclid(2.0 * PI) - PI;
                        }
                        let near = closest_point(obstacle, &model.tool_pose(&q).translation.vector);
                        q[4] = pointing_spin(&model, &q, &near);
                        let sc = score(&mut robot, &q, &obstacles);
                        if sc.1 > 0.0
                            && sc.2 > 0.005
                            && sc.0 >= min_static
                            && !found.iter().any(|(f, _)| f.iter().zip(&q).all(|(a, b)| (a - b).abs() < 1e-3))
                        {
                            found.push((q, sc.0));
                        }
                    }
                }
                println!("region {region}: point {p:?}: {} candidates", found.len());
                list.push(found);
            }
            candidates.extend(list);
            let _ = value;
        }
        // Beam search over the whole tour from home.
        let unwrap = |q: &[f64], near: &[f64]| -> Vec<f64> {
            q.iter()
                .zip(near)
                .map(|(v, n)| v + (2.0 * PI) * ((n - v) / (2.0 * PI)).round())
                .collect()
        };
        let lambda: f64 = std::env::var("LAMBDA").ok().and_then(|v| v.parse().ok()).unwrap_or(0.01);
        let width: usize = std::env::var("WIDTH").ok().and_then(|v| v.parse().ok()).unwrap_or(8);
        let threshold: f64 = std::env::var("THRESH").ok().and_then(|v| v.parse().ok()).unwrap_or(0.06);
        let home_target: Vec<f64> = serde_json::from_str(&std::env::var("HOME_TARGET").expect("HOME_TARGET")).expect("json");
        let mut beam: Vec<(f64, f64, Vec<Vec<f64>>)> = Vec::new();
        for _ in 0..400 {
            let seed: Vec<f64> = (0..5).map(|j| if j < 4 { rng.random_range(-PI..PI) } else { 0.0 }).collect();
            if let Some(mut q) = ik(&model, &Vector3::new(home_target[0], home_target[1], home_target[2]), &seed) {
                for v in q.iter_mut().take(4) {
                    *v = ((*v + PI).rem_euclid(2.0 * PI) - PI) * 1000.0;
                    *v = v.round() / 1000.0;
                }
                q[4] = 0.0;
                let sc = score(&mut robot, &q, &obstacles);
                if sc.1 > 0.0 && sc.2 > 0.005 && sc.0 > 0.1 {
                    beam.push((f64::INFINITY, 0.0, vec![q]));
                }
            }
        }
        if let Ok(home) = std::env::var("HOME_Q") {
            let q: Vec<f64> = serde_json::from_str(&home).expect("json");
            println!("fixed home {q:?}: {:?}", score(&mut robot, &q, &obstacles));
            beam = vec![(f64::INFINITY, 0.0, vec![q])];
        }
        println!("{} home candidates", beam.len());
        for (index, list) in candidates.iter().enumerate() {
            let mut next: Vec<(f64, f64, Vec<Vec<f64>>)> = Vec::new();
            for (worst, travel, chain) in &beam {
                let previous = chain.last().expect("nonempty");
                for (q, _) in list {
                    let u = unwrap(q, previous);
                    if u.iter().any(|v| v.abs() > 2.0 * PI) {
                        continue;
                    }
                    let jump: f64 = u
                        .iter()
                        .zip(previous)
                        .take(4)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max)
                        .powi(2);
                    let path = path_clearance(&mut robot, previous, &u, &obstacles, 0.02);
                    let w = worst.min(path);
                    if w < threshold {
                        continue;
                    }
                    let mut c = chain.clone();
                    c.push(u);
                    next.push((w, travel + jump, c));
                }
            }
            next.sort_by(|a, b| (a.1 - b.0 / lambda).total_cmp(&(b.1 - a.0 / lambda)));
            let mut kept: Vec<(f64, f64, Vec<Vec<f64>>)> = Vec::new();
            for state in next {
                let last = state.2.last().expect("nonempty");
                if kept.iter().any(|k| k.2.last().expect("nonempty") == last) {
                    continue;
                }
                kept.push(state);
                if kept.len() == width {
                    break;
                }
            }
            let next = kept;
            if next.is_empty() {
                println!("dead end at goal {index}");
                return;
            }
            beam = next;
        }
        let (worst, travel, chain) = &beam[0];
        println!("tour worst path clearance {worst:.4} travel {travel:.2}");
        println!("home {:?}", chain[0]);
        let mut previous = chain[0].clone();
        for (i, q) in chain.iter().skip(1).enumerate() {
            let s = score(&mut robot, q, &obstacles);
            let p = path_clearance(&mut robot, &previous, q, &obstacles, COURSE_PATH_STEP_RAD);
            println!(
                "            [{}], // {i}: static {:.3} path {:.3} self {:.3}",
                q.iter().map(|v| format!("{v:.3}")).collect::<Vec<_>>().join(", "),
                s.0,
                p,
                s.2
            );
            previous = q.clone();
        }
    }

    fn path_clearance(robot: &mut CapsuleRobot<'_>, a: &[f64], b: &[f64], obstacles: &[Obstacle], step: f64) -> f64 {
        let delta: Vec<f64> = b.iter().zip(a).map(|(b, a)| b - a).collect();
        let largest = delta.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
        let steps = (largest / step).ceil().max(1.0) as usize;
        let half: Vec<f64> = delta.iter().map(|d| d / steps as f64 / 2.0).collect();
        let slack = robot.motion_bounds(&half);
        let mut worst = f64::INFINITY;
        for i in 0..=steps {
            let s = i as f64 / steps as f64;
            let q: Vec<f64> = a.iter().zip(&delta).map(|(a, d)| a + d * s).collect();
            robot.set(&q);
            let floor = robot.floor_clearance(FLOOR_HEIGHT_M, &slack);
            let v = if floor <= 0.0 {
                -1.0
            } else {
                robot.obstacle_clearance(obstacles, &slack)
            };
            worst = worst.min(v);
        }
        worst
    }

    #[test]
    #[ignore = "exploration aid: prints the tour"]
    fn explore_course() {
        let model = modular_model(&COURSE_MODULES);
        let mut robot = CapsuleRobot::new(&model);
        let obstacles = course_obstacles();
        robot.set(&COURSE_HOME);
        println!(
            "home: tool {:?} obstacles {:.3} floor {:.3} self {:.3}",
            robot.tool().translation.vector.as_slice(),
            robot.obstacle_clearance(&obstacles, &robot.exact()),
            robot.floor_clearance(FLOOR_HEIGHT_M, &robot.exact()),
            robot.self_clearance()
        );
        for (i, q) in course_configurations().iter().enumerate() {
            robot.set(q);
            let tool = robot.tool();
            let p = tool.translation.vector;
            let z = tool.rotation * Vector3::z();
            let per: Vec<String> = obstacles
                .iter()
                .map(|o| format!("{:.3}", robot.obstacle_clearance(std::slice::from_ref(o), &robot.exact())))
                .collect();
            println!(
                "{i:2} q [{}] tool [{:.3}, {:.3}, {:.3}] z [{:.2}, {:.2}, {:.2}] obst {} floor {:.3} self {:.3}",
                q.iter().map(|v| format!("{v:.3}")).collect::<Vec<_>>().join(", "),
                p.x,
                p.y,
                p.z,
                z.x,
                z.y,
                z.z,
                per.join(" "),
                robot.floor_clearance(FLOOR_HEIGHT_M, &robot.exact()),
                robot.self_clearance()
            );
        }
        println!("{:?}", course_margins());
        let extra: Vec<Vec<f64>> = serde_json::from_str(&std::env::var("CONFIGS").unwrap_or("[]".into())).expect("json");
        for q in extra {
            robot.set(&q);
            println!(
                "{q:?}: tool {:?} pairs {:?}",
                robot.tool().translation.vector.as_slice(),
                robot.self_clearance_by_pair()
            );
        }
    }
}
