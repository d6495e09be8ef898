//! A goal whose every configuration within the tolerance collides, near a fold of the arm's
//! solutions where no certificate around the pose's own solutions covers them:
//! `free-offset-6dof`'s goal 7 on cluttered task 06 (link4 and link6, joints 5 and 6). The
//! proof (`ik::enclose`) is checked against an oracle that shares none of its parts: poses
//! sampled within the tolerance, each solved by the numeric solver alone from many random
//! starts (no closed form, no elimination), every configuration it ends at within the tolerance
//! and the limits measured in the exact geometry. Each must collide.

mod common;

use nalgebra::UnitQuaternion;
use proving_ground::collide::{clear, Distances};
use proving_ground::ik::{goal_error, solve_goals, IkOptions, REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use proving_ground::pipeline::{collision_world, load_model, load_scenario, LoadOptions};
use proving_ground::scenario::Scenario;
use rand::{Rng, SeedableRng};

#[test]
fn a_tolerance_enclosed_in_the_colliding_pairs_joints_holds_no_free_configuration() {
    let model = load_model(&common::repo().join("designs/free-offset-6dof.json"), &LoadOptions::default()).expect("design loads");
    let task = load_scenario(&common::repo().join("scenarios/cluttered/task-06.json")).expect("scenario loads");
    let goal = task.goals[7].clone();
    let scenario = Scenario {
        goals: vec![goal.clone()],
        ..task.clone()
    };
    let world = collision_world(&model, &scenario, &[]).expect("world builds");
    let solved = solve_goals(&model, &scenario, Some(&world), &IkOptions::default());
    let proof = solved[0].proof.as_deref().unwrap_or_default();
    assert!(
        !solved[0].reached() && proof.contains("every configuration within the goal's tolerance collides"),
        "expected the enclosure's proof: {:?} / {:?}",
        solved[0].proof,
        solved[0].undecided
    );

    // The oracle: 150 poses within 0.98 of the tolerance, 48 numeric starts each.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let numeric = IkOptions {
        analytic: false,
        seeds: 48,
        branch_starts: 0,
        search_boxes: 0,
        ..Default::default()
    };
    let mut poses = Vec::new();
    for _ in 0..150 {
        let mut near = goal.clone();
        near.position += common::unit_vector(&mut rng) * (0.98 * REACHED_POSITION_M * rng.random::<f64>().cbrt());
        let turn = common::unit_vector(&mut rng) * (0.98 * REACHED_ORIENTATION_RAD * rng.random::<f64>().cbrt());
        near.rotation = UnitQuaternion::from_scaled_axis(turn) * near.rotation;
        poses.push(near);
    }
    let sampled = Scenario {
        goals: poses,
        ..task.clone()
    };
    let mut ws = model.workspace();
    let mut out = Distances::new();
    let mut measured = 0;
    for found in solve_goals(&model, &sampled, None, &numeric) {
        for solution in found.solutions.iter().filter(|s| s.pose_reached) {
            let error = goal_error(&goal, &model.tool_pose(&solution.q));
            if error.position_m >= REACHED_POSITION_M || error.orientation_rad >= REACHED_ORIENTATION_RAD {
                continue;
            }
            if !common::within_limits(&model, &solution.q) {
                continue;
            }
            model.forward(&solution.q, &mut ws);
            assert!(
                !clear(&world, &ws.link_in_world, 0.0, &mut out),
                "a free configuration within the tolerance: {:?}",
                solution.q
            );
            measured += 1;
        }
    }
    // The oracle must have looked: the tolerance holds two branches and a fold's pair.
    assert!(measured >= 300, "only {measured} configurations within the tolerance measured");
}
