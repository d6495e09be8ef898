//! IK quality on goals that are reachable by construction (FK of random configurations), and
//! agreement with closed-form cases.

mod common;

use proving_ground::ik::{goal_error, Ik, IkOptions, REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use proving_ground::pipeline::{load_model, LoadOptions};
use proving_ground::scenario::{Goal, Tolerance};
use rand::SeedableRng;

/// Goals made from the FK of random configurations; returns the fraction reached.
fn reach_rate(design: &str, goals: usize, tolerance: Tolerance, seed: u64) -> f64 {
    let model = load_model(&common::repo().join(design), &LoadOptions::default()).expect("design loads");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut ik = Ik::new(&model, IkOptions::default());
    let mut reached = 0;
    for index in 0..goals {
        let q = model.random_configuration(&mut rng);
        let tool = model.tool_pose(&q);
        let goal = Goal {
            name: format!("goal {index}"),
            position: tool.translation.vector,
            rotation: tool.rotation,
            tolerance,
        };
        let result = ik.solve(&goal, index, None);
        if result.reached() {
            reached += 1;
            for solution in &result.solutions {
                // Independent re-check of the verdict from the solution's own FK.
                let error = goal_error(&goal, &model.tool_pose(&solution.q));
                assert!(
                    error.position_m < REACHED_POSITION_M && error.orientation_rad < REACHED_ORIENTATION_RAD,
                    "{design} goal {index}: {error:?}"
                );
                for (value, joint) in solution.q.iter().zip(&model.joints) {
                    let [lower, upper] = joint.limits.expect("design joints have limits");
                    assert!(
                        *value >= lower && *value <= upper,
                        "{design} goal {index}: joint {} at {value} outside [{lower}, {upper}]",
                        joint.name
                    );
                }
            }
        }
    }
    reached as f64 / goals as f64
}

#[test]
fn ur_presets_reach_at_least_99_5_percent_of_10000_fk_goals_with_4_seeds() {
    for design in ["designs/ur5e.json", "designs/ur10e.json", "designs/ur20.json"] {
        let rate = reach_rate(design, 10_000, Tolerance::Pose, 11);
        println!("{design}: {:.2}% of 10000 pose goals reached", 100.0 * rate);
        assert!(rate >= 0.995, "{design}: only {:.2}% reached", 100.0 * rate);
    }
}

#[test]
fn other_designs_and_tolerance_modes_reach_fk_goals() {
    for design in [
        "designs/paper-real-world.json",
        "designs/modular-elbow.json",
        "designs/free-redundant-7dof.json",
        "designs/economic-scara.json",
    ] {
        for tolerance in [Tolerance::Pose, Tolerance::ZSymmetric, Tolerance::Position] {
            let rate = reach_rate(design, 500, tolerance, 5);
            println!("{design} {tolerance:?}: {:.1}%", 100.0 * rate);
            assert!(rate >= 0.95, "{design} {tolerance:?}: only {:.1}% reached", 100.0 * rate);
        }
    }
}

/// A goal whose FK configuration runs the forearm through a sphere: the IK must either find
/// another, collision-free branch or say the goal is not reached, and every solution it calls
/// reached must be free by an independent exact query.
#[test]
fn collision_aware_ik_never_calls_a_colliding_solution_reached() {
    use proving_ground::collide::{self, CollideOptions, Distances, QueryOptions};
    use proving_ground::model::Shape;
    use proving_ground::scenario::{Obstacle, Scenario};

    // UR20: its wrist links are long enough not to overlap by construction (see README).
    let model = load_model(&common::repo().join("designs/ur20.json"), &LoadOptions::default()).expect("loads");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
    let mut ws = model.workspace();
    let (mut reached, mut blocked, mut tried) = (0, 0, 0);
    for index in 0..40 {
        let q = model.random_configuration(&mut rng);
        model.forward(&q, &mut ws);
        // A sphere on the elbow of the FK configuration: that configuration collides.
        let elbow = ws.link_in_world[3].translation.vector;
        let tool = model.tool_pose(&q);
        if (tool.translation.vector - elbow).norm() < 0.3 {
            continue;
        }
        tried += 1;
        let scenario = Scenario {
            name: "elbow".into(),
            world_from_base: nalgebra::Isometry3::identity(),
            floor: None,
            obstacles: vec![Obstacle {
                name: "ball".into(),
                world_from_shape: nalgebra::Isometry3::translation(elbow.x, elbow.y, elbow.z),
                shape: Shape::Sphere { radius: 0.08 },
            }],
            goals: vec![Goal {
                name: "g".into(),
                position: tool.translation.vector,
                rotation: tool.rotation,
                tolerance: Tolerance::Pose,
            }],
            home: None,
            provenance: None,
        };
        let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("world builds");
        let mut ik = Ik::with_collisions(&model, &world, IkOptions::default());
        let result = ik.solve(&scenario.goals[0], index, Some(&q));
        let mut check = Distances::new();
        for solution in &result.solutions {
            model.forward(&solution.q, &mut ws);
            collide::distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut check);
            let free = !check.in_contact();
            let clearance = solution.clearance.expect("solved with a collision world");
            assert_eq!(
                free,
                clearance.exact_m > 0.0,
                "goal {index}: clearance {clearance:?} vs independent query {:?}",
                check.closest
            );
            if solution.reached {
                assert!(
                    free && solution.pose_reached,
                    "goal {index}: a colliding solution was called reached"
                );
            }
        }
        if result.reached() {
            reached += 1;
        } else {
            blocked += 1;
        }
    }
    println!("elbow-sphere goals: {tried} tried, {reached} reached collision-free, {blocked} not");
    assert!(
        reached > tried / 2,
        "collision-aware IK should find another branch for most goals: {reached} of {tried}"
    );
}

#[test]
fn a_clearance_margin_makes_ik_call_a_solution_closer_than_it_not_reached() {
    use proving_ground::collide::{self, CollideOptions};
    use proving_ground::model::Shape;
    use proving_ground::scenario::{Obstacle, Scenario};

    let model = load_model(&common::repo().join("designs/ur20.json"), &LoadOptions::default()).expect("loads");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut compared, mut tightened) = (0, 0);
    for index in 0..20 {
        let q = model.random_configuration(&mut rng);
        let tool = model.tool_pose(&q);
        let scenario = Scenario {
            name: "margin".into(),
            world_from_base: nalgebra::Isometry3::identity(),
            floor: None,
            obstacles: vec![Obstacle {
                name: "ball".into(),
                world_from_shape: nalgebra::Isometry3::translation(0.0, 0.0, 3.0),
                shape: Shape::Sphere { radius: 0.1 },
            }],
            goals: vec![Goal {
                name: "g".into(),
                position: tool.translation.vector,
                rotation: tool.rotation,
                tolerance: Tolerance::Pose,
            }],
            home: None,
            provenance: None,
        };
        let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("world builds");
        let plain = Ik::with_collisions(&model, &world, IkOptions::default()).solve(&scenario.goals[0], index, None);
        let margin = 0.05;
        let opts = IkOptions {
            clearance_m: margin,
            ..Default::default()
        };
        let strict = Ik::with_collisions(&model, &world, opts).solve(&scenario.goals[0], index, None);
        for solution in &strict.solutions {
            let clearance = solution.clearance.expect("measured").exact_m;
            assert_eq!(
                solution.reached,
                solution.pose_reached && clearance > margin,
                "goal {index}: {solution:?}"
            );
        }
        compared += 1;
        let close = |s: &proving_ground::ik::IkSolution| s.reached && s.clearance.is_some_and(|c| c.exact_m <= margin);
        tightened += usize::from(plain.solutions.iter().any(close));
    }
    // Some plain solutions are free but closer than the margin: the margin is not vacuous.
    assert!(compared == 20 && tightened > 0, "{tightened} of {compared}");
}
