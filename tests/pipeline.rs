//! End to end: the whole validation of a design on a scenario, and the report's verdict.

mod common;

use common::repo;
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use proving_ground::model::Shape;
use proving_ground::pipeline::{load, validate, Engines, LoadOptions, ValidateOptions};
use proving_ground::report::{self, FindingKind, Severity};
use proving_ground::scenario::{generate, Goal, Obstacle, Scenario, Tolerance};
use std::f64::consts::FRAC_PI_4;

fn paper_robot() -> proving_ground::pipeline::Loaded {
    load(&repo().join("designs/paper-real-world.json"), &LoadOptions::default()).expect("shipped design loads")
}

#[test]
fn the_paper_robot_passes_the_course_in_both_engines_with_no_contacts_and_every_goal_held() {
    let validation = validate(paper_robot(), generate::course(generate::COURSE_SEED), &ValidateOptions::default()).expect("runs");
    let report = report::build(&validation);
    // Warnings only for contacts rapier's f32 cylinders invent (exact geometry refutes them).
    let fails: Vec<_> = report
        .findings_at_least(Severity::Warn)
        .filter(|f| f.kind != FindingKind::EngineContactNotConfirmed || f.engine != Some("rapier"))
        .collect();
    assert!(report.verdict.passed && fails.is_empty(), "{fails:#?}");
    let trajectory = report.trajectory.as_ref().expect("a full run plans a trajectory");
    assert_eq!(trajectory.reached, 36);
    assert!(trajectory.certified_clearance_m.is_some_and(|c| c > 0.0));
    assert_eq!(report.engines.len(), 2);
    for engine in &report.engines {
        assert_eq!(engine.goals_held, 36, "{}", engine.engine);
        assert!(
            engine.contacts.iter().all(|c| c.parry_distance_m.is_some_and(|d| d > 0.0)) && engine.replay_contacts.is_empty(),
            "{}: {:?}",
            engine.engine,
            engine.contacts
        );
        assert!(engine.worst_hold_position_m < 1e-3 && engine.worst_hold_orientation_deg < 1.0);
    }
    assert!(report.goals.iter().all(|g| g.held_by == ["rapier", "mujoco"]));
    let load = report.static_load.as_ref().expect("MuJoCo ran");
    assert!(
        load.joints.iter().all(|j| !j.over) && load.max_relative_disagreement.is_some_and(|d| d < 1e-9),
        "{load:?}"
    );
}

#[test]
fn a_path_through_an_obstacle_is_caught_by_all_three_checkers_at_the_same_segment() {
    // The ball, and a cube mesh in its place: the engines collide the mesh as its convex pieces,
    // and name the contact after the obstacle.
    through_an_obstacle(Shape::Sphere { radius: 0.05 });
    through_an_obstacle(Shape::Mesh(cube_mesh(0.05)));
}

/// A closed cube mesh of half side `half` (m), centred on its frame.
fn cube_mesh(half: f64) -> proving_ground::model::TriMesh {
    let vertices: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            let sign = |bit: u32| if i & (1 << bit) == 0 { -half } else { half };
            [sign(0), sign(1), sign(2)]
        })
        .collect();
    // Two outward triangles per face.
    let triangles = vec![
        [0, 2, 3],
        [0, 3, 1],
        [4, 5, 7],
        [4, 7, 6],
        [0, 1, 5],
        [0, 5, 4],
        [2, 6, 7],
        [2, 7, 3],
        [0, 4, 6],
        [0, 6, 2],
        [1, 3, 7],
        [1, 7, 5],
    ];
    proving_ground::model::TriMesh {
        uri: "cube.stl".into(),
        file: std::path::PathBuf::from("cube.stl"),
        scale: [1.0; 3],
        vertices,
        triangles,
    }
}

fn through_an_obstacle(shape: Shape) {
    // One joint turning a 0.6 m arm (0.3 m up) from 0 to the goal at +90 degrees (its other turn,
    // -270, is beyond the -3 rad limit), and a ball in the way at 45 degrees.
    let text = r#"{"name": "swing", "mode": "free", "joints": [{"d": 0.3, "a": 0.6, "alpha": 0, "limits": [-3, 3]}]}"#;
    let design = proving_ground::design::parse(text, std::path::Path::new("swing.json")).expect("valid design");
    let loaded = proving_ground::pipeline::Loaded {
        model: proving_ground::model::from_design(&design),
        design: Some(design),
    };
    let ball = Obstacle {
        name: "ball".into(),
        world_from_shape: Isometry3::translation(0.4 * FRAC_PI_4.cos(), 0.4 * FRAC_PI_4.sin(), 0.3),
        shape,
    };
    let goal = Goal {
        name: "left".into(),
        position: Vector3::new(0.0, 0.6, 0.3),
        rotation: UnitQuaternion::identity(),
        tolerance: Tolerance::Position,
        task: None,
    };
    let scenario = Scenario {
        name: "swing-past-a-ball".into(),
        world_from_base: Isometry3::identity(),
        floor: None,
        obstacles: vec![ball],
        goals: vec![goal],
        home: None,
        provenance: None,
        notes: Vec::new(),
    };
    // The goal's other way round is beyond the joint limit: no budget finds a path, and a small
    // one keeps the exact checks of the mesh variant (slower than the ball's) short.
    let opts = ValidateOptions {
        planner: proving_ground::plan::PlannerOptions {
            budget: 1000,
            ..Default::default()
        },
        ..Default::default()
    };
    let validation = validate(loaded, scenario, &opts).expect("runs");
    let report = report::build(&validation);
    assert!(!report.verdict.passed);
    // The other way round (-270 degrees) is beyond the limit: no planner finds a path.
    let blocked: Vec<_> = report.findings.iter().filter(|f| f.kind == FindingKind::GoalNoPath).collect();
    assert_eq!(blocked.len(), 1, "{:#?}", report.findings);
    // parry3d: the segment stops where link 1 (the arm) touches the ball, before 45 degrees.
    let trajectory = report.trajectory.as_ref().expect("a full run plans a trajectory");
    let stop = trajectory.segments[0].attempt_stop.as_ref().expect("the certified check stops");
    assert_eq!((stop.a.as_str(), stop.b.as_str()), ("link1", "ball"), "{stop:?}");
    assert!(stop.q[0] > 0.0 && stop.q[0] < FRAC_PI_4, "{stop:?}");
    // Both engines' kinematic replays find the same pair on the same (only) replayed segment.
    for engine in ["rapier", "mujoco"] {
        let confirmed: Vec<_> = report
            .findings
            .iter()
            .filter(|f| f.kind == FindingKind::ReplayContactConfirmed && f.engine == Some(engine))
            .collect();
        assert_eq!(confirmed.len(), 1, "{engine}: {:#?}", report.findings);
        assert_eq!(confirmed[0].goal, Some(0));
        let contacts = &report.engines.iter().find(|e| e.engine == engine).expect("ran").replay_contacts;
        assert!(!contacts.is_empty(), "{engine}");
        for contact in contacts {
            assert_eq!((contact.a.as_str(), contact.b.as_str()), ("link1", "ball"), "{engine}: {contact:?}");
            // Replay clock: segment 0 is [0, 1); the contact begins near where parry stopped.
            assert!(
                contact.start_s < 1.0 && (contact.start_s - stop.s).abs() < 0.02,
                "{engine}: {contact:?} vs {stop:?}"
            );
        }
    }
}

#[test]
fn the_report_is_the_same_with_one_engine_at_a_time_and_without_engines() {
    let scenario = generate::cluttered(0, generate::CLUTTERED_MASTER_SEED);
    let run = |engines: Engines| {
        let opts = ValidateOptions {
            engines,
            ..Default::default()
        };
        let validation = validate(
            load(&repo().join("designs/ur5e.json"), &LoadOptions::default()).expect("loads"),
            scenario.clone(),
            &opts,
        )
        .expect("runs");
        report::build(&validation)
    };
    let none = run(Engines::none());
    // Without MuJoCo the static load comes from our own gravity torques, with no cross-check.
    assert!(none.engines.is_empty() && none.static_load.as_ref().is_some_and(|l| l.max_relative_disagreement.is_none()));
    let both = run(Engines::default());
    // The engines change only their own sections: the goals, trajectory and loss are the same.
    assert_eq!(
        serde_json::to_string(&none.trajectory).expect("json"),
        serde_json::to_string(&both.trajectory).expect("json")
    );
    assert_eq!(
        none.goals.iter().map(|g| g.on_trajectory).collect::<Vec<_>>(),
        both.goals.iter().map(|g| g.on_trajectory).collect::<Vec<_>>()
    );
}

#[test]
fn a_joint_over_its_rated_torque_fails_the_design_and_one_within_does_not() {
    // A modular arm with four long elbow tubes, held out straight: gravity alone needs far more
    // than the modules' 60 N m at joint 2. Its one goal is its own tool pose there.
    let text = r#"{"name": "long-arm", "mode": "modular", "modules": ["direct", "L-long", "L-long", "L-long", "L-long", "I-long"]}"#;
    let design = proving_ground::design::parse(text, std::path::Path::new("long-arm.json")).expect("valid design");
    let model = proving_ground::model::from_design(&design);
    let q = vec![0.0; 6];
    let tool = model.tool_pose(&q);
    let scenario = Scenario {
        name: "reach-out".into(),
        world_from_base: Isometry3::identity(),
        floor: None,
        obstacles: vec![],
        goals: vec![Goal {
            name: "out".into(),
            position: tool.translation.vector,
            rotation: tool.rotation,
            tolerance: Tolerance::Position,
            task: None,
        }],
        home: Some(q),
        provenance: None,
        notes: Vec::new(),
    };
    let opts = ValidateOptions {
        engines: "mujoco".parse::<Engines>().expect("an engine"),
        ..Default::default()
    };
    // Judged from MuJoCo's gravity torques, and from ours alone when MuJoCo does not run.
    for mujoco in [true, false] {
        let loaded = proving_ground::pipeline::Loaded {
            model: model.clone(),
            design: Some(design.clone()),
        };
        let engines = if mujoco {
            "mujoco".parse().expect("an engine")
        } else {
            Engines::none()
        };
        let report = report::build(&validate(loaded, scenario.clone(), &ValidateOptions { engines, ..opts.clone() }).expect("runs"));
        let overloads: Vec<_> = report.findings.iter().filter(|f| f.kind == FindingKind::StaticOverload).collect();
        assert!(
            !overloads.is_empty() && overloads.iter().all(|f| f.severity == Severity::Fail),
            "{:#?}",
            report.findings
        );
        assert!(
            overloads
                .iter()
                .any(|f| f.message.starts_with("joint 2 ") && f.values["peak_torque"] > 100.0),
            "{overloads:#?}"
        );
        assert!(
            report.verdict.reasons.iter().any(|r| r.contains("rated torque under gravity")),
            "{:?}",
            report.verdict
        );
    }

    // The paper's robot on its course stays within the rating at every joint.
    let paper = report::build(&validate(paper_robot(), generate::course(generate::COURSE_SEED), &opts).expect("runs"));
    assert!(paper.findings.iter().all(|f| f.kind != FindingKind::StaticOverload));
    let load = paper.static_load.expect("MuJoCo ran");
    assert!(
        load.joints.iter().all(|j| j.rated == Some(60.0) && j.peak_torque < 60.0),
        "{load:?}"
    );
}

#[test]
fn a_mesh_notch_stays_open_in_both_engines() {
    // One joint swings a 0.6 m tube (0.12 m thick, 0.3 m up) a quarter turn into the notch of a
    // U-shaped mesh: 40 mm from the notch's floor and from both prongs at the goal, and free all
    // the way in exact geometry. The U's convex hull swallows the tube: MuJoCo, which collides a
    // mesh as its hull, once pushed the arm 536 mm off the goal. Both engines now get the U's
    // convex pieces, which keep the notch open.
    let text = r#"{"name": "swing", "mode": "free", "joints": [{"d": 0.3, "a": 0.6, "alpha": 0, "limits": [-3, 3]}]}"#;
    let design = proving_ground::design::parse(text, std::path::Path::new("swing.json")).expect("valid design");
    let loaded = proving_ground::pipeline::Loaded {
        model: proving_ground::model::from_design(&design),
        design: Some(design),
    };
    // The mesh's +y (the notch's opening) faces world +x, where the tube comes from; its x (across
    // the notch) is world z, its extrusion world y.
    let rotation = Rotation3::from_matrix_unchecked(Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0));
    let u = Obstacle {
        name: "u".into(),
        world_from_shape: Isometry3::from_parts(Translation3::new(-0.3, 0.3, 0.0), UnitQuaternion::from_rotation_matrix(&rotation)),
        // 0.6 x 0.6 m, the notch 0.2 m wide (x in [0.2, 0.4]) and 0.4 m deep towards +y, 0.2 m thick.
        shape: Shape::Mesh(common::u_mesh(0.2)),
    };
    let scenario = Scenario {
        name: "into-a-notch".into(),
        world_from_base: Isometry3::identity(),
        floor: None,
        obstacles: vec![u],
        goals: vec![Goal {
            name: "in the notch".into(),
            position: Vector3::new(0.0, 0.6, 0.3),
            rotation: UnitQuaternion::identity(),
            tolerance: Tolerance::Position,
            task: None,
        }],
        home: None,
        provenance: None,
        notes: Vec::new(),
    };
    let validation = validate(loaded, scenario, &ValidateOptions::default()).expect("runs");
    let report = report::build(&validation);
    let trajectory = report.trajectory.as_ref().expect("planned");
    assert_eq!(trajectory.reached, 1, "{:#?}", report.findings);
    // Exact geometry: free, with the 40 mm of the notch at the goal.
    let clearance = report.goals[0].exact_clearance_m.expect("measured");
    assert!((clearance - 0.04).abs() < 1e-6, "{clearance}");
    // Neither engine touches the U, and both hold the goal.
    for engine in &report.engines {
        assert!(engine.contacts.is_empty(), "{}: {:?}", engine.engine, engine.contacts);
    }
    assert!(
        report.findings.iter().all(|f| f.engine.is_none() || f.severity < Severity::Warn),
        "{:#?}",
        report.findings
    );
    assert_eq!(report.goals[0].held_by, ["rapier", "mujoco"]);
    assert!(report.verdict.passed, "{:?}", report.verdict);
}

/// A closed prism of `sides` sides around z standing in for a cylinder (centred, like ours).
fn prism_mesh(radius: f64, length: f64, sides: u32) -> proving_ground::model::TriMesh {
    let mut vertices = Vec::new();
    for z in [-length / 2.0, length / 2.0] {
        for k in 0..sides {
            let angle = std::f64::consts::TAU * f64::from(k) / f64::from(sides);
            vertices.push([radius * angle.cos(), radius * angle.sin(), z]);
        }
    }
    let mut triangles = Vec::new();
    for k in 1..sides - 1 {
        triangles.push([0, k + 1, k]); // bottom, facing -z
        triangles.push([sides, sides + k, sides + k + 1]); // top, facing +z
    }
    for k in 0..sides {
        let next = (k + 1) % sides;
        triangles.push([k, next, sides + next]);
        triangles.push([k, sides + next, sides + k]);
    }
    proving_ground::model::TriMesh {
        uri: "prism.stl".into(),
        file: std::path::PathBuf::from("prism.stl"),
        scale: [1.0; 3],
        vertices,
        triangles,
    }
}

#[test]
fn a_link_mesh_in_contact_is_named_after_its_link_in_both_engines() {
    // The swinging arm of the ball test with its link's cylinders made prism meshes: the engines
    // collide the meshes' convex pieces (MuJoCo geoms `link1/<k>/<p>`), and report the pair by
    // the link's name at the angle exact geometry has.
    let text = r#"{"name": "swing", "mode": "free", "joints": [{"d": 0.3, "a": 0.6, "alpha": 0, "limits": [-3, 3]}]}"#;
    let design = proving_ground::design::parse(text, std::path::Path::new("swing.json")).expect("valid design");
    let mut model = proving_ground::model::from_design(&design);
    let mut meshes = 0;
    for collider in &mut model.links[1].colliders {
        if let Shape::Cylinder { radius, length } = collider.shape {
            collider.shape = Shape::Mesh(prism_mesh(radius, length, 24));
            meshes += 1;
        }
    }
    assert!(meshes > 0, "the arm has cylinders: {:?}", model.links[1].colliders);
    let scenario = Scenario {
        name: "swing-past-a-ball".into(),
        world_from_base: Isometry3::identity(),
        floor: None,
        obstacles: vec![Obstacle {
            name: "ball".into(),
            world_from_shape: Isometry3::translation(0.4 * FRAC_PI_4.cos(), 0.4 * FRAC_PI_4.sin(), 0.3),
            shape: Shape::Sphere { radius: 0.05 },
        }],
        goals: Vec::new(),
        home: None,
        provenance: None,
        notes: Vec::new(),
    };
    let world = proving_ground::pipeline::collision_world(&model, &scenario, &[]).expect("world");
    // Exact geometry: the first sampled angle where link1 meets the ball.
    let samples: Vec<(f64, Vec<f64>)> = (0..=300).map(|k| (f64::from(k) * 0.005, vec![f64::from(k) * 0.005])).collect();
    let mut ws = model.workspace();
    let mut out = proving_ground::collide::Distances::new();
    let query = proving_ground::collide::QueryOptions {
        margin: 1.0,
        hulls: false,
        exact_depth: true,
        mesh_hulls: false,
    };
    let first_touch = samples
        .iter()
        .find(|(_, q)| {
            model.forward(q, &mut ws);
            proving_ground::collide::distances(&world, &ws.link_in_world, &query, &mut out);
            world
                .pairs()
                .iter()
                .zip(&out.estimates)
                .any(|(pair, e)| pair.a_name == "link1" && pair.b_name == "ball" && e.distance < 0.0)
        })
        .map(|(t, _)| *t)
        .expect("exact geometry has the contact");
    let opts = proving_ground::engine::RunOptions::default();
    let runs = [
        proving_ground::engine::replay_rapier(&model, &scenario, &world, &samples, &opts).expect("rapier replays"),
        proving_ground::engine::replay_mujoco(&model, &scenario, &world, &samples, &opts).expect("MuJoCo replays"),
    ];
    for run in runs {
        assert!(!run.contacts.is_empty(), "{}", run.engine);
        for contact in &run.contacts {
            assert_eq!(
                (contact.a.as_str(), contact.b.as_str()),
                ("link1", "ball"),
                "{}: {contact:?}",
                run.engine
            );
        }
        // Within two samples (0.01 rad) of exact geometry: the pieces hug the prism.
        let start = run.contacts.iter().map(|c| c.start_s).fold(f64::INFINITY, f64::min);
        assert!((start - first_touch).abs() <= 0.0101, "{}: {start} vs {first_touch}", run.engine);
    }
}

/// Counts the goals done and asks the run to stop after `after` of them.
struct StopAfter {
    after: usize,
    done: std::sync::atomic::AtomicUsize,
}

impl proving_ground::progress::Progress for StopAfter {
    fn stage(&self, _name: &str, _total: Option<u64>) {}
    fn advance(&self) {
        self.done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }
    fn stopped(&self) -> bool {
        self.done.load(std::sync::atomic::Ordering::Relaxed) >= self.after
    }
}

/// A run asked to stop ends with `Error::Stopped` and no report, in the IK stage (whose goals
/// not yet started are skipped) and in the planner's; asked never, it finishes.
#[test]
fn a_run_asked_to_stop_ends_stopped_without_a_report() {
    let scenario = proving_ground::scenario::load(&repo().join("scenarios/course.json")).expect("loads");
    let opts = ValidateOptions {
        engines: Engines::none(),
        ..ValidateOptions::default()
    };
    let goals = scenario.goals.len();
    for (after, stops) in [(1, true), (goals + 1, true), (usize::MAX, false)] {
        let progress = StopAfter {
            after,
            done: Default::default(),
        };
        let result = proving_ground::pipeline::validate_with_progress(paper_robot(), scenario.clone(), &opts, &progress);
        let done = progress.done.load(std::sync::atomic::Ordering::Relaxed);
        if stops {
            assert!(
                matches!(result, Err(proving_ground::error::Error::Stopped)),
                "after {after}: {result:?}"
            );
            // Stopped promptly: IK's two threads finish the goals they hold, the planner its goal.
            assert!(done <= after + 2, "after {after}: {done} goals done");
        } else {
            assert!(result.is_ok(), "{result:?}");
            assert_eq!(done, 2 * goals, "every goal solved and joined");
        }
    }
}
