//! The whole `validate-design` run of the paper's robot on the course, both engines (target in
//! issue 5: <= 3 s on 2 cores): the binary as a user runs it, and the library stages alone.
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

criterion_group!(benches, whole_run);
criterion_main!(benches);
