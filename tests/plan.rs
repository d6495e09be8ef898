//! The plan stage: certified continuous collision checking of joint-space segments, and the
//! trajectory through a course.

mod common;

use common::repo;
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use proving_ground::collide::{self, Body, CollideOptions};
use proving_ground::model::{Collider, Joint, JointKind, Link, Model, ModelSource, Shape};
use proving_ground::pipeline::{collision_world, load_model, LoadOptions};
use proving_ground::plan::{CertifyOptions, MotionBounds, SegmentChecker, TOUCH_TOLERANCE_M};
use proving_ground::scenario::{generate, Obstacle, Scenario};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const WAND_RADIUS_M: f64 = 0.002;
const WAND_LENGTH_M: f64 = 1.0;

/// A fixed base and one link turning about z: a rod of radius 2 mm from the axis out to 1 m along
/// the link's x axis, in the plane z = 0.
fn wand() -> Model {
    let rod = Collider {
        link_from_shape: Isometry3::from_parts(
            Translation3::new(WAND_LENGTH_M / 2.0, 0.0, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2),
        ),
        shape: Shape::Cylinder {
            radius: WAND_RADIUS_M,
            length: WAND_LENGTH_M,
        },
        label: "rod".into(),
    };
    let link = |name: &str, colliders: Vec<Collider>| Link {
        name: name.into(),
        merged: vec![],
        colliders,
        inertial: None,
        segments: vec![],
    };
    Model {
        name: "wand".into(),
        source: ModelSource::Design {
            mode: "free".into(),
            choices: vec![],
        },
        world_from_base: Isometry3::identity(),
        joints: vec![Joint {
            name: "turn".into(),
            kind: JointKind::Revolute,
            parent_from_joint: Isometry3::identity(),
            axis: Unit::new_normalize(Vector3::z()),
            limits: Some([-3.0, 3.0]),
            max_velocity: None,
            max_effort: None,
        }],
        links: vec![
            link("base", vec![]),
            // A moving link needs mass for a full validation's torque check (`Error::NoMass`).
            Link {
                inertial: Some(proving_ground::model::Inertial::solid_cylinder(0.5, WAND_RADIUS_M, WAND_LENGTH_M)),
                ..link("rod", vec![rod])
            },
        ],
        last_from_tool: Isometry3::identity(),
        diagnostics: vec![],
    }
}

fn with_obstacles(obstacles: Vec<Obstacle>) -> Scenario {
    Scenario {
        name: "test".into(),
        world_from_base: Isometry3::identity(),
        floor: None,
        obstacles,
        goals: vec![],
        home: None,
        provenance: None,
        notes: Vec::new(),
    }
}

fn ball(name: &str, position: Vector3<f64>, radius: f64) -> Obstacle {
    Obstacle {
        name: name.into(),
        world_from_shape: Isometry3::translation(position.x, position.y, position.z),
        shape: Shape::Sphere { radius },
    }
}

#[test]
fn a_thin_obstacle_between_samples_is_missed_by_fixed_steps_and_caught_by_the_certified_check() {
    let model = wand();
    // A 2 mm ball 0.9 m out at 0.01 rad: midway between the samples of a sweep from -1 to 1 rad
    // at 10 steps (0.2 rad apart) and at 100 steps (0.02 rad apart), 9 mm beside the rod there.
    let angle: f64 = 0.01;
    let scenario = with_obstacles(vec![ball("pin", Vector3::new(0.9 * angle.cos(), 0.9 * angle.sin(), 0.0), 0.002)]);
    let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("valid");
    let mut checker = SegmentChecker::new(&model, &world, CertifyOptions::default());
    let (from, to) = ([-1.0], [1.0]);
    for samples in [10, 100] {
        let sampled = checker.sampled_clearance(&from, &to, samples);
        assert!(sampled > 0.004, "{samples} steps: {sampled}");
    }
    let check = checker.check(&from, &to);
    assert!(!check.free, "{check:?}");
    let touch = check.touch.expect("stops at the pin");
    assert_eq!((touch.a.as_str(), touch.b.as_str()), ("rod", "pin"));
    // It stops where the rod's side reaches the pin: 4 mm of gap at 0.9 m before 0.01 rad.
    let expected_angle = angle - (0.004f64 / 0.9).asin();
    let stopped_angle = -1.0 + 2.0 * touch.s;
    assert!((stopped_angle - expected_angle).abs() < 1e-5, "{stopped_angle} vs {expected_angle}");
    assert!(touch.distance_m <= TOUCH_TOLERANCE_M && touch.distance_m > -1e-9, "{touch:?}");
    assert!(check.certified_clearance_m <= touch.distance_m);
}

#[test]
fn grazing_contact_ends_at_the_threshold_in_few_steps() {
    let model = wand();
    // Balls above the rod's plane, tangent to the swept rod (4 mm centre height), 10 nm above
    // tangency (within the touch tolerance), and 1 mm above.
    for (lift, touches) in [(0.0, true), (1e-8, true), (1e-3, false)] {
        let height = 2.0 * WAND_RADIUS_M + lift;
        let scenario = with_obstacles(vec![ball("cap", Vector3::new(0.0, 0.7, height), WAND_RADIUS_M)]);
        let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("valid");
        let mut checker = SegmentChecker::new(&model, &world, CertifyOptions::default());
        let check = checker.check(&[0.0], &[3.0]);
        assert_eq!(!check.free, touches, "lift {lift}: {check:?}");
        // Near tangency the clearance falls quadratically while the bound is linear, so the steps
        // shrink harmonically: 266 queries to reach the 1 um tolerance at exact tangency.
        assert!(check.queries < 1000, "lift {lift}: {} queries", check.queries);
        if touches {
            let touch = check.touch.expect("touch reported");
            // Stopped on the approach, within the tolerance of tangency, before 90 degrees.
            assert!(touch.distance_m <= TOUCH_TOLERANCE_M, "{touch:?}");
            assert!(-1.0 + touch.s * 3.0 < std::f64::consts::FRAC_PI_2);
        } else {
            let closest = check.closest.clone().expect("measured");
            assert!(
                check.certified_clearance_m > 0.0 && check.certified_clearance_m <= closest.distance_m,
                "{check:?}"
            );
            assert!(closest.distance_m < lift + 1e-3, "{closest:?}");
        }
    }
}

/// A straight segment that is free but keeps less than the planner's room is its fallback when
/// no detour with room is found (here: no samples at all), and a blocked one reports where it
/// stops.
#[test]
fn a_free_grazing_straight_segment_is_the_fallback_and_a_blocked_one_says_where_it_stops() {
    use proving_ground::plan::{Planner, RrtConnect, ROOM_M};
    let model = wand();
    for (lift, free) in [(1e-3, true), (0.0, false)] {
        assert!(lift < ROOM_M);
        let scenario = with_obstacles(vec![ball("cap", Vector3::new(0.0, 0.7, 2.0 * WAND_RADIUS_M + lift), WAND_RADIUS_M)]);
        let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("valid");
        let mut checker = SegmentChecker::new(&model, &world, CertifyOptions::default());
        let mut planner = RrtConnect {
            limits: vec![None],
            budget: 0,
            straight_attempts: 1,
        };
        let result = planner.connect(&mut checker, &[0.0], &[vec![3.0]], 0);
        if free {
            let path = result.expect("the grazing straight segment");
            assert_eq!(path.waypoints, vec![vec![3.0]]);
            assert!(path.segments[0].free && path.segments[0].closest.as_ref().is_some_and(|c| c.distance_m < ROOM_M));
        } else {
            let failure = result.expect_err("blocked");
            let stop = failure.stop.expect("where it stops");
            assert!(stop.distance_m <= TOUCH_TOLERANCE_M, "{stop:?}");
        }
    }
}

#[test]
fn a_safety_margin_is_a_threshold_the_segment_must_keep() {
    let model = wand();
    let scenario = with_obstacles(vec![ball("cap", Vector3::new(0.0, 0.7, 2.0 * WAND_RADIUS_M + 0.01), WAND_RADIUS_M)]);
    let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("valid");
    let free = SegmentChecker::new(&model, &world, CertifyOptions { threshold_m: 0.005 }).check(&[0.0], &[3.0]);
    assert!(free.free && free.certified_clearance_m >= 0.005, "{free:?}");
    let close = SegmentChecker::new(&model, &world, CertifyOptions { threshold_m: 0.02 }).check(&[0.0], &[3.0]);
    assert!(!close.free, "{close:?}");
}

/// Points on a collider to follow: its centre and the ends of its extents along each local axis;
/// for a mesh, up to 64 of its vertices (the bounds measure each point's distance from the
/// joint axes, which a mesh's extreme vertices decide).
fn probe_points(collider: &Collider) -> Vec<Vector3<f64>> {
    if let Shape::Mesh(mesh) = &collider.shape {
        let stride = mesh.vertices.len().div_ceil(64).max(1);
        return mesh
            .vertices
            .iter()
            .step_by(stride)
            .map(|v| (collider.link_from_shape * nalgebra::Point3::from(*v)).coords)
            .collect();
    }
    let extent = match &collider.shape {
        Shape::Sphere { radius } => Vector3::repeat(*radius),
        Shape::Cylinder { radius, length } => Vector3::new(*radius, *radius, length / 2.0),
        Shape::Capsule { radius, length } => Vector3::new(*radius, *radius, length / 2.0 + radius),
        Shape::Box { half_extents } => Vector3::from(*half_extents),
        Shape::Mesh(_) => Vector3::zeros(),
    };
    let mut points = vec![Vector3::zeros()];
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let mut p = Vector3::zeros();
            p[axis] = sign * extent[axis];
            points.push(p);
        }
    }
    points
        .iter()
        .map(|p| collider.link_from_shape * nalgebra::Point3::from(*p))
        .map(|p| p.coords)
        .collect()
}

#[test]
fn motion_bounds_hold_for_every_collider_point_on_random_segments() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut tightest: f64 = 0.0;
    for design in [
        "designs/paper-real-world.json",
        "designs/ur5e.json",
        "designs/free-redundant-7dof.json",
        "designs/economic-scara.json",
        // Meshes whose joint axes run along the links: the bounds' distances from each axis.
        "tests/fixtures/urdf/example-robot-data/robots/ur_description/urdf/ur5_gripper.urdf",
    ] {
        let model = load_model(&repo().join(design), &LoadOptions::default()).expect("loads");
        let bounds = MotionBounds::of(&model);
        let (mut ws0, mut ws1) = (model.workspace(), model.workspace());
        for _ in 0..200 {
            let (q0, q1) = (model.random_configuration(&mut rng), model.random_configuration(&mut rng));
            let delta: Vec<f64> = q0.iter().zip(&q1).map(|(a, b)| b - a).collect();
            let (s0, s1) = (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
            let at = |s: f64| -> Vec<f64> { q0.iter().zip(&delta).map(|(a, d)| a + s * d).collect() };
            model.forward(&at(s0), &mut ws0);
            model.forward(&at(s1), &mut ws1);
            for (k, link) in model.links.iter().enumerate() {
                for collider in &link.colliders {
                    for p in probe_points(collider) {
                        // Against the world (obstacles), and relative to every earlier link.
                        let moved =
                            (ws1.link_in_world[k] * nalgebra::Point3::from(p) - ws0.link_in_world[k] * nalgebra::Point3::from(p)).norm();
                        let bound = bounds.relative_motion(Body::Link(k), Body::Obstacle(0), &delta) * (s1 - s0).abs();
                        assert!(moved <= bound + 1e-12, "{design} link {k}: moved {moved} > bound {bound}");
                        if bound > 0.0 {
                            tightest = tightest.max(moved / bound);
                        }
                        for a in 0..k {
                            let in_a = |ws: &proving_ground::model::KinematicsWorkspace| {
                                ws.link_in_world[a].inverse() * ws.link_in_world[k] * nalgebra::Point3::from(p)
                            };
                            let moved = (in_a(&ws1) - in_a(&ws0)).norm();
                            let bound = bounds.relative_motion(Body::Link(a), Body::Link(k), &delta) * (s1 - s0).abs();
                            assert!(moved <= bound + 1e-12, "{design} links {a}-{k}: moved {moved} > bound {bound}");
                        }
                    }
                }
            }
        }
    }
    // Not vacuous: some point moves by more than a third of its bound.
    assert!(tightest > 0.33, "tightest ratio {tightest}");
}

/// The last link moves with the tool whatever the joints do: its points' displacement between
/// any two configurations stays within the tool's displacement and turn, which is what lets a
/// certificate near a singularity (where no joint motion is bounded) decide a deep contact of
/// the last link with the world.
#[test]
fn the_last_links_motion_is_bounded_by_the_tools() {
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let mut tightest: f64 = 0.0;
    for design in [
        "designs/paper-real-world.json",
        "designs/ur5e.json",
        "designs/free-redundant-7dof.json",
        "tests/fixtures/urdf/example-robot-data/robots/ur_description/urdf/ur5_gripper.urdf",
    ] {
        let model = load_model(&repo().join(design), &LoadOptions::default()).expect("loads");
        let bounds = MotionBounds::of(&model);
        let last = model.links.len() - 1;
        assert!(bounds.tool_rigid_motion(Body::Link(last - 1), Body::Floor, 0.0, 0.0).is_none());
        assert!(bounds.tool_rigid_motion(Body::Link(last), Body::Link(1), 0.0, 0.0).is_none());
        let (mut ws0, mut ws1) = (model.workspace(), model.workspace());
        for _ in 0..300 {
            let q0 = model.random_configuration(&mut rng);
            // Small and large changes alike.
            let scale = [1e-3, 0.1, 3.0][rng.random_range(0..3)];
            let q1: Vec<f64> = q0.iter().map(|a| a + scale * rng.random_range(-1.0..1.0)).collect();
            model.forward(&q0, &mut ws0);
            model.forward(&q1, &mut ws1);
            let (t0, t1) = (ws0.tool_in_world, ws1.tool_in_world);
            let position = (t1.translation.vector - t0.translation.vector).norm();
            let angle = t1.rotation.angle_to(&t0.rotation);
            let bound = bounds
                .tool_rigid_motion(Body::Link(last), Body::Obstacle(0), position, angle)
                .expect("the last link");
            for collider in &model.links[last].colliders {
                for p in probe_points(collider) {
                    let at = |ws: &proving_ground::model::KinematicsWorkspace| ws.link_in_world[last] * nalgebra::Point3::from(p);
                    let moved = (at(&ws1) - at(&ws0)).norm();
                    assert!(moved <= bound + 1e-12, "{design}: moved {moved} > bound {bound}");
                    if bound > 0.0 {
                        tightest = tightest.max(moved / bound);
                    }
                }
            }
        }
    }
    assert!(tightest > 0.5, "tightest ratio {tightest}");
}

/// The paper's robot placed on the course (the generated one), with its collision world.
fn paper_robot_on_the_course() -> (Scenario, Model, collide::CollisionWorld) {
    let model = load_model(&repo().join("designs/paper-real-world.json"), &LoadOptions::default()).expect("loads");
    let scenario = generate::course(generate::COURSE_SEED);
    let placed = model.placed(&scenario.world_from_base);
    let world = collision_world(&placed, &scenario, &[]).expect("builds");
    (scenario, placed, world)
}

#[test]
fn the_course_tour_is_certified_free_and_the_certificate_is_below_every_sample() {
    let (_, placed, world) = paper_robot_on_the_course();
    let mut checker = SegmentChecker::new(&placed, &world, CertifyOptions::default());
    let mut previous = generate::COURSE_HOME.to_vec();
    let mut queries = 0;
    for (goal, q) in generate::course_configurations().into_iter().enumerate() {
        let check = checker.check(&previous, &q);
        assert!(check.free, "segment to goal {goal}: {check:?}");
        let sampled = checker.sampled_clearance(&previous, &q, 100);
        assert!(
            check.certified_clearance_m > 0.0 && check.certified_clearance_m <= sampled + 1e-12,
            "goal {goal}: {check:?} vs {sampled}"
        );
        queries += check.queries;
        previous = q;
    }
    assert!(queries < 5000, "{queries} queries for the tour");
}

/// Each kind's certified bound (obstacles, self, floor) is below that kind's exact clearance at
/// 50 samples of every segment of the course tour, and the lowest kind is the whole bound.
#[test]
fn each_kind_of_pair_has_a_certified_bound_below_its_sampled_clearance() {
    let (_, placed, world) = paper_robot_on_the_course();
    let mut checker = SegmentChecker::new(&placed, &world, CertifyOptions::default());
    let every_pair = collide::QueryOptions {
        margin: f64::INFINITY,
        ..Default::default()
    };
    let (mut out, mut ws) = (collide::Distances::new(), placed.workspace());
    let mut previous = generate::COURSE_HOME.to_vec();
    for (goal, q) in generate::course_configurations().into_iter().enumerate() {
        let check = checker.check(&previous, &q);
        let bound = check.certified_by_kind;
        let kinds = |k: collide::ClearanceByKind| [k.obstacles_m, k.self_m, k.floor_m];
        let lowest = kinds(bound).into_iter().flatten().fold(f64::INFINITY, f64::min);
        assert_eq!(lowest, check.certified_clearance_m, "goal {goal}: {bound:?}");
        for i in 0..=50 {
            let s = f64::from(i) / 50.0;
            let at: Vec<f64> = previous.iter().zip(&q).map(|(a, b)| a + s * (b - a)).collect();
            placed.forward(&at, &mut ws);
            collide::distances(&world, &ws.link_in_world, &every_pair, &mut out);
            let sampled = collide::ClearanceByKind::of(&out);
            for (kind, (b, x)) in kinds(bound).into_iter().zip(kinds(sampled)).enumerate() {
                let (b, x) = (b.expect("every kind is checked on the course"), x.expect("measured"));
                assert!(b <= x + 1e-12, "goal {goal}, kind {kind}, s = {s}: bound {b} m, sampled {x} m");
            }
        }
        previous = q;
    }
}

/// `keeps_room` stops early but answers as `roomy_free` does, on short random segments of a mesh
/// robot among obstacles (free with room, free but grazing, and colliding ones) and of a design.
#[test]
fn keeps_room_answers_as_roomy_free() {
    let fixtures = repo().join("tests/fixtures/urdf");
    let robots = [
        (
            fixtures.join("example-robot-data/robots/ur_description/urdf/ur5_gripper.urdf"),
            "scenarios/cluttered/task-00.json",
        ),
        (repo().join("designs/modular-elbow.json"), "scenarios/cluttered/task-06.json"),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for (robot, scenario) in robots {
        let model = load_model(&robot, &LoadOptions::default()).expect("loads");
        let scenario = proving_ground::scenario::load(&repo().join(scenario)).expect("loads");
        let placed = model.placed(&scenario.world_from_base);
        let world = collision_world(&placed, &scenario, &[]).expect("builds");
        let mut checker = SegmentChecker::new(&placed, &world, CertifyOptions::default());
        let (mut kept, mut refused) = (0, 0);
        for segment in 0..60 {
            let from = placed.random_configuration(&mut rng);
            let to: Vec<f64> = from.iter().map(|x| x + rng.random_range(-0.4..0.4)).collect();
            let room = [0.002, 0.02, 0.05][segment % 3];
            let (expected, _) = checker.roomy_free(&from, &to, room);
            assert_eq!(
                checker.keeps_room(&from, &to, room),
                expected,
                "{}: segment {segment}",
                robot.display()
            );
            kept += usize::from(expected);
            refused += usize::from(!expected);
        }
        assert!(kept >= 5 && refused >= 5, "{}: {kept} kept, {refused} refused", robot.display());
    }
}

// ---------------------------------------------------------------------------------------------
// Trajectory

use proving_ground::ik::{solve_goals, IkOptions};
use proving_ground::plan::{
    home_configuration, nearest_equivalent, plan, GoalStep, PlanError, PlannerKind, PlannerOptions, TrajectoryOptions,
};
use proving_ground::scenario::{Goal, Tolerance};

/// The wand with its tool at the rod's tip.
fn wand_with_tip() -> Model {
    let mut model = wand();
    model.last_from_tool = Isometry3::translation(WAND_LENGTH_M, 0.0, 0.0);
    model
}

fn position_goal(name: &str, x: f64, y: f64) -> Goal {
    Goal {
        name: name.into(),
        position: Vector3::new(x, y, 0.0),
        rotation: UnitQuaternion::identity(),
        tolerance: Tolerance::Position,
        task: None,
    }
}

#[test]
fn the_paper_robot_tours_the_course_with_every_segment_certified() {
    let (scenario, placed, world) = paper_robot_on_the_course();
    let solutions = solve_goals(&placed, &scenario, Some(&world), &IkOptions::default());
    let trajectory = plan(&placed, &scenario, &world, &solutions, &TrajectoryOptions::default()).expect("plans");
    assert_eq!(trajectory.home, generate::COURSE_HOME.to_vec());
    assert_eq!(
        trajectory.reached(),
        36,
        "{:?}",
        trajectory
            .steps
            .iter()
            .filter(|s| !matches!(s, GoalStep::Reached { .. }))
            .collect::<Vec<_>>()
    );
    for step in &trajectory.steps {
        let GoalStep::Reached { segments, q, goal, .. } = step else {
            unreachable!()
        };
        for segment in segments {
            assert!(segment.free && segment.certified_clearance_m > 0.0, "goal {goal}: {segment:?}");
        }
        let error = proving_ground::ik::goal_error(&scenario.goals[*goal], &placed.tool_pose(q));
        assert!(
            error.position_m < 1e-3 && error.orientation_rad < 1f64.to_radians(),
            "goal {goal}: {error:?}"
        );
    }
    // The timed reference rests at every goal, in course order.
    let holds = trajectory.timed.holds();
    assert_eq!(holds.iter().map(|h| h.goal).collect::<Vec<_>>(), (0..36).collect::<Vec<_>>());
    assert!(
        trajectory.tool_path_m > 1.0 && trajectory.joint_length > 1.0,
        "{} {}",
        trajectory.tool_path_m,
        trajectory.joint_length
    );
}

#[test]
fn a_goal_in_a_closed_pocket_is_no_path_naming_the_pair_and_the_tour_goes_on_from_the_last_reached_configuration() {
    let model = wand_with_tip();
    // Goal "left" needs +90 degrees (its other turn, -270, is beyond the -3 rad limit) and a pin
    // at +45 degrees stands in the way; goal "right" at -90 degrees is clear from home.
    let mut scenario = with_obstacles(vec![ball("pin", Vector3::new(0.5 * 0.5f64.sqrt(), 0.5 * 0.5f64.sqrt(), 0.0), 0.01)]);
    scenario.goals = vec![position_goal("left", 0.0, 1.0), position_goal("right", 0.0, -1.0)];
    let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("valid");
    let solutions = solve_goals(&model, &scenario, Some(&world), &IkOptions::default());
    assert!(solutions.iter().all(|s| s.reached()), "IK reaches both goals: {solutions:?}");
    // The pocket [pi/4, 3] is closed off: the pin on one side, the joint limit on the other.
    for kind in [PlannerKind::Straight, PlannerKind::RrtConnect] {
        let opts = TrajectoryOptions {
            planner: PlannerOptions {
                kind,
                budget: 500,
                seed: 0,
            },
            ..Default::default()
        };
        let trajectory = plan(&model, &scenario, &world, &solutions, &opts).expect("plans");
        let GoalStep::NoPath {
            tried,
            stop,
            budget,
            samples,
            ..
        } = &trajectory.steps[0]
        else {
            panic!("{kind:?}: left must have no path: {:?}", trajectory.steps[0])
        };
        match kind {
            PlannerKind::Straight => assert_eq!((*tried, *budget, *samples), (1, 0, 0)),
            PlannerKind::RrtConnect => assert_eq!((*budget, *samples), (500, 500), "the budget is spent and named"),
        }
        let stop = stop.as_ref().expect("the blocking pair");
        assert_eq!((stop.a.as_str(), stop.b.as_str()), ("rod", "pin"));
        assert!(stop.q[0] > 0.0 && stop.q[0] < std::f64::consts::FRAC_PI_4, "{stop:?}");
        let GoalStep::Reached { q, segments, .. } = &trajectory.steps[1] else {
            panic!("right must be reached: {:?}", trajectory.steps[1])
        };
        // From home (0), not from the goal without a path.
        assert!(
            (q[0] + std::f64::consts::FRAC_PI_2).abs() < 1e-3 && segments.iter().all(|s| s.free),
            "{q:?}"
        );
        assert_eq!(trajectory.timed.holds().len(), 1);
    }
}

#[test]
fn home_defaults_to_zero_or_mid_range_and_a_wrong_home_is_an_error() {
    let mut model = wand();
    let mut scenario = with_obstacles(vec![]);
    assert_eq!(home_configuration(&model, &scenario).expect("default"), [0.0]);
    model.joints[0].limits = Some([0.5, 1.5]);
    assert_eq!(home_configuration(&model, &scenario).expect("mid-range"), [1.0]);
    scenario.home = Some(vec![1.0, 2.0]);
    let error = home_configuration(&model, &scenario).expect_err("two values");
    assert!(matches!(error, PlanError::HomeLength { found: 2, dof: 1, .. }), "{error}");
    scenario.home = Some(vec![2.0]);
    let message = home_configuration(&model, &scenario).expect_err("outside").to_string();
    assert!(
        message.contains("home[0]") && message.contains("turn") && message.contains("[0.5, 1.5]"),
        "{message}"
    );
}

#[test]
fn equivalent_angles_are_the_nearest_whole_turn_within_limits() {
    let mut model = wand();
    model.joints[0].limits = Some([-7.0, 7.0]);
    let near = nearest_equivalent(&model, &[0.1], &[6.0]);
    assert!((near[0] - (0.1 + std::f64::consts::TAU)).abs() < 1e-12, "{near:?}");
    // Beyond the limits the angle stays as it is.
    model.joints[0].limits = Some([-3.0, 3.0]);
    assert_eq!(nearest_equivalent(&model, &[0.1], &[6.0]), [0.1]);
}

#[test]
fn a_default_home_in_collision_is_replaced_by_the_nearest_free_configuration_but_a_given_one_stays() {
    let model = wand_with_tip();
    // A ball on the rod at zero; the goal at +90 degrees is clear.
    let mut scenario = with_obstacles(vec![ball("block", Vector3::new(0.5, 0.0, 0.0), 0.05)]);
    scenario.goals = vec![position_goal("left", 0.0, 1.0)];
    let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("valid");
    let solutions = solve_goals(&model, &scenario, Some(&world), &IkOptions::default());
    let trajectory = plan(&model, &scenario, &world, &solutions, &TrajectoryOptions::default()).expect("plans");
    let reason = trajectory.home_replaced.as_deref().expect("replaced");
    assert!(reason.contains("is in collision (rod and block"), "{reason}");
    // The nearest free turn: the ball (0.05 m at 0.5 m) plus the rod's 2 mm and 1 cm to spare.
    let home = trajectory.home[0];
    assert!(home.abs() > (0.062f64 / 0.5).asin() && home.abs() < 0.3, "{home}");
    assert!(trajectory.home_clearance.as_ref().is_some_and(|c| c.distance_m > 0.01));
    assert_eq!(trajectory.reached(), 1);

    scenario.home = Some(vec![0.0]);
    let trajectory = plan(&model, &scenario, &world, &solutions, &TrajectoryOptions::default()).expect("plans");
    assert!(trajectory.home_replaced.is_none() && trajectory.home == [0.0]);
    assert!(trajectory.home_clearance.as_ref().is_some_and(|c| c.distance_m < 0.0));
    assert_eq!(trajectory.reached(), 0);
}

#[test]
fn a_default_home_clear_of_contact_but_inside_the_margin_is_called_that_not_in_collision() {
    let model = wand_with_tip();
    // The ball's surface 7 cm from the rod's axis at zero: clear, but not by a 10 cm margin.
    let mut scenario = with_obstacles(vec![ball("block", Vector3::new(0.5, 0.12, 0.0), 0.05)]);
    scenario.goals = vec![position_goal("left", 0.0, -1.0)];
    let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("valid");
    let solutions = solve_goals(&model, &scenario, Some(&world), &IkOptions::default());
    let mut opts = TrajectoryOptions::default();
    opts.certify.threshold_m = 0.1;
    let trajectory = plan(&model, &scenario, &world, &solutions, &opts).expect("plans");
    let reason = trajectory.home_replaced.as_deref().expect("replaced");
    assert!(
        reason.contains("keeps less than the margin (margin 100.0 mm) (rod and block at +"),
        "{reason}"
    );
    assert!(!reason.contains("in collision ("), "{reason}");
}

// ---------------------------------------------------------------------------------------------
// Planner: detours, outcomes, determinism

use proving_ground::pipeline::{validate, Loaded, ValidateOptions};

/// A planar arm of two 0.5 m DH tubes (0.12 m across) turning about z, joint 1 limited to half a
/// turn each way so that the only way from +x to +y is the short way round.
fn planar_arm() -> Model {
    let text = r#"{"mode": "free", "joints": [
        {"d": 0, "a": 0.5, "alpha": 0, "limits": [-3.1, 3.1]},
        {"d": 0, "a": 0.5, "alpha": 0, "limits": [-3.1, 3.1]}]}"#;
    let design = proving_ground::design::parse(text, std::path::Path::new("planar.json")).expect("valid design");
    proving_ground::model::from_design(&design)
}

/// From the arm stretched along +x to stretched along +y, with a ball on the 45 degree line at
/// 0.8 m: the straight joint-space segment sweeps the stretched arm through it; folding the
/// elbow while passing it is a way round.
fn wall_scenario() -> Scenario {
    let mut scenario = with_obstacles(vec![ball(
        "wall",
        Vector3::new(0.8 * 0.5f64.sqrt(), 0.8 * 0.5f64.sqrt(), 0.0),
        0.05,
    )]);
    scenario.goals = vec![position_goal("x", 1.0, 0.0), position_goal("y", 0.0, 1.0)];
    scenario.home = Some(vec![0.0, 0.0]);
    scenario
}

#[test]
fn a_wall_the_straight_segment_crosses_is_routed_around_with_every_edge_certified() {
    let model = planar_arm();
    let scenario = wall_scenario();
    let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("valid");
    let solutions = solve_goals(&model, &scenario, Some(&world), &IkOptions::default());
    assert!(solutions.iter().all(|s| s.reached()), "IK reaches both goals: {solutions:?}");

    let straight = TrajectoryOptions {
        planner: PlannerOptions {
            kind: PlannerKind::Straight,
            ..Default::default()
        },
        ..Default::default()
    };
    let trajectory = plan(&model, &scenario, &world, &solutions, &straight).expect("plans");
    assert!(
        matches!(&trajectory.steps[1], GoalStep::NoPath { stop: Some(stop), .. } if stop.b == "wall"),
        "the paper's heuristic is stopped by the wall: {:?}",
        trajectory.steps[1]
    );

    let trajectory = plan(&model, &scenario, &world, &solutions, &TrajectoryOptions::default()).expect("plans");
    let GoalStep::Reached {
        waypoints, segments, q, ..
    } = &trajectory.steps[1]
    else {
        panic!("the planner routes around the wall: {:?}", trajectory.steps[1])
    };
    assert!(segments.len() > 1, "a detour has more than one edge: {waypoints:?}");
    assert_eq!(waypoints.last(), Some(q));
    // Every edge certified, and checked again here by a fresh checker, and sampled densely.
    let mut checker = SegmentChecker::new(&model, &world, CertifyOptions::default());
    let mut from = match &trajectory.steps[0] {
        GoalStep::Reached { q, .. } => q.clone(),
        other => panic!("goal x is reached: {other:?}"),
    };
    for (to, segment) in waypoints.iter().zip(segments) {
        assert!(segment.free && segment.certified_clearance_m > 0.0, "{segment:?}");
        assert!(checker.check(&from, to).free, "{from:?} -> {to:?}");
        assert!(checker.sampled_clearance(&from, to, 2000) > 0.0, "{from:?} -> {to:?}");
        from.clone_from(to);
    }
    let error = proving_ground::ik::goal_error(&scenario.goals[1], &model.tool_pose(q));
    assert!(error.position_m < 1e-3, "{error:?}");
    // The engines follow the whole path: one timed edge per waypoint, a rest at each goal only.
    let edges: usize = trajectory
        .steps
        .iter()
        .map(|s| match s {
            GoalStep::Reached { segments, .. } => segments.len(),
            _ => 0,
        })
        .sum();
    assert_eq!(trajectory.timed.segments.len(), edges);
    assert_eq!(trajectory.timed.holds().iter().map(|h| h.goal).collect::<Vec<_>>(), [0, 1]);
    assert!(trajectory.joint_length <= trajectory.joint_length_before_shortcut + 1e-12);
    let replayed = proving_ground::plan::replay_segments(&trajectory);
    assert_eq!(replayed.len(), edges);
}

fn report_of(model: Model, scenario: Scenario, opts: &ValidateOptions) -> proving_ground::report::Report {
    let loaded = Loaded { model, design: None };
    let validation = validate(loaded, scenario, opts).expect("runs");
    proving_ground::report::build(&validation)
}

fn kinematic() -> ValidateOptions {
    ValidateOptions {
        engines: proving_ground::pipeline::Engines::none(),
        ..Default::default()
    }
}

#[test]
fn a_goal_inside_a_closed_box_is_unreachable_and_proven_and_one_beyond_reach_too() {
    let mut scenario = wall_scenario();
    scenario.obstacles = vec![Obstacle {
        name: "crate".into(),
        world_from_shape: Isometry3::translation(0.0, 0.8, 0.0),
        shape: Shape::Box {
            half_extents: [0.1, 0.1, 0.1],
        },
    }];
    scenario.goals = vec![position_goal("in the crate", 0.0, 0.8), position_goal("too far", 1.2, 0.0)];
    let report = report_of(planar_arm(), scenario, &kinematic());
    for goal in &report.goals {
        assert_eq!(goal.outcome, "unreachable", "{goal:?}");
    }
    let crate_proof = report.goals[0].proven.as_deref().expect("proven");
    assert!(
        crate_proof.contains("inside crate") && crate_proof.contains("link2"),
        "{crate_proof}"
    );
    let reach_proof = report.goals[1].proven.as_deref().expect("proven");
    assert!(reach_proof.contains("1.200 m") && reach_proof.contains("1.000 m"), "{reach_proof}");
    assert_eq!(report.verdict.reasons, ["2 goals unreachable (proven)"]);
}

#[test]
fn the_verdict_names_the_budget_of_a_goal_without_a_path() {
    let mut scenario = with_obstacles(vec![ball("pin", Vector3::new(0.5 * 0.5f64.sqrt(), 0.5 * 0.5f64.sqrt(), 0.0), 0.01)]);
    scenario.goals = vec![position_goal("left", 0.0, 1.0)];
    let opts = ValidateOptions {
        planner: PlannerOptions {
            budget: 300,
            ..Default::default()
        },
        ..kinematic()
    };
    let report = report_of(wand_with_tip(), scenario, &opts);
    assert_eq!(report.goals[0].outcome, "no_path");
    assert_eq!(report.verdict.reasons, ["1 goal without a path found in 300 samples"]);
    let trajectory = report.trajectory.as_ref().expect("a trajectory");
    assert_eq!((trajectory.no_path, trajectory.segments[0].samples), (1, 300));
}

#[test]
fn reach_only_runs_no_trajectory_and_says_so() {
    let opts = ValidateOptions {
        reach_only: true,
        ..kinematic()
    };
    let report = report_of(planar_arm(), wall_scenario(), &opts);
    assert_eq!(report.criteria.mode, "reach_only");
    assert!(report.trajectory.is_none() && report.engines.is_empty() && report.static_load.is_none());
    assert!(report.goals.iter().all(|g| g.outcome == "reached"), "{:?}", report.goals);
    assert!(report.verdict.passed);
}

#[test]
fn planned_detours_are_byte_identical_on_one_and_on_two_threads() {
    let design = repo().join("designs/ur10e.json");
    let scenario = proving_ground::scenario::load(&repo().join("scenarios/cluttered/task-00.json")).expect("task loads");
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        pool.install(|| {
            let loaded = proving_ground::pipeline::load(&design, &LoadOptions::default()).expect("loads");
            let validation = validate(loaded, scenario.clone(), &kinematic()).expect("runs");
            serde_json::to_string_pretty(&proving_ground::report::build(&validation)).expect("serialises")
        })
    };
    let first = run(1);
    assert!(
        first.contains("\"edges\": 2") || first.contains("\"edges\": 3"),
        "the run has detours"
    );
    assert_eq!(first, run(2), "one thread and two threads differ");
}
