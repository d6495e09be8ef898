//! Dynamics: our gravity torques and reflected inertia against MuJoCo on every shipped design,
//! the paper's robot holding course goals in MuJoCo, kinematic replays against the exact parry
//! check, the static load against the rated torque, and determinism.

mod common;

use common::{box_crossing_samples, course, engine_depths, parry_depths, tour};

use mujoco_rs::prelude::*;
use nalgebra::Isometry3;
use proving_ground::collide::Body;
use proving_ground::engine::{replay_mujoco, run_mujoco, static_load, EngineRun, RunOptions};
use proving_ground::export::{to_mjcf, MjcfOptions};
use proving_ground::model::{self, Model, Shape};
use proving_ground::pipeline::{self, LoadOptions};
use proving_ground::scenario::{generate, Obstacle};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::path::Path;

/// Our gravity torques against MuJoCo's `qfrc_bias` at rest, relative to the largest torque of
/// the configuration: both are exact rigid-body statics in f64.
const GRAVITY_AGREEMENT: f64 = 1e-9;
/// Our mass-matrix diagonal against MuJoCo's `mj_fullM`, relative.
const INERTIA_AGREEMENT: f64 = 1e-9;
/// The paper's hold tolerance: 1 mm and 1 degree at the tool.
const HOLD_POSITION_M: f64 = 1e-3;
const HOLD_ORIENTATION_RAD: f64 = 0.017_453_292_519_943_295;
/// MuJoCo's penetration depth against parry's exact one for a box or sphere obstacle against
/// the links' cylinders (m): MuJoCo's cylinder collisions are approximate (docs/collision.md, "Collision
/// checking").
const DEPTH_AGREEMENT_M: f64 = 2e-3;

fn load(path: &Path) -> Model {
    pipeline::load_model(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn gravity_torques_and_reflected_inertia_match_mujoco_on_every_design() {
    for path in common::design_files() {
        let model = load(&path);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let samples: Vec<Vec<f64>> = (0..100).map(|_| model.random_configuration(&mut rng)).collect();
        let load = static_load(&model, &samples, 9.81).expect("MuJoCo loads the export");
        let disagreement = load.max_relative_disagreement.expect("MuJoCo ran");
        println!(
            "{:24} gravity disagreement {:.1e}, peaks {:?}",
            common::stem(&path),
            disagreement,
            load.joints
                .iter()
                .map(|j| (j.peak_torque * 10.0).round() / 10.0)
                .collect::<Vec<_>>()
        );
        assert!(disagreement < GRAVITY_AGREEMENT, "{}: {disagreement}", path.display());

        // The diagonal of MuJoCo's joint-space mass matrix (the export has one dof per joint,
        // in chain order).
        let xml = to_mjcf(&model, &MjcfOptions::default()).expect("exports");
        // Direct mujoco-rs calls need the library loaded first (it is loaded at first use).
        proving_ground::engine::check_version().expect("MuJoCo is available");
        let mj = MjModel::from_xml_string(&xml).expect("MuJoCo loads the export");
        let mut data = mj.make_data();
        let dof = model.dof();
        let mut full = vec![0.0; dof * dof];
        for q in samples.iter().take(20) {
            data.qpos_mut().copy_from_slice(q);
            data.forward();
            data.full_m(&mut full).expect("buffer fits");
            let ours = model.reflected_inertia(q);
            for j in 0..dof {
                let theirs = full[j * dof + j];
                assert!(
                    (ours[j] - theirs).abs() <= INERTIA_AGREEMENT * theirs.abs().max(1e-6),
                    "{}: joint {j} at {q:?}: ours {} MuJoCo {theirs}",
                    path.display(),
                    ours[j]
                );
            }
        }
    }
}

#[test]
fn paper_robot_holds_the_first_course_goals_in_mujoco_without_contact() {
    let course = course();
    let (path, gains) = tour(&course, 6);
    // The stiffest natural frequency at the smallest inertia along the tour, times the step:
    // what an explicit integrator would have to resolve (the module docs of engine::gains).
    let step = RunOptions::default().timestep_s;
    let mut worst = 0.0_f64;
    for segment in &path.segments {
        let inertia = course.model.reflected_inertia(&segment.to);
        for (kp, i) in gains.stiffness.iter().zip(&inertia) {
            worst = worst.max((kp / i).sqrt() * step);
        }
    }
    println!("gains kp {:?} kd {:?}; largest w h {worst:.3}", gains.stiffness, gains.damping);
    assert!(worst < 1.0, "w h = {worst}");

    let started = std::time::Instant::now();
    let run = run_mujoco(
        &course.model,
        &course.scenario,
        &course.world,
        &path,
        &gains,
        &RunOptions::default(),
    )
    .expect("MuJoCo runs");
    println!(
        "{} steps ({:.2} s simulated) in {:.2} s",
        run.steps,
        path.duration_s(),
        started.elapsed().as_secs_f64()
    );
    println!(
        "max joint error {:?} rad, max tool error {:.2e} m {:.2e} rad, peak effort {:?} N m",
        run.max_joint_error, run.max_tool_position_error_m, run.max_tool_orientation_error_rad, run.peak_effort
    );
    assert_eq!((run.engine, run.mode), ("mujoco", "dynamic"));
    assert_eq!(run.holds.len(), 6);
    for hold in &run.holds {
        println!(
            "goal {} at {:.3} s: {:.2e} m, {:.2e} rad, joint {:.2e} rad",
            hold.goal, hold.time_s, hold.position_error_m, hold.orientation_error_rad, hold.joint_error
        );
        assert!(
            hold.position_error_m < HOLD_POSITION_M && hold.orientation_error_rad < HOLD_ORIENTATION_RAD,
            "goal {} not held: {hold:?}",
            hold.goal
        );
    }
    assert!(run.contacts.is_empty(), "contacts on a clear tour: {:?}", run.contacts);
}

#[test]
fn two_mujoco_runs_are_identical() {
    let course = course();
    let (path, gains) = tour(&course, 2);
    let run = || -> EngineRun {
        run_mujoco(
            &course.model,
            &course.scenario,
            &course.world,
            &path,
            &gains,
            &RunOptions::default(),
        )
        .expect("MuJoCo runs")
    };
    assert_eq!(run(), run());
}

#[test]
fn replay_through_the_course_box_reports_the_penetration_parry_measures() {
    let course = course();
    let box_index = course
        .scenario
        .obstacles
        .iter()
        .position(|o| o.name == "box")
        .expect("the course has a box");
    assert!(course.world.pairs().iter().any(|p| p.b == Body::Obstacle(box_index)));
    let samples = box_crossing_samples();
    let run = replay_mujoco(&course.model, &course.scenario, &course.world, &samples, &RunOptions::default()).expect("MuJoCo replays");
    let parry = parry_depths(&course.model, &course.world, &samples);
    let mujoco = engine_depths(&run);
    println!("mujoco {mujoco:?}\nparry  {parry:?}");
    assert_eq!((run.mode, run.steps), ("kinematic", samples.len()));
    assert!(run.max_tool_position_error_m < 1e-9, "{}", run.max_tool_position_error_m);
    assert!(
        parry.iter().any(|(_, b, _)| b == "box"),
        "the path should run through the box: {parry:?}"
    );
    let box_pairs = |depths: &[(String, String, f64)]| -> Vec<(String, f64)> {
        depths
            .iter()
            .filter(|(_, b, _)| b == "box")
            .map(|(a, _, d)| (a.clone(), *d))
            .collect()
    };
    let (ours, theirs) = (box_pairs(&parry), box_pairs(&mujoco));
    assert_eq!(
        ours.iter().map(|(a, _)| a).collect::<Vec<_>>(),
        theirs.iter().map(|(a, _)| a).collect::<Vec<_>>(),
        "MuJoCo and parry disagree on the links in the box"
    );
    for ((link, exact), (_, depth)) in ours.iter().zip(&theirs) {
        assert!(
            (depth - exact).abs() < DEPTH_AGREEMENT_M,
            "{link}-box: MuJoCo {depth} m, parry {exact} m"
        );
    }
}

#[test]
fn replay_with_a_ball_around_the_tool_reports_that_contact() {
    let mut course = course();
    // A ball of radius 0.05 m centred on the tool frame at home: it overlaps the tool-side tube.
    let q = generate::COURSE_HOME.to_vec();
    let tool = course.model.tool_pose(&q);
    course.scenario.obstacles = vec![Obstacle {
        name: "probe".into(),
        world_from_shape: Isometry3::from_parts(tool.translation, nalgebra::UnitQuaternion::identity()),
        shape: Shape::Sphere { radius: 0.05 },
    }];
    course.world = pipeline::collision_world(&course.model, &course.scenario, &[]).expect("world builds");
    let samples = vec![(0.0, q)];
    let run = replay_mujoco(&course.model, &course.scenario, &course.world, &samples, &RunOptions::default()).expect("MuJoCo replays");
    let parry = parry_depths(&course.model, &course.world, &samples);
    let mujoco = engine_depths(&run);
    println!("mujoco {mujoco:?}\nparry  {parry:?}");
    assert!(!parry.is_empty(), "the probe should overlap the robot");
    assert_eq!(
        mujoco.iter().map(|(a, b, _)| (a, b)).collect::<Vec<_>>(),
        parry.iter().map(|(a, b, _)| (a, b)).collect::<Vec<_>>()
    );
    for ((a, b, depth), (_, _, exact)) in mujoco.iter().zip(&parry) {
        assert!(
            (depth - exact).abs() < DEPTH_AGREEMENT_M,
            "{a}-{b}: MuJoCo {depth} m, parry {exact} m"
        );
    }
}

#[test]
fn a_long_horizontal_arm_is_over_its_rated_torque_and_the_paper_robot_is_not() {
    // Four elbow tubes with parallel axes after a vertical first joint: at q = 0 the arm is a
    // 1.4 m horizontal beam carried by joint 2 (its axis horizontal after the `direct` slot).
    let text = r#"{"mode": "modular", "modules": ["direct", "L-long", "L-long", "L-long", "L-long", "I-long"]}"#;
    let design = proving_ground::design::parse(text, Path::new("long.json")).expect("valid design");
    let long = model::from_design(&design);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut samples: Vec<Vec<f64>> = vec![vec![0.0; 6]];
    samples.extend((0..20).map(|_| long.random_configuration(&mut rng)));
    let load = static_load(&long, &samples, 9.81).expect("MuJoCo loads the export");
    println!("long arm: {:?}", load.joints);
    assert!(load.max_relative_disagreement.is_some_and(|d| d < GRAVITY_AGREEMENT));
    assert!(load.joints.iter().all(|j| j.rated == Some(60.0)));
    let shoulder = &load.joints[1];
    assert!(shoulder.over && shoulder.peak_torque > 60.0, "{shoulder:?}");
    assert_eq!(shoulder.sample, 0, "the stretched configuration is the worst: {shoulder:?}");

    let course = course();
    let mut samples = vec![generate::COURSE_HOME.to_vec()];
    samples.extend(generate::course_configurations());
    let load = static_load(&course.model, &samples, 9.81).expect("MuJoCo loads the export");
    println!("paper robot on the course: {:?}", load.joints);
    assert!(load.joints.iter().all(|j| !j.over && j.rated == Some(60.0)), "{:?}", load.joints);
}
