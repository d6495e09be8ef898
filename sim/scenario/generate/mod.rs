//! Scenario generators: the paper's cluttered benchmark tasks, its workspace task, and a course
//! for its real-world robot. Each is seeded (`ChaCha8Rng::seed_from_u64`), uses only operations
//! that give the same bits on every platform (uniform sampling, arithmetic, `sqrt`, `sin`, `cos`;
//! no hash-map order), and records how to make it again in [`Provenance`].
//!
//! Shared conventions: the robot base is the world origin; the floor is the plane
//! `z = `[`FLOOR_HEIGHT_M`]; orientations are unit quaternions; goal positions and obstacles are
//! in metres in the world frame.

mod clearance;
mod cluttered;
mod course;
mod request;
mod workspace;

pub use cluttered::{
    cluttered, cluttered_witness, ClutteredWitness, BASE_KEEP_OUT_RADIUS_M, CLUTTERED_GOALS, CLUTTERED_MASTER_SEED,
    CLUTTERED_MAX_DISTANCE_M, CLUTTERED_OBSTACLES, CLUTTERED_OBSTACLE_RADIUS_M, CLUTTERED_SLOTS, CLUTTERED_TASKS, GOAL_MARGIN_M,
    GOAL_NEIGHBOURHOOD_M, TOOL_LINK_RADIUS_M,
};
pub use course::{
    course, course_configurations, course_margins, course_obstacles, CourseMargins, COURSE_CLEARANCE_M, COURSE_GOALS_PER_REGION,
    COURSE_HOME, COURSE_MODULES, COURSE_PATH_STEP_RAD, COURSE_SEED,
};
pub use request::{outputs, Generator, Request};
pub use workspace::{workspace, WORKSPACE_BOX_CENTRE_M, WORKSPACE_BOX_SIZE_M, WORKSPACE_GOALS, WORKSPACE_SCALE_RANGE, WORKSPACE_SEED};

use super::Provenance;
use crate::design::catalog::SlotOption;
use crate::model::Model;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use rand::Rng;
use std::collections::BTreeMap;
use std::path::Path;

/// Height of the floor under every generated scenario (m): the robot stands on a 0.1 m mount, so
/// the first joint module housing, a 0.12 m cylinder centred at the base origin, ends 0.04 m
/// above the floor (and its bounding sphere, radius 0.085 m, 0.015 m above).
pub const FLOOR_HEIGHT_M: f64 = -0.1;

/// Provenance with the generator's name, seed and parameters (sorted by name).
fn provenance(generator: &str, seed: u64, parameters: &[(&str, serde_json::Value)]) -> Provenance {
    Provenance {
        generator: generator.into(),
        seed,
        parameters: parameters
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect::<BTreeMap<_, _>>(),
    }
}

/// A rotation drawn uniformly from SO(3) by Shoemake's method ("Uniform random rotations",
/// Graphics Gems III, 1992) from three uniforms in [0, 1).
fn uniform_rotation<R: Rng>(rng: &mut R) -> UnitQuaternion<f64> {
    let u1: f64 = rng.random_range(0.0..1.0);
    let u2: f64 = rng.random_range(0.0..1.0);
    let u3: f64 = rng.random_range(0.0..1.0);
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let tau = std::f64::consts::TAU;
    let (x, y) = ((tau * u2).sin() * a, (tau * u2).cos() * a);
    let (z, w) = ((tau * u3).sin() * b, (tau * u3).cos() * b);
    unit(Quaternion::new(w, x, y, z))
}

/// The quaternion normalised the way the file reader keeps it, so a written scenario reads back
/// bit for bit; `+ 0.0` turns `-0.0` into `0.0` for tidier files.
fn unit(q: Quaternion<f64>) -> UnitQuaternion<f64> {
    let q = super::file::unit_quaternion(q).into_inner();
    super::file::unit_quaternion(Quaternion::new(q.w + 0.0, q.i + 0.0, q.j + 0.0, q.k + 0.0))
}

/// Tool pose of the modular robot made of `modules` at joint angles `q` (rad), base at the
/// origin: the standard DH product `prod Rot_z(q_i) Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i)` of
/// robots.md. Goals are computed with it rather than with the model stage's forward kinematics so
/// that the committed files do not move when that code is reorganised or sped up; the two agree
/// to rounding (tests/scenario.rs).
fn dh_tool_pose(modules: &[SlotOption], q: &[f64]) -> Isometry3<f64> {
    let mut pose = Isometry3::identity();
    for (module, &angle) in modules.iter().zip(q) {
        let [d, a, alpha] = module.dh();
        pose = pose
            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), angle)
            * Translation3::new(a, 0.0, d)
            * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), alpha);
    }
    pose
}

/// The model of a modular design made of `modules` (base at the origin, no tool offset).
fn modular_model(modules: &[SlotOption]) -> Model {
    let names: Vec<String> = modules.iter().map(|m| format!("\"{}\"", m.name())).collect();
    let text = format!(r#"{{"mode": "modular", "modules": [{}]}}"#, names.join(", "));
    let design =
        crate::design::parse(&text, Path::new("generated-robot.json")).expect("catalog modules always make a valid modular design");
    crate::model::from_design(&design)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn shoemake_rotations_are_unit_and_spread_evenly() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let rotations: Vec<_> = (0..4000).map(|_| uniform_rotation(&mut rng)).collect();
        assert!(rotations.iter().all(|r| (r.quaternion().norm() - 1.0).abs() < 1e-15));
        // Uniform on SO(3): the rotated z axis is uniform on the sphere, so its mean z is ~0
        // and a third of its square; the rotation angle has mean pi/2 + 2/pi.
        let n = rotations.len() as f64;
        let z: Vec<f64> = rotations.iter().map(|r| (r * nalgebra::Vector3::z()).z).collect();
        let mean = z.iter().sum::<f64>() / n;
        let mean_square = z.iter().map(|v| v * v).sum::<f64>() / n;
        let mean_angle = rotations.iter().map(|r| r.angle()).sum::<f64>() / n;
        assert!(mean.abs() < 0.03 && (mean_square - 1.0 / 3.0).abs() < 0.02, "{mean} {mean_square}");
        let expected = std::f64::consts::FRAC_PI_2 + 2.0 / std::f64::consts::PI;
        assert!((mean_angle - expected).abs() < 0.03, "{mean_angle} vs {expected}");
    }
}
