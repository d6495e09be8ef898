//! One second of simulated time of the paper's robot in MuJoCo on the course: position
//! actuators following a timed move from the course home to the first goal, 1 ms steps,
//! contacts recorded. The throughput is 1 s divided by the time per iteration.
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, Criterion};
use proving_ground::engine::{self, run_mujoco, GainOptions, RunOptions};
use proving_ground::pipeline::{self, load_model, LoadOptions};
use proving_ground::plan::{TimedPath, TimingLimits};
use proving_ground::scenario::generate;
use std::hint::black_box;
use std::path::Path;

fn mujoco(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scenario = generate::course(generate::COURSE_SEED);
    let model = load_model(&root.join("designs/paper-real-world.json"), &LoadOptions::default())
        .expect("shipped design loads")
        .placed(&scenario.world_from_base);
    let world = pipeline::collision_world(&model, &scenario, &[]).expect("world builds");
    let waypoints = vec![generate::COURSE_HOME.to_vec(), generate::course_configurations()[0].clone()];
    // Time the move at the model's limits, then scale speed by k and acceleration by k^2 so
    // the trapezoid takes exactly 1 s.
    let mut limits = TimingLimits {
        dwell_s: 0.0,
        ..TimingLimits::of(&model)
    };
    let natural_s = TimedPath::through(&waypoints, &[None], &limits).duration_s();
    let k = natural_s / 1.0;
    limits.velocity.iter_mut().for_each(|v| *v *= k);
    limits.acceleration.iter_mut().for_each(|a| *a *= k * k);
    let path = TimedPath::through(&waypoints, &[None], &limits);
    assert!((path.duration_s() - 1.0).abs() < 1e-9, "{}", path.duration_s());
    let gains = engine::gains(&model, &path, &GainOptions::default());
    let opts = RunOptions::default();
    let mut group = c.benchmark_group("mujoco");
    group.sample_size(20);
    group.bench_function("paper-real-world/1s-simulated", |b| {
        b.iter(|| {
            black_box(
                run_mujoco(&model, &scenario, &world, &path, &gains, &opts)
                    .expect("MuJoCo runs")
                    .steps,
            )
        })
    });
    group.finish();
}

criterion_group!(benches, mujoco);
criterion_main!(benches);
