//! One second of simulated time of the paper's robot following a path through the course in
//! rapier (1 ms steps, joint motors, contacts on): simulated seconds per wall second is the
//! reciprocal of the time per iteration.
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, Criterion};
use proving_ground::engine::{gains, run_rapier, GainOptions, RunOptions};
use proving_ground::pipeline::{self, load_model, LoadOptions};
use proving_ground::plan::{TimedPath, TimingLimits};
use proving_ground::scenario::generate;
use std::hint::black_box;
use std::path::Path;

/// Simulated time per iteration (s).
const SIMULATED_S: f64 = 1.0;

fn rapier(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let model = load_model(&root.join("designs/paper-real-world.json"), &LoadOptions::default()).expect("shipped design loads");
    let scenario = generate::course(generate::COURSE_SEED);
    let placed = model.placed(&scenario.world_from_base);
    let world = pipeline::collision_world(&placed, &scenario, &[]).expect("world builds");
    // Home to the first goal, then a dwell that makes the path last exactly one second.
    let waypoints = [generate::COURSE_HOME.to_vec(), generate::course_configurations()[0].clone()];
    let mut limits = TimingLimits {
        dwell_s: 0.0,
        ..TimingLimits::of(&placed)
    };
    let motion_s = TimedPath::through(&waypoints, &[Some(0)], &limits).duration_s();
    limits.dwell_s = (SIMULATED_S - motion_s).max(0.0);
    let path = TimedPath::through(&waypoints, &[Some(0)], &limits);
    let gains = gains(&placed, &path, &GainOptions::default());
    let opts = RunOptions::default();
    let mut group = c.benchmark_group("rapier");
    group.sample_size(10);
    group.bench_function(format!("{}/{SIMULATED_S}-s-simulated", placed.name), |b| {
        b.iter(|| {
            black_box(
                run_rapier(&placed, &scenario, &world, &path, &gains, &opts)
                    .expect("rapier runs")
                    .steps,
            )
        })
    });
    group.finish();
}

criterion_group!(benches, rapier);
criterion_main!(benches);
