//! Convex pieces of the engines' meshes (sim/convex.rs): VHACD on every collision mesh of
//! example-robot-data's UR5 (7 meshes, 5.4k triangles), computed ("cold") and read back from the
//! disk cache ("warm", the in-memory cache emptied first). Targets (issue 11): the cold
//! decomposition is paid once per mesh and machine, within a few seconds per robot; a warm read
//! stays within 10 ms per robot. Measured on 2 cores: 1.64 s cold, 0.57 ms warm.
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, Criterion};
use proving_ground::convex;
use proving_ground::model::Shape;
use proving_ground::pipeline::{load_model, LoadOptions};
use std::hint::black_box;
use std::path::Path;

fn pieces(c: &mut Criterion) {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/urdf/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf");
    let opts = LoadOptions {
        tip_link: Some("tool0".into()),
        ..Default::default()
    };
    let model = load_model(&path, &opts).expect("the UR5 fixture loads");
    let meshes: Vec<_> = model
        .links
        .iter()
        .flat_map(|link| &link.colliders)
        .filter_map(|collider| match &collider.shape {
            Shape::Mesh(mesh) => Some(mesh),
            _ => None,
        })
        .collect();
    let dir = tempfile::tempdir().expect("temp dir");
    let mut group = c.benchmark_group("convex");
    group.sample_size(10).measurement_time(std::time::Duration::from_secs(20));
    group.bench_function("ur5/decompose", |b| {
        b.iter(|| {
            for mesh in &meshes {
                black_box(convex::decompose(&mesh.vertices, &mesh.triangles));
            }
        })
    });
    for mesh in &meshes {
        convex::pieces_with_cache(&mesh.vertices, &mesh.triangles, Some(dir.path()));
    }
    group.bench_function("ur5/disk-cache", |b| {
        b.iter(|| {
            convex::forget_in_memory();
            for mesh in &meshes {
                black_box(convex::pieces_with_cache(&mesh.vertices, &mesh.triangles, Some(dir.path())));
            }
        })
    });
    group.finish();
}

criterion_group!(benches, pieces);
criterion_main!(benches);
