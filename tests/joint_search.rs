//! The joint-space search (`ik::search`) against oracles it does not use: its box test never
//! rules out a box that holds a configuration known to be within the tolerance (the model's own
//! FK at random configurations), and the goals it proves stay unreached by a dense numeric
//! search.

mod common;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use proving_ground::ik::search::{rules_out, search, Search};
use proving_ground::ik::{Ik, IkOptions};
use proving_ground::model::Model;
use proving_ground::pipeline::{self, LoadOptions};
use proving_ground::scenario::{generate, Goal, Tolerance};
use proving_ground::sweep::inputs::{catalog_entry, modular6_slots};
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;

/// A configuration and a goal of `tolerance` within 0.999 mm and 0.999 deg of its tool pose
/// (a `z_symmetric` goal also turned about tool z): the configuration is a witness that the
/// goal is reachable.
fn witnessed_goal(model: &Model, tolerance: Tolerance, rng: &mut impl Rng) -> (Vec<f64>, Goal) {
    let q = model.random_configuration(rng);
    let tool = model.tool_pose(&q);
    let turn = UnitQuaternion::from_scaled_axis(common::unit(rng) * rng.random_range(0.0..0.999_f64.to_radians()));
    let spin = match tolerance {
        Tolerance::ZSymmetric => UnitQuaternion::from_scaled_axis(Vector3::z() * rng.random_range(-PI..PI)),
        _ => UnitQuaternion::identity(),
    };
    let goal = Goal {
        name: "witnessed".into(),
        position: tool.translation.vector + common::unit(rng) * rng.random_range(0.0..0.999e-3),
        rotation: turn * tool.rotation * spin,
        tolerance,
        task: None,
    };
    (q, goal)
}

fn models() -> Vec<(String, Model)> {
    let mut models: Vec<(String, Model)> = common::shipped_models();
    for index in (0..15_625).step_by(977) {
        let entry = catalog_entry(&modular6_slots(index));
        models.push((entry.id.clone(), entry.load().model));
    }
    let place = Isometry3::from_parts(Translation3::new(0.3, -0.2, 0.1), UnitQuaternion::from_euler_angles(0.2, -0.4, 1.1));
    models.into_iter().map(|(name, model)| (name, model.placed(&place))).collect()
}

#[test]
fn no_box_holding_a_configuration_within_the_tolerance_is_ruled_out() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut checked = 0;
    for (name, model) in models() {
        for tolerance in [Tolerance::Pose, Tolerance::ZSymmetric, Tolerance::Position] {
            for _ in 0..40 {
                let (q, goal) = witnessed_goal(&model, tolerance, &mut rng);
                for _ in 0..25 {
                    // Widths from a tenth of a milliradian to about a turn, the witness anywhere
                    // in the box: the coarse and the first-order tests both get their turn.
                    let scale = rng.random_range((1e-4_f64).ln()..(3.0_f64).ln()).exp();
                    let (mut lower, mut upper) = (q.clone(), q.clone());
                    for i in 0..q.len() {
                        let width = scale * rng.random_range(0.2..1.0);
                        let below = rng.random_range(0.0..1.0) * width;
                        lower[i] -= below;
                        upper[i] += width - below;
                    }
                    assert!(
                        !rules_out(&model, &goal, &lower, &upper),
                        "{name}: a {} goal ruled out over a box holding a configuration within its tolerance: q {q:?}, box {lower:?} .. {upper:?}",
                        tolerance.name()
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 10_000, "{checked} boxes checked");
}

#[test]
fn a_reachable_goal_is_never_proven_and_is_found() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
    for (name, model) in models().into_iter().step_by(3) {
        for tolerance in [Tolerance::Pose, Tolerance::ZSymmetric] {
            let (_, goal) = witnessed_goal(&model, tolerance, &mut rng);
            let outcome = search(&model, &goal, 20_000, |_| false);
            assert!(!matches!(outcome, Some(Search::Proven { .. })), "{name}: {outcome:?}");
        }
    }
}

/// The paper's real-world robot on the workspace task (5 joints on `z_symmetric` goals): the
/// goals the search proves out of the tolerance stay unreached from 300 numeric starts each.
#[test]
fn proofs_hold_against_a_dense_numeric_search() {
    let path = common::repo().join("designs/paper-real-world.json");
    let scenario = generate::workspace(100, 1.0, Tolerance::ZSymmetric, generate::WORKSPACE_SEED).expect("valid parameters");
    let model = pipeline::load_model(&path, &LoadOptions::default())
        .expect("shipped design")
        .placed(&scenario.world_from_base);
    let mut ik = Ik::new(&model, common::dense_numeric());
    let mut proven = 0;
    for (index, goal) in scenario.goals.iter().enumerate() {
        let Some(Search::Proven { .. }) = search(&model, goal, 300_000, |_| false) else {
            continue;
        };
        proven += 1;
        common::assert_unreached(&mut ik, goal, index, "proven", "workspace task");
    }
    assert!(proven >= 10, "only {proven} goals proven");
}

/// Free designs as the paper's generator makes them (`a = 0` and `alpha = 0` between two
/// joints puts them on one axis: joints 4 and 5; 1 and 2; 1 and 2 and 4 and 5) on the shipped
/// cluttered tasks, at a sweep's budget: the goals proven by the search of the arm with those
/// joints merged stay unreached from 300 numeric starts of the arm itself (which knows nothing
/// of the merge), and such proofs are made (the arm's own searches left every one of them open;
/// on the first design, whose joints 3 to 6 are parallel, the planar run's search proves them
/// first, on the third, whose joints turn about two directions, the turning axes' proof: theirs
/// are checked the same way).
#[test]
fn proofs_of_arms_with_coaxial_joints_merged_hold_against_a_dense_numeric_search() {
    let row = |d: f64, a: f64, alpha: f64| format!(r#"{{"d": {d}, "a": {a}, "alpha": {alpha}}}"#);
    let (down, up) = (-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2);
    let designs = [
        (
            "4 and 5",
            [
                row(0.3, 0.4, down),
                row(0.3, 0.0, up),
                row(0.2, 0.4, 0.0),
                row(0.3, 0.0, 0.0),
                row(0.3, 0.2, 0.0),
                row(0.0, 0.2, 0.0),
            ],
        ),
        (
            "1 and 2",
            [
                row(0.1, 0.0, 0.0),
                row(0.3, 0.4, 0.0),
                row(0.3, 0.4, down),
                row(0.1, 0.0, down),
                row(0.1, 0.0, up),
                row(0.1, 0.2, up),
            ],
        ),
        (
            "1 and 2; joints 4 and 5",
            [
                row(0.1, 0.0, 0.0),
                row(0.3, 0.4, 0.0),
                row(0.3, 0.2, down),
                row(0.1, 0.0, 0.0),
                row(0.1, 0.3, 0.0),
                row(0.2, 0.4, down),
            ],
        ),
    ];
    let sweep = IkOptions {
        search_boxes: proving_ground::ik::SWEEP_SEARCH_BOXES,
        ..IkOptions::default()
    };
    let dense = common::dense_numeric();
    for (joints, rows) in designs {
        let text = format!(r#"{{"name": "coaxial", "mode": "free", "joints": [{}]}}"#, rows.join(","));
        let design = proving_ground::design::parse(&text, std::path::Path::new("coaxial.json")).expect("design");
        let mut proven = 0;
        for task in 0..12 {
            let path = common::repo().join(format!("scenarios/cluttered/task-{task:02}.json"));
            let scenario = pipeline::load_scenario(&path).expect("shipped task");
            let model = proving_ground::model::from_design(&design).placed(&scenario.world_from_base);
            let mut ik = Ik::new(&model, sweep.clone());
            let mut numeric = Ik::new(&model, dense.clone());
            for (index, goal) in scenario.goals.iter().enumerate() {
                let result = ik.solve(goal, index, None);
                // Four parallel axes in a row (joints 3 to 6 of the first) go to the planar run's
                // search first, and two directions of turning (the third) to the turning axes'
                // proof (the pipeline's, IK's searches skipped): their proofs stand in for the
                // merged arm's, and are checked alike.
                let proof = result
                    .proof
                    .clone()
                    .or_else(|| proving_ground::ik::turning_axes_out_of_reach(&model, goal));
                let merged_or_other = |p: &&str| {
                    p.starts_with(&format!("joints {joints} ")) || p.contains("turn about parallel axes") || p.contains("about another")
                };
                let Some(proof) = proof.as_deref().filter(merged_or_other) else {
                    continue;
                };
                proven += 1;
                common::assert_unreached(&mut numeric, goal, index, proof, &format!("task {task}"));
            }
        }
        assert!(proven >= 3, "joints {joints}: only {proven} goals proven with them merged");
    }
}

/// The arm with coaxial joints merged into five and a virtual sixth about tool z (or into six),
/// solved exactly (issue 22): random free designs of the paper's generator's values with one
/// pair on one axis. Goals within 0.999 mm and 0.999 deg of a configuration's tool pose
/// (witnessed reachable; a third of the 6-joint arms' `z_symmetric`, which the five merged
/// joints solve as they are) never get its proof; goals 2 to 20 mm and degrees off one (out of a
/// five-joint arm's reach by a little, the hardest to prove) get it, and a dense numeric search
/// of the arm itself reaches none of those.
#[test]
fn merged_arms_with_a_virtual_tool_joint_prove_only_what_is_unreachable() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
    let values = |rng: &mut rand_chacha::ChaCha8Rng| {
        [
            [0.0, 0.1, 0.2, 0.3][rng.random_range(0..4)],
            [0.0, 0.2, 0.3, 0.4][rng.random_range(0..4)],
            [0.0, PI / 2.0, -PI / 2.0][rng.random_range(0..3)],
        ]
    };
    let dense = common::dense_numeric();
    let (mut designs, mut proven, mut offered, mut zsym) = (0, 0, 0, 0);
    // Six 6-joint designs (five joints merged, a virtual sixth), then three 7-joint ones (six
    // merged, no virtual joint).
    while designs < 9 {
        let joints = if designs < 6 { 6 } else { 7 };
        let mut rows: Vec<[f64; 3]> = (0..joints).map(|_| values(&mut rng)).collect();
        let pair = rng.random_range(0..4);
        rows[pair] = [rows[pair][0], 0.0, 0.0];
        let model = common::dh_design(&format!("coaxial-{designs}"), &rows);
        let proves = |result: &proving_ground::ik::GoalSolutions| {
            result
                .proof
                .as_deref()
                .filter(|p| p.contains("the arm so merged has joints"))
                .map(str::to_owned)
        };
        let sweep = IkOptions {
            search_boxes: proving_ground::ik::SWEEP_SEARCH_BOXES,
            ..IkOptions::default()
        };
        let mut ik = Ik::new(&model, sweep);
        let mut numeric = Ik::new(&model, dense.clone());
        for index in 0..12 {
            // A third `z_symmetric` (the five merged joints as they are), and on 6-joint arms
            // only: a 7-joint arm's six merged joints have a self-motion there.
            let tolerance = if index % 3 == 2 && joints == 6 {
                Tolerance::ZSymmetric
            } else {
                Tolerance::Pose
            };
            let (q, goal) = witnessed_goal(&model, tolerance, &mut rng);
            let result = ik.solve(&goal, index, None);
            assert!(
                proves(&result).is_none(),
                "{rows:?}: goal {index} is within the tolerance at {q:?}, yet {:?}",
                result.proof
            );
            // The same pose moved by 2 to 20 mm and turned by 2 to 20 degrees.
            let shift = common::unit(&mut rng) * rng.random_range(0.002..0.02);
            let turn = UnitQuaternion::from_scaled_axis(common::unit(&mut rng) * rng.random_range(2.0_f64..20.0).to_radians());
            let off = Goal {
                position: goal.position + shift,
                rotation: turn * goal.rotation,
                ..goal
            };
            let result = ik.solve(&off, index, None);
            let Some(proof) = proves(&result) else {
                offered += usize::from(tolerance == Tolerance::Pose);
                continue;
            };
            if tolerance == Tolerance::Pose {
                (offered, proven) = (offered + 1, proven + 1);
            } else {
                zsym += 1;
            }
            common::assert_unreached(&mut numeric, &off, index, &proof, &format!("{rows:?}"));
        }
        designs += 1;
    }
    // 17 of 84 pose goals and 1 of 24 z_symmetric ones when written (a proof fails where a
    // solution's virtual angle is within what the tolerance can move it, or a complex root is
    // within four times its change of the real angles; five joints on a `z_symmetric` goal's
    // five constraints mostly reach it).
    assert!(
        proven >= 10 && zsym >= 1,
        "only {proven} of {offered} pose goals just out of reach proven, {zsym} z_symmetric"
    );
}
