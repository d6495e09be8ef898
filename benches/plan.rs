//! The certified continuous check of one full course trajectory (target in issue 4: <= 20 ms).
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, Criterion};
use proving_ground::ik::{solve_goals, IkOptions};
use proving_ground::pipeline::{collision_world, load_model, LoadOptions};
use proving_ground::plan::{plan, CertifyOptions, GoalStep, SegmentChecker, TrajectoryOptions};
use proving_ground::scenario::generate;
use std::hint::black_box;
use std::path::Path;

fn course(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let model = load_model(&root.join("designs/paper-real-world.json"), &LoadOptions::default()).expect("shipped design loads");
    let scenario = generate::course(generate::COURSE_SEED);
    let placed = model.placed(&scenario.world_from_base);
    let world = collision_world(&placed, &scenario, &[]).expect("world builds");
    let solutions = solve_goals(&placed, &scenario, Some(&world), &IkOptions::default());
    let trajectory = plan(&placed, &scenario, &world, &solutions, &TrajectoryOptions::default()).expect("plans");
    let mut waypoints = vec![trajectory.home.clone()];
    waypoints.extend(trajectory.steps.iter().filter_map(|s| match s {
        GoalStep::Reached { q, .. } => Some(q.clone()),
        GoalStep::Blocked { .. } => None,
    }));
    let mut checker = SegmentChecker::new(&placed, &world, CertifyOptions::default());
    let mut group = c.benchmark_group("certify");
    group.sample_size(20);
    group.bench_function("paper-real-world/course-trajectory", |b| {
        b.iter(|| {
            let mut queries = 0;
            for pair in waypoints.windows(2) {
                queries += checker.check(black_box(&pair[0]), black_box(&pair[1])).queries;
            }
            black_box(queries)
        })
    });
    group.bench_function("paper-real-world/course-plan", |b| {
        b.iter(|| black_box(plan(&placed, &scenario, &world, &solutions, &TrajectoryOptions::default()).map(|t| t.reached())))
    });
    group.finish();
}

criterion_group!(benches, course);
criterion_main!(benches);
