//! The proof that every configuration collides, whatever the goal (an obstacle through the
//! arm's first links), against random configurations of the whole arm: wherever it is claimed,
//! thousands of them all collide; where a free configuration exists it is never claimed.

mod common;

use nalgebra::Vector3;
use proving_ground::collide::{clear, Distances};
use proving_ground::ik::{solve_goals, IkOptions};
use proving_ground::model::Model;
use proving_ground::pipeline::{collision_world, load_model, LoadOptions};
use proving_ground::scenario::Scenario;
use rand::{Rng, SeedableRng};

const CLAIM: &str = "every configuration collides";

/// A scenario of one sphere and one goal (the tool's pose at `q`).
fn scenario(model: &Model, centre: Vector3<f64>, radius: f64, q: &[f64]) -> Scenario {
    common::sphere_and_goal(centre, radius, &model.tool_pose(q))
}

/// Whether each of `count` random configurations within the limits collides; the first free
/// one otherwise.
fn first_free(model: &Model, scenario: &Scenario, count: usize, rng: &mut impl Rng) -> Option<Vec<f64>> {
    let world = collision_world(model, scenario, &[]).expect("world builds");
    let mut ws = model.workspace();
    let mut distances = Distances::new();
    (0..count).map(|_| model.random_configuration(rng)).find(|q| {
        model.forward(q, &mut ws);
        clear(&world, &ws.link_in_world, 0.0, &mut distances)
    })
}

/// Spheres about the first joints of four arms, some through them (the claim holds), some
/// beside them (a free configuration exists): every claim is checked against 3 000 random
/// configurations, and a goal is decided (by this proof or another) where the sphere swallows
/// link 1's origin.
#[test]
fn claimed_only_where_every_sampled_configuration_collides() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let opts = IkOptions {
        search_boxes: 20_000,
        ..IkOptions::default()
    };
    let (mut claimed, mut not_claimed) = (0, 0);
    for design in ["ur5e", "free-offset-6dof", "economic-scara", "free-redundant-7dof"] {
        let path = common::repo().join(format!("designs/{design}.json"));
        let model = load_model(&path, &LoadOptions::default()).expect("design loads");
        let mut ws = model.workspace();
        model.forward(&vec![0.0; model.dof()], &mut ws);
        // Link 1's origin, on joint 1's axis: joint 1 only turns the link about it.
        let shoulder = ws.link_in_world[1].translation.vector;
        for trial in 0..12 {
            let (centre, radius) = if trial < 4 {
                (shoulder, rng.random_range(0.06..0.12))
            } else {
                let offset = common::unit(&mut rng) * rng.random_range(0.05..0.4);
                (shoulder + offset, rng.random_range(0.03..0.15))
            };
            let q = model.random_configuration(&mut rng);
            let scene = scenario(&model, centre, radius, &q);
            let world = collision_world(&model, &scene, &[]).expect("world builds");
            let solved = solve_goals(&model, &scene, Some(&world), &opts);
            let proof = solved[0].proof.clone().unwrap_or_default();
            let free = first_free(&model, &scene, 3_000, &mut rng);
            if proof.contains(CLAIM) {
                claimed += 1;
                assert!(free.is_none(), "{design} trial {trial}: {free:?} is free; proof: {proof}");
                assert!(!solved[0].reached(), "{design} trial {trial}: reached, and proven: {proof}");
            } else {
                not_claimed += 1;
            }
            if trial < 4 {
                assert!(
                    !proof.is_empty(),
                    "{design} trial {trial}: a sphere of {radius} m about link 1's origin, undecided: {:?}",
                    solved[0].undecided
                );
            }
        }
    }
    println!("{claimed} claimed, {not_claimed} not");
    assert!(claimed > 0 && not_claimed > 0, "{claimed} claimed, {not_claimed} not");
}
