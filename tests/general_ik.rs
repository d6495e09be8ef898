//! The general 6R solver (every solution of a pose, any 6R arm) against independent oracles:
//! the model's own FK, a dense multi-start numeric search, and the UR closed form.

mod common;

use nalgebra::Isometry3;
use proving_ground::design;
use proving_ground::ik::general::General6R;
use proving_ground::model::{from_design, Model};
use proving_ground::pipeline::{load_model, LoadOptions};
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;
use std::path::Path;

fn random_free_design(rng: &mut impl Rng, index: usize) -> Model {
    let rows: Vec<[f64; 3]> = (0..6)
        .map(|_| [rng.random_range(-0.3..0.3), rng.random_range(-0.5..0.5), rng.random_range(-PI..PI)].map(four_places))
        .collect();
    common::dh_design(&format!("random-{index}"), &rows)
}

/// `x` to four decimal places, as the random designs are written.
fn four_places(x: f64) -> f64 {
    (x * 1e4).round() / 1e4
}

fn shipped(path: &str) -> Model {
    load_model(&common::repo().join(path), &LoadOptions::default()).expect("design loads")
}

fn fk_error(model: &Model, q: &[f64], goal: &Isometry3<f64>) -> f64 {
    let (p, a) = proving_ground::frames::pose_difference(&model.tool_pose(q), goal);
    p.max(a)
}

fn same(a: &[f64], b: &[f64], tolerance: f64) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| proving_ground::ik::wrap_angle(x - y).abs() <= tolerance)
}

/// Solves 40 random poses of `model` (FK of random configurations) with `solve`: each pose's
/// configuration is among the solutions, and every solution reaches the pose. Returns the
/// solutions and unresolved poses counted.
fn check_poses(name: &str, model: &Model, seed: u64, solve: impl Fn(&Isometry3<f64>) -> (Vec<[f64; 6]>, bool)) -> (usize, usize) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let (mut total, mut unresolved) = (0, 0);
    for _ in 0..40 {
        let q: [f64; 6] = std::array::from_fn(|_| rng.random_range(-PI..PI));
        let goal = model.tool_pose(&q);
        let (configurations, resolved) = solve(&goal);
        unresolved += usize::from(!resolved);
        total += configurations.len();
        let worst = configurations.iter().map(|c| fk_error(model, c, &goal)).fold(0.0, f64::max);
        assert!(worst < 1e-6, "{name}: a solution misses the pose by {worst}");
        assert!(
            configurations.iter().any(|c| same(c, &q, 1e-5)),
            "{name}: the pose's own configuration {q:?} is missing from {configurations:?}"
        );
    }
    (total, unresolved)
}

/// [`check_poses`] with the general solver.
fn check_model(name: &str, model: &Model, seed: u64) -> (usize, usize) {
    let solver = General6R::new(model).unwrap_or_else(|| panic!("{name}: no general solver"));
    let counts = check_poses(name, model, seed, |goal| {
        let found = solver.solve(goal);
        (found.configurations, found.resolved)
    });
    println!(
        "{name}: {counts:?} solutions and unresolved poses over 40, reversed {}",
        solver.is_reversed()
    );
    counts
}

/// A random arm with a spherical wrist (standard DH: `a4 = a5 = d5 = 0`), its positioning
/// made special by `kind`: 0 general (the resultant), 1 axes 1 and 2 meeting (`a1 = 0`), 2
/// axes 1 and 2 parallel (`alpha1 = 0`), 3 axes 2 and 3 meeting (`a2 = 0`), 4 axes 2 and 3
/// parallel (`alpha2 = 0`).
fn random_wrist_design(rng: &mut impl Rng, index: usize, kind: usize) -> Model {
    // Twists kept 0.2 rad from parallel: nearly parallel axes that meet make the unpolished
    // roots ill-conditioned (the pipeline polishes them; this compares them raw).
    let mut rows: Vec<[f64; 3]> = (0..6)
        .map(|_| {
            let twist = rng.random_range(0.2..PI - 0.2) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            [rng.random_range(-0.3..0.3), rng.random_range(-0.5..0.5), twist]
        })
        .collect();
    rows[3][1] = 0.0;
    rows[4][0] = 0.0;
    rows[4][1] = 0.0;
    match kind {
        1 => rows[0][1] = 0.0,
        2 => rows[0][2] = 0.0,
        3 => rows[1][1] = 0.0,
        4 => rows[1][2] = 0.0,
        _ => {}
    }
    let rows: Vec<[f64; 3]> = rows.iter().map(|row| row.map(four_places)).collect();
    common::dh_design(&format!("wrist-{kind}-{index}"), &rows)
}

/// Random spherical-wrist arms, the general positioning (the resultant) and each closed-form
/// special case: every pose's own configuration among the solutions, each verified by FK (the
/// dense numeric search below checks that none is missed).
#[test]
fn random_spherical_wrist_arms_every_pose_its_configuration() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(23);
    for kind in 0..5 {
        for index in 0..4 {
            let model = random_wrist_design(&mut rng, index, kind);
            let name = model.name.clone();
            check_wrist(&name, &model, index as u64);
        }
    }
}

#[test]
fn random_general_arms_every_pose_its_configuration() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    for index in 0..20 {
        let model = random_free_design(&mut rng, index);
        check_model(&model.name.clone(), &model, index as u64);
    }
}

#[test]
fn shipped_six_joint_designs() {
    for path in [
        "designs/free-offset-6dof.json",
        "designs/economic-elbow.json",
        "designs/paper-real-world.json",
        "designs/modular-long-reach.json",
        "designs/ur5e.json",
        "designs/modular-elbow.json",
        "designs/abb-irb-2600.json",
        "designs/economic-spherical-wrist.json",
    ] {
        let model = shipped(path);
        if General6R::new(&model).is_none() {
            println!("{path}: degenerate");
            continue;
        }
        check_model(path, &model, 5);
    }
}

/// [`check_poses`] with the spherical-wrist solver.
fn check_wrist(name: &str, model: &Model, seed: u64) {
    use proving_ground::ik::wrist::SphericalWrist;
    let solver = SphericalWrist::detect(model).unwrap_or_else(|| panic!("{name}: no spherical wrist"));
    let counts = check_poses(name, model, seed, |goal| {
        let found = solver.solve(goal);
        (found.configurations, found.resolved)
    });
    println!(
        "{name}: wrist: {counts:?} solutions and unresolved poses over 40, at base {}",
        solver.at_base()
    );
}

#[test]
fn spherical_wrist_designs() {
    for path in ["designs/abb-irb-2600.json", "designs/economic-spherical-wrist.json"] {
        check_wrist(path, &shipped(path), 7);
    }
}

/// A wrist spherical only to within rounding, as in real arms' files (MuJoCo Menagerie's Doosan
/// M1013 turns its last frames by quaternions of 0.707035 and 0.707179, so its last axes pass
/// 25 um apart): the wrist flip's two solutions share joints 1 to 3 to within microns, so the
/// elimination's roots come in pairs a rounding's split apart at some poses. Such a pair is two
/// solutions, not a double root: of 2 000 random poses at most 1 % stay unresolved (68 did
/// before the pairs were resolved), no resolved pose lists fewer solutions than the exactly
/// spherical arm's closed form, and every one listed reaches its pose.
#[test]
fn a_wrist_spherical_to_within_rounding_is_resolved() {
    use proving_ground::ik::wrist::SphericalWrist;
    let mut rows = [
        [0.445, 0.15, -PI / 2.0],
        [0.0, 0.7, 0.0],
        [0.0, 0.115, -PI / 2.0],
        [0.795, 0.0, PI / 2.0],
        [0.0, 0.0, -PI / 2.0],
        [0.085, 0.0, 0.0],
    ];
    let wrist = SphericalWrist::detect(&common::dh_design("exact", &rows)).expect("a spherical wrist");
    rows[4][0] = 2.5e-5;
    let model = common::dh_design("wrist-25-um-off", &rows);
    let solver = General6R::new(&model).expect("the elimination holds");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let (mut unresolved, mut listed, mut spherical) = (0, 0, 0);
    for _ in 0..2000 {
        let q: [f64; 6] = std::array::from_fn(|_| rng.random_range(-PI..PI));
        let goal = model.tool_pose(&q);
        let found = solver.solve(&goal);
        if !found.resolved {
            unresolved += 1;
            continue;
        }
        let exact = wrist.solve(&goal).configurations.len();
        assert!(
            found.configurations.len() >= exact,
            "{} solutions, the spherical arm has {exact}",
            found.configurations.len()
        );
        let worst = found.configurations.iter().map(|c| fk_error(&model, c, &goal)).fold(0.0, f64::max);
        assert!(worst < 1e-5, "a solution misses the pose by {worst}");
        listed += found.configurations.len();
        spherical += exact;
    }
    println!("{unresolved} of 2000 poses unresolved; {listed} solutions listed ({spherical} exactly spherical)");
    assert!(unresolved <= 20, "{unresolved} of 2000 poses unresolved");
}

/// A dense multi-start numeric search (2000 starts within the limits) finds no solution the
/// all-solutions method missed, on random general arms, the shipped free design, the
/// spherical-wrist designs and catalog arms of the other methods.
#[test]
fn a_dense_numeric_search_finds_nothing_the_all_solutions_methods_miss() {
    use proving_ground::ik::solvers::AllSolutions;
    use proving_ground::ik::{Ik, IkOptions};
    use proving_ground::scenario::Tolerance;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
    let mut models: Vec<Model> = (0..3).map(|i| random_free_design(&mut rng, 100 + i)).collect();
    // The wrist's resultant, and its closed forms for a shoulder and an elbow whose axes meet
    // (the ABB covers parallel elbow axes).
    models.extend([0, 1, 3].map(|kind| random_wrist_design(&mut rng, 100, kind)));
    for path in [
        "designs/free-offset-6dof.json",
        "designs/abb-irb-2600.json",
        "designs/economic-spherical-wrist.json",
    ] {
        models.push(shipped(path));
    }
    // Catalog arms: the elimination keeping joints 2 to 4 (forward, reversed) and three
    // parallel axes (joints 4 to 6; joints 2-3 and 4 to 6).
    for index in [12_019, 1_470, 370, 1_998] {
        use proving_ground::sweep::inputs::{catalog_entry, modular6_slots};
        models.push(catalog_entry(&modular6_slots(index)).load().model);
    }
    let dense = IkOptions {
        analytic: false,
        seeds: 2000,
        branch_starts: 0,
        ..Default::default()
    };
    let (mut numeric_total, mut all_total) = (0, 0);
    for model in &models {
        let (method, _) = AllSolutions::of(model).expect("a method applies");
        let mut numeric = Ik::new(model, dense.clone());
        for k in 0..4 {
            let q = model.random_configuration(&mut rng);
            let pose = model.tool_pose(&q);
            let goal = common::pose_goal(format!("g{k}"), &pose, Tolerance::Pose);
            let all = method.solve(&pose);
            assert!(all.resolved, "{}: pose {k} unresolved", model.name);
            let found = numeric.solve(&goal, k, None);
            let converged: Vec<&[f64]> = found
                .solutions
                .iter()
                .filter(|s| s.pose_reached && s.error.position_m < 1e-6 && s.error.orientation_rad < 1e-6)
                .map(|s| s.q.as_slice())
                .collect();
            for q in &converged {
                // Within 0.01 rad is the same root: near a wrist singularity the search's
                // convergence (1e-6 in the pose) leaves joints 4 to 6 a few mrad off.
                assert!(
                    all.configurations.iter().any(|c| same(c, q, 1e-2)),
                    "{}: pose {k}: the dense search found {q:?}, missing from the {} of {}",
                    model.name,
                    all.configurations.len(),
                    method.name()
                );
            }
            numeric_total += converged.len();
            all_total += all.configurations.len();
        }
    }
    println!("dense search: {numeric_total} solutions within the limits; all-solutions: {all_total}");
    assert!(numeric_total > 0);
}

/// The solutions are distinct and never more than the arm can have: 16 for a general 6R, 8 for
/// a spherical wrist.
#[test]
fn counts_never_exceed_the_truth() {
    use proving_ground::ik::solvers::AllSolutions;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let mut most = 0;
    for index in 0..40 {
        let model = random_free_design(&mut rng, 200 + index);
        let Some((method, _)) = AllSolutions::of(&model) else { continue };
        let limit = match method {
            AllSolutions::Wrist(_) => 8,
            AllSolutions::General(_) => 16,
            AllSolutions::Parallel(_) => 8,
        };
        for _ in 0..50 {
            let q: [f64; 6] = std::array::from_fn(|_| rng.random_range(-PI..PI));
            let pose = model.tool_pose(&q);
            let found = method.solve(&pose).configurations;
            assert!(found.len() <= limit, "{}: {} solutions", model.name, found.len());
            for (i, a) in found.iter().enumerate() {
                for b in &found[i + 1..] {
                    assert!(!same(a, b, 1e-9), "{}: a solution listed twice: {a:?}", model.name);
                }
            }
            most = most.max(found.len());
        }
    }
    println!("most solutions of one pose: {most}");
}

/// A general 6R with a pose of 16 real solutions (found by a seeded search over random arms and
/// poses): all 16 are listed, each reaches the pose, no two alike, and a 2000-start numeric
/// search finds none besides them.
#[test]
fn a_pose_with_sixteen_real_solutions_gives_sixteen() {
    use proving_ground::ik::solvers::AllSolutions;
    use proving_ground::ik::{Ik, IkOptions};
    use proving_ground::scenario::{Goal, Tolerance};
    let text = r#"{"name": "sixteen", "mode": "free", "joints": [
        {"d": -0.096, "a": 0.044, "alpha": -1.573}, {"d": -0.222, "a": -0.469, "alpha": 2.391},
        {"d": -0.066, "a": 0.047, "alpha": -1.657}, {"d": -0.249, "a": -0.439, "alpha": -1.871},
        {"d": -0.155, "a": 0.143, "alpha": 1.359}, {"d": -0.340, "a": -0.333, "alpha": -0.663}]}"#;
    let model = from_design(&design::parse(text, Path::new("sixteen.json")).expect("parses"));
    // The search's stream: 18 draws made the arm, then six per pose; pose 113 has 16.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(79);
    for _ in 0..18 {
        let _: f64 = rng.random_range(-PI..PI);
    }
    let mut q = [0.0; 6];
    for _ in 0..=113 {
        q = std::array::from_fn(|_| rng.random_range(-PI..PI));
    }
    let pose = model.tool_pose(&q);
    let (method, _) = AllSolutions::of(&model).expect("a method applies");
    let found = method.solve(&pose);
    assert!(found.resolved);
    assert_eq!(found.configurations.len(), 16, "{:?}", found.configurations);
    for c in &found.configurations {
        assert!(fk_error(&model, c, &pose) < 1e-6);
    }
    let goal = Goal {
        name: "sixteen".into(),
        position: pose.translation.vector,
        rotation: pose.rotation,
        tolerance: Tolerance::Pose,
        task: None,
    };
    let solved = Ik::new(&model, IkOptions::default()).solve(&goal, 0, None);
    assert!(solved.complete);
    assert_eq!(solved.solutions.len(), 16, "every solution within the limits, polished and judged");
    let dense = IkOptions {
        analytic: false,
        seeds: 2000,
        branch_starts: 0,
        ..Default::default()
    };
    let numeric = Ik::new(&model, dense).solve(&goal, 0, None);
    for s in numeric.solutions.iter().filter(|s| s.error.position_m < 1e-6) {
        assert!(found.configurations.iter().any(|c| same(c, &s.q, 1e-4)), "{:?} missing", s.q);
    }
    println!("dense numeric search: {} of the 16", numeric.solutions.len());
}

/// A pose whose wrist centre is out of reach is proven so by the spherical-wrist method, and a
/// reachable pose is never called out of reach.
#[test]
fn spherical_wrist_out_of_reach_is_proven_and_never_claimed_for_a_reachable_pose() {
    use proving_ground::ik::wrist::SphericalWrist;
    for path in ["designs/abb-irb-2600.json", "designs/economic-spherical-wrist.json"] {
        let model = shipped(path);
        let wrist = SphericalWrist::detect(&model).expect("a spherical wrist");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(31);
        let mut proven = 0;
        for _ in 0..20 {
            let q: [f64; 6] = std::array::from_fn(|_| rng.random_range(-PI..PI));
            let pose = model.tool_pose(&q);
            assert!(
                wrist.solve(&pose).out_of_reach.is_none(),
                "{path}: a reachable pose called out of reach"
            );
            // Pushed 5 m away: no solution, and the wrist centre proves it.
            let far = nalgebra::Isometry3::from_parts(
                nalgebra::Translation3::from(pose.translation.vector * 5.0 + nalgebra::Vector3::new(2.0, 0.0, 0.0)),
                pose.rotation,
            );
            let found = wrist.solve(&far);
            assert!(found.configurations.is_empty());
            proven += usize::from(found.out_of_reach.is_some());
        }
        assert_eq!(proven, 20, "{path}: far poses not proven out of reach");
    }
}

/// A 6R arm on a `z_symmetric` goal: the self-motion over the free turn about tool z is swept.
/// With joint 1 limited to +-0.1 rad and the goal to the arm's side, no turn has a solution
/// within the limits: proven, and a sweep ten times denser than the certificate's finds every
/// solution outside the limits too.
#[test]
fn a_z_symmetric_goal_of_a_six_joint_arm_is_decided_over_the_free_turn() {
    use nalgebra::{UnitQuaternion, Vector3};
    use proving_ground::ik::analytic::UrArm;
    use proving_ground::ik::{Ik, IkOptions};
    use proving_ground::scenario::{Goal, Tolerance};
    let mut model = shipped("designs/ur5e.json");
    model.joints[0].limits = Some([-0.1, 0.1]);
    let goal = Goal {
        name: "side".into(),
        position: Vector3::new(0.05, -0.45, 0.25),
        rotation: UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI),
        tolerance: Tolerance::ZSymmetric,
        task: None,
    };
    let solved = Ik::new(&model, IkOptions::default()).solve(&goal, 0, None);
    assert!(!solved.reached());
    let proof = solved.proof.clone().unwrap_or_default();
    assert!(
        proof.contains("over the free turn about tool z") && proof.contains("outside the joint limits"),
        "{solved:?}"
    );
    let arm = UrArm::detect(&model).expect("UR-type");
    for k in 0..720 {
        let turn = k as f64 * std::f64::consts::TAU / 720.0;
        let rotation = goal.rotation * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn);
        let pose = nalgebra::Isometry3::from_parts(goal.position.into(), rotation);
        for q in arm.solve(&pose).configurations {
            let wrapped = proving_ground::ik::wrap_angle(q[0]);
            assert!(wrapped.abs() > 0.1, "turn {k}: joint 1 at {wrapped} is within its limits");
        }
    }

    // The same goal with joint 1 free: a turn reaches it.
    let free = shipped("designs/ur5e.json");
    let opts = IkOptions {
        seeds: 0,
        ..Default::default()
    };
    assert!(Ik::new(&free, opts).solve(&goal, 0, None).reached());
}

/// A pose near the workspace boundary: its 4 exact solutions all collide, but a configuration
/// 0.8 mm off the pose (on a branch pair born within the tolerance) is free. The numeric
/// cross-check before a proof finds it: the goal is reached, never "proven unreachable".
#[test]
fn solutions_born_within_the_tolerance_are_no_proof() {
    use proving_ground::pipeline::{load, validate, ValidateOptions};
    let path = common::repo().join("designs/economic-spherical-wrist.json");
    let scenario = proving_ground::scenario::generate::cluttered(4, 7);
    let opts = ValidateOptions {
        reach_only: true,
        ..Default::default()
    };
    let validation = validate(load(&path, &LoadOptions::default()).expect("loads"), scenario, &opts).expect("runs");
    let report = proving_ground::report::build(&validation);
    let goal = &report.goals[6];
    assert_eq!(goal.outcome, "reached", "{:?}", goal.proven);
}

/// A pose whose roots barely move at the centre of its tolerance and turn real near its edge:
/// on this modular catalog arm the first-order bound alone (the roots' rates at the centre, four
/// times over) claimed "none appears within 1 mm and 1 deg" of a pose 0.95 mm and 0.95 deg from
/// one with solutions (FK-checked here). The bound's check at the tolerance's edges
/// refuses it; cut into parts it is not proven either.
#[test]
fn roots_that_turn_real_near_the_edge_of_the_tolerance_are_no_proof() {
    use nalgebra::{Quaternion, Translation3, UnitQuaternion, Vector3};
    use proving_ground::ik::search::Radii;
    use proving_ground::scenario::{Goal, Tolerance};
    use proving_ground::sweep::inputs::{catalog_entry, modular6_slots};
    let index = (0..15_625)
        .find(|&i| catalog_entry(&modular6_slots(i)).id == "modular6/D-D-D-Ls-Ll-Ls")
        .expect("a catalog arm");
    let model = catalog_entry(&modular6_slots(index)).load().model;
    let solver = General6R::new(&model).expect("the elimination holds");
    let pose = |p: [f64; 3], q: [f64; 4]| {
        Isometry3::from_parts(
            Translation3::from(Vector3::from(p)),
            UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2])),
        )
    };
    let centre = pose(
        [-0.393_837_074_203_161_8, -0.500_812_481_053_439_3, 0.182_619_212_251_307_73],
        [
            -0.416_089_553_175_637_8,
            -0.590_221_044_850_429_9,
            0.468_357_408_637_410_9,
            -0.509_067_716_250_22,
        ],
    );
    // 1.0 mm and 1.0 deg away, four solutions; 0.95 of the way, two.
    let edge = pose(
        [-0.393_363_446_366_926_1, -0.501_692_808_069_965_1, 0.182_592_735_531_012],
        [
            -0.411_376_459_187_831_33,
            -0.587_715_385_674_428_2,
            0.468_121_358_837_624_24,
            -0.515_967_467_644_673_6,
        ],
    );
    let inside = centre.lerp_slerp(&edge, 0.95);
    let offset_mm = (centre.translation.vector - inside.translation.vector).norm() * 1e3;
    let offset_deg = centre.rotation.angle_to(&inside.rotation).to_degrees();
    assert!(offset_mm < 0.96 && offset_deg < 0.96, "{offset_mm} mm, {offset_deg} deg");
    assert!(solver.solve(&centre).configurations.is_empty());
    let found = solver.solve(&inside).configurations;
    assert!(!found.is_empty());
    assert!(found.iter().all(|q| fk_error(&model, q, &inside) < 1e-9));
    let claim = solver.out_of_reach_within(&centre, Radii::REACHED, 0.0);
    assert!(claim.is_none(), "{claim:?}");
    let goal = Goal {
        name: "edge".into(),
        position: centre.translation.vector,
        rotation: centre.rotation,
        tolerance: Tolerance::Pose,
        task: None,
    };
    let parts = solver.out_of_reach_in_parts(&goal, &mut 256);
    assert!(parts.is_none(), "{parts:?}");
}

/// First-order proofs the exact solver refutes (`examples/proof_audit.rs`, seeds 0 and 1):
/// poses a little past the workspace boundary whose tolerance holds poses with solutions
/// (found here by sampling, FK-checked), where the roots' rates at the centre said none can
/// turn real. A modular arm whose roots 1.6 rad off the real angles turn real inside the
/// tolerance and leave them again at its boundary (the probes' linearity check); an economic
/// arm and a modular one where roots turn real only near a corner of the tolerance, its shift
/// and turn both near whole (the corner search). Each proof is refused, in a sweep and in a
/// validation.
#[test]
fn roots_that_turn_real_far_from_linearly_are_no_proof() {
    use nalgebra::{Quaternion, Translation3, UnitQuaternion, Vector3};
    use proving_ground::ik::search::Radii;
    use proving_ground::sweep::inputs::{catalog_entry, modular6_slots};
    let catalog = |id: &str| {
        let index = (0..15_625)
            .find(|&i| catalog_entry(&modular6_slots(i)).id == id)
            .expect("a catalog arm");
        catalog_entry(&modular6_slots(index)).load().model
    };
    let half_turn = PI / 2.0;
    let economic = common::dh_design(
        "economic-547",
        &[
            [0.0, 0.0, half_turn],
            [0.2, 0.4, -half_turn],
            [0.1, 0.2, half_turn],
            [0.0, 0.0, -half_turn],
            [0.3, 0.2, -half_turn],
            [0.2, 0.0, half_turn],
        ],
    );
    let cases = [
        (
            catalog("modular6/D-D-Is-Ls-Ll-Is"),
            [0.621_441_655_517_782_7, 0.648_624_967_272_875_3, 0.262_587_657_304_180_3],
            [
                0.113_252_003_127_323_31,
                -0.073_848_722_317_965_7,
                0.989_441_896_722_451_2,
                0.052_202_327_629_433_984,
            ],
        ),
        (
            economic,
            [-0.883_605_498_293_199_6, 0.253_116_983_124_883_6, -0.464_503_198_098_206_2],
            [
                -0.485_041_957_532_536_6,
                0.790_848_167_939_232_5,
                -0.241_348_528_202_308_12,
                -0.284_682_915_951_667_06,
            ],
        ),
        (
            catalog("modular6/Is-Is-D-Ll-Is-Ll"),
            [0.219_598_117_935_102_62, 0.389_392_008_758_686_7, 0.956_991_753_884_512_6],
            [
                -0.339_239_993_659_183_8,
                0.196_250_223_434_691_9,
                0.692_662_689_849_341_2,
                0.605_491_927_769_996_2,
            ],
        ),
    ];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for (model, p, [w, i, j, k]) in cases {
        let solver = General6R::new(&model).expect("the elimination holds");
        let centre = Isometry3::from_parts(
            Translation3::from(Vector3::from(p)),
            UnitQuaternion::from_quaternion(Quaternion::new(w, i, j, k)),
        );
        assert!(solver.solve(&centre).configurations.is_empty(), "{}", model.name);
        // A pose within the tolerance (on its boundary, where these are likeliest) with a solution.
        let witness = (0..20_000).find_map(|_| {
            let sample = Isometry3::from_parts(
                Translation3::from(centre.translation.vector + common::unit_vector(&mut rng) * 0.999e-3),
                centre.rotation * UnitQuaternion::from_scaled_axis(common::unit_vector(&mut rng) * 0.999f64.to_radians()),
            );
            let solutions = solver.solve(&sample).configurations;
            solutions.iter().any(|q| fk_error(&model, q, &sample) < 1e-9).then_some(sample)
        });
        assert!(witness.is_some(), "{}: no pose of the tolerance sampled has a solution", model.name);
        let sweep = solver.out_of_reach_within(&centre, Radii::REACHED, 0.0);
        assert!(sweep.is_none(), "{}: {sweep:?}", model.name);
        let validation = solver.out_of_reach_checked(&centre, Radii::REACHED, 0.0);
        assert!(validation.is_none(), "{}: {validation:?}", model.name);
    }
}

/// Modular catalog arms: every pair of consecutive axes meets or is parallel, which makes
/// Raghavan and Roth's own choice of kept joints degenerate for all of them; another choice
/// holds for most, and three consecutive parallel axes have their own method. Through the
/// pipeline (roots polished by Newton on the model's FK), each resolved pose's own configuration
/// is among the solutions; unresolved poses (left to the numeric search, never claimed
/// complete) are rare.
#[test]
fn modular_catalog_arms_every_pose_its_configuration() {
    use proving_ground::ik::solvers::AllSolutions;
    use proving_ground::ik::{Ik, IkOptions};
    use proving_ground::scenario::Tolerance;
    use proving_ground::sweep::inputs::{catalog_entry, modular6_slots};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(31);
    let mut variants = std::collections::BTreeMap::new();
    let (mut poses, mut unresolved) = (0, 0);
    for index in (0..15_625).step_by(97) {
        let model = catalog_entry(&modular6_slots(index)).load().model;
        let (method, variant) = match AllSolutions::of(&model) {
            Some((AllSolutions::General(general), _)) => {
                let variant = general.variant();
                (AllSolutions::General(general), variant)
            }
            Some((method @ AllSolutions::Parallel(_), _)) => (method, "three parallel axes".to_string()),
            _ => continue,
        };
        *variants.entry(variant.clone()).or_insert(0) += 1;
        let mut ik = Ik::new(&model, IkOptions::default());
        for k in 0..5 {
            let q = model.random_configuration(&mut rng);
            let pose = model.tool_pose(&q);
            let goal = common::pose_goal(format!("g{k}"), &pose, Tolerance::Pose);
            poses += 1;
            if !method.solve(&pose).resolved {
                // Left to the numeric search, never claimed complete.
                unresolved += 1;
                continue;
            }
            let found = ik.solve(&goal, k, None);
            assert!(found.reached(), "{}: pose {k} not reached", model.name);
            assert!(
                found.solutions.iter().any(|s| same(&s.q, &q, 1e-6)),
                "{}: pose {k}: its own configuration {q:?} is not among the {} solutions ({})",
                model.name,
                found.solutions.len(),
                variant
            );
        }
    }
    println!("catalog arms by method: {variants:?}; {unresolved} of {poses} poses unresolved");
    assert!(unresolved * 50 <= poses, "{unresolved} of {poses} poses unresolved");
    assert!(variants.values().sum::<usize>() >= 100, "{variants:?}");
    assert!(variants.get("three parallel axes").is_some_and(|n| *n >= 5), "{variants:?}");
}

/// Companion matrices on which nalgebra's unbounded QR iteration cycles forever (the kept
/// joints' choices that degenerate for the catalog arms `D-D-D-Ls-Ls-D` and `D-D-D-Ls-Ls-Is`,
/// met while choosing their method, and a pose of `Ls-Ls-D-D-Il-Ls` before the probes rejected
/// its choice): choosing the method and solving return.
#[test]
fn a_cycling_eigenvalue_iteration_does_not_hang_the_solver() {
    use proving_ground::ik::solvers::AllSolutions;
    use proving_ground::sweep::inputs::{catalog_entry, modular6_slots};
    let q = [
        0.772_627_362_709_411_8,
        -2.630_759_024_212_576_7,
        -1.113_344_855_679_505_6,
        -2.616_081_095_828_868_7,
        0.603_127_571_734_481_7,
        1.945_940_612_879_750_7,
    ];
    for index in [90, 91, 11_263] {
        let model = catalog_entry(&modular6_slots(index)).load().model;
        if let Some((method, _)) = AllSolutions::of(&model) {
            let pose = model.tool_pose(&q);
            let found = method.solve(&pose);
            assert!(found.configurations.iter().all(|c| fk_error(&model, c, &pose) < 1e-4));
        }
    }
}

/// The general 6R's proof that a pose without solution has none within the tolerance (every
/// complex root of its determinant stays off the real angles), against the exact solver on
/// the tolerance sampled. Poses are pushed past the workspace boundary along a random
/// direction of pose space, found by bisection, by 0.3 to 6 times the tolerance: none whose
/// tolerance holds the boundary is proven, and no pose sampled within a proven one's
/// tolerance (half on its edge) has a solution; likewise where the proof over the whole
/// tolerance fails and the tolerance is cut into parts. Random free designs, economic ones (the
/// paper's grid of offsets and quarter-turn twists, as `python/bench.py` draws them) and arms
/// of the modular catalog (874 poses, 152 proven, 79 in parts, with the parts as boxes and the
/// edge check).
#[test]
fn general_out_of_reach_proofs_hold_near_the_workspace_boundary() {
    use nalgebra::{Translation3, UnitQuaternion};
    use proving_ground::ik::search::Radii;
    use proving_ground::scenario::{Goal, Tolerance};
    let economic = |rng: &mut rand_chacha::ChaCha8Rng, index: usize| {
        let rows: Vec<[f64; 3]> = (0..6)
            .map(|_| {
                [
                    [0.0, 0.1, 0.2, 0.3][rng.random_range(0..4)],
                    [0.0, 0.2, 0.3, 0.4][rng.random_range(0..4)],
                    [0.0, PI / 2.0, -PI / 2.0][rng.random_range(0..3)],
                ]
            })
            .collect();
        common::dh_design(&format!("economic-{index}"), &rows)
    };
    // Each design with its own seed, the designs spread over the cores: the test is long.
    let case = |index: usize| {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41 + index as u64);
        let (mut tried, mut proven, mut inside, mut in_parts) = (0, 0, 0, 0);
        let model = match index % 3 {
            0 => random_free_design(&mut rng, index),
            1 => economic(&mut rng, index),
            // The modular catalog's arms: offsets and axes the modules' geometry repeats.
            _ => {
                use proving_ground::sweep::inputs::{catalog_entry, modular6_slots};
                catalog_entry(&modular6_slots(rng.random_range(0..15_625))).load().model
            }
        };
        let Some(solver) = General6R::new(&model) else {
            return (tried, proven, inside, in_parts);
        };
        for _ in 0..3 {
            let start = model.tool_pose(&model.random_configuration(&mut rng));
            // One unit of `s` moves the pose by at most the tolerance: `cos` of it in position,
            // `sin` in rotation.
            let split: f64 = rng.random_range(0.0..PI / 2.0);
            let (dp, dr) = (
                common::unit_vector(&mut rng) * (split.cos() * 1e-3),
                common::unit_vector(&mut rng) * split.sin().to_radians(),
            );
            let along = |s: f64| {
                Isometry3::from_parts(
                    Translation3::from(start.translation.vector + dp * s),
                    start.rotation * UnitQuaternion::from_scaled_axis(dr * s),
                )
            };
            let solvable = |s: f64| !solver.solve(&along(s)).configurations.is_empty();
            let mut high = 1.0;
            while solvable(high) && high < 4096.0 {
                high *= 2.0;
            }
            if high >= 4096.0 {
                continue;
            }
            let mut low = if high > 1.0 { high / 2.0 } else { 0.0 };
            for _ in 0..40 {
                let middle = 0.5 * (low + high);
                if solvable(middle) {
                    low = middle;
                } else {
                    high = middle;
                }
            }
            for beyond in [0.3, 0.95, 1.5, 3.0, 6.0] {
                let centre = along(high + beyond);
                if solver.solve(&centre).configurations.is_empty() {
                    tried += 1;
                } else {
                    continue;
                }
                let goal = Goal {
                    name: "beyond".into(),
                    position: centre.translation.vector,
                    rotation: centre.rotation,
                    tolerance: Tolerance::Pose,
                    task: None,
                };
                let proof = match solver.out_of_reach_within(&centre, Radii::REACHED, 0.0) {
                    Some(proof) => proof,
                    None => {
                        let Some(proof) = solver.out_of_reach_in_parts(&goal, &mut 256) else {
                            continue;
                        };
                        in_parts += 1;
                        proof
                    }
                };
                proven += 1;
                // Within 1 unit the boundary's solutions are within the tolerance.
                inside += usize::from(beyond < 1.0);
                for k in 0..300 {
                    let (rp, ro) = if k % 2 == 0 {
                        (1e-3, 1f64.to_radians())
                    } else {
                        (1e-3 * rng.random::<f64>(), 1f64.to_radians() * rng.random::<f64>())
                    };
                    let (u, w) = (common::unit_vector(&mut rng), common::unit_vector(&mut rng));
                    let sample = Isometry3::from_parts(
                        Translation3::from(centre.translation.vector + u * rp),
                        centre.rotation * UnitQuaternion::from_scaled_axis(w * ro),
                    );
                    assert!(
                        solver.solve(&sample).configurations.is_empty(),
                        "{}: a pose within the tolerance has a solution, yet: {proof}",
                        model.name
                    );
                }
            }
        }
        (tried, proven, inside, in_parts)
    };
    use rayon::prelude::*;
    let (tried, proven, inside, in_parts) = (0..72usize)
        .into_par_iter()
        .map(case)
        .reduce(|| (0, 0, 0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2, a.3 + b.3));
    println!("{tried} poses beyond the boundary, {proven} proven ({in_parts} in parts)");
    assert_eq!(
        inside, 0,
        "a pose whose tolerance holds the workspace boundary was proven out of reach"
    );
    assert!(tried > 150 && proven > 10, "too few cases: {tried} tried, {proven} proven");
}
