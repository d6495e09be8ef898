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
            task: None,
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
        let scenario = common::sphere_and_goal(elbow, 0.08, &tool);
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

    let model = load_model(&common::repo().join("designs/ur20.json"), &LoadOptions::default()).expect("loads");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut compared, mut tightened) = (0, 0);
    for index in 0..20 {
        let q = model.random_configuration(&mut rng);
        let tool = model.tool_pose(&q);
        let scenario = common::sphere_and_goal(nalgebra::Vector3::new(0.0, 0.0, 3.0), 0.1, &tool);
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

/// The distinct converged solutions of `result` (errors below 1e-6 m and rad: a start stuck at a
/// workspace boundary may end within the tolerance but at no exact solution).
fn converged(result: &proving_ground::ik::GoalSolutions) -> Vec<Vec<f64>> {
    result
        .solutions
        .iter()
        .filter(|s| s.error.position_m < 1e-6 && s.error.orientation_rad < 1e-6)
        .map(|s| s.q.clone())
        .collect()
}

/// Issue 11, item 4 ("every solution") beyond UR-type arms: the default solver's solutions
/// against a brute-force oracle (500 random starts, no branch restarts), per design over 20 FK
/// goals; the oracle's set is the union of both, so a branch only the default found counts too.
///
/// Measured (default 32 branch starts; found, starts per goal; without branch restarts):
/// free-offset-6dof 100 % of 6.60, 32.1 starts (46 %); economic-spherical-wrist 100 % of 7.80,
/// 13.9 (41 %); economic-elbow 97.2 % of 7.20, 8.9 (39 %: one goal near the shoulder singularity
/// keeps one shoulder, and near a stretched elbow the oracle counts one solution twice, 3e-3 rad
/// apart); abb-irb-2600 100 % of 8.00, 14.1 (39 %); modular-compact 99.3 % of 7.45, 8.9 (38 %).
#[test]
fn on_non_ur_6r_designs_the_default_finds_most_solutions_of_a_500_start_oracle() {
    for design in [
        "designs/free-offset-6dof.json",
        "designs/economic-spherical-wrist.json",
        "designs/economic-elbow.json",
        "designs/abb-irb-2600.json",
        "designs/modular-compact.json",
    ] {
        let model = load_model(&common::repo().join(design), &LoadOptions::default()).expect("design loads");
        // The closed form off: economic-elbow and modular-compact are UR-type.
        let numeric = IkOptions {
            analytic: false,
            ..Default::default()
        };
        let mut default = Ik::new(&model, numeric.clone());
        let mut plain = Ik::new(
            &model,
            IkOptions {
                branch_starts: 0,
                ..numeric.clone()
            },
        );
        let mut oracle = Ik::new(
            &model,
            IkOptions {
                seeds: 500,
                branch_starts: 0,
                seed: 1,
                ..numeric
            },
        );
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
        let goals = 20;
        let (mut union, mut found, mut found_plain, mut starts) = (0, 0, 0, 0);
        for index in 0..goals {
            let tool = model.tool_pose(&model.random_configuration(&mut rng));
            let goal = Goal {
                name: format!("goal {index}"),
                position: tool.translation.vector,
                rotation: tool.rotation,
                tolerance: Tolerance::Pose,
                task: None,
            };
            let result = default.solve(&goal, index, None);
            starts += result.starts;
            let mine = converged(&result);
            let theirs = converged(&oracle.solve(&goal, index, None));
            let plain_found = converged(&plain.solve(&goal, index, None));
            let mut all = theirs.clone();
            for q in &mine {
                if !all.iter().any(|t| default.same_configuration(t, q)) {
                    all.push(q.clone());
                }
            }
            union += all.len();
            found += mine.len();
            found_plain += plain_found.len();
        }
        let fraction = found as f64 / union as f64;
        println!(
            "{design}: oracle {:.2} solutions per goal; default finds {:.1}% ({:.1} starts per goal), without branch restarts {:.1}%",
            union as f64 / goals as f64,
            100.0 * fraction,
            starts as f64 / goals as f64,
            100.0 * found_plain as f64 / union as f64,
        );
        // The worst measured is 97.2 %; a margin for seeds that change with the code.
        assert!(fraction >= 0.95, "{design}: the default found {found} of {union}");
    }
}

/// The caller's starts per goal (`IkOptions::goal_starts`, an optimizer's configurations) are
/// tried beside the random ones: with no random start and the search off, a 5-joint arm on a pose
/// it reaches finds it from a start near the solution, and nothing without.
#[test]
fn given_starts_are_tried_per_goal() {
    let model = load_model(&common::repo().join("designs/paper-real-world.json"), &LoadOptions::default()).expect("loads");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(22);
    let mut found = 0;
    for _ in 0..10 {
        let q0 = model.random_configuration(&mut rng);
        let tool = model.tool_pose(&q0);
        let goal = Goal {
            name: "fk".into(),
            position: tool.translation.vector,
            rotation: tool.rotation,
            tolerance: Tolerance::Pose,
            task: None,
        };
        let near: Vec<f64> = q0.iter().map(|x| x + 0.02).collect();
        let opts = IkOptions {
            seeds: 0,
            search_boxes: 0,
            ..Default::default()
        };
        let alone = Ik::new(&model, opts.clone()).solve(&goal, 0, None);
        assert!(!alone.reached(), "no start, no solution: {alone:?}");
        let given = IkOptions {
            goal_starts: vec![vec![near]],
            ..opts
        };
        let result = Ik::new(&model, given).solve(&goal, 0, None);
        assert_eq!(result.starts, 1);
        found += usize::from(result.reached());
        // Another goal's starts are not this goal's.
        let other = Ik::new(
            &model,
            IkOptions {
                goal_starts: vec![vec![], vec![q0.clone()]],
                seeds: 0,
                search_boxes: 0,
                ..Default::default()
            },
        )
        .solve(&goal, 0, None);
        assert!(!other.reached());
    }
    assert!(found >= 9, "{found} of 10 found from a start 0.02 rad off");
}
