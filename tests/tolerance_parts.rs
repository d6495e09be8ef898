//! A goal's tolerance cut into parts where one certificate around each exact solution is too
//! coarse (issue 22): a proof that every configuration within the tolerance collides, checked
//! by solving thousands of poses sampled throughout the tolerance in closed form and measuring
//! each solution with an independent distance query; and a free configuration found where the
//! one certificate could not decide, checked the same way.

mod common;

use common::{in_ball, repo, within_limits};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use proving_ground::collide::{self, CollisionWorld, Distances, QueryOptions};
use proving_ground::ik::{goal_error, Ik, IkOptions, REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use proving_ground::model::Model;
use proving_ground::pipeline::{collision_world, load, LoadOptions};
use proving_ground::scenario::{load as load_scenario, Goal, Scenario, Tolerance};
use rand::SeedableRng;

/// A design placed on a scenario, with the collision world a run checks.
fn placed(design: &str, scenario: &str) -> (Model, Scenario, CollisionWorld) {
    place(design, load_scenario(&repo().join(scenario)).expect("the scenario loads"))
}

fn place(design: &str, scenario: Scenario) -> (Model, Scenario, CollisionWorld) {
    let model = load(&repo().join(design), &LoadOptions::default()).expect("the design loads").model;
    let model = model.placed(&scenario.world_from_base);
    let world = collision_world(&model, &scenario, &[]).expect("the world builds");
    (model, scenario, world)
}

/// The proof IK gives goal `index` of cluttered task `task` of generator seed `seed` (not a
/// shipped task) for `design`, with the placed model and its scenario.
fn proof_on_generated_task(design: &str, task: usize, seed: u64, index: usize) -> (Model, Scenario, CollisionWorld, String) {
    let (model, scenario, world) = place(design, proving_ground::scenario::generate::cluttered(task, seed));
    let result = Ik::with_collisions(&model, &world, IkOptions::default()).solve(&scenario.goals[index], index, None);
    let proof = result
        .proof
        .unwrap_or_else(|| panic!("expected a proof: undecided {:?}", result.undecided));
    (model, scenario, world, proof)
}

/// Solves 4 000 poses sampled throughout `goal`'s tolerance in closed form and measures every
/// solution within the limits with an independent distance query: each must collide. Returns
/// the solutions measured.
fn sampled_solutions_all_collide(model: &Model, world: &CollisionWorld, goal: &Goal, seed: u64) -> usize {
    let closed_form = Ik::new(model, IkOptions::default());
    let arm = closed_form.closed_form().expect("a UR-type arm");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut ws = model.workspace();
    let mut check = Distances::new();
    let mut solutions = 0;
    for _ in 0..4000 {
        let pose = Isometry3::from_parts(
            Translation3::from(goal.position + in_ball(&mut rng, REACHED_POSITION_M * 0.999)),
            UnitQuaternion::from_scaled_axis(in_ball(&mut rng, REACHED_ORIENTATION_RAD * 0.999)) * goal.rotation,
        );
        let found = arm.solve(&pose);
        assert!(found.finite, "a sampled pose is singular");
        for q in &found.configurations {
            if !within_limits(model, q) {
                continue;
            }
            solutions += 1;
            model.forward(q, &mut ws);
            collide::distances(world, &ws.link_in_world, &QueryOptions::default(), &mut check);
            assert!(
                check.in_contact(),
                "a free configuration {q:?} within the tolerance (pose {pose:?}) of a goal proven unreachable"
            );
        }
    }
    solutions
}

/// economic-elbow on cluttered task 30, goal 5: its eight exact solutions all collide, one of
/// them by 1.6 mm where the goal's tolerance may move the pair by 1.8 mm, so only the parts
/// decide it (the goal was `undecided` before them; the proof lists the parts' pair among
/// "more").
#[test]
fn a_proof_by_parts_holds_for_poses_sampled_throughout_the_tolerance() {
    let (model, scenario, world) = placed("designs/economic-elbow.json", "scenarios/cluttered/task-30.json");
    let goal = &scenario.goals[5];
    let result = Ik::with_collisions(&model, &world, IkOptions::default()).solve(goal, 5, None);
    assert!(
        !result.reached() && result.proof.is_some(),
        "expected a proof: undecided {:?}",
        result.undecided
    );

    let solutions = sampled_solutions_all_collide(&model, &world, goal, 22);
    assert!(solutions > 4000, "the samples must exercise the solutions: {solutions}");
}

/// Parts also find what the one certificate misses: economic-spherical-wrist on the course,
/// where goals with a colliding solution within reach of the tolerance are reached by a free
/// configuration of one part, verified by FK and an independent distance query.
#[test]
fn a_free_configuration_found_by_parts_is_within_the_tolerance_and_free() {
    let (model, scenario, world) = placed("designs/economic-spherical-wrist.json", "scenarios/course.json");
    let mut ws = model.workspace();
    let mut check = Distances::new();
    let mut reached = 0;
    for index in [4usize, 7] {
        let goal: &Goal = &scenario.goals[index];
        assert_eq!(goal.tolerance, Tolerance::ZSymmetric);
        let result = Ik::with_collisions(&model, &world, IkOptions::default()).solve(goal, index, None);
        let Some(best) = result.solutions.first().filter(|s| s.reached) else {
            continue;
        };
        reached += 1;
        let error = goal_error(goal, &model.tool_pose(&best.q));
        assert!(error.position_m <= REACHED_POSITION_M && error.orientation_rad <= REACHED_ORIENTATION_RAD);
        model.forward(&best.q, &mut ws);
        collide::distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut check);
        assert!(!check.in_contact(), "goal {index}: the configuration found collides");
        assert!(within_limits(&model, &best.q));
    }
    assert_eq!(reached, 2, "both goals are reached by a free configuration within the tolerance");
}

/// Boxes straddling the tolerance's edge are certified over what of it the tolerance holds, and
/// cut down to 1/64 of the tolerance: ur10e on cluttered task 15 of seed 7 (not a shipped
/// task), goal 5, where a solution's link3 and obstacle 3 overlap by 6.3 mm and the tolerance
/// may move them by 9.8 mm, was `undecided` with boxes certified whole down to a sixteenth
/// (the clearest part, at 0.0 mm, had its centre outside the tolerance). Its proof holds for
/// 4 000 poses sampled throughout the tolerance, solved in closed form and measured by an
/// independent distance query.
#[test]
fn a_proof_by_parts_clipped_to_the_tolerance_holds_for_sampled_poses() {
    let (model, scenario, world, proof) = proof_on_generated_task("designs/ur10e.json", 15, 7, 5);
    let goal = &scenario.goals[5];
    assert!(proof.contains("parts of the tolerance"), "{proof}");

    let solutions = sampled_solutions_all_collide(&model, &world, goal, 64);
    assert!(solutions > 4000, "the samples must exercise the solutions: {solutions}");
}

/// A pose a few millimetres beyond a UR-type arm's shell whose closed-form proof over the whole
/// tolerance falls short and whose searches leave it open is proven out of reach part by part:
/// modular-elbow on cluttered task 5 of seed 7 (not a shipped task), goal 1, `undecided` before
/// (closest miss 6.5 mm). No pose sampled throughout the tolerance has a solution.
#[test]
fn a_pose_beyond_reach_is_proven_part_by_part_and_no_sampled_pose_has_a_solution() {
    let (model, scenario, _, proof) = proof_on_generated_task("designs/modular-elbow.json", 5, 7, 1);
    let goal = &scenario.goals[1];
    assert!(proof.contains("parts, each out of reach"), "{proof}");

    let closed_form = Ik::new(&model, IkOptions::default());
    let arm = closed_form.closed_form().expect("modular-elbow is a UR-type arm");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(65);
    for _ in 0..4000 {
        let pose = Isometry3::from_parts(
            Translation3::from(goal.position + in_ball(&mut rng, REACHED_POSITION_M)),
            UnitQuaternion::from_scaled_axis(in_ball(&mut rng, REACHED_ORIENTATION_RAD)) * goal.rotation,
        );
        let found = arm.solve(&pose);
        assert!(
            found.configurations.is_empty(),
            "a pose within the tolerance has solutions: {pose:?}"
        );
    }
}
