//! Goals whose own pose has only colliding solutions, or none, while poses within the
//! tolerance have free ones (branches born inside it, near a workspace boundary): the paper's
//! real-world arm on goals 50 and 79 of its workspace task. The witness found by sampling the
//! tolerance is checked independently of the solver: its pose error by FK, its clearance by the
//! exact geometry, its joints within the limits, and it is none of the exact solutions of the goal's own pose.

mod common;

use nalgebra::{Isometry3, Translation3};
use proving_ground::collide::{clear, Distances};
use proving_ground::ik::solvers::AllSolutions;
use proving_ground::ik::{goal_error, solve_goals, wrap_angle, IkOptions, REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use proving_ground::pipeline::{collision_world, load_model, load_scenario, LoadOptions};
use proving_ground::scenario::Scenario;

#[test]
fn a_free_configuration_within_the_tolerance_off_every_exact_branch_is_found_and_holds() {
    let model = load_model(&common::repo().join("designs/paper-real-world.json"), &LoadOptions::default()).expect("design loads");
    let workspace = load_scenario(&common::repo().join("scenarios/workspace/z_symmetric.json")).expect("scenario loads");
    let (method, _) = AllSolutions::of(&model).expect("a 5R arm has the all-solutions method");
    for index in [50, 79] {
        let goal = workspace.goals[index].clone();
        let scenario = Scenario {
            goals: vec![goal.clone()],
            ..workspace.clone()
        };
        let world = collision_world(&model, &scenario, &[]).expect("world builds");
        let solved = solve_goals(&model, &scenario, Some(&world), &IkOptions::default());
        assert!(solved[0].reached(), "goal {index}: {:?}", solved[0].undecided);
        let q = &solved[0].solutions[0].q;
        let error = goal_error(&goal, &model.tool_pose(q));
        assert!(
            error.position_m < REACHED_POSITION_M && error.orientation_rad < REACHED_ORIENTATION_RAD,
            "goal {index}: {error:?}"
        );
        assert!(common::within_limits(&model, q), "goal {index}: {q:?} outside the limits");
        let mut ws = model.workspace();
        model.forward(q, &mut ws);
        assert!(
            clear(&world, &ws.link_in_world, 0.0, &mut Distances::new()),
            "goal {index}: {q:?} collides"
        );
        // The goal's own pose: the witness is none of its exact solutions (if it has any).
        let own = method.solve(&Isometry3::from_parts(Translation3::from(goal.position), goal.rotation));
        for exact in &own.configurations {
            let apart = exact.iter().zip(q).map(|(a, b)| wrap_angle(a - b).abs()).fold(0.0, f64::max);
            assert!(apart > 1e-3, "goal {index}: the witness is the exact solution {exact:?}");
        }
    }
}
