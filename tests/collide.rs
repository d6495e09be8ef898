//! The collision stage against independent oracles: closed-form distances, parry called directly
//! on every collider pair (no broad phase), and MuJoCo's `mj_geomDistance`.

mod common;

use common::{panda_urdf, repo};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use parry3d_f64::query;
use parry3d_f64::shape::{Ball, Capsule, Cylinder, Segment as Segment3, SharedShape};
use proving_ground::collide::{
    self, approximate_distances, compare, distances, ApproximationFinding, Body, CollideError, CollideOptions, CollisionFinding, Distances,
    ExcludedPair, PairDistance, QueryOptions,
};
use proving_ground::engine::MujocoGeomDistance;
use proving_ground::frames::{parry_pose, parry_vector, wxyz, xyz};
use proving_ground::model::{Collider, Link, Model, ModelSource, Segment, Shape, TriMesh, PAPER_CAPSULE_RADIUS_M};
use proving_ground::pipeline::{load_model, LoadOptions};
use proving_ground::scenario::{Floor, Obstacle, Scenario};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::PathBuf;

/// Exact shapes against their closed forms. Worst measured: 8e-16 (spheres, boxes, capsules,
/// parallel cylinders), 6e-11 (crossed cylinders: GJK, then alternating projections until the
/// supporting planes certify the gap to 1e-10 m).
const CLOSED_FORM_M: f64 = 1e-9;
/// EPA depth of two overlapping cylinders: EPA refines a polytope inside a curved surface; worst
/// measured 3e-10.
const PENETRATION_DEPTH_M: f64 = 1e-9;
/// Our closed-form capsule distances against parry's closed-form segment distance minus the
/// radii; worst measured 5e-16.
const CAPSULE_AGREEMENT_M: f64 = 1e-9;
/// Branch and bound against each collider pair measured alone: the same narrow phase on poses
/// composed in another order (EPA turns 1e-16 into 3e-10 on overlapping cylinders); worst
/// measured 3e-10.
const BRUTE_FORCE_M: f64 = 1e-9;
/// parry's own GJK on `Capsule` and `Cylinder` shapes stops early; it was up to 1.3e-5 m off.
const PARRY_GJK_M: f64 = 5e-5;
/// MuJoCo's `mj_geomDistance` against ours for spheres, capsules and boxes; worst measured 7e-16.
const MUJOCO_AGREEMENT_M: f64 = 1e-6;
const SEED: u64 = 3;

// ---------------------------------------------------------------------------------------------
// Builders

fn design(name: &str) -> Model {
    let path = repo().join("designs").join(name);
    load_model(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn collider(pose: Isometry3<f64>, shape: Shape) -> Collider {
    Collider {
        link_from_shape: pose,
        shape,
        label: "probe".into(),
    }
}

/// A robot of one fixed link carrying `colliders` and `segments`; its pairs are base-obstacle pairs.
fn one_link(colliders: Vec<Collider>, segments: Vec<Segment>) -> Model {
    Model {
        name: "probe".into(),
        source: ModelSource::Design {
            mode: "free".into(),
            choices: vec![],
        },
        world_from_base: Isometry3::identity(),
        joints: vec![],
        links: vec![Link {
            name: "body".into(),
            merged: vec![],
            colliders,
            inertial: None,
            segments,
        }],
        last_from_tool: Isometry3::identity(),
        diagnostics: vec![],
    }
}

fn obstacle(name: &str, pose: Isometry3<f64>, shape: Shape) -> Obstacle {
    Obstacle {
        name: name.into(),
        world_from_shape: pose,
        shape,
    }
}

fn scenario(obstacles: Vec<Obstacle>, floor: Option<f64>) -> Scenario {
    Scenario {
        name: "test".into(),
        world_from_base: Isometry3::identity(),
        floor: floor.map(|height| Floor { height }),
        obstacles,
        goals: vec![],
        home: None,
        provenance: None,
        notes: Vec::new(),
    }
}

/// The exact closest pair of shape `a` (on the link) and shape `b` (an obstacle).
fn exact_pair(a: &Shape, pose_a: Isometry3<f64>, b: &Shape, pose_b: Isometry3<f64>) -> PairDistance {
    let model = one_link(vec![collider(pose_a, a.clone())], vec![]);
    let world = collide::world(
        &model,
        &scenario(vec![obstacle("b", pose_b, b.clone())], None),
        &CollideOptions::default(),
    )
    .expect("valid shapes");
    let mut out = Distances::new();
    distances(&world, &[Isometry3::identity()], &QueryOptions::default(), &mut out);
    out.closest.expect("one pair is checked")
}

fn random_rotation(rng: &mut ChaCha8Rng) -> UnitQuaternion<f64> {
    let axis = Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    UnitQuaternion::from_scaled_axis(axis * std::f64::consts::PI)
}

fn random_pose(rng: &mut ChaCha8Rng, reach: f64) -> Isometry3<f64> {
    let t = Translation3::new(
        rng.random_range(-reach..reach),
        rng.random_range(-reach..reach),
        rng.random_range(-reach..reach),
    );
    Isometry3::from_parts(t, random_rotation(rng))
}

/// Asserts the witness data of a measured pair is consistent: unit normal, `b - a` along it by
/// the signed distance for a gap.
fn assert_witnesses(pair: &PairDistance, context: &str) {
    assert!((pair.normal.norm() - 1.0).abs() < 1e-9, "{context}: normal {}", pair.normal);
    if pair.distance > 1e-9 {
        let between = pair.point_b - pair.point_a;
        assert!(
            (between - pair.normal * pair.distance).norm() < 1e-7,
            "{context}: witnesses {} -> {} do not span the distance {} along {}",
            pair.point_a,
            pair.point_b,
            pair.distance,
            pair.normal
        );
    }
}

/// Tracks the worst error of a check and prints it, so the tolerances above stay honest.
struct Worst(&'static str, f64);

impl Worst {
    fn check(&mut self, error: f64, tolerance: f64, context: impl FnOnce() -> String) {
        assert!(error <= tolerance, "{}: error {error} > {tolerance}: {}", self.0, context());
        self.1 = self.1.max(error);
    }
}

impl Drop for Worst {
    fn drop(&mut self) {
        eprintln!("{}: worst error {:e}", self.0, self.1);
    }
}

// ---------------------------------------------------------------------------------------------
// Closed forms

#[test]
fn sphere_sphere_distance_and_depth_match_the_closed_form() {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut worst = Worst("sphere-sphere", 0.0);
    for sample in 0..500 {
        let (ra, rb) = (rng.random_range(0.01..0.3), rng.random_range(0.01..0.3));
        let (pa, pb) = (random_pose(&mut rng, 0.4), random_pose(&mut rng, 0.4));
        let pair = exact_pair(&Shape::Sphere { radius: ra }, pa, &Shape::Sphere { radius: rb }, pb);
        let centres = pb.translation.vector - pa.translation.vector;
        let expected = centres.norm() - ra - rb;
        let context = || format!("seed {SEED} sample {sample}: radii {ra} {rb}, centres {pa} {pb}");
        worst.check((pair.distance - expected).abs(), CLOSED_FORM_M, context);
        worst.check((pair.point_a - pa.translation.vector).norm() - ra, CLOSED_FORM_M, context);
        worst.check((pair.normal - centres.normalize()).norm(), CLOSED_FORM_M, context);
        assert_witnesses(&pair, &context());
    }
}

#[test]
fn sphere_cylinder_distance_matches_the_closed_form_beside_beyond_and_at_the_rim() {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut worst = Worst("sphere-cylinder", 0.0);
    let (radius, length, ball) = (0.1, 0.4, 0.05);
    let cylinder = Shape::Cylinder { radius, length };
    for sample in 0..600 {
        // Sphere centre in cylinder coordinates: rho from the axis, z along it.
        let angle = rng.random_range(0.0..std::f64::consts::TAU);
        let (rho, z, expected) = match sample % 4 {
            0 => {
                let (rho, z) = (rng.random_range(0.11..0.5), rng.random_range(-0.19..0.19));
                (rho, z, rho - radius - ball)
            }
            1 => {
                let (rho, z) = (rng.random_range(0.0..0.099), rng.random_range(0.21..0.6));
                (rho, z, z - length / 2.0 - ball)
            }
            2 => {
                let (rho, z) = (rng.random_range(0.11..0.5), -rng.random_range(0.21..0.6));
                (rho, z, (rho - radius).hypot(-z - length / 2.0) - ball)
            }
            _ => {
                // Centre inside, nearer the side than the caps: the depth is to the side.
                let (rho, z) = (rng.random_range(0.05..0.099), rng.random_range(-0.1..0.1));
                (rho, z, -(radius - rho) - ball)
            }
        };
        let pose = random_pose(&mut rng, 0.5);
        let centre = pose * Point3::new(rho * angle.cos(), rho * angle.sin(), z);
        let sphere_pose = Isometry3::from_parts(centre.into(), random_rotation(&mut rng));
        let context = || format!("seed {SEED} sample {sample}: rho {rho} z {z} cylinder at {pose}");
        // Both ways round: the cylinder on the link, then the sphere on the link.
        let pair = exact_pair(&cylinder, pose, &Shape::Sphere { radius: ball }, sphere_pose);
        worst.check((pair.distance - expected).abs(), CLOSED_FORM_M, context);
        assert_witnesses(&pair, &context());
        let pair = exact_pair(&Shape::Sphere { radius: ball }, sphere_pose, &cylinder, pose);
        worst.check((pair.distance - expected).abs(), CLOSED_FORM_M, context);
        assert!(
            ((pair.point_a - centre.coords).norm() - ball).abs() < CLOSED_FORM_M,
            "{}",
            context()
        );
    }
}

#[test]
fn parallel_cylinders_are_apart_by_axis_distance_minus_radii() {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut worst = Worst("parallel cylinders", 0.0);
    let mut depth = Worst("parallel cylinders, penetration", 0.0);
    for sample in 0..300 {
        let (ra, rb) = (rng.random_range(0.03..0.1), rng.random_range(0.03..0.1));
        let (la, lb) = (rng.random_range(0.3..0.6), rng.random_range(0.3..0.6));
        // Axes parallel, offset across them, z ranges overlapping by a good part.
        let offset = if sample % 3 == 0 {
            rng.random_range(0.6..0.95) * (ra + rb)
        } else {
            rng.random_range(1.05..4.0) * (ra + rb)
        };
        let angle = rng.random_range(0.0..std::f64::consts::TAU);
        let shift = rng.random_range(-0.05..0.05);
        let frame = random_pose(&mut rng, 0.5);
        let spin = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), rng.random_range(0.0..6.0));
        let pose_b = frame * Isometry3::from_parts(Translation3::new(offset * angle.cos(), offset * angle.sin(), shift), spin);
        let pair = exact_pair(
            &Shape::Cylinder { radius: ra, length: la },
            frame,
            &Shape::Cylinder { radius: rb, length: lb },
            pose_b,
        );
        let expected = offset - ra - rb;
        let context = || format!("seed {SEED} sample {sample}: radii {ra} {rb}, offset {offset}");
        if expected < 0.0 {
            assert!(pair.distance < 0.0, "{}", context());
            depth.check((pair.distance - expected).abs(), PENETRATION_DEPTH_M, context);
        } else {
            worst.check((pair.distance - expected).abs(), CLOSED_FORM_M, context);
            assert_witnesses(&pair, &context());
        }
    }
}

#[test]
fn crossed_cylinders_are_apart_by_height_minus_radii() {
    // Axes perpendicular, one above the other: both closest points are on curved sides, where
    // GJK converges slowest.
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut worst = Worst("crossed cylinders", 0.0);
    for sample in 0..300 {
        let (ra, rb) = (rng.random_range(0.03..0.1), rng.random_range(0.03..0.1));
        let height = ra + rb + rng.random_range(0.0001..0.3);
        let frame = random_pose(&mut rng, 0.5);
        let along_x = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
        let along_y = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2);
        let (sx, sy) = (rng.random_range(-0.1..0.1), rng.random_range(-0.1..0.1));
        let pose_a = frame * Isometry3::from_parts(Translation3::new(0.0, sy, 0.0), along_x);
        let pose_b = frame * Isometry3::from_parts(Translation3::new(sx, 0.0, height), along_y);
        let pair = exact_pair(
            &Shape::Cylinder { radius: ra, length: 0.5 },
            pose_a,
            &Shape::Cylinder { radius: rb, length: 0.5 },
            pose_b,
        );
        let context = || format!("seed {SEED} sample {sample}: radii {ra} {rb}, height {height}");
        worst.check((pair.distance - (height - ra - rb)).abs(), CLOSED_FORM_M, context);
        assert_witnesses(&pair, &context());
    }
}

#[test]
fn box_sphere_distance_matches_the_closed_form_at_faces_edges_and_corners() {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut worst = Worst("box-sphere", 0.0);
    let half = [0.2, 0.1, 0.05];
    let ball = 0.04;
    for sample in 0..600 {
        // Per axis: inside the slab, or outside it by a gap.
        let outside = match sample % 4 {
            0 => [true, false, false],
            1 => [false, true, true],
            2 => [true, true, true],
            _ => [false, false, false],
        };
        let mut local = [0.0_f64; 3];
        let mut gaps = [0.0_f64; 3];
        for axis in 0..3 {
            let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            if outside[axis] {
                gaps[axis] = rng.random_range(0.001..0.3);
                local[axis] = sign * (half[axis] + gaps[axis]);
            } else {
                local[axis] = sign * rng.random_range(0.0..half[axis] * 0.9);
            }
        }
        let expected = if outside.iter().any(|&o| o) {
            (gaps[0] * gaps[0] + gaps[1] * gaps[1] + gaps[2] * gaps[2]).sqrt() - ball
        } else {
            // Inside: the depth is to the nearest face.
            -(0..3).map(|a| half[a] - local[a].abs()).fold(f64::INFINITY, f64::min) - ball
        };
        let pose = random_pose(&mut rng, 0.5);
        let centre = pose * Point3::from(Vector3::from(local));
        let sphere = Isometry3::from_parts(centre.into(), UnitQuaternion::identity());
        let pair = exact_pair(&Shape::Box { half_extents: half }, pose, &Shape::Sphere { radius: ball }, sphere);
        let context = || format!("seed {SEED} sample {sample}: local centre {local:?}, box at {pose}");
        worst.check((pair.distance - expected).abs(), CLOSED_FORM_M, context);
        assert_witnesses(&pair, &context());
    }
}

#[test]
fn capsule_capsule_distance_of_skew_segments_matches_the_closed_form() {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut worst = Worst("capsule-capsule", 0.0);
    for sample in 0..400 {
        let (ra, rb) = (rng.random_range(0.02..0.1), rng.random_range(0.02..0.1));
        let (la, lb): (f64, f64) = (rng.random_range(0.2..0.8), rng.random_range(0.2..0.8));
        let height = rng.random_range(0.0..0.5);
        // Segment a along x, centred at the origin; segment b along a direction in the plane
        // z = height. Interior case: b crosses above a's interior, so the closest points are
        // on the common perpendicular. End case: b is shifted past a's end along x.
        let interior = sample % 2 == 0;
        let angle: f64 = rng.random_range(0.3..2.8);
        let along = if interior {
            rng.random_range(-0.3..0.3) * la
        } else {
            la / 2.0 + rng.random_range(0.05..0.3)
        };
        let direction = Vector3::new(angle.cos(), angle.sin(), 0.0);
        let centre_b = Vector3::new(along, 0.0, height);
        let expected = if interior {
            height - ra - rb
        } else {
            // a's end (la/2, 0, 0) against b's line: x = along + s cos, y = s sin.
            let end = Vector3::new(la / 2.0, 0.0, 0.0);
            let s = ((end - centre_b).dot(&direction)).clamp(-lb / 2.0, lb / 2.0);
            (centre_b + direction * s - end).norm() - ra - rb
        };
        if !interior {
            // The closest point on a must really be its end: b's closest point lies past it.
            let end = Vector3::new(la / 2.0, 0.0, 0.0);
            let s = ((end - centre_b).dot(&direction)).clamp(-lb / 2.0, lb / 2.0);
            if (centre_b + direction * s).x < la / 2.0 {
                continue;
            }
        }
        let frame = random_pose(&mut rng, 0.5);
        let lay_along_x = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
        let lay_along_b = UnitQuaternion::rotation_between(&Vector3::z(), &direction).expect("not opposite");
        let pose_a = frame * Isometry3::from_parts(Translation3::identity(), lay_along_x);
        let pose_b = frame * Isometry3::from_parts(centre_b.into(), lay_along_b);
        let pair = exact_pair(
            &Shape::Capsule { radius: ra, length: la },
            pose_a,
            &Shape::Capsule { radius: rb, length: lb },
            pose_b,
        );
        let context = || format!("seed {SEED} sample {sample}: interior {interior}, height {height}, along {along}, angle {angle}");
        worst.check((pair.distance - expected).abs(), CLOSED_FORM_M, context);
        assert_witnesses(&pair, &context());
    }
}

#[test]
fn penetration_is_negative_and_the_normal_points_from_a_to_b() {
    let sphere = Shape::Sphere { radius: 0.1 };
    let pair = exact_pair(&sphere, Isometry3::identity(), &sphere, Isometry3::translation(0.15, 0.0, 0.0));
    assert!((pair.distance + 0.05).abs() < 1e-15, "{pair:?}");
    assert!((pair.normal - Vector3::x()).norm() < 1e-15, "{pair:?}");
    assert!((pair.point_a - Vector3::new(0.1, 0.0, 0.0)).norm() < 1e-15, "{pair:?}");
    assert!((pair.point_b - Vector3::new(0.05, 0.0, 0.0)).norm() < 1e-15, "{pair:?}");

    let block = Shape::Box { half_extents: [0.1; 3] };
    let pair = exact_pair(&block, Isometry3::identity(), &block, Isometry3::translation(0.0, 0.0, -0.17));
    assert!((pair.distance + 0.03).abs() < 1e-12, "{pair:?}");
    assert!((pair.normal + Vector3::z()).norm() < 1e-12, "{pair:?}");
}

#[test]
fn floor_is_the_half_space_below_its_height() {
    let model = one_link(
        vec![collider(
            Isometry3::translation(0.0, 0.0, 0.3),
            Shape::Cylinder { radius: 0.1, length: 0.4 },
        )],
        vec![],
    );
    // The base against the floor is excluded; a link above it is what matters, so lift the body
    // by making it a second link.
    let mut model = model;
    model.links.insert(0, model.links[0].clone());
    model.links[0].name = "base".into();
    model.links[0].colliders.clear();
    model.joints.push(proving_ground::model::Joint {
        name: "lift".into(),
        kind: proving_ground::model::JointKind::Prismatic,
        parent_from_joint: Isometry3::identity(),
        axis: Vector3::z_axis(),
        limits: Some([0.0, 1.0]),
        max_velocity: None,
        max_effort: None,
    });
    let world = collide::world(&model, &scenario(vec![], Some(0.05)), &CollideOptions::default()).expect("valid");
    assert!(world.excluded().iter().any(|e| e.a == "base" && e.b == "floor"));
    let mut out = Distances::new();
    let mut ws = model.workspace();
    for (lift, expected) in [(0.0, 0.05), (-0.2, -0.15)] {
        model.forward(&[lift], &mut ws);
        distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut out);
        let closest = out.closest.expect("link-floor pair");
        assert_eq!(closest.b.body, Body::Floor);
        assert!((closest.distance - expected).abs() < 1e-12, "lift {lift}: {closest:?}");
        assert!((closest.normal + Vector3::z()).norm() < 1e-12);
        // The link has no capsule: the pair is checked but has nothing to measure in that model.
        approximate_distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut out);
        assert!(out.closest.is_none() && out.estimates[0].distance == f64::INFINITY, "{out:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// The approximate model

/// parry's signed distances between two capsules: its closed-form segment-segment distance minus
/// the radii (a capsule is its segment grown by the radius), and its `contact` of two `Capsule`
/// shapes (or a ball for a zero-length segment), which runs GJK.
fn parry_capsules(a: [Vector3<f64>; 2], ra: f64, b: [Vector3<f64>; 2], rb: f64) -> (f64, f64) {
    let segment = |[s, e]: [Vector3<f64>; 2]| Segment3::new(parry_vector(&s), parry_vector(&e));
    let identity = parry_pose(&Isometry3::identity());
    let axes = query::distance(&identity, &segment(a), &identity, &segment(b))
        .expect("supported")
        .distance;
    let shape = |[s, e]: [Vector3<f64>; 2], r: f64| -> SharedShape {
        if (e - s).norm() == 0.0 {
            SharedShape::new(Ball::new(r))
        } else {
            SharedShape::new(Capsule::new(parry_vector(&Vector3::zeros()), parry_vector(&(e - s)), r))
        }
    };
    let pose = |[s, _]: [Vector3<f64>; 2]| parry_pose(&Isometry3::translation(s.x, s.y, s.z));
    let gjk = query::contact(&pose(a), &*shape(a, ra), &pose(b), &*shape(b, rb), f64::MAX)
        .expect("supported")
        .expect("unbounded prediction")
        .dist;
    (axes - ra - rb, gjk)
}

#[test]
fn approximate_distances_equal_parry_capsules() {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut worst = Worst("closed-form capsules vs parry segments minus radii", 0.0);
    let mut gjk = Worst("closed-form capsules vs parry Capsule (GJK), apart", 0.0);
    let mut gjk_depth = 0.0_f64;
    for name in ["paper-real-world.json", "economic-spherical-wrist.json", "ur5e.json"] {
        let model = design(name);
        let obstacles: Vec<Obstacle> = (0..6)
            .map(|k| {
                let pose = random_pose(&mut rng, 0.7);
                let shape = if k % 2 == 0 {
                    Shape::Sphere { radius: 0.1 }
                } else {
                    Shape::Capsule { radius: 0.05, length: 0.3 }
                };
                obstacle(&format!("o{k}"), pose, shape)
            })
            .collect();
        let scenario = scenario(obstacles.clone(), None);
        let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("valid");
        let mut ws = model.workspace();
        let mut out = Distances::new();
        // A margin beyond any distance here reports every pair.
        let everything = QueryOptions {
            margin: 100.0,
            hulls: true,
            exact_depth: true,
            mesh_hulls: false,
        };
        for sample in 0..100 {
            let q = model.random_configuration(&mut rng);
            model.forward(&q, &mut ws);
            approximate_distances(&world, &ws.link_in_world, &everything, &mut out);
            assert_eq!(out.within_margin.len(), world.pairs().len());
            let segments = |link: usize| -> Vec<[Vector3<f64>; 2]> {
                let pose = ws.link_in_world[link];
                model.links[link]
                    .segments
                    .iter()
                    .map(|s| [(pose * Point3::from(s.start)).coords, (pose * Point3::from(s.end)).coords])
                    .collect()
            };
            for pair in &out.within_margin {
                let Body::Link(a) = pair.a.body else { panic!("a is a link") };
                let others: Vec<([Vector3<f64>; 2], f64)> = match pair.b.body {
                    Body::Link(b) => segments(b).into_iter().map(|s| (s, PAPER_CAPSULE_RADIUS_M)).collect(),
                    Body::Obstacle(k) => {
                        let o = &obstacles[k];
                        let centre = o.world_from_shape.translation.vector;
                        match o.shape {
                            Shape::Sphere { radius } => vec![([centre, centre], radius)],
                            Shape::Capsule { radius, length } => {
                                let half = o.world_from_shape.rotation * Vector3::new(0.0, 0.0, length / 2.0);
                                vec![([centre - half, centre + half], radius)]
                            }
                            _ => unreachable!("spheres and capsules only"),
                        }
                    }
                    Body::Floor => unreachable!("no floor"),
                };
                let (expected, by_gjk) = segments(a)
                    .into_iter()
                    .flat_map(|s| others.iter().map(move |&(o, r)| parry_capsules(s, PAPER_CAPSULE_RADIUS_M, o, r)))
                    .fold((f64::INFINITY, f64::INFINITY), |(x, y), (d, g)| (x.min(d), y.min(g)));
                let context = || format!("{name} seed {SEED} sample {sample} q {q:?}: {pair:?}");
                worst.check((pair.distance - expected).abs(), CAPSULE_AGREEMENT_M, context);
                if expected > 0.0 {
                    gjk.check((pair.distance - by_gjk).abs(), PARRY_GJK_M, context);
                } else {
                    gjk_depth = gjk_depth.max((pair.distance - by_gjk).abs());
                }
                assert_witnesses(pair, name);
            }
        }
    }
    eprintln!("closed-form capsules vs parry Capsule (EPA), overlapping: worst difference {gjk_depth:e}");
}

#[test]
fn capsule_against_a_box_is_measured_by_parry_and_against_the_floor_in_closed_form() {
    let segment = Segment {
        start: Vector3::new(0.0, 0.0, 0.5),
        end: Vector3::new(0.0, 0.0, 0.9),
    };
    let mut model = one_link(vec![], vec![segment]);
    model.links.insert(
        0,
        Link {
            name: "base".into(),
            merged: vec![],
            colliders: vec![],
            inertial: None,
            segments: vec![],
        },
    );
    model.joints.push(proving_ground::model::Joint {
        name: "spin".into(),
        kind: proving_ground::model::JointKind::Revolute,
        parent_from_joint: Isometry3::identity(),
        axis: Vector3::z_axis(),
        limits: Some([-1.0, 1.0]),
        max_velocity: None,
        max_effort: None,
    });
    let table = obstacle(
        "table",
        Isometry3::translation(0.0, 0.0, 0.2),
        Shape::Box {
            half_extents: [0.3, 0.3, 0.1],
        },
    );
    let world = collide::world(&model, &scenario(vec![table], Some(-0.1)), &CollideOptions::default()).expect("valid");
    let mut ws = model.workspace();
    model.forward(&[0.3], &mut ws);
    let mut out = Distances::new();
    approximate_distances(
        &world,
        &ws.link_in_world,
        &QueryOptions {
            margin: 10.0,
            hulls: true,
            exact_depth: true,
            mesh_hulls: false,
        },
        &mut out,
    );
    let to = |body: Body| out.within_margin.iter().find(|p| p.b.body == body).expect("reported").distance;
    assert!((to(Body::Obstacle(0)) - (0.5 - 0.06 - 0.3)).abs() < 1e-9, "{out:?}");
    assert!((to(Body::Floor) - (0.5 - 0.06 + 0.1)).abs() < 1e-15, "{out:?}");
}

#[test]
fn capsules_contain_plain_tubes_so_the_approximation_is_never_unsafe_for_them() {
    // UR5e: tubes of radius 0.06 on exactly the capsule segments, no joint housings; a capsule
    // contains its tube, so its signed distance can only be smaller.
    let model = design("ur5e.json");
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let obstacles = (0..8)
        .map(|k| obstacle(&format!("o{k}"), random_pose(&mut rng, 0.6), Shape::Sphere { radius: 0.1 }))
        .collect();
    let world = collide::world(&model, &scenario(obstacles, Some(-0.05)), &CollideOptions::default()).expect("valid");
    let (mut exact, mut approx) = (Distances::new(), Distances::new());
    let mut ws = model.workspace();
    let mut unsafe_findings = 0;
    let mut conservative = 0;
    for sample in 0..300 {
        let q = model.random_configuration(&mut rng);
        model.forward(&q, &mut ws);
        distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut exact);
        approximate_distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut approx);
        for (e, a) in exact.estimates.iter().zip(&approx.estimates) {
            assert!(
                a.distance <= e.distance + PENETRATION_DEPTH_M || !e.exact,
                "sample {sample} q {q:?}: capsules {a:?} farther than tubes {e:?}"
            );
        }
        for finding in compare(&exact, &approx, 1e-9) {
            match finding {
                ApproximationFinding::UnsafeApproximation { .. } => unsafe_findings += 1,
                ApproximationFinding::ConservativeApproximation {
                    exact_distance,
                    approximate_distance,
                    ..
                } => {
                    assert!(approximate_distance <= 0.0 && exact_distance > 0.0);
                    conservative += 1;
                }
            }
        }
    }
    assert_eq!(unsafe_findings, 0);
    eprintln!("ur5e: {conservative} conservative findings in 300 configurations");
}

#[test]
fn joint_housings_outside_the_capsules_make_unsafe_findings() {
    // A modular robot's joint housing (a 0.12 x 0.12 m cylinder centred on the joint) reaches
    // 0.06 m behind the joint, where the capsule of the tube starting there ends in a hemisphere:
    // the housing's rim is outside the capsule. A sphere touching just that rim collides exactly
    // and is free for the capsules.
    let model = design("modular-elbow.json");
    let mut ws = model.workspace();
    model.forward(&vec![0.0; model.dof()], &mut ws);
    let link = 2;
    let housing = ws.link_in_world[link] * Point3::new(0.06, 0.0, -0.06);
    let outward = (ws.link_in_world[link].rotation * Vector3::new(1.0, 0.0, -1.0)).normalize();
    let centre = housing + outward * (0.02 - 0.005);
    let ball = obstacle(
        "pebble",
        Isometry3::translation(centre.x, centre.y, centre.z),
        Shape::Sphere { radius: 0.02 },
    );
    let world = collide::world(&model, &scenario(vec![ball], None), &CollideOptions::default()).expect("valid");
    let (mut exact, mut approx) = (Distances::new(), Distances::new());
    distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut exact);
    approximate_distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut approx);
    let findings = compare(&exact, &approx, 1e-9);
    assert!(
        findings.iter().any(|f| matches!(f,
            ApproximationFinding::UnsafeApproximation { a: Body::Link(2), b: Body::Obstacle(0), exact_distance, approximate_distance, .. }
                if *exact_distance < 0.0 && *approximate_distance > 0.0)),
        "{findings:?}\nexact {:?}\napprox {:?}",
        exact.closest,
        approx.closest
    );
}

// ---------------------------------------------------------------------------------------------
// Broad phase and branch and bound against brute force

/// parry's shape for a model collider and its pose in the link frame, derived here from the
/// shape conventions, not taken from the world.
fn parry_collider(c: &Collider) -> (Isometry3<f64>, SharedShape) {
    match c.shape {
        Shape::Sphere { radius } => (c.link_from_shape, SharedShape::new(Ball::new(radius))),
        Shape::Cylinder { radius, length } => {
            let y_to_z = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2);
            (c.link_from_shape * y_to_z, SharedShape::new(Cylinder::new(length / 2.0, radius)))
        }
        _ => unreachable!("designs have spheres and cylinders"),
    }
}

#[test]
fn clear_agrees_with_the_closest_pair_against_the_margin() {
    // A DH design among spheres, a box and a cylinder over the floor, and the Panda's meshes among
    // the same: `clear` must say what comparing `distances`' closest pair with the margin says.
    let panda = load_model(&panda_urdf(), &LoadOptions::default()).expect("the Panda loads");
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut obstacles: Vec<Obstacle> = (0..3)
        .map(|k| {
            let centre = Isometry3::translation(rng.random_range(-0.6..0.6), rng.random_range(-0.6..0.6), rng.random_range(0.0..0.9));
            obstacle(
                &format!("o{k}"),
                centre,
                Shape::Sphere {
                    radius: rng.random_range(0.03..0.08),
                },
            )
        })
        .collect();
    obstacles.push(obstacle(
        "box",
        random_pose(&mut rng, 0.7),
        Shape::Box {
            half_extents: [0.05, 0.1, 0.03],
        },
    ));
    obstacles.push(obstacle(
        "can",
        random_pose(&mut rng, 0.7),
        Shape::Cylinder {
            radius: 0.03,
            length: 0.15,
        },
    ));
    for model in [design("modular-elbow.json"), design("free-offset-6dof.json"), panda] {
        // With the structural exclusions and allowances, as every validation builds it.
        let world = proving_ground::pipeline::collision_world(&model, &scenario(obstacles.clone(), Some(-0.3)), &[]).expect("valid");
        let mut ws = model.workspace();
        let (mut out, mut scratch) = (Distances::new(), Distances::new());
        let mut outcomes = [0usize; 2];
        for sample in 0..600 {
            let q = model.random_configuration(&mut rng);
            model.forward(&q, &mut ws);
            for margin in [0.0, 0.03] {
                let query = QueryOptions {
                    margin,
                    hulls: false,
                    exact_depth: false,
                    mesh_hulls: false,
                };
                distances(&world, &ws.link_in_world, &query, &mut out);
                let expected = out.closest.is_none_or(|c| c.distance > margin);
                let got = collide::clear(&world, &ws.link_in_world, margin, &mut scratch);
                assert_eq!(
                    got, expected,
                    "{} sample {sample} margin {margin} q {q:?}: closest {:?}",
                    model.name, out.closest
                );
                outcomes[usize::from(got)] += 1;
            }
        }
        // Both answers occur, or the comparison proves little.
        assert!(outcomes.iter().all(|&n| n > 50), "{}: {outcomes:?} {:?}", model.name, out.closest);
    }
}

#[test]
fn branch_and_bound_finds_the_same_closest_pair_and_closest_of_each_kind_as_brute_force() {
    let model = design("modular-elbow.json");
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let obstacles: Vec<Obstacle> = (0..8)
        .map(|k| {
            let centre = Isometry3::translation(
                rng.random_range(-0.8..0.8),
                rng.random_range(-0.8..0.8),
                rng.random_range(-0.2..1.0),
            );
            obstacle(
                &format!("o{k}"),
                centre,
                Shape::Sphere {
                    radius: rng.random_range(0.05..0.15),
                },
            )
        })
        .collect();
    let world = collide::world(&model, &scenario(obstacles.clone(), None), &CollideOptions::default()).expect("valid");
    let parry_colliders: Vec<Vec<(Isometry3<f64>, SharedShape)>> = model
        .links
        .iter()
        .map(|l| l.colliders.iter().map(parry_collider).collect())
        .collect();
    let near_margin = 0.05;
    let margin = QueryOptions {
        margin: near_margin,
        hulls: true,
        exact_depth: true,
        mesh_hulls: false,
    };
    let (mut contacts, mut near, mut kinds) = (Distances::new(), Distances::new(), Distances::new());
    let mut ws = model.workspace();
    let (mut calls, mut all, mut ties) = (0, 0, 0);
    let mut alone = Worst("brute force: branch and bound vs each collider pair alone", 0.0);
    let mut parry = Worst("brute force: ours vs parry's own contact per collider pair", 0.0);
    for sample in 0..1000 {
        let q = model.random_configuration(&mut rng);
        model.forward(&q, &mut ws);
        distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut contacts);
        distances(&world, &ws.link_in_world, &margin, &mut near);
        let context = || format!("seed {SEED} sample {sample} q {q:?}");

        // Brute force, no broad phase: every collider pair of every checked pair measured on its
        // own (a world of that one pair), and, independently, by parry's `contact` on shapes
        // built here (its GJK stops early on two cylinders; ours is polished, never farther).
        let mut pair_minimum = vec![f64::INFINITY; world.pairs().len()];
        for (index, pair) in world.pairs().iter().enumerate() {
            let Body::Link(a) = pair.a else { panic!("a is a link") };
            let side = |link: usize| -> Vec<(Shape, Isometry3<f64>, Isometry3<f64>, SharedShape)> {
                model.links[link]
                    .colliders
                    .iter()
                    .zip(&parry_colliders[link])
                    .map(|(c, (p, s))| {
                        (
                            c.shape.clone(),
                            ws.link_in_world[link] * c.link_from_shape,
                            ws.link_in_world[link] * p,
                            s.clone(),
                        )
                    })
                    .collect()
            };
            let side_b = match pair.b {
                Body::Link(b) => side(b),
                Body::Obstacle(k) => {
                    let Shape::Sphere { radius } = obstacles[k].shape else {
                        unreachable!()
                    };
                    let pose = obstacles[k].world_from_shape;
                    vec![(obstacles[k].shape.clone(), pose, pose, SharedShape::new(Ball::new(radius)))]
                }
                Body::Floor => unreachable!("no floor"),
            };
            let mut by_parry = f64::INFINITY;
            for (shape_a, pose_a, parry_pose_a, parry_a) in side(a) {
                for (shape_b, pose_b, parry_pose_b, parry_b) in &side_b {
                    let alone = exact_pair(&shape_a, pose_a, shape_b, *pose_b).distance;
                    pair_minimum[index] = pair_minimum[index].min(alone);
                    let contact = query::contact(
                        &parry_pose(&parry_pose_a),
                        &*parry_a,
                        &parry_pose(parry_pose_b),
                        &**parry_b,
                        f64::MAX,
                    )
                    .expect("supported")
                    .expect("unbounded prediction");
                    by_parry = by_parry.min(contact.dist);
                }
            }
            // Poses composed in nalgebra here and in parry there round differently (~1e-16 m),
            // which EPA turns into ~1e-12 m.
            assert!(
                pair_minimum[index] <= by_parry + 1e-9,
                "{}: pair {index}: ours {}, parry {by_parry}",
                context(),
                pair_minimum[index]
            );
            parry.check((pair_minimum[index] - by_parry).abs(), PARRY_GJK_M, context);
        }

        // Each kind's closest by its own branch and bound.
        let by_kind = collide::clearance_by_kind(&world, &ws.link_in_world, &mut kinds);
        let kind_minimum = |obstacles: bool| {
            world
                .pairs()
                .iter()
                .zip(&pair_minimum)
                .filter(|(pair, _)| matches!(pair.b, Body::Obstacle(_)) == obstacles)
                .fold(f64::INFINITY, |a, (_, &d)| a.min(d))
        };
        for (found, expected) in [(by_kind.obstacles_m, kind_minimum(true)), (by_kind.self_m, kind_minimum(false))] {
            alone.check((found.expect("pairs of the kind") - expected).abs(), BRUTE_FORCE_M, context);
        }
        assert_eq!(by_kind.floor_m, None, "{}", context());
        let (best_pair, best) = pair_minimum
            .iter()
            .copied()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("pairs");
        let closest = contacts.closest.expect("pairs are checked");
        alone.check((closest.distance - best).abs(), BRUTE_FORCE_M, context);
        // The design has pairs overlapping by exactly 0.02 m in every configuration (links i and
        // i + 2 around a `direct` slot), so the closest pair may tie to rounding.
        if closest.pair != best_pair {
            assert!(
                (pair_minimum[closest.pair] - best).abs() <= BRUTE_FORCE_M,
                "{}: {closest:?} vs brute force pair {best_pair} at {best}",
                context()
            );
            ties += 1;
        }
        assert_eq!(near.closest, contacts.closest, "{}", context());
        // Every pair within the margin, and nothing else, with the brute-force distance.
        let within: Vec<usize> = near.within_margin.iter().map(|p| p.pair).collect();
        let expected: Vec<usize> = pair_minimum
            .iter()
            .enumerate()
            .filter(|(_, &d)| d <= near_margin)
            .map(|(i, _)| i)
            .collect();
        assert_eq!(within, expected, "{}", context());
        for reported in &near.within_margin {
            alone.check((reported.distance - pair_minimum[reported.pair]).abs(), BRUTE_FORCE_M, context);
        }
        let in_contact: Vec<usize> = contacts.within_margin.iter().map(|p| p.pair).collect();
        let expected: Vec<usize> = pair_minimum.iter().enumerate().filter(|(_, &d)| d <= 0.0).map(|(i, _)| i).collect();
        assert_eq!(in_contact, expected, "{}", context());
        for (estimate, &minimum) in near.estimates.iter().zip(&pair_minimum) {
            if estimate.exact {
                assert!(
                    (estimate.distance - minimum).abs() <= BRUTE_FORCE_M,
                    "{}: {estimate:?} vs {minimum}",
                    context()
                );
            } else {
                assert!(
                    estimate.distance <= minimum && estimate.distance > near_margin,
                    "{}: {estimate:?} vs {minimum}",
                    context()
                );
            }
        }
        for pair in &contacts.within_margin {
            assert_witnesses(pair, &context());
        }
        calls += contacts.narrow_phase_calls;
        all += world.collider_pair_count();
    }
    eprintln!(
        "modular-elbow, 8 spheres: {calls} narrow-phase calls for {all} collider pairs ({:.1}%); {ties} closest pairs tied",
        100.0 * calls as f64 / all as f64
    );
    assert!(calls * 4 < all, "the broad phase should skip most pairs");
}

// ---------------------------------------------------------------------------------------------
// MuJoCo

fn mjcf_geom(name: &str, shape: &Shape, pose: &Isometry3<f64>) -> String {
    let size = match shape {
        Shape::Sphere { radius } => format!(r#"type="sphere" size="{radius}""#),
        Shape::Capsule { radius, length } => format!(r#"type="capsule" size="{radius} {}""#, length / 2.0),
        Shape::Cylinder { radius, length } => format!(r#"type="cylinder" size="{radius} {}""#, length / 2.0),
        Shape::Box { half_extents: [x, y, z] } => format!(r#"type="box" size="{x} {y} {z}""#),
        Shape::Mesh(_) => unreachable!("no meshes here"),
    };
    let [px, py, pz] = xyz(&pose.translation.vector);
    let [w, x, y, z] = wxyz(&pose.rotation);
    format!(r#"<body name="{name}" pos="{px} {py} {pz}" quat="{w} {x} {y} {z}"><geom name="{name}" {size}/></body>"#)
}

fn random_shape(rng: &mut ChaCha8Rng, kind: &str) -> Shape {
    match kind {
        "sphere" => Shape::Sphere {
            radius: rng.random_range(0.03..0.2),
        },
        "capsule" => Shape::Capsule {
            radius: rng.random_range(0.03..0.15),
            length: rng.random_range(0.05..0.4),
        },
        "cylinder" => Shape::Cylinder {
            radius: rng.random_range(0.03..0.15),
            length: rng.random_range(0.05..0.4),
        },
        _ => Shape::Box {
            half_extents: [
                rng.random_range(0.03..0.2),
                rng.random_range(0.03..0.2),
                rng.random_range(0.03..0.2),
            ],
        },
    }
}

/// A polytope grown by a radius: vertices, edge directions and face normals in the world, and
/// the radius.
type Grown = (Vec<Vector3<f64>>, Vec<Vector3<f64>>, Vec<Vector3<f64>>, f64);

/// A box or capsule as a polytope grown by a radius.
fn polytope(shape: &Shape, pose: &Isometry3<f64>) -> Grown {
    let axes: Vec<Vector3<f64>> = [Vector3::x(), Vector3::y(), Vector3::z()]
        .iter()
        .map(|a| pose.rotation * a)
        .collect();
    match *shape {
        Shape::Box { half_extents: [x, y, z] } => {
            let mut vertices = Vec::new();
            for sx in [-x, x] {
                for sy in [-y, y] {
                    for sz in [-z, z] {
                        vertices.push((pose * Point3::new(sx, sy, sz)).coords);
                    }
                }
            }
            (vertices, axes.clone(), axes, 0.0)
        }
        Shape::Capsule { radius, length } => {
            let ends = [-length / 2.0, length / 2.0].map(|z| (pose * Point3::new(0.0, 0.0, z)).coords);
            (ends.to_vec(), vec![axes[2]], vec![], radius)
        }
        _ => unreachable!("boxes and capsules only"),
    }
}

/// Signed distance of a box or capsule against a box, independently of parry: when the polytopes
/// (the box, the capsule's segment) are apart, their distance minimised along the segment (the
/// distance from a point to a box is closed-form and convex along a segment) minus the radius;
/// when they overlap, minus the separating-axis depth.
fn box_signed_distance(a: &Shape, pa: &Isometry3<f64>, b: &Shape, pb: &Isometry3<f64>) -> f64 {
    if let (Shape::Capsule { radius, length }, Shape::Box { half_extents }) = (a, b) {
        let ends = [-length / 2.0, *length / 2.0].map(|z| pb.inverse() * (pa * Point3::new(0.0, 0.0, z)));
        let point_to_box = |t: f64| {
            let p = ends[0].coords * (1.0 - t) + ends[1].coords * t;
            let outside = Vector3::from_fn(|i, _| (p[i].abs() - half_extents[i]).max(0.0));
            outside.norm()
        };
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..200 {
            let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
            if point_to_box(m1) <= point_to_box(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        let apart = point_to_box(lo).min(point_to_box(0.0)).min(point_to_box(1.0));
        if apart > 1e-12 {
            return apart - radius;
        }
    }
    -separating_axis_depth(a, pa, b, pb)
}

/// Penetration depth (minimum translation) of a box or capsule against a box whose polytopes
/// overlap, by the separating axis theorem on the polytopes (the face normals of their Minkowski
/// difference: faces, and cross products of edges), plus the radii.
fn separating_axis_depth(a: &Shape, pa: &Isometry3<f64>, b: &Shape, pb: &Isometry3<f64>) -> f64 {
    let (va, ea, fa, ra) = polytope(a, pa);
    let (vb, eb, fb, rb) = polytope(b, pb);
    let mut axes: Vec<Vector3<f64>> = fa.iter().chain(&fb).copied().collect();
    for e in &ea {
        for f in &eb {
            if let Some(axis) = e.cross(f).try_normalize(1e-9) {
                axes.push(axis);
            }
        }
    }
    let range = |vertices: &[Vector3<f64>], n: &Vector3<f64>| {
        vertices
            .iter()
            .map(|v| v.dot(n))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)))
    };
    axes.iter()
        .map(|n| {
            let ((lo_a, hi_a), (lo_b, hi_b)) = (range(&va, n), range(&vb, n));
            (hi_a - lo_b).min(hi_b - lo_a) + ra + rb
        })
        .fold(f64::INFINITY, f64::min)
}

/// Our exact distance against `mj_geomDistance` on an MJCF holding the same shapes. MuJoCo's
/// capsule-box and box-box colliders are contact generators: in penetration the depth they report
/// is along their contact normal, not the minimum translation, so those depths are checked
/// against the separating axis theorem instead (and MuJoCo's difference is printed).
fn mujoco_agreement(kinds: &[(&str, &str)], samples: usize, tolerance: f64, label: &'static str) {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut cases = Vec::new();
    for &(kind_a, kind_b) in kinds {
        for _ in 0..samples {
            let (a, b) = (random_shape(&mut rng, kind_a), random_shape(&mut rng, kind_b));
            cases.push((a, random_pose(&mut rng, 0.25), b, random_pose(&mut rng, 0.25)));
        }
    }
    let bodies: String = cases
        .iter()
        .enumerate()
        .map(|(i, (a, pa, b, pb))| mjcf_geom(&format!("a{i}"), a, pa) + &mjcf_geom(&format!("b{i}"), b, pb))
        .collect();
    let xml = format!(r#"<mujoco model="pairs"><worldbody>{bodies}</worldbody></mujoco>"#);
    let mujoco = MujocoGeomDistance::from_xml_str(&xml, "pairs").expect("MuJoCo loads the pairs");
    let names: Vec<(String, String)> = (0..cases.len()).map(|i| (format!("a{i}"), format!("b{i}"))).collect();
    let pairs: Vec<(&str, &str)> = names.iter().map(|(a, b)| (a.as_str(), b.as_str())).collect();
    let theirs = mujoco.distances(&pairs, 10.0).expect("geoms exist");
    let mut worst = Worst(label, 0.0);
    let mut by_axes = Worst("capsule-box and box-box overlaps vs an independent oracle", 0.0);
    let mut mujoco_depth = 0.0_f64;
    let (mut separated, mut penetrating) = (0, 0);
    for (i, ((a, pa, b, pb), mj)) in cases.iter().zip(&theirs).enumerate() {
        let ours = exact_pair(a, *pa, b, *pb);
        let context = || format!("seed {SEED} case {i}: {a:?} at {pa} vs {b:?} at {pb}: ours {ours:?}, MuJoCo {mj:?}");
        let generator = matches!((a, b), (Shape::Box { .. } | Shape::Capsule { .. }, Shape::Box { .. }));
        if ours.distance > 0.0 {
            separated += 1;
        } else {
            penetrating += 1;
        }
        if generator && ours.distance <= 0.0 && tolerance <= MUJOCO_AGREEMENT_M {
            by_axes.check(
                (ours.distance - box_signed_distance(a, pa, b, pb)).abs(),
                PENETRATION_DEPTH_M,
                context,
            );
            mujoco_depth = mujoco_depth.max((ours.distance - mj.distance).abs());
            continue;
        }
        worst.check((ours.distance - mj.distance).abs(), tolerance, context);
        if ours.distance > 1e-6 && tolerance <= MUJOCO_AGREEMENT_M {
            // Witnesses of boxes may not be unique (face against face): compare the span only.
            let span = Vector3::from(mj.to) - Vector3::from(mj.from);
            assert!((span.norm() - ours.distance).abs() < tolerance, "{}", context());
        }
    }
    eprintln!("{label}: {separated} separated, {penetrating} penetrating cases; MuJoCo's contact-generator depths differ by up to {mujoco_depth:e}");
}

#[test]
fn mujoco_geom_distance_agrees_on_spheres_capsules_and_boxes() {
    let kinds = [
        ("sphere", "sphere"),
        ("sphere", "capsule"),
        ("capsule", "capsule"),
        ("sphere", "box"),
        ("capsule", "box"),
        ("box", "box"),
    ];
    mujoco_agreement(&kinds, 100, MUJOCO_AGREEMENT_M, "MuJoCo spheres, capsules, boxes");
}

/// MuJoCo has no exact cylinder collider: it runs its general convex solver on cylinders (and on
/// mesh hulls), so cylinder pairs are only checked loosely. Worst measured: see the printed line.
#[test]
fn mujoco_geom_distance_roughly_agrees_on_cylinders() {
    let kinds = [("cylinder", "sphere"), ("cylinder", "box"), ("cylinder", "cylinder")];
    mujoco_agreement(&kinds, 100, 1e-3, "MuJoCo cylinders (loose)");
}

// ---------------------------------------------------------------------------------------------
// Meshes and hulls

/// The U of [`common::u_mesh`] at 0.1 m per unit: 0.3 x 0.3 m in x-y, a notch 0.1 m wide and
/// 0.2 m deep opening towards +y, 0.1 m thick.
fn u_mesh() -> TriMesh {
    common::u_mesh(0.1)
}

#[test]
fn sphere_in_the_opening_of_a_u_is_free_but_its_hull_collides() {
    for (mesh_on_link, pose) in [(true, Isometry3::identity()), (false, Isometry3::translation(0.4, -0.2, 0.1))] {
        let u = Shape::Mesh(u_mesh());
        let centre = pose * Point3::new(0.15, 0.2, 0.05);
        let ball_pose = Isometry3::translation(centre.x, centre.y, centre.z);
        let ball = Shape::Sphere { radius: 0.03 };
        let (model, scenario) = if mesh_on_link {
            (
                one_link(vec![collider(pose, u)], vec![]),
                scenario(vec![obstacle("ball", ball_pose, ball)], None),
            )
        } else {
            (
                one_link(vec![collider(ball_pose, ball)], vec![]),
                scenario(vec![obstacle("u", pose, u)], None),
            )
        };
        let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("valid");
        let mut out = Distances::new();
        distances(&world, &[Isometry3::identity()], &QueryOptions::default(), &mut out);
        let closest = out.closest.expect("one pair");
        assert!((closest.distance - 0.02).abs() < 1e-12, "mesh on link {mesh_on_link}: {closest:?}");
        assert!(!closest.enclosed && out.within_margin.is_empty());
        assert_witnesses(&closest, "u");
        assert_eq!(out.hull_calls, 1);
        match out.findings[..] {
            [CollisionFinding::HullDisagreement {
                pair: 0,
                exact_distance,
                hull_distance,
                ..
            }] => {
                assert!((exact_distance - 0.02).abs() < 1e-12);
                assert!((hull_distance + 0.08).abs() < 1e-9, "{hull_distance}");
            }
            _ => panic!(
                "mesh on link {mesh_on_link}: expected one hull disagreement, got {:?}",
                out.findings
            ),
        }
        let quiet = QueryOptions {
            margin: 0.0,
            hulls: false,
            exact_depth: true,
            mesh_hulls: false,
        };
        distances(&world, &[Isometry3::identity()], &quiet, &mut out);
        assert!(out.findings.is_empty() && out.hull_calls == 0);
    }
}

#[test]
fn sphere_inside_a_closed_mesh_is_enclosed_and_penetrating() {
    // Inside the U's base bar (0.3 x 0.1 x 0.1 m), 0.04 m from its nearest face.
    let model = one_link(vec![collider(Isometry3::identity(), Shape::Mesh(u_mesh()))], vec![]);
    let pebble = obstacle("pebble", Isometry3::translation(0.05, 0.05, 0.05), Shape::Sphere { radius: 0.01 });
    let world = collide::world(&model, &scenario(vec![pebble], None), &CollideOptions::default()).expect("valid");
    let mut out = Distances::new();
    distances(&world, &[Isometry3::identity()], &QueryOptions::default(), &mut out);
    let closest = out.closest.expect("one pair");
    assert!(closest.enclosed, "{closest:?}");
    assert!((closest.distance + 0.04).abs() < 1e-12, "{closest:?}");
    assert_eq!(out.within_margin.len(), 1);
    assert!(out.findings.is_empty(), "the hull agrees: contact");
}

/// A closed cube mesh of edge 1 m centred at the origin, faces outwards.
fn cube_mesh() -> TriMesh {
    let vertices: Vec<[f64; 3]> = (0..8)
        .map(|i| [(i & 1) as f64 - 0.5, ((i >> 1) & 1) as f64 - 0.5, ((i >> 2) & 1) as f64 - 0.5])
        .collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let triangles = quads.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
    TriMesh {
        uri: "cube.stl".into(),
        file: PathBuf::from("cube.stl"),
        scale: [1.0; 3],
        vertices,
        triangles,
    }
}

#[test]
fn bodies_inside_a_closed_mesh_obstacle_are_enclosed_in_both_models() {
    // A box collider and a capsule segment well inside a 1 m cube obstacle.
    let segment = Segment {
        start: Vector3::new(-0.1, 0.0, 0.0),
        end: Vector3::new(0.1, 0.0, 0.0),
    };
    let model = one_link(
        vec![collider(
            Isometry3::identity(),
            Shape::Box {
                half_extents: [0.1, 0.05, 0.05],
            },
        )],
        vec![segment],
    );
    let cube = obstacle("cube", Isometry3::translation(0.05, 0.0, 0.0), Shape::Mesh(cube_mesh()));
    let world = collide::world(&model, &scenario(vec![cube], None), &CollideOptions::default()).expect("valid");
    let mut out = Distances::new();
    distances(&world, &[Isometry3::identity()], &QueryOptions::default(), &mut out);
    let exact = out.closest.expect("one pair");
    // The cube spans x in [-0.45, 0.55]: the box's -x face is 0.35 m from the cube's.
    assert!(exact.enclosed && (exact.distance + 0.35).abs() < 1e-12, "{exact:?}");
    approximate_distances(&world, &[Isometry3::identity()], &QueryOptions::default(), &mut out);
    let approx = out.closest.expect("one pair");
    assert!(approx.enclosed && (approx.distance + (0.35 - 0.06)).abs() < 1e-12, "{approx:?}");
}

#[test]
fn panda_meshes_build_and_branch_and_bound_matches_an_exhaustive_margin() {
    let opts = LoadOptions {
        tip_link: Some("panda_hand".into()),
        ..LoadOptions::default()
    };
    let model = load_model(&panda_urdf(), &opts).expect("the Panda loads");
    let table = obstacle(
        "table",
        Isometry3::translation(0.5, 0.0, 0.2),
        Shape::Box {
            half_extents: [0.2, 0.4, 0.02],
        },
    );
    let post = obstacle(
        "post",
        Isometry3::translation(0.3, 0.3, 0.4),
        Shape::Cylinder { radius: 0.05, length: 0.8 },
    );
    let world = collide::world(&model, &scenario(vec![table, post], Some(0.0)), &CollideOptions::default()).expect("valid");
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut ws = model.workspace();
    let (mut fast, mut exhaustive) = (Distances::new(), Distances::new());
    let everything = QueryOptions {
        margin: 100.0,
        hulls: false,
        exact_depth: true,
        mesh_hulls: false,
    };
    for sample in 0..20 {
        let q = model.random_configuration(&mut rng);
        model.forward(&q, &mut ws);
        distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut fast);
        distances(&world, &ws.link_in_world, &everything, &mut exhaustive);
        assert_eq!(exhaustive.within_margin.len(), world.pairs().len());
        assert!(exhaustive.estimates.iter().all(|e| e.exact));
        let minimum = exhaustive.within_margin.iter().map(|p| p.distance).fold(f64::INFINITY, f64::min);
        let closest = fast.closest.expect("pairs");
        assert_eq!(closest.distance, minimum, "sample {sample} q {q:?}");
        assert_witnesses(&closest, "panda");
    }
}

/// A partial query measures the pairs it must (below their level, or within the margin) exactly
/// as the whole query does, bounds the others it looks at from below, and leaves the rest alone.
#[test]
fn partial_queries_measure_below_each_level_and_bound_the_rest() {
    let model = load_model(&panda_urdf(), &LoadOptions::default()).expect("the Panda loads");
    let table = obstacle(
        "table",
        Isometry3::translation(0.5, 0.0, 0.2),
        Shape::Box {
            half_extents: [0.2, 0.4, 0.02],
        },
    );
    let world = collide::world(&model, &scenario(vec![table], Some(0.0)), &CollideOptions::default()).expect("valid");
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut ws = model.workspace();
    let (mut partial, mut exact) = (Distances::new(), Distances::new());
    let everything = QueryOptions {
        margin: 100.0,
        ..QueryOptions::default()
    };
    let (mut measured, mut bounded, mut skipped) = (0, 0, 0);
    for _ in 0..20 {
        let q = model.random_configuration(&mut rng);
        model.forward(&q, &mut ws);
        distances(&world, &ws.link_in_world, &everything, &mut exact);
        let levels: Vec<Option<f64>> = (0..world.pairs().len())
            .map(|_| match rng.random_range(0..3) {
                0 => None,
                1 => Some(rng.random_range(0.0..0.3)),
                _ => Some(f64::NEG_INFINITY),
            })
            .collect();
        collide::distances_among(&world, &ws.link_in_world, &QueryOptions::default(), Some(&levels), &mut partial);
        for ((level, got), truth) in levels.iter().zip(&partial.estimates).zip(&exact.estimates) {
            match level {
                None => {
                    assert!(got.distance == f64::INFINITY && !got.exact, "{got:?}");
                    skipped += 1;
                }
                Some(level) if truth.distance < *level => {
                    assert!((got.distance - truth.distance).abs() < 1e-9, "{got:?} vs {truth:?}");
                    measured += 1;
                }
                Some(_) => {
                    assert!(got.distance <= truth.distance + 1e-9, "{got:?} vs {truth:?}");
                    bounded += usize::from(got.distance < truth.distance - 1e-6);
                }
            }
        }
        let closest = partial.closest.map(|c| c.distance);
        let smallest_measured = partial
            .within_margin
            .iter()
            .map(|p| p.distance)
            .chain(closest)
            .fold(f64::INFINITY, f64::min);
        assert_eq!(closest.unwrap_or(f64::INFINITY), smallest_measured);
    }
    // Not vacuous: each case happened.
    assert!(measured > 10 && bounded > 10 && skipped > 10, "{measured} {bounded} {skipped}");
}

// ---------------------------------------------------------------------------------------------
// Pairs and exclusions

#[test]
fn excluded_pairs_are_listed_with_reasons_and_bad_names_are_errors() {
    let model = design("modular-elbow.json");
    let obstacles = vec![obstacle(
        "ball",
        Isometry3::translation(0.5, 0.0, 0.5),
        Shape::Sphere { radius: 0.1 },
    )];
    let opts = CollideOptions {
        excluded_pairs: vec![ExcludedPair::new("link4", "link2", "never in contact (SRDF)")],
        ..Default::default()
    };
    let world = collide::world(&model, &scenario(obstacles.clone(), Some(0.0)), &opts).expect("valid");
    for (i, joint) in model.joints.iter().enumerate() {
        let (a, b) = (&model.links[i].name, &model.links[i + 1].name);
        let excluded = world
            .excluded()
            .iter()
            .find(|e| &e.a == a && &e.b == b)
            .unwrap_or_else(|| panic!("{a}-{b} not listed"));
        assert!(
            excluded.reason.contains(&format!("joined by joint `{}`", joint.name)),
            "{excluded:?}"
        );
    }
    assert!(world
        .excluded()
        .contains(&ExcludedPair::new("link2", "link4", "never in contact (SRDF)")));
    let checked = |a: &str, b: &str| world.pairs().iter().any(|p| p.a_name == a && p.b_name == b);
    assert!(!checked("link2", "link4") && checked("link2", "link5") && checked("link1", "link3"));
    assert!(checked("link6", "ball") && checked("link1", "floor"));
    // Every robot pair is either checked or excluded: none is dropped.
    let links = model.links.len();
    let expected = links * (links - 1) / 2 + links * obstacles.len() + links;
    assert_eq!(world.pairs().len() + world.excluded().len(), expected);
    assert_eq!(world.body_name(Body::Obstacle(0)), "ball");

    let opts = CollideOptions {
        excluded_pairs: vec![ExcludedPair::new("link2", "elbow", "typo")],
        ..Default::default()
    };
    let error = collide::world(&model, &scenario(obstacles, None), &opts)
        .err()
        .expect("unknown link");
    assert!(
        matches!(&error, CollideError::UnknownLink { link, .. } if link == "elbow"),
        "{error}"
    );
    let message = error.to_string();
    assert!(
        message.contains("no link named `elbow`") && message.contains("`link6`"),
        "{message}"
    );
}

/// Links two apart joined by a `direct` module (d = 0.1 m < the 0.12 m tube diameter) overlap at
/// every configuration around the joint between them: those shape pairs, and only those, are
/// excluded by sampling, with the reason; the rest of the two links stays checked.
#[test]
fn structural_overlaps_are_found_by_sampling_and_only_those() {
    use proving_ground::collide::{structural_overlaps, StructuralOptions};
    let load = |design: &str| proving_ground::pipeline::load_model(&common::repo().join(design), &Default::default()).expect("loads");
    // The paper robot's direct slots: links i and i + 2 overlap around the joint between them, and
    // what else of them could touch stays within that 20 mm slab at 1024 more samples: excluded
    // whole, the overlapping shapes named in the reason.
    let paper = load("designs/paper-real-world.json");
    let found = structural_overlaps(&paper, &StructuralOptions::default()).expect("builds");
    let pairs: Vec<(&str, &str)> = found.pairs.iter().map(|e| (e.a.as_str(), e.b.as_str())).collect();
    assert_eq!(pairs, [("link2", "link4"), ("link3", "link5")]);
    assert!(found.shapes.is_empty() && found.allowances.is_empty(), "{found:?}");
    let reason = &found.pairs[1].reason;
    assert!(reason.contains("in contact at all 256 sampled configurations"), "{reason}");
    assert!(
        reason.contains("joint module 3 / joint module 5") && reason.contains("by up to 21.0 mm") && reason.contains("any of 1024 more"),
        "{reason}"
    );
    // UR5e's wrist links are one tube each (0.12 m across, 0.0997 m apart along the wrist): they
    // overlap in most configurations and touch end to end (within 1e-17 m) in the rest, and no
    // other shape is left to check, so the link pair is excluded whole. Its links 3 and 6 overlap
    // in about 16% of configurations: checked.
    let ur5e = structural_overlaps(&load("designs/ur5e.json"), &StructuralOptions::default()).expect("builds");
    let pairs: Vec<(&str, &str)> = ur5e.pairs.iter().map(|e| (e.a.as_str(), e.b.as_str())).collect();
    assert_eq!(pairs, [("link4", "link6")]);
    assert!(ur5e.shapes.is_empty());
    assert!(ur5e.pairs[0].reason.contains("in contact at all 256 sampled configurations"));

    // An L-long slot two joints on folds its 0.4 m tube right into link 1: only the shapes that
    // overlap by construction are left out, and the rest is checked beyond their 21 mm.
    let arm = r#"{"name": "fold", "mode": "modular", "modules": ["direct", "direct", "L-long", "direct"]}"#;
    let design = proving_ground::design::parse(arm, std::path::Path::new("fold.json")).expect("valid design");
    let model = proving_ground::model::from_design(&design);
    let found = structural_overlaps(&model, &StructuralOptions::default()).expect("builds");
    let allowance = found
        .allowances
        .iter()
        .find(|a| a.a == "link1" && a.b == "link3")
        .expect("link1-link3 overlap by construction");
    let world = proving_ground::pipeline::collision_world(&model, &scenario(vec![], None), &[]).expect("builds");
    let pair = world
        .pairs()
        .iter()
        .position(|p| p.a_name == "link1" && p.b_name == "link3")
        .expect("link1-link3 still checked");
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut ws = model.workspace();
    let mut out = Distances::new();
    let (mut free, mut folded) = (0, 0);
    for _ in 0..500 {
        model.forward(&model.random_configuration(&mut rng), &mut ws);
        distances(&world, &ws.link_in_world, &QueryOptions::default(), &mut out);
        match out.within_margin.iter().find(|d| d.pair == pair) {
            Some(contact) => {
                folded += 1;
                let (a, b) = ((1, contact.a.element), (3, contact.b.element));
                assert!(world.shape_pair_checked(a, b), "{contact:?}");
                // The reported distance is the exact one plus the allowance: deeper than it.
                let exact = world.collider_distance(&ws.link_in_world, a, b).expect("colliders");
                assert!((contact.distance - (exact + allowance.depth_m)).abs() < 1e-9, "{contact:?} {exact}");
                assert!(exact < -allowance.depth_m, "{exact} vs {allowance:?}");
            }
            None => free += 1,
        }
    }
    assert!(free > 0 && folded > 0, "free {free}, folded {folded}");
}

#[test]
fn estimated_depths_keep_every_verdict_and_are_never_shallower() {
    let (mut estimated, mut exact) = (Distances::new(), Distances::new());
    let (mut overlaps, mut deeper) = (0, 0);
    for name in ["ur5e.json", "modular-elbow.json", "abb-irb-2600.json", "free-redundant-7dof.json"] {
        let model = design(name);
        let mut rng = ChaCha8Rng::seed_from_u64(SEED);
        let obstacles: Vec<Obstacle> = (0..8)
            .map(|k| {
                let pose = random_pose(&mut rng, 0.8);
                let shape = match k % 4 {
                    0 => Shape::Sphere { radius: 0.1 },
                    1 => Shape::Box {
                        half_extents: [0.1, 0.05, 0.2],
                    },
                    2 => Shape::Cylinder { radius: 0.06, length: 0.3 },
                    _ => Shape::Capsule { radius: 0.05, length: 0.2 },
                };
                obstacle(&format!("o{k}"), pose, shape)
            })
            .collect();
        let world = collide::world(&model, &scenario(obstacles, Some(-0.1)), &CollideOptions::default()).expect("valid");
        let mut ws = model.workspace();
        for sample in 0..300 {
            model.forward(&model.random_configuration(&mut rng), &mut ws);
            let all = |exact_depth| QueryOptions {
                margin: 100.0,
                hulls: false,
                exact_depth,
                mesh_hulls: false,
            };
            distances(&world, &ws.link_in_world, &all(true), &mut exact);
            distances(&world, &ws.link_in_world, &all(false), &mut estimated);
            assert_eq!(exact.within_margin.len(), estimated.within_margin.len(), "{name} sample {sample}");
            for (x, e) in exact.within_margin.iter().zip(&estimated.within_margin) {
                let context = format!("{name} sample {sample}: {} vs {}", x.distance, e.distance);
                assert_eq!((x.a.body, x.b.body), (e.a.body, e.b.body), "{context}");
                // Touching within rounding (UR5e's links 4 and 6 by construction), GJK's overlap
                // test may call it either way.
                if x.distance.abs() < 1e-9 {
                    continue;
                }
                assert_eq!(x.distance > 0.0, e.distance > 0.0, "{context}");
                if x.distance > 0.0 {
                    // Unpolished GJK: never shorter than the certified gap, at most 1.3e-5 m longer.
                    assert!(e.distance >= x.distance - 1e-10 && e.distance <= x.distance + 2e-5, "{context}");
                } else {
                    overlaps += 1;
                    assert!(e.distance <= x.distance + 1e-9, "{context}");
                    deeper += usize::from(e.distance < x.distance - 1e-6);
                }
            }
        }
    }
    // Enough overlaps of the kinds EPA would measure, and the estimate really used on them.
    assert!(overlaps > 500 && deeper > 100, "{overlaps} overlaps, {deeper} estimated deeper");
}

#[test]
fn mesh_robots_find_the_same_closest_pair_and_contacts_with_the_hull_bounds_as_with_everything_measured() {
    let model = load_model(
        &panda_urdf(),
        &LoadOptions {
            tip_link: Some("panda_hand".into()),
            ..Default::default()
        },
    )
    .expect("panda loads");
    let course = proving_ground::scenario::generate::course(proving_ground::scenario::generate::COURSE_SEED);
    let world = collide::world(&model, &course, &CollideOptions::default()).expect("valid");
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let (mut bounded, mut everything) = (Distances::new(), Distances::new());
    let all = QueryOptions {
        margin: 1e3,
        hulls: false,
        exact_depth: true,
        mesh_hulls: false,
    };
    let near = QueryOptions {
        margin: 0.02,
        hulls: false,
        exact_depth: true,
        mesh_hulls: false,
    };
    let mut ws = model.workspace();
    let mut hull_bounded = 0;
    for sample in 0..60 {
        model.forward(&model.random_configuration(&mut rng), &mut ws);
        distances(&world, &ws.link_in_world, &all, &mut everything);
        distances(&world, &ws.link_in_world, &near, &mut bounded);
        let truth = everything.closest.expect("pairs").distance;
        assert_eq!(bounded.closest.expect("pairs").distance, truth, "sample {sample}");
        let within: Vec<usize> = everything
            .within_margin
            .iter()
            .filter(|p| p.distance <= 0.02)
            .map(|p| p.pair)
            .collect();
        assert_eq!(
            bounded.within_margin.iter().map(|p| p.pair).collect::<Vec<_>>(),
            within,
            "sample {sample}"
        );
        // Every bound is below the true distance.
        for (estimate, exact) in bounded.estimates.iter().zip(&everything.estimates) {
            assert!(
                estimate.distance <= exact.distance + 1e-12,
                "sample {sample}: {estimate:?} vs {exact:?}"
            );
            hull_bounded += usize::from(!estimate.exact && estimate.distance > 0.0);
        }
    }
    assert!(hull_bounded > 50, "{hull_bounded}");
}

/// `mesh_hulls` measures mesh links by their convex hulls: every pair it reports is at most as far
/// apart as the exact geometry says (a hull holds its mesh; an overlap's capsule estimate is at
/// least as deep), within GJK's early stop on curved obstacles; and it does report pairs the
/// exact query finds apart where only the hulls meet.
#[test]
fn mesh_hulls_never_measure_farther_than_the_meshes() {
    let urdf = repo().join("tests/fixtures/urdf/example-robot-data/robots/ur_description/urdf/ur5_gripper.urdf");
    let model = load_model(&urdf, &LoadOptions::default()).expect("fixture loads");
    let scenario = proving_ground::scenario::load(&repo().join("scenarios/cluttered/task-00.json")).expect("loads");
    let placed = model.placed(&scenario.world_from_base);
    let world = proving_ground::pipeline::collision_world(&placed, &scenario, &[]).expect("builds");
    let everything = |mesh_hulls: bool| QueryOptions {
        margin: 10.0,
        hulls: false,
        exact_depth: !mesh_hulls,
        mesh_hulls,
    };
    let (mut exact, mut hulls) = (Distances::new(), Distances::new());
    let mut ws = placed.workspace();
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let (mut compared, mut closer) = (0, 0);
    for _ in 0..40 {
        placed.forward(&placed.random_configuration(&mut rng), &mut ws);
        collide::distances(&world, &ws.link_in_world, &everything(false), &mut exact);
        collide::distances(&world, &ws.link_in_world, &everything(true), &mut hulls);
        assert_eq!(exact.within_margin.len(), hulls.within_margin.len());
        for (e, h) in exact.within_margin.iter().zip(&hulls.within_margin) {
            assert_eq!(e.pair, h.pair);
            assert!(
                h.distance <= e.distance + 2e-5,
                "pair {}: hulls {} m, exact {} m",
                e.pair,
                h.distance,
                e.distance
            );
            compared += 1;
            closer += usize::from(h.distance < e.distance - 1e-3);
        }
    }
    assert!(
        compared > 1000 && closer > 100,
        "{closer} of {compared} pairs closer by their hulls"
    );
}

/// The extent of two overlapping shapes along a direction bounds their depth from above (the
/// structural check skips EPA by it): at least EPA's depth along random directions, and EPA's
/// depth itself along EPA's normal (worst measured 1.5e-6 m, on a degenerate overlap 20 mm deep
/// that GJK and EPA answered as touching until it was asked again turned; 1.7e-7 m elsewhere).
#[test]
fn overlap_along_any_direction_bounds_the_depth_and_along_the_normal_is_it() {
    let model = design("modular-elbow.json");
    let world = collide::world(&model, &scenario(vec![], None), &CollideOptions::default()).expect("valid");
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut ws = model.workspace();
    let (mut overlaps, mut along_normal) = (0, Worst("extent along EPA's normal vs EPA's depth", 0.0));
    for sample in 0..300 {
        let q = model.random_configuration(&mut rng);
        model.forward(&q, &mut ws);
        for i in 0..model.links.len() {
            for j in i + 1..model.links.len() {
                for a in 0..model.links[i].colliders.len() {
                    for b in 0..model.links[j].colliders.len() {
                        let Some((distance, normal)) = world.collider_contact(&ws.link_in_world, (i, a), (j, b)) else {
                            continue;
                        };
                        if distance >= 0.0 {
                            continue;
                        }
                        overlaps += 1;
                        let context = || format!("sample {sample}: link {i} shape {a}, link {j} shape {b}, depth {}", -distance);
                        let extent = world
                            .collider_overlap_along(&ws.link_in_world, (i, a), (j, b), &normal)
                            .expect("convex shapes");
                        // Shapes just touching (tubes end to end, 1e-17 m) have no normal to speak of.
                        if distance < -1e-6 {
                            along_normal.check((extent + distance).abs(), 2e-6, context);
                        } else {
                            assert!(extent >= -distance - 1e-9, "{}: {extent}", context());
                        }
                        for _ in 0..8 {
                            let direction = random_rotation(&mut rng) * Vector3::x();
                            let bound = world
                                .collider_overlap_along(&ws.link_in_world, (i, a), (j, b), &direction)
                                .expect("convex shapes");
                            assert!(bound >= -distance - 1e-9, "{}: {bound} along {direction:?}", context());
                        }
                    }
                }
            }
        }
    }
    eprintln!("{overlaps} overlapping shape pairs");
    assert!(overlaps > 100, "{overlaps}");
}

/// A deep overlap in exactly degenerate geometry is measured as deep, never as touching: a
/// random free design (`python/bench.py`'s grid, design 16) with joint 3 folded back over
/// link 1, link 3's first tube's end face in a plane holding link 1's axis, 60 mm into it. At
/// this configuration (as the general 6R elimination solves task 32's goal 6) and one 1e-9 rad
/// away, GJK and EPA answered 3e-17 m (free: the goal counted reached); at the neighbours
/// either side, -60 mm.
#[test]
fn a_degenerate_deep_overlap_is_never_measured_as_touching() {
    use proving_ground::plan::{CertifyOptions, SegmentChecker};
    let half = std::f64::consts::FRAC_PI_2;
    let rows = [
        [0.0, 0.4, -half],
        [0.0, 0.2, 0.0],
        [0.1, 0.3, -half],
        [0.3, 0.2, 0.0],
        [0.1, 0.4, half],
        [0.3, 0.2, 0.0],
    ];
    let model = common::dh_design("design-0016", &rows);
    let scenario = proving_ground::pipeline::load_scenario(&repo().join("scenarios/cluttered/task-32.json")).expect("shipped task loads");
    let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("world builds");
    let mut checker = SegmentChecker::new(&model, &world, CertifyOptions::default());
    let q = [
        1.1355407917916147,
        -2.8835607414829103,
        1.7289868593718465,
        2.814694764658295,
        -2.409081250717008,
        -1.5976056104755108,
    ];
    for step in [0.0, 1e-9, -1e-9, 1e-6] {
        let mut at = q.to_vec();
        at[1] += step;
        let closest = checker.clearance(&at).expect("a pair is checked");
        assert_eq!((closest.a.as_str(), closest.b.as_str()), ("link1", "link3"));
        assert!(
            (closest.distance_m + 0.06).abs() < 1e-6,
            "joint 2 moved by {step}: {} m",
            closest.distance_m
        );
    }
}
