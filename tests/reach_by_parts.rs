//! A `z_symmetric` goal just beyond a UR-type arm's reach (modular-elbow, workspace goal 69:
//! the numeric search's closest miss 1.5 mm off) whose out-of-reach proof over the whole
//! tolerance fails at a few turns about tool z, proven by cutting the tolerance into parts.
//! Checked against the closed form itself: 20 000 random poses within the tolerance, at random
//! turns, have no solution at all.

mod common;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use proving_ground::ik::analytic::UrArm;
use proving_ground::ik::{solve_goals, IkOptions, REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use proving_ground::pipeline::{collision_world, load_model, load_scenario, LoadOptions};
use proving_ground::scenario::Scenario;
use rand::{Rng, SeedableRng};

#[test]
fn a_goal_just_beyond_reach_is_proven_by_parts_and_no_pose_within_its_tolerance_has_a_solution() {
    let model = load_model(&common::repo().join("designs/modular-elbow.json"), &LoadOptions::default()).expect("design loads");
    let workspace = load_scenario(&common::repo().join("scenarios/workspace/z_symmetric.json")).expect("scenario loads");
    let goal = workspace.goals[69].clone();
    let scenario = Scenario {
        goals: vec![goal.clone()],
        ..workspace
    };
    let world = collision_world(&model, &scenario, &[]).expect("world builds");
    let solved = solve_goals(&model, &scenario, Some(&world), &IkOptions::default());
    let proof = solved[0].proof.clone().unwrap_or_default();
    assert!(
        proof.contains("out of reach") && proof.contains("cut into parts"),
        "not proven by parts: {proof:?}, undecided: {:?}",
        solved[0].undecided
    );

    let arm = UrArm::detect(&model).expect("UR-type");
    let (x, y) = (goal.rotation * Vector3::x(), goal.rotation * Vector3::y());
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(69);
    for _ in 0..20_000 {
        let shift = common::in_ball(&mut rng, 0.999 * REACHED_POSITION_M);
        // Uniform over the disc of tilts (its rim, where a goal just beyond reach is closest,
        // as often as its area).
        let (radius, angle) = (
            0.999 * REACHED_ORIENTATION_RAD * rng.random::<f64>().sqrt(),
            rng.random_range(0.0..std::f64::consts::TAU),
        );
        let across = (x * angle.cos() + y * angle.sin()) * radius;
        let turn = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        let rotation = UnitQuaternion::from_scaled_axis(across) * goal.rotation * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn);
        let pose = Isometry3::from_parts(Translation3::from(goal.position + shift), rotation);
        let found = arm.solve(&pose);
        assert!(
            found.configurations.is_empty(),
            "a pose within the tolerance has solutions {:?}; proof: {proof}",
            found.configurations
        );
    }
}
