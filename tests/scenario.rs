//! The scenario stage: the committed scenarios are exactly what the generators make, the loader
//! rejects broken files naming the file and the field, and the generated tasks keep the promises
//! their generators document, checked here with independent formulas.

mod common;

use assert_cmd::Command;
use common::{fixture, repo};
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use parry3d_f64::shape::{Ball, Capsule, Cuboid, Cylinder, Shape as ParryShape};
use proving_ground::frames::{parry_pose, parry_vector};
use proving_ground::model::{self, Model, Shape, PAPER_CAPSULE_RADIUS_M};
use proving_ground::pipeline::{load_model, LoadOptions};
use proving_ground::scenario::{self, generate, Obstacle, Scenario, Tolerance};
use std::path::{Path, PathBuf};

fn validate_design() -> Command {
    let mut cmd = Command::cargo_bin("validate-design").expect("binary is built");
    cmd.current_dir(repo());
    cmd
}

/// Every committed scenario file, as a path relative to the repository root, sorted.
fn committed() -> Vec<PathBuf> {
    let mut files = vec![
        PathBuf::from("scenarios/course.json"),
        PathBuf::from("scenarios/workspace/pose.json"),
        PathBuf::from("scenarios/workspace/z_symmetric.json"),
        PathBuf::from("scenarios/workspace/position.json"),
    ];
    files.extend((0..generate::CLUTTERED_TASKS).map(|task| PathBuf::from(format!("scenarios/cluttered/task-{task:02}.json"))));
    files
}

fn load_committed(path: &Path) -> Scenario {
    scenario::load(&repo().join(path)).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn paper_robot() -> Model {
    load_model(&repo().join("designs/paper-real-world.json"), &LoadOptions::default()).expect("the paper robot loads")
}

// ---------------------------------------------------------------------------------------------
// Determinism

#[test]
fn committed_scenarios_regenerate_byte_for_byte_with_the_binary() {
    let out = tempfile::tempdir().expect("temp dir");
    let runs: Vec<Vec<String>> = vec![
        vec!["cluttered".into(), "--all".into(), "--out".into(), "cluttered".into()],
        vec![
            "workspace".into(),
            "--tolerance".into(),
            "pose".into(),
            "--out".into(),
            "workspace/pose.json".into(),
        ],
        vec![
            "workspace".into(),
            "--tolerance".into(),
            "z_symmetric".into(),
            "--out".into(),
            "workspace/z_symmetric.json".into(),
        ],
        vec![
            "workspace".into(),
            "--tolerance".into(),
            "position".into(),
            "--out".into(),
            "workspace/position.json".into(),
        ],
        vec!["course".into(), "--out".into(), "course.json".into()],
    ];
    for args in runs {
        let output = Command::cargo_bin("validate-design")
            .expect("binary is built")
            .current_dir(out.path())
            .arg("generate")
            .args(&args)
            .output()
            .expect("runs");
        assert_eq!(
            output.status.code(),
            Some(0),
            "{args:?}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
    }
    for path in committed() {
        let relative = path.strip_prefix("scenarios").expect("under scenarios/");
        let fresh = std::fs::read(out.path().join(relative)).unwrap_or_else(|e| panic!("{}: {e}", relative.display()));
        let kept = std::fs::read(repo().join(&path)).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            fresh == kept,
            "{} differs from what the generator makes now; regenerate with `validate-design generate ... --force` and say why in the commit",
            path.display()
        );
    }
    let cluttered = std::fs::read_dir(repo().join("scenarios/cluttered"))
        .expect("scenarios/cluttered")
        .count();
    assert_eq!(
        cluttered,
        generate::CLUTTERED_TASKS,
        "scenarios/cluttered holds exactly the 36 tasks"
    );
}

#[test]
fn generators_give_the_same_bytes_twice_in_a_process_and_on_other_threads() {
    let seed = generate::CLUTTERED_MASTER_SEED;
    let task = scenario::to_json(&generate::cluttered(7, seed));
    assert_eq!(
        task,
        scenario::to_json(&generate::cluttered(7, seed)),
        "cluttered task 7, seed {seed}"
    );
    let course = scenario::to_json(&generate::course(generate::COURSE_SEED));
    let workspace =
        || generate::workspace(generate::WORKSPACE_GOALS, 1.0, Tolerance::ZSymmetric, generate::WORKSPACE_SEED).expect("valid parameters");
    let space = scenario::to_json(&workspace());

    let threads = [
        std::thread::spawn(move || scenario::to_json(&generate::cluttered(7, seed))),
        std::thread::spawn(|| scenario::to_json(&generate::course(generate::COURSE_SEED))),
        std::thread::spawn(move || scenario::to_json(&workspace())),
    ];
    let [a, b, c] = threads.map(|t| t.join().expect("generator thread"));
    assert_eq!(a, task, "cluttered on another thread");
    assert_eq!(b, course, "course on another thread");
    assert_eq!(c, space, "workspace on another thread");
    // Different tasks and seeds do differ.
    assert_ne!(task, scenario::to_json(&generate::cluttered(8, seed)));
    assert_ne!(course, scenario::to_json(&generate::course(generate::COURSE_SEED + 1)));
}

#[test]
fn committed_scenarios_load_and_round_trip_exactly() {
    for path in committed() {
        let text = std::fs::read_to_string(repo().join(&path)).expect("readable");
        let scenario = scenario::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            scenario::to_json(&scenario),
            text,
            "{}: parse then write must give the same bytes",
            path.display()
        );
        let provenance = scenario.provenance.as_ref().expect("generated files say how they were made");
        assert!(
            ["cluttered", "workspace", "course"].contains(&provenance.generator.as_str()),
            "{}",
            path.display()
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Broken files

/// Runs the binary with a scenario fixture, asserting exit code 2, no panic, and a message
/// naming the file; returns stderr.
fn error_for(name: &str) -> String {
    let output = validate_design()
        .args(["designs/paper-real-world.json", "--describe", "--scenario"])
        .arg(fixture(&format!("scenarios/{name}")))
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(2), "{name}: expected exit 2, stderr: {stderr}");
    assert!(stderr.contains(name), "{name}: the message must name the file: {stderr}");
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    stderr
}

#[test]
fn rejects_unknown_obstacle_type() {
    let stderr = error_for("unknown_obstacle_type.json");
    assert!(
        stderr.contains("obstacles[1].type: unknown obstacle type `cone`; expected one of sphere, capsule, box, cylinder, mesh"),
        "{stderr}"
    );
}

#[test]
fn rejects_negative_radius() {
    let stderr = error_for("negative_radius.json");
    assert!(
        stderr.contains("obstacles[1].radius: -0.1 m: expected a finite number > 0"),
        "{stderr}"
    );
}

#[test]
fn rejects_nan_and_out_of_range_numbers_with_line() {
    let stderr = error_for("nan_position.json");
    assert!(stderr.contains("line 4"), "NaN is not JSON; serde names the line: {stderr}");
    let stderr = error_for("huge_number.json");
    assert!(stderr.contains("line 3") && stderr.contains("out of range"), "{stderr}");
}

#[test]
fn rejects_non_unit_quaternion_naming_the_norm() {
    let stderr = error_for("non_unit_quaternion.json");
    assert!(
        stderr.contains("goals[1].quaternion") && stderr.contains("has norm 1.00497") && stderr.contains("within 0.000001"),
        "{stderr}"
    );
}

#[test]
fn rejects_non_orthonormal_rotation() {
    let stderr = error_for("non_orthonormal_rotation.json");
    assert!(
        stderr.contains("goals[0].rotation") && stderr.contains("is not orthonormal"),
        "{stderr}"
    );
}

#[test]
fn rejects_missing_mesh_naming_field_and_resolved_path() {
    let stderr = error_for("missing_mesh_file.json");
    assert!(
        stderr.contains("obstacles[0].file")
            && stderr.contains("tests/fixtures/scenarios/../meshes/bracket.stl")
            && stderr.contains("not found"),
        "{stderr}"
    );
}

#[test]
fn rejects_empty_goal_list() {
    let stderr = error_for("empty_goals.json");
    assert!(stderr.contains("goals: is empty; a scenario needs at least one goal"), "{stderr}");
}

#[test]
fn rejects_a_goal_with_both_orientations() {
    let stderr = error_for("both_orientations.json");
    assert!(
        stderr.contains("goals[0]: gives both `quaternion` and `rotation`; give exactly one orientation"),
        "{stderr}"
    );
}

#[test]
fn loads_a_mesh_obstacle_and_both_orientation_forms() {
    let path = fixture("scenarios/mesh_and_both_orientation_forms.json");
    let scenario = scenario::load(&path).expect("valid fixture");
    let Shape::Mesh(mesh) = &scenario.obstacles[0].shape else {
        panic!("obstacle 0 is a mesh")
    };
    assert_eq!(mesh.triangles.len(), 4);
    assert_eq!(mesh.scale, [0.2; 3]);
    assert!(matches!(scenario.obstacles[3].shape, Shape::Box { half_extents } if half_extents == [0.1, 0.05, 0.2]));
    let [by_quaternion, by_matrix] = [&scenario.goals[0], &scenario.goals[1]];
    assert!(
        by_quaternion.rotation.angle_to(&by_matrix.rotation) < 1e-15,
        "both forms say 90 degrees about z"
    );
    assert_eq!(
        (by_quaternion.tolerance, by_matrix.tolerance),
        (Tolerance::ZSymmetric, Tolerance::Pose)
    );
    assert!((scenario.world_from_base.rotation.angle() - 0.5).abs() < 1e-15);

    let output = validate_design()
        .args(["designs/paper-real-world.json", "--describe", "--scenario"])
        .arg(&path)
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(
        stdout.contains("scenario fixture-with-mesh: 4 obstacles, 2 goals, tolerance pose (1), z_symmetric (1)"),
        "{stdout}"
    );

    // Written and read back (mesh paths stay relative to the file), the scenario is unchanged.
    let text = scenario::to_json(&scenario);
    let again = scenario::parse(&text, &path).expect("round trip");
    assert_eq!(scenario::to_json(&again), text);
}

#[test]
fn the_default_scenario_is_the_course_and_prints_one_summary_line() {
    let output = validate_design()
        .args(["designs/paper-real-world.json", "--describe"])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0));
    assert!(
        stdout.contains("scenario course: 3 obstacles, 36 goals, tolerance z_symmetric"),
        "{stdout}"
    );
}

#[test]
fn generate_never_overwrites_without_force_and_checks_its_parameters() {
    let dir = tempfile::tempdir().expect("temp dir");
    let target = dir.path().join("course.json");
    std::fs::write(&target, "keep me").expect("write");
    let run = |args: &[&str]| {
        Command::cargo_bin("validate-design")
            .expect("binary is built")
            .current_dir(dir.path())
            .arg("generate")
            .args(args)
            .output()
            .expect("runs")
    };
    let output = run(&["course", "--out", "course.json"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("cannot write course.json: the file exists; pass --force"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(&target).expect("read"), "keep me");

    let output = run(&["course", "--out", "course.json", "--force"]);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));
    assert_eq!(
        std::fs::read(&target).expect("read"),
        std::fs::read(repo().join("scenarios/course.json")).expect("committed")
    );

    // With --all, one existing task stops the whole set before anything is written.
    std::fs::create_dir(dir.path().join("tasks")).expect("mkdir");
    std::fs::write(dir.path().join("tasks/task-17.json"), "keep me").expect("write");
    let output = run(&["cluttered", "--all", "--out", "tasks"]);
    assert_eq!(output.status.code(), Some(2));
    assert_eq!(std::fs::read_dir(dir.path().join("tasks")).expect("dir").count(), 1);

    for (args, message) in [
        (
            &["workspace", "--scale", "2", "--out", "w.json"][..],
            "workspace generator: scale 2: expected a factor in [0.5, 1.5]",
        ),
        (
            &["workspace", "--count", "0", "--out", "w.json"][..],
            "invalid value '0' for '--count <N>': 0 is not in 1..=10000",
        ),
        (
            &["course", "--count", "5", "--out", "c.json"][..],
            "--count does not apply to the course generator",
        ),
        (&["cluttered", "--out", "t.json"][..], "give --task K or --all"),
        (
            &["workspace", "--tolerance", "loose", "--out", "w.json"][..],
            "invalid value 'loose'",
        ),
    ] {
        let output = run(args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
    }
    assert!(!dir.path().join("w.json").exists() && !dir.path().join("c.json").exists());
}

// ---------------------------------------------------------------------------------------------
// Cluttered tasks

#[test]
fn every_cluttered_goal_is_reachable_in_principle_and_clear_of_obstacles() {
    for task in 0..generate::CLUTTERED_TASKS {
        let path = PathBuf::from(format!("scenarios/cluttered/task-{task:02}.json"));
        let scenario = load_committed(&path);
        let context = format!("{} (task {task}, master seed {})", path.display(), generate::CLUTTERED_MASTER_SEED);
        assert_eq!(scenario.goals.len(), generate::CLUTTERED_GOALS, "{context}");
        assert_eq!(scenario.obstacles.len(), generate::CLUTTERED_OBSTACLES, "{context}");
        let floor = scenario.floor.expect("cluttered tasks have a floor").height;
        assert_eq!(floor, generate::FLOOR_HEIGHT_M);

        for goal in &scenario.goals {
            let p = goal.position;
            assert_eq!(goal.tolerance, Tolerance::Pose, "{context}");
            assert!(p.norm() <= generate::CLUTTERED_MAX_DISTANCE_M, "{context}: {} at {p:?}", goal.name);
            assert!(
                p.norm() - generate::GOAL_NEIGHBOURHOOD_M >= generate::BASE_KEEP_OUT_RADIUS_M,
                "{context}: {}",
                goal.name
            );
            assert!(p.z - generate::GOAL_NEIGHBOURHOOD_M >= floor, "{context}: {}", goal.name);
        }
        for obstacle in &scenario.obstacles {
            let Shape::Sphere { radius } = obstacle.shape else {
                panic!("{context}: {} is not a sphere", obstacle.name)
            };
            let [low, high] = generate::CLUTTERED_OBSTACLE_RADIUS_M;
            assert!((low..high).contains(&radius), "{context}: {} radius {radius}", obstacle.name);
            let centre = obstacle.world_from_shape.translation.vector;
            assert!(centre.norm() <= generate::CLUTTERED_MAX_DISTANCE_M, "{context}: {}", obstacle.name);
            assert!(centre.z - radius > floor, "{context}: {} touches the floor", obstacle.name);
            assert!(
                centre.norm() - radius > generate::BASE_KEEP_OUT_RADIUS_M,
                "{context}: {} in the base keep-out",
                obstacle.name
            );
            for goal in &scenario.goals {
                let gap = (centre - goal.position).norm() - radius;
                assert!(
                    gap > generate::GOAL_NEIGHBOURHOOD_M,
                    "{context}: {} is {gap} m from {}, inside its neighbourhood",
                    obstacle.name,
                    goal.name
                );
            }
        }

        // The catalog robot the goals were made with reaches each of them exactly: the model
        // stage's forward kinematics reproduces the goal poses.
        let witness = generate::cluttered_witness(task, generate::CLUTTERED_MASTER_SEED);
        assert_eq!(witness.modules.len(), generate::CLUTTERED_SLOTS, "{context}");
        let names: Vec<String> = witness.modules.iter().map(|m| format!("\"{}\"", m.name())).collect();
        let text = format!(r#"{{"mode": "modular", "modules": [{}]}}"#, names.join(", "));
        let robot = model::from_design(&proving_ground::design::parse(&text, Path::new("witness.json")).expect("catalog design"));
        for (goal, q) in scenario.goals.iter().zip(&witness.configurations) {
            let tool = robot.tool_pose(q);
            let position_error = (tool.translation.vector - goal.position).norm();
            let angle_error = tool.rotation.angle_to(&goal.rotation);
            assert!(
                position_error < 1e-12 && angle_error < 1e-12,
                "{context}: {}: {position_error} m, {angle_error} rad",
                goal.name
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Workspace

#[test]
fn workspace_goals_fill_the_documented_box() {
    let [sx, sy, sz] = generate::WORKSPACE_BOX_SIZE_M;
    let [cx, cy, cz] = generate::WORKSPACE_BOX_CENTRE_M;
    let mut lowest = Vector3::repeat(f64::INFINITY);
    let mut highest = Vector3::repeat(f64::NEG_INFINITY);
    for (name, tolerance) in [
        ("pose", Tolerance::Pose),
        ("z_symmetric", Tolerance::ZSymmetric),
        ("position", Tolerance::Position),
    ] {
        let scenario = load_committed(Path::new(&format!("scenarios/workspace/{name}.json")));
        assert_eq!(scenario.goals.len(), generate::WORKSPACE_GOALS);
        assert!(scenario.obstacles.is_empty());
        for goal in &scenario.goals {
            assert_eq!(goal.tolerance, tolerance);
            let p = goal.position;
            assert!(
                (p.x - cx).abs() <= sx / 2.0 && (p.y - cy).abs() <= sy / 2.0 && (p.z - cz).abs() <= sz / 2.0,
                "{name}: {p:?}"
            );
            lowest = lowest.inf(&p);
            highest = highest.sup(&p);
        }
    }
    // 1000 uniform samples come within 1 % of every face of the box.
    let size = Vector3::new(sx, sy, sz);
    assert!(
        (highest - lowest - size).abs().max() < 0.02,
        "spread {:?} vs box {size:?}",
        highest - lowest
    );

    // Scale multiplies the box about the base.
    let half = generate::workspace(200, 0.5, Tolerance::Pose, 1).expect("valid");
    assert!(half
        .goals
        .iter()
        .all(|g| g.position.x <= 0.5 * (cx + sx / 2.0) && g.position.z <= 0.5 * (cz + sz / 2.0)));
}

// ---------------------------------------------------------------------------------------------
// Course

/// Everything solid on one link at one configuration, for parry: the paper's capsules and the
/// exact colliders (tubes and joint module housings).
fn link_shapes(model: &Model, ws: &model::KinematicsWorkspace) -> Vec<(usize, parry3d_f64::math::Pose, Box<dyn ParryShape>)> {
    let mut shapes: Vec<(usize, parry3d_f64::math::Pose, Box<dyn ParryShape>)> = Vec::new();
    for (index, link) in model.links.iter().enumerate() {
        let frame = ws.link_in_world[index];
        for segment in &link.segments {
            let capsule = Capsule::new(parry_vector(&segment.start), parry_vector(&segment.end), PAPER_CAPSULE_RADIUS_M);
            shapes.push((index, parry_pose(&frame), Box::new(capsule)));
        }
        for collider in &link.colliders {
            let pose = frame * collider.link_from_shape;
            shapes.push((index, shape_pose(&pose, &collider.shape), parry_shape(&collider.shape)));
        }
    }
    shapes
}

/// parry's cylinders run along y, ours along z: turn y onto z.
fn shape_pose(pose: &Isometry3<f64>, shape: &Shape) -> parry3d_f64::math::Pose {
    match shape {
        Shape::Cylinder { .. } => parry_pose(&(pose * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2))),
        _ => parry_pose(pose),
    }
}

fn parry_shape(shape: &Shape) -> Box<dyn ParryShape> {
    match shape {
        Shape::Sphere { radius } => Box::new(Ball::new(*radius)),
        Shape::Cylinder { radius, length } => Box::new(Cylinder::new(length / 2.0, *radius)),
        Shape::Box { half_extents } => Box::new(Cuboid::new(parry3d_f64::math::Vector::new(
            half_extents[0],
            half_extents[1],
            half_extents[2],
        ))),
        other => panic!("the course has no {} shapes", other.kind()),
    }
}

fn obstacle_distance(shapes: &[(usize, parry3d_f64::math::Pose, Box<dyn ParryShape>)], obstacle: &Obstacle) -> f64 {
    let pose = shape_pose(&obstacle.world_from_shape, &obstacle.shape);
    let solid = parry_shape(&obstacle.shape);
    shapes
        .iter()
        .map(|(_, p, s)| {
            parry3d_f64::query::distance(p, s.as_ref(), &pose, solid.as_ref())
                .expect("supported pair")
                .distance
        })
        .fold(f64::INFINITY, f64::min)
}

fn lowest_point(shapes: &[(usize, parry3d_f64::math::Pose, Box<dyn ParryShape>)]) -> f64 {
    shapes
        .iter()
        .map(|(_, p, s)| s.compute_aabb(p).mins.z)
        .fold(f64::INFINITY, f64::min)
}

/// Closed-form distance from point `p` to segment `a`-`b`.
fn point_segment(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let t = if ab.norm_squared() > 0.0 {
        ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

/// Every point of the paper robot is within this distance of every joint origin (m): its chain
/// is 0.1 + |(0.2, 0, 0.1)| + 0.1 + 0.1 + 0.4 = 0.92 m long, plus the 0.085 m housing and 0.06 m
/// tube radii. A joint turning by `t` moves any point by at most this times `t`.
const PAPER_ROBOT_EXTENT_M: f64 = 1.1;

/// Joint step of the test's own sweep along the tour (rad), finer than the generator's.
const TEST_STEP_RAD: f64 = 0.0025;

#[test]
fn course_goals_are_the_paper_robot_tool_poses_and_the_tour_keeps_its_clearance() {
    let design = proving_ground::design::load(&repo().join("designs/paper-real-world.json")).expect("design");
    assert_eq!(
        design.modules.as_deref(),
        Some(&generate::COURSE_MODULES[..]),
        "the course is built for the paper robot"
    );
    let robot = paper_robot();
    let scenario = load_committed(Path::new("scenarios/course.json"));
    let configurations = generate::course_configurations();
    assert_eq!(scenario.goals.len(), 3 * generate::COURSE_GOALS_PER_REGION);
    assert_eq!(configurations.len(), scenario.goals.len());
    assert!(scenario.goals.iter().all(|g| g.tolerance == Tolerance::ZSymmetric));
    assert_eq!(scenario.home.as_deref(), Some(&generate::COURSE_HOME[..]));

    // Each goal is the robot's tool pose up to a spin about the tool z axis.
    for (goal, q) in scenario.goals.iter().zip(&configurations) {
        let tool = robot.tool_pose(q);
        let position_error = (tool.translation.vector - goal.position).norm();
        let z_alignment = (tool.rotation * Vector3::z()).dot(&(goal.rotation * Vector3::z()));
        assert!(
            position_error < 1e-12 && z_alignment > 1.0 - 1e-12,
            "{}: {position_error} m, z.z' = {z_alignment}",
            goal.name
        );
    }
    // Goals are distributed evenly: 12 closer to each obstacle than to the others.
    for (index, goal) in scenario.goals.iter().enumerate() {
        let nearest = (0..3)
            .min_by(|&a, &b| {
                let d = |i: usize| (scenario.obstacles[i].world_from_shape.translation.vector - goal.position).norm();
                d(a).total_cmp(&d(b))
            })
            .expect("three obstacles");
        assert_eq!(nearest, index / generate::COURSE_GOALS_PER_REGION, "{}", goal.name);
    }

    // Sweep the tour from home with exact parry distances (capsules and exact colliders), and
    // subtract what any point can move between two samples.
    let mut ws = robot.workspace();
    let mut worst_obstacle = f64::INFINITY;
    let mut worst_floor = f64::INFINITY;
    let floor = scenario.floor.expect("the course has a floor").height;
    let mut previous = generate::COURSE_HOME.to_vec();
    for (goal, q) in scenario.goals.iter().zip(&configurations) {
        let delta: Vec<f64> = q.iter().zip(&previous).map(|(b, a)| b - a).collect();
        let steps = (delta.iter().fold(0.0_f64, |m, d| m.max(d.abs())) / TEST_STEP_RAD).ceil().max(1.0) as usize;
        let slack = PAPER_ROBOT_EXTENT_M * delta.iter().map(|d| d.abs()).sum::<f64>() / steps as f64 / 2.0;
        for i in 0..=steps {
            let s = i as f64 / steps as f64;
            let sample: Vec<f64> = previous.iter().zip(&delta).map(|(a, d)| a + d * s).collect();
            robot.forward(&sample, &mut ws);
            let shapes = link_shapes(&robot, &ws);
            for obstacle in &scenario.obstacles {
                let clearance = obstacle_distance(&shapes, obstacle) - slack;
                assert!(
                    clearance >= generate::COURSE_CLEARANCE_M,
                    "on the way to {} at {sample:?}: {clearance} m from {}",
                    goal.name,
                    obstacle.name
                );
                worst_obstacle = worst_obstacle.min(clearance);
            }
            worst_floor = worst_floor.min(lowest_point(&shapes) - slack - floor);
        }
        previous = q.clone();
    }
    assert!(worst_floor > 0.0, "the robot dips {worst_floor} m into the floor");
    eprintln!("course: worst obstacle clearance {worst_obstacle:.4} m, floor {worst_floor:.4} m (test sweep)");

    // At the goals, no self-collision between the paper's capsules of non-adjacent links
    // (closed-form point-segment distances on the 0.1 m joint hops). Links 2-4 and 3-5 are
    // joined through a 0.1 m "direct" module, shorter than two capsule radii, so their capsules
    // touch in every configuration: the paper leaves such pairs to the joint design.
    for (goal, q) in scenario.goals.iter().zip(&configurations) {
        robot.forward(q, &mut ws);
        let axis = |link: usize| -> Vec<Vector3<f64>> {
            robot.links[link]
                .segments
                .iter()
                .flat_map(|s| [s.start, s.end])
                .map(|p| ws.link_in_world[link].transform_point(&Point3::from(p)).coords)
                .collect()
        };
        for (i, j) in [(1, 3), (1, 4), (1, 5), (2, 5)] {
            let (a, b) = (axis(i), axis(j));
            // Sample link i's axis finely and measure closed-form to each segment of link j.
            let mut nearest = f64::INFINITY;
            for pair in a.chunks(2) {
                for k in 0..=200 {
                    let p = pair[0] + (pair[1] - pair[0]) * (k as f64 / 200.0);
                    for other in b.chunks(2) {
                        nearest = nearest.min(point_segment(&p, &other[0], &other[1]));
                    }
                }
            }
            let length = a.chunks(2).map(|pair| (pair[1] - pair[0]).norm()).fold(0.0, f64::max);
            let clearance = nearest - length / 200.0 / 2.0 - 2.0 * PAPER_CAPSULE_RADIUS_M;
            assert!(clearance > 0.0, "{}: links {i} and {j}: {clearance} m", goal.name);
        }
        for (i, j) in [(2, 4), (3, 5)] {
            let hop = (ws.link_in_world[i + 1].translation.vector - ws.link_in_world[j].translation.vector).norm();
            assert!(
                hop < 2.0 * PAPER_CAPSULE_RADIUS_M,
                "links {i} and {j} are {hop} m apart: not a structural pair"
            );
        }
    }
}

#[test]
fn course_obstacles_are_in_the_way_of_a_careless_path() {
    let robot = paper_robot();
    let scenario = load_committed(Path::new("scenarios/course.json"));
    let configurations = generate::course_configurations();
    let mut ws = robot.workspace();
    for (region, obstacle) in scenario.obstacles.iter().enumerate() {
        let (first, last) = (
            region * generate::COURSE_GOALS_PER_REGION,
            (region + 1) * generate::COURSE_GOALS_PER_REGION - 1,
        );
        // Moving the tool in a straight line between the two low goals that open and close a
        // region, instead of over the obstacle, runs the tool link through it.
        let (a, b) = (scenario.goals[first].position, scenario.goals[last].position);
        let line = Capsule::new(parry_vector(&a), parry_vector(&b), PAPER_CAPSULE_RADIUS_M);
        let pose = shape_pose(&obstacle.world_from_shape, &obstacle.shape);
        let gap = parry3d_f64::query::distance(
            &parry_pose(&Isometry3::identity()),
            &line,
            &pose,
            parry_shape(&obstacle.shape).as_ref(),
        )
        .expect("supported pair")
        .distance;
        assert_eq!(gap, 0.0, "{}: the straight tool line keeps {gap} m", obstacle.name);
        // For the box and the post, even the straight joint-space path between those goals does
        // (the ball's region changes IK branch over its top, so its shortcut swings elsewhere).
        if obstacle.name != "ball" {
            let mut nearest = f64::INFINITY;
            for i in 0..=200 {
                let s = i as f64 / 200.0;
                let sample: Vec<f64> = configurations[first]
                    .iter()
                    .zip(&configurations[last])
                    .map(|(p, q)| p + (q - p) * s)
                    .collect();
                robot.forward(&sample, &mut ws);
                nearest = nearest.min(obstacle_distance(&link_shapes(&robot, &ws), obstacle));
            }
            assert_eq!(nearest, 0.0, "{}: the direct joint path keeps {nearest} m", obstacle.name);
        }
    }
}

#[test]
fn rejects_duplicate_obstacle_names() {
    let stderr = error_for("duplicate_obstacle_names.json");
    assert!(
        stderr.contains("obstacles[1].name: `ball` is already the name of another obstacle"),
        "{stderr}"
    );
}

#[test]
fn rejects_an_obstacle_named_like_a_robot_link() {
    let name = "obstacle_named_like_a_link.json";
    let output = validate_design()
        .args(["designs/paper-real-world.json", "--engines", "none", "--scenario"])
        .arg(fixture(&format!("scenarios/{name}")))
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("`obstacles[0].name` is `link2`, the name of a link of paper-real-world"),
        "{stderr}"
    );
}
