//! The whole `validate-design` run of the paper's robot on the course, both engines (target in
//! issue 5: <= 3 s on 2 cores): the binary as a user runs it, and the library stages alone.
//! A mesh robot with detours, the UR5 URDF with its gripper, without engines (target in issue 28:
//! <= 5 s each on 2 cores): on cluttered task 00 (two detours) and on the course.
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, Criterion};
use proving_ground::pipeline::{load, validate, LoadOptions, ValidateOptions};
use proving_ground::scenario::load as load_scenario;
use std::hint::black_box;
use std::path::Path;
use std::process::Command;

fn whole_run(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut group = c.benchmark_group("validate-design");
    group.sample_size(10);
    group.bench_function("paper-real-world/course/binary", |b| {
        b.iter(|| {
            let status = Command::new(env!("CARGO_BIN_EXE_validate-design"))
                .current_dir(root)
                .args(["designs/paper-real-world.json", "--quiet"])
                .status()
                .expect("the binary runs");
            assert!(status.success());
        })
    });
    let scenario = load_scenario(&root.join("scenarios/course.json")).expect("course loads");
    group.bench_function("paper-real-world/course/validate", |b| {
        b.iter(|| {
            let loaded = load(&root.join("designs/paper-real-world.json"), &LoadOptions::default()).expect("loads");
            let validation = validate(loaded, scenario.clone(), &ValidateOptions::default()).expect("runs");
            black_box(proving_ground::report::build(&validation).verdict.passed)
        })
    });
    group.finish();
}

fn mesh_robot(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let urdf = "tests/fixtures/urdf/example-robot-data/robots/ur_description/urdf/ur5_gripper.urdf";
    let mut group = c.benchmark_group("validate-design");
    group.sample_size(10);
    for (name, scenario) in [
        ("cluttered-00", "scenarios/cluttered/task-00.json"),
        ("course", "scenarios/course.json"),
    ] {
        group.bench_function(format!("ur5-gripper-urdf/{name}/binary"), |b| {
            b.iter(|| {
                let status = Command::new(env!("CARGO_BIN_EXE_validate-design"))
                    .current_dir(root)
                    .args([urdf, "--scenario", scenario, "--engines", "none", "--quiet"])
                    .status()
                    .expect("the binary runs");
                // Exit 1 is the design's FAIL (a goal proven out of reach): a finished run.
                assert!(matches!(status.code(), Some(0 | 1)), "{status}");
            })
        });
    }
    group.finish();
}

criterion_group!(benches, whole_run, mesh_robot);
criterion_main!(benches);
