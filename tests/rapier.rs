//! rapier runs: the motor law on a pendulum, the paper's robot holding course goals, kinematic
//! replays against the exact parry check, and determinism.

mod common;

use common::{box_crossing_samples, course, engine_depths, parry_depths, tour};

use nalgebra::{Isometry3, Vector3};
use proving_ground::collide::Body;
use proving_ground::engine::{self, replay_rapier, run_rapier, EngineRun, GainOptions, Gains, RunOptions};
use proving_ground::model::{Collider, Inertial, Joint, JointKind, Link, Model, ModelSource, Shape};
use proving_ground::pipeline::{self};
use proving_ground::plan::{TimedPath, TimingLimits};
use proving_ground::scenario::{generate, Scenario};

/// The paper's hold tolerance: 1 mm and 1 degree at the tool.
const HOLD_POSITION_M: f64 = 1e-3;
const HOLD_ORIENTATION_RAD: f64 = 0.017_453_292_519_943_295;
/// Pendulum rest angle against the closed form (rad): f32 joint coordinates resolve 1e-7 rad
/// near 0.05 rad; the settle after 2 s of critical damping is below 1e-12 rad.
const PENDULUM_REST_RAD: f64 = 1e-5;
/// rapier's penetration depth against parry's exact one on the course box (m): rapier runs in f32
/// and stops EPA earlier.
const DEPTH_AGREEMENT_M: f64 = 1e-3;

/// A rod hinged about world y at the origin, its mass `mass_kg` at `length_m` along x.
fn pendulum(mass_kg: f64, length_m: f64) -> Model {
    let bob = Inertial {
        com: Vector3::new(length_m, 0.0, 0.0),
        ..Inertial::solid_sphere(mass_kg, 0.05)
    };
    let link = |name: &str, colliders: Vec<Collider>, inertial: Option<Inertial>| Link {
        name: name.into(),
        merged: Vec::new(),
        colliders,
        inertial,
        segments: Vec::new(),
    };
    Model {
        name: "pendulum".into(),
        source: ModelSource::Design {
            mode: "test".into(),
            choices: vec![],
        },
        world_from_base: Isometry3::identity(),
        joints: vec![Joint {
            name: "hinge".into(),
            kind: JointKind::Revolute,
            parent_from_joint: Isometry3::identity(),
            axis: Vector3::y_axis(),
            limits: Some([-3.0, 3.0]),
            max_velocity: None,
            max_effort: None,
        }],
        links: vec![
            link("base", Vec::new(), None),
            link(
                "rod",
                vec![Collider {
                    link_from_shape: Isometry3::translation(length_m, 0.0, 0.0),
                    shape: Shape::Sphere { radius: 0.05 },
                    label: "bob".into(),
                }],
                Some(bob),
            ),
        ],
        last_from_tool: Isometry3::translation(length_m, 0.0, 0.0),
        diagnostics: Vec::new(),
    }
}

fn empty_scenario() -> Scenario {
    Scenario {
        name: "empty".into(),
        world_from_base: Isometry3::identity(),
        floor: None,
        obstacles: Vec::new(),
        goals: Vec::new(),
        home: None,
        provenance: None,
        notes: Vec::new(),
    }
}

#[test]
fn pendulum_settles_where_stiffness_balances_gravity() {
    let (mass, length, stiffness) = (2.0, 0.5, 200.0);
    let model = pendulum(mass, length);
    let scenario = empty_scenario();
    let world = pipeline::collision_world(&model, &scenario, &[]).expect("world builds");
    // Hold the reference at 0 for 2 s; gravity sags the bob by the angle where the stiffness
    // torque kp theta meets the gravity torque m g l cos(theta).
    let limits = TimingLimits {
        dwell_s: 2.0,
        ..TimingLimits::of(&model)
    };
    let path = TimedPath::through(&[vec![0.0], vec![0.0]], &[Some(0)], &limits);
    let inertia = mass * length * length + 0.4 * mass * 0.05 * 0.05;
    let gains = Gains {
        stiffness: vec![stiffness],
        damping: vec![2.0 * (stiffness * inertia).sqrt()],
    };
    let run = run_rapier(&model, &scenario, &world, &path, &gains, &RunOptions::default()).expect("rapier runs");
    let gravity_torque = |theta: f64| mass * 9.81 * length * theta.cos();
    let mut expected = 0.0;
    for _ in 0..50 {
        expected = gravity_torque(expected) / stiffness;
    }
    let hold = &run.holds[0];
    println!("pendulum rest {:.7} rad, closed form {expected:.7} rad", hold.joint_error);
    assert!(
        (hold.joint_error - expected).abs() < PENDULUM_REST_RAD,
        "rest angle {} rad, closed form {expected} rad (m {mass} kg, l {length} m, kp {stiffness} N m/rad)",
        hold.joint_error
    );
    // The motor carried the bob: at rest its effort is the gravity torque (the peak, from the
    // initial sag, is larger).
    assert!(
        run.peak_effort[0] >= gravity_torque(expected),
        "peak effort {:?} N m",
        run.peak_effort
    );
}

#[test]
fn paper_robot_holds_the_first_course_goals_without_contact() {
    let course = course();
    let (path, gains) = tour(&course, 6);
    let started = std::time::Instant::now();
    let run = run_rapier(
        &course.model,
        &course.scenario,
        &course.world,
        &path,
        &gains,
        &RunOptions::default(),
    )
    .expect("rapier runs");
    println!(
        "{} steps ({:.2} s simulated) in {:.2} s; gains kp {:?} kd {:?}",
        run.steps,
        path.duration_s(),
        started.elapsed().as_secs_f64(),
        gains.stiffness,
        gains.damping
    );
    println!(
        "max joint error {:?} rad, max tool error {:.2e} m {:.2e} rad, peak effort {:?} N m",
        run.max_joint_error, run.max_tool_position_error_m, run.max_tool_orientation_error_rad, run.peak_effort
    );
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
    let run = replay_rapier(&course.model, &course.scenario, &course.world, &samples, &RunOptions::default()).expect("rapier replays");
    let parry = parry_depths(&course.model, &course.world, &samples);
    let rapier = engine_depths(&run);
    println!("rapier {rapier:?}\nparry  {parry:?}");
    assert_eq!(run.mode, "kinematic");
    assert!(
        parry.iter().any(|(_, b, _)| b == "box"),
        "the path should run through the box: {parry:?}"
    );
    assert_eq!(
        rapier.iter().map(|(a, b, _)| (a, b)).collect::<Vec<_>>(),
        parry.iter().map(|(a, b, _)| (a, b)).collect::<Vec<_>>(),
        "rapier and parry disagree on the pairs in contact"
    );
    for ((a, b, depth), (_, _, exact)) in rapier.iter().zip(&parry) {
        assert!(*depth > 0.0, "{a}-{b}: depth {depth}");
        assert!(
            (depth - exact).abs() < DEPTH_AGREEMENT_M,
            "{a}-{b}: rapier {depth} m, parry {exact} m"
        );
    }
}

#[test]
fn replay_of_the_clean_course_configurations_reports_no_contact() {
    let course = course();
    let mut samples = vec![(0.0, generate::COURSE_HOME.to_vec())];
    samples.extend(
        generate::course_configurations()
            .into_iter()
            .enumerate()
            .map(|(i, q)| ((i + 1) as f64, q)),
    );
    let run = replay_rapier(&course.model, &course.scenario, &course.world, &samples, &RunOptions::default()).expect("rapier replays");
    assert_eq!(run.steps, samples.len());
    assert!(run.contacts.is_empty(), "{:?}", run.contacts);
}

#[test]
fn two_runs_are_identical() {
    let course = course();
    let (path, gains) = tour(&course, 1);
    let once = || -> EngineRun {
        run_rapier(
            &course.model,
            &course.scenario,
            &course.world,
            &path,
            &gains,
            &RunOptions::default(),
        )
        .expect("rapier runs")
    };
    let first = once();
    assert!(first.steps > 0);
    assert_eq!(first, once());
}

#[test]
fn rejects_gains_for_the_wrong_number_of_joints() {
    let course = course();
    let (path, mut gains) = tour(&course, 1);
    gains.stiffness.pop();
    let error = run_rapier(
        &course.model,
        &course.scenario,
        &course.world,
        &path,
        &gains,
        &RunOptions::default(),
    )
    .expect_err("4 gains for 5 joints");
    assert!(error.to_string().contains("gains for 4 and 5 joints"), "{error}");
}

#[test]
fn dynamic_run_through_the_course_box_records_the_contact() {
    let course = course();
    let configurations = generate::course_configurations();
    let waypoints = [configurations[12].clone(), configurations[23].clone()];
    let path = TimedPath::through(&waypoints, &[Some(23)], &TimingLimits::of(&course.model));
    let gains = engine::gains(&course.model, &path, &GainOptions::default());
    let run = run_rapier(
        &course.model,
        &course.scenario,
        &course.world,
        &path,
        &gains,
        &RunOptions::default(),
    )
    .expect("rapier runs");
    println!("{:?}", run.contacts);
    let hit = run
        .contacts
        .iter()
        .find(|c| c.a == "link5" && c.b == "box")
        .expect("link5 hits the box");
    assert!(hit.max_depth_m > 0.0 && hit.end_s > hit.start_s, "{hit:?}");
}
