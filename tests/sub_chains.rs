//! Sub-chains standing in for the arm in the joint-space search, and the tolerance aimed at
//! directly (issue 22), against oracles they do not use: poses sampled throughout a proven
//! goal's tolerance, each solved exactly (the general 6R elimination, the spherical wrist's
//! closed form) and each solution measured by an independent distance query; a configuration
//! found within the tolerance checked by FK, where the closed form says the pose itself has no
//! solution.

mod common;

use common::{in_ball, repo, within_limits};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use proving_ground::collide::{self, Distances, QueryOptions};
use proving_ground::ik::{goal_error, Ik, IkOptions, REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use proving_ground::model::Model;
use proving_ground::pipeline::{collision_world, load_model, LoadOptions};
use proving_ground::scenario::generate::cluttered;
use proving_ground::scenario::{Goal, Scenario};
use rand::{Rng, SeedableRng};

/// The cluttered tasks of another seed than the shipped ones, as a new user makes them.
const SEED: u64 = 77;

/// A pose within the goal's tolerance, anywhere in it (a third of them on its edge).
fn within_tolerance(goal: &Goal, rng: &mut impl Rng) -> Isometry3<f64> {
    let edge = rng.random_bool(1.0 / 3.0);
    let (shift, turn) = if edge {
        (
            common::unit(rng) * REACHED_POSITION_M * 0.999,
            common::unit(rng) * REACHED_ORIENTATION_RAD * 0.999,
        )
    } else {
        (
            in_ball(rng, REACHED_POSITION_M * 0.999),
            in_ball(rng, REACHED_ORIENTATION_RAD * 0.999),
        )
    };
    Isometry3::from_parts(
        Translation3::from(goal.position + shift),
        UnitQuaternion::from_scaled_axis(turn) * goal.rotation,
    )
}

fn placed(design: &str, task: usize) -> (Model, Scenario) {
    let scenario = cluttered(task, SEED);
    let model = load_model(&repo().join(design), &LoadOptions::default())
        .expect("shipped design")
        .placed(&scenario.world_from_base);
    (model, scenario)
}

/// free-offset-6dof (a general 6R arm, no closed form) on goals just out of its reach: the line
/// of its last axis proves them (the whole arm's search ran out of boxes on each). No pose of
/// 1 500 sampled throughout each tolerance has an exact solution.
#[test]
fn goals_proven_by_the_last_axis_have_no_solution_anywhere_in_their_tolerance() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(22);
    let mut proven = 0;
    for task in [1, 2, 13, 34] {
        let (model, scenario) = placed("designs/free-offset-6dof.json", task);
        let mut ik = Ik::new(&model, IkOptions::default());
        for (index, goal) in scenario.goals.iter().enumerate() {
            let result = ik.solve(goal, index, None);
            let Some(proof) = result
                .proof
                .as_deref()
                .filter(|p| p.starts_with("joint-space search of joints 1 to 5"))
            else {
                continue;
            };
            assert!(proof.contains("the axis of joint 6"), "{proof}");
            proven += 1;
            let exact = ik.all_solutions().expect("the general 6R elimination applies");
            for _ in 0..1500 {
                let pose = within_tolerance(goal, &mut rng);
                let found = exact.solve(&pose);
                assert!(
                    found.configurations.iter().all(|q| !within_limits(&model, q)),
                    "task {task} goal {index}: proven by the last axis, yet {pose:?} within its tolerance has {:?}",
                    found.configurations
                );
            }
        }
    }
    assert!(proven >= 4, "only {proven} goals proven by the last axis");
}

/// UR-type arms on goals just beyond their reach, where turning the tool by up to a degree
/// brings a pose within the tolerance back in: the numeric solver, aiming at the pose, ends
/// millimetres off (1.6 to 3 mm at 0.02 to 0.3 deg); aiming at the tolerance finds a free
/// configuration. Checked by FK, an independent distance query and the closed form (no
/// solution at the goal's own pose).
#[test]
fn a_goal_just_beyond_reach_is_reached_within_its_tolerance() {
    for (design, task, index) in [
        ("designs/modular-elbow.json", 27, 6),
        ("designs/modular-elbow.json", 23, 6),
        ("designs/modular-long-reach.json", 4, 3),
    ] {
        let (model, scenario) = placed(design, task);
        let world = collision_world(&model, &scenario, &[]).expect("the world builds");
        let goal = &scenario.goals[index];
        let pose = Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
        let exact = Ik::new(&model, IkOptions::default());
        let arm = exact.closed_form().expect("a UR-type arm");
        assert!(
            arm.solve(&pose).configurations.is_empty(),
            "{design} task {task} goal {index}: the pose itself has a solution"
        );
        let result = Ik::with_collisions(&model, &world, IkOptions::default()).solve(goal, index, None);
        assert!(result.reached(), "{design} task {task} goal {index}: {:?}", result.undecided);
        let best = &result.solutions[0];
        let error = goal_error(goal, &model.tool_pose(&best.q));
        assert!(
            error.position_m < REACHED_POSITION_M && error.orientation_rad < REACHED_ORIENTATION_RAD,
            "{error:?}"
        );
        assert!(within_limits(&model, &best.q));
        let mut ws = model.workspace();
        let mut check = Distances::new();
        model.forward(&best.q, &mut ws);
        collide::distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut check);
        assert!(
            !check.in_contact(),
            "{design} task {task} goal {index}: the configuration found collides"
        );
        // Without the joint-space stage, where the tolerance is aimed at, the goal stays open.
        let options = IkOptions {
            search_boxes: 0,
            ..IkOptions::default()
        };
        let without = Ik::with_collisions(&model, &world, options).solve(goal, index, None);
        assert!(!without.reached(), "{design} task {task} goal {index} was reached before");
    }
}

/// abb-irb-2600 (a spherical wrist) on a goal whose every solution collides, one near a
/// singularity where no certificate around it holds: the line of its last axis, with the
/// collisions among links 1 to 5, proves it. Every solution within the limits of 1 500 poses
/// sampled throughout the tolerance collides by an independent distance query.
#[test]
fn a_proof_in_collision_by_a_sub_chain_holds_throughout_the_tolerance() {
    let (model, scenario) = placed("designs/abb-irb-2600.json", 29);
    let world = collision_world(&model, &scenario, &[]).expect("the world builds");
    let index = 5;
    let goal = &scenario.goals[index];
    let result = Ik::with_collisions(&model, &world, IkOptions::default()).solve(goal, index, None);
    let proof = result.proof.as_deref().unwrap_or_default();
    assert!(
        proof.contains("collides among links 1 to"),
        "expected a sub-chain's proof in collision: {proof:?} {:?}",
        result.undecided
    );

    let exact_ik = Ik::new(&model, IkOptions::default());
    let exact = exact_ik.all_solutions().expect("the spherical wrist's method applies");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(23);
    let mut ws = model.workspace();
    let mut check = Distances::new();
    let mut solutions = 0;
    for _ in 0..1500 {
        let pose = within_tolerance(goal, &mut rng);
        for q in exact.solve(&pose).configurations {
            if !within_limits(&model, &q) {
                continue;
            }
            solutions += 1;
            model.forward(&q, &mut ws);
            collide::distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut check);
            assert!(
                check.in_contact(),
                "a free configuration {q:?} within the tolerance ({pose:?}) of a goal proven unreachable"
            );
        }
    }
    assert!(solutions > 1500, "the samples must exercise the solutions: {solutions}");
}
