//! One collision query of a 6-dof design against 8 spheres, self pairs included (target in
//! issue 3: <= 10 us for the exact query), and the same query in the paper's capsule model.
//!
//! Mesh robots (issue 11): one exact query as the certified continuous check makes it (no hulls,
//! exact depth), in configurations free of contact, for the shipped Panda (STL meshes, 8.8k
//! triangles) on the course and example-robot-data's UR5 (STL, 5.4k triangles) on cluttered
//! task 00; and one mesh-against-mesh pair, the UR5's wrist 1 and wrist 3 (always within 15 mm
//! of each other, so always the closest pair). Targets: <= 0.5 ms for a mesh robot's query and
//! <= 0.3 ms for the pair (what keeps the Panda's whole course run within 5 s; the certified
//! check makes a few thousand queries). Measured on 2 shared cores: before (parry's descent)
//! 847 us, 2.3 ms and 638 us; after (sphere-and-capsule trees) 455 us, 850 us and 271 us.
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Isometry3;
use proving_ground::collide::{self, approximate_distances, distances, CollideOptions, Distances, ExcludedPair, QueryOptions};
use proving_ground::model::{Model, Shape};
use proving_ground::pipeline::{load_model, LoadOptions};
use proving_ground::scenario::{Obstacle, Scenario};
use rand::SeedableRng;
use std::collections::BTreeSet;
use std::hint::black_box;
use std::path::Path;

const CONFIGURATIONS: usize = 64;

/// Eight spheres of radius 0.08 m around the base, 0.3 to 0.8 m out, 0.1 to 0.7 m up.
fn spheres() -> Scenario {
    let obstacles = (0..8)
        .map(|k| {
            let angle = k as f64 * std::f64::consts::FRAC_PI_4;
            let out = 0.3 + 0.5 * (k % 4) as f64 / 3.0;
            let up = 0.1 + 0.6 * ((k * 3) % 8) as f64 / 7.0;
            Obstacle {
                name: format!("sphere {k}"),
                world_from_shape: Isometry3::translation(out * angle.cos(), out * angle.sin(), up),
                shape: Shape::Sphere { radius: 0.08 },
            }
        })
        .collect();
    Scenario {
        name: "eight spheres".into(),
        world_from_base: Isometry3::identity(),
        floor: None,
        obstacles,
        goals: vec![],
        home: None,
        provenance: None,
        notes: Vec::new(),
    }
}

/// Link poses of configurations drawn with a fixed seed, those for which `keep` holds.
fn configurations(model: &Model, mut keep: impl FnMut(&[Isometry3<f64>]) -> bool) -> Vec<Vec<Isometry3<f64>>> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let mut ws = model.workspace();
    let mut kept = Vec::with_capacity(CONFIGURATIONS);
    for _ in 0..100_000 {
        model.forward(&model.random_configuration(&mut rng), &mut ws);
        if keep(&ws.link_in_world) {
            kept.push(ws.link_in_world.clone());
            if kept.len() == CONFIGURATIONS {
                break;
            }
        }
    }
    kept
}

fn collision(c: &mut Criterion) {
    let scenario = spheres();
    let query = QueryOptions::default();
    for design in ["designs/modular-elbow.json", "designs/ur5e.json"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(design);
        let model = load_model(&path, &LoadOptions::default()).expect("shipped design loads");
        let world = collide::world(&model, &scenario, &CollideOptions::default()).expect("valid world");
        let mut out = Distances::new();

        // Link pairs in contact in every one of the random configurations.
        let mut always: Option<BTreeSet<usize>> = None;
        let sampled = configurations(&model, |_| true);
        for poses in &sampled {
            distances(&world, poses, &query, &mut out);
            let touching: BTreeSet<usize> = out.within_margin.iter().map(|p| p.pair).collect();
            always = Some(always.map_or(touching.clone(), |a| a.intersection(&touching).copied().collect()));
        }
        let excluded_pairs = always
            .unwrap_or_default()
            .iter()
            .map(|&p| {
                let pair = &world.pairs()[p];
                ExcludedPair::new(&pair.a_name, &pair.b_name, "in contact in every sampled configuration")
            })
            .collect();
        let free_world = collide::world(
            &model,
            &scenario,
            &CollideOptions {
                excluded_pairs,
                ..Default::default()
            },
        )
        .expect("valid world");
        let free = configurations(&model, |poses| {
            distances(&free_world, poses, &query, &mut out);
            out.within_margin.is_empty()
        });

        let name = model.name.clone();
        let mut i = 0;
        for (label, world, poses) in [("random", &world, &sampled), ("free", &free_world, &free)] {
            c.bench_function(&format!("collision/exact/{name}/{label}"), |b| {
                b.iter(|| {
                    i = (i + 1) % poses.len();
                    distances(world, black_box(&poses[i]), &query, &mut out);
                    black_box(out.closest.map(|c| c.distance))
                })
            });
        }
        c.bench_function(&format!("collision/approximate/{name}/random"), |b| {
            b.iter(|| {
                i = (i + 1) % sampled.len();
                approximate_distances(&world, black_box(&sampled[i]), &query, &mut out);
                black_box(out.closest.map(|c| c.distance))
            })
        });
    }
}

/// A mesh robot in a scenario, both from the repository.
fn mesh_world(robot: &str, tip: &str, scenario: &str) -> (Model, collide::CollisionWorld) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let opts = LoadOptions {
        tip_link: Some(tip.into()),
        ..Default::default()
    };
    let model = load_model(&root.join(robot), &opts).expect("shipped robot loads");
    let scenario = proving_ground::scenario::load(&root.join(scenario)).expect("shipped scenario loads");
    let placed = model.placed(&scenario.world_from_base);
    let world = proving_ground::pipeline::collision_world(&placed, &scenario, &[]).expect("valid world");
    (placed, world)
}

fn mesh_collision(c: &mut Criterion) {
    let query = QueryOptions {
        margin: 0.0,
        hulls: false,
        exact_depth: true,
        mesh_hulls: false,
    };
    let mut out = Distances::new();
    for (label, robot, tip, scenario) in [
        (
            "panda/course",
            "designs/urdf/example-robot-data/robots/panda_description/urdf/panda.urdf",
            "panda_hand",
            "scenarios/course.json",
        ),
        (
            "ur5/cluttered-00",
            "tests/fixtures/urdf/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf",
            "tool0",
            "scenarios/cluttered/task-00.json",
        ),
    ] {
        let (model, world) = mesh_world(robot, tip, scenario);
        let free = configurations(&model, |poses| {
            distances(&world, poses, &query, &mut out);
            out.within_margin.is_empty()
        });
        let mut i = 0;
        c.bench_function(&format!("collision/mesh/{label}"), |b| {
            b.iter(|| {
                i = (i + 1) % free.len();
                distances(&world, black_box(&free[i]), &query, &mut out);
                black_box(out.closest.map(|c| c.distance))
            })
        });
        if label.starts_with("ur5") {
            let link = |name: &str| model.links.iter().position(|l| l.name == name).expect("UR5 link");
            let (a, b) = ((link("wrist_1_link"), 0), (link("wrist_3_link"), 0));
            c.bench_function("collision/mesh-pair/ur5/wrist_1-wrist_3", |bench| {
                bench.iter(|| {
                    i = (i + 1) % free.len();
                    black_box(world.collider_distance(black_box(&free[i]), a, b))
                })
            });
        }
    }
}

criterion_group!(benches, collision, mesh_collision);
criterion_main!(benches);
