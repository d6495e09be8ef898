//! The reach proofs (`ik::beyond_reach`) against the model's own FK: never claimed for a pose
//! within the tolerance of a reachable one, and made where a goal fixes the last joint's
//! origin beyond the offsets' reach.

mod common;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use proving_ground::ik::beyond_reach;
use proving_ground::model::Model;
use proving_ground::scenario::{Goal, Tolerance};
use proving_ground::sweep::inputs::{catalog_entry, modular6_slots};
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;

/// A pose within 0.99 mm and 0.99 deg of the tool at a random configuration, placed off the
/// origin and turned, as a goal of `tolerance`; a `z_symmetric` goal is turned about tool z.
fn nearby_goal(model: &Model, tolerance: Tolerance, rng: &mut impl Rng) -> Goal {
    let q = model.random_configuration(rng);
    let tool = model.tool_pose(&q);
    let turn = UnitQuaternion::from_scaled_axis(common::unit(rng) * 0.99_f64.to_radians());
    let spin = match tolerance {
        Tolerance::ZSymmetric => UnitQuaternion::from_scaled_axis(Vector3::z() * rng.random_range(-PI..PI)),
        _ => UnitQuaternion::identity(),
    };
    Goal {
        name: "nearby".into(),
        position: tool.translation.vector + common::unit(rng) * 0.99e-3,
        rotation: turn * tool.rotation * spin,
        tolerance,
        task: None,
    }
}

#[test]
fn never_claimed_for_a_pose_within_the_tolerance_of_a_reachable_one() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
    let mut models: Vec<(String, Model)> = common::shipped_models();
    for index in (0..15_625).step_by(211) {
        let entry = catalog_entry(&modular6_slots(index));
        models.push((entry.id.clone(), entry.load().model));
    }
    for (name, model) in &mut models {
        // Off the origin and turned: the proofs measure from joint 1's origin.
        *model = model.placed(&Isometry3::from_parts(
            Translation3::new(0.3, -0.2, 0.1),
            UnitQuaternion::from_euler_angles(0.2, -0.4, 1.1),
        ));
        for tolerance in [Tolerance::Pose, Tolerance::ZSymmetric, Tolerance::Position] {
            for _ in 0..200 {
                let goal = nearby_goal(model, tolerance, &mut rng);
                assert!(
                    beyond_reach(model, &goal).is_none(),
                    "{name}: {} goal within the tolerance of a reachable pose claimed out of reach: {:?}",
                    tolerance.name(),
                    beyond_reach(model, &goal)
                );
            }
        }
    }
}

/// A catalog arm on the first cluttered task: the tool points back towards the base, so the
/// goal itself is within the tool's reach but joint 6's origin, where the goal puts it, is not.
#[test]
fn the_last_joints_origin_beyond_reach_proves_a_goal_the_tool_reach_does_not() {
    let slots = ["direct", "direct", "direct", "direct", "direct", "I-short"];
    let index = slots.iter().fold(0, |acc, s| {
        acc * 5
            + ["direct", "I-short", "I-long", "L-short", "L-long"]
                .iter()
                .position(|o| o == s)
                .unwrap_or(0)
    });
    let model = catalog_entry(&modular6_slots(index)).load().model;
    let scenario = proving_ground::scenario::load(&common::repo().join("scenarios/cluttered/task-00.json")).expect("the task loads");
    let model = model.placed(&scenario.world_from_base);
    let goal = &scenario.goals[0];
    let origin = (model.world_from_base * model.joints[0].parent_from_joint).translation.vector;
    assert!(
        (goal.position - origin).norm() < proving_ground::ik::reach_bound(&model),
        "the tool reach alone does not decide it"
    );
    let proof = beyond_reach(&model, goal).expect("proven out of reach");
    assert!(proof.contains("joint 6's origin"), "{proof}");
}

/// The circles: on catalog arms and the first cluttered task, some goals are proven only from
/// joint 2's circle about joint 1's axis, or from the circle of joint 5's origin about joint 6's
/// axis (each also checked never to be claimed for nearby reachable poses above).
#[test]
fn the_circles_prove_goals_the_points_do_not() {
    let scenario = proving_ground::scenario::load(&common::repo().join("scenarios/cluttered/task-00.json")).expect("the task loads");
    let (mut second, mut before_last) = (0, 0);
    for index in (0..15_625).step_by(31) {
        let model = catalog_entry(&modular6_slots(index)).load().model.placed(&scenario.world_from_base);
        for goal in &scenario.goals {
            let Some(proof) = beyond_reach(&model, goal) else { continue };
            second += usize::from(proof.contains("joint 2's origin"));
            before_last += usize::from(proof.contains("joint 5's origin"));
        }
    }
    println!("proofs from joint 2's circle: {second}, from joint 5's circle: {before_last}");
    assert!(second > 0 && before_last > 0);
}
