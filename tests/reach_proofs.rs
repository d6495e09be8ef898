//! The reach proofs (`ik::beyond_reach`) against the model's own FK: never claimed for a pose
//! within the tolerance of a reachable one, and made where a goal fixes the last joint's
//! origin beyond the offsets' reach, or turns the tool off the only directions its joints turn
//! about.

mod common;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use proving_ground::ik::{beyond_reach, planar_group_out_of_reach, planar_numbers, turning_axes_out_of_reach, PLANAR_BOXES};
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

/// Arms whose revolute joints turn about two directions: every catalog arm with four or more of
/// its first five slots L-shaped (four parallel axes in a row, or two triples), random DH arms
/// with one non-zero twist, and planar ones (one direction, no twist). A goal within the tolerance
/// of a configuration's pose is never claimed; the tool turned about the normal of joint 1's
/// and the last joint's axes (the turn that changes their angle most) is claimed from just
/// beyond 1 deg, never below.
#[test]
fn the_turning_axes_prove_orientations_off_their_angle_and_never_one_within_the_tolerance() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(43);
    let mut models: Vec<(String, Model)> = Vec::new();
    for index in 0..15_625 {
        let entry = catalog_entry(&modular6_slots(index));
        let shaped = entry
            .id
            .trim_start_matches("modular6/")
            .split('-')
            .take(5)
            .filter(|s| s.starts_with('L'))
            .count();
        if shaped >= 4 && index % 5 == 0 {
            models.push((entry.id.clone(), entry.load().model));
        }
    }
    for k in 0..12 {
        // Twist at joints 1 to 5, or none (planar).
        let twisted = rng.random_range(0..6);
        let rows: Vec<[f64; 3]> = (0..6)
            .map(|j| {
                let alpha = if j == twisted { rng.random_range(0.2..3.0) } else { 0.0 };
                [rng.random_range(-0.3..0.3), rng.random_range(0.0..0.4), alpha]
            })
            .collect();
        models.push((format!("random two-direction arm {k}"), common::dh_design("two", &rows)));
    }
    assert!(models.len() > 100);
    let (mut claimed, mut tight) = (0, 0);
    for (name, model) in &mut models {
        *model = model.placed(&Isometry3::from_parts(
            Translation3::new(0.3, -0.2, 0.1),
            UnitQuaternion::from_euler_angles(0.2, -0.4, 1.1),
        ));
        let revolute: Vec<usize> = (0..model.dof())
            .filter(|&j| model.joints[j].kind != proving_ground::model::JointKind::Prismatic)
            .collect();
        let (first, last) = (revolute[0], revolute[revolute.len() - 1]);
        for _ in 0..20 {
            for tolerance in [Tolerance::Pose, Tolerance::ZSymmetric] {
                let goal = nearby_goal(model, tolerance, &mut rng);
                let proof = turning_axes_out_of_reach(model, &goal);
                assert!(
                    proof.is_none(),
                    "{name}: a {} goal within the tolerance claimed: {proof:?}",
                    tolerance.name()
                );
            }
            let q = model.random_configuration(&mut rng);
            let mut ws = model.workspace();
            model.forward(&q, &mut ws);
            let axis = |j: usize| ws.link_in_world[j + 1].rotation * model.joints[j].axis.into_inner();
            let normal = axis(first).cross(&axis(last));
            // Parallel axes (a planar arm): any normal to them.
            let normal = if normal.norm() > 1e-3 {
                normal.normalize()
            } else {
                axis(first).cross(&Vector3::x()).normalize()
            };
            for (degrees, proven) in [(0.99, false), (-0.99, false), (1.01, true), (-1.01, true), (30.0, true)] {
                let turn = UnitQuaternion::from_scaled_axis(normal * f64::to_radians(degrees));
                let goal = Goal {
                    name: "turned".into(),
                    position: ws.tool_in_world.translation.vector,
                    rotation: turn * ws.tool_in_world.rotation,
                    tolerance: Tolerance::Pose,
                    task: None,
                };
                let proof = turning_axes_out_of_reach(model, &goal);
                // Turned towards 0 or 180 deg, the angle folds back: a claim needs room.
                let angle = proving_ground::ik::angle_between(&axis(first), &axis(last)).to_degrees();
                let room = angle - degrees.abs() > 0.0 && angle + degrees.abs() < 180.0;
                if !proven {
                    assert!(proof.is_none(), "{name}: turned {degrees} deg, claimed: {proof:?}");
                } else if room && degrees.abs() < 2.0 {
                    assert!(
                        proof.is_some(),
                        "{name}: turned {degrees} deg off the axes' angle {angle:.2}, not claimed"
                    );
                    tight += 1;
                }
                claimed += usize::from(proof.is_some());
            }
        }
    }
    println!(
        "{} arms: {claimed} turned goals claimed, {tight} of them just beyond 1 deg",
        models.len()
    );
    assert!(tight > 1000);
}

/// The planar run's search on catalog arms (every 23rd; those with one run of parallel axes of
/// three or more and single joints elsewhere): a goal within the
/// tolerance of a configuration's pose is never claimed; goals 30 mm and 5 deg off one are, on
/// arms with four parallel axes (no pose of theirs has a neighbourhood), and goals 0.4 m off
/// one on arms with three (out of the run's reach across its axes); a dense numeric search (300
/// starts, no closed form) reaches none of those claimed.
#[test]
fn the_planar_run_proves_poses_off_its_axis_and_never_one_within_the_tolerance() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(47);
    // Claims by the run's length (3 to 6 joints), and those checked.
    let (mut claimed, mut checked) = ([0usize; 7], 0);
    for index in (0..15_625).step_by(23) {
        let entry = catalog_entry(&modular6_slots(index));
        let model = entry.load().model.placed(&Isometry3::from_parts(
            Translation3::new(0.3, -0.2, 0.1),
            UnitQuaternion::from_euler_angles(0.2, -0.4, 1.1),
        ));
        // Runs of two (four numbers) only at a validation's budget, after IK's other searches.
        if planar_numbers(&model, Tolerance::Pose).is_none_or(|n| n > 3) {
            continue;
        }
        for _ in 0..4 {
            for tolerance in [Tolerance::Pose, Tolerance::ZSymmetric] {
                let goal = nearby_goal(&model, tolerance, &mut rng);
                let proof = planar_group_out_of_reach(&model, &goal, 3, PLANAR_BOXES);
                assert!(
                    proof.is_none(),
                    "{}: a {} goal within the tolerance claimed: {proof:?}",
                    entry.id,
                    tolerance.name()
                );
            }
            for away in [0.03, 0.4] {
                let tool = model.tool_pose(&model.random_configuration(&mut rng));
                let goal = Goal {
                    name: "off".into(),
                    position: tool.translation.vector + common::unit(&mut rng) * away,
                    rotation: UnitQuaternion::from_scaled_axis(common::unit(&mut rng) * 5f64.to_radians()) * tool.rotation,
                    tolerance: Tolerance::Pose,
                    task: None,
                };
                let Some(proof) = planar_group_out_of_reach(&model, &goal, 3, PLANAR_BOXES) else {
                    continue;
                };
                let run = (3..=6).find(|r| (1..=6 - r + 1).any(|a| proof.starts_with(&format!("joints {a} to {} turn", a + r - 1))));
                claimed[run.unwrap_or(0)] += 1;
                if claimed.iter().sum::<usize>() % 20 == 1 {
                    let mut numeric = proving_ground::ik::Ik::new(&model, common::dense_numeric());
                    common::assert_unreached(&mut numeric, &goal, 0, &proof, &entry.id);
                    checked += 1;
                }
            }
        }
    }
    println!("goals claimed by the run's length (index): {claimed:?}, {checked} checked by the dense numeric search");
    assert!(claimed[0] == 0 && claimed[3] > 100 && claimed[4] > 100 && checked > 20);
}
