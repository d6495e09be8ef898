//! The certified continuous check of one full course trajectory (target in issue 4: <= 20 ms),
//! and certified planning of the segments the straight heuristic cannot join on the cluttered
//! tasks (UR5e, modular-elbow; target in issue 9: median <= 20 ms, p95 <= 200 ms per segment).
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, Criterion};
use proving_ground::ik::{solve_goals, IkOptions};
use proving_ground::pipeline::{collision_world, load_model, LoadOptions};
use proving_ground::plan::{
    nearest_equivalent, plan, whole_turn_equivalents, CertifyOptions, GoalStep, Planner, PlannerKind, PlannerOptions, RrtConnect,
    SegmentChecker, TrajectoryOptions, DEFAULT_PLAN_BUDGET,
};
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
        _ => None,
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

/// One segment the straight heuristic leaves blocked: the placed model, its world, where the
/// tour stands and the goal set (every collision-free solution and its whole-turn equivalents).
struct Blocked {
    model: proving_ground::model::Model,
    world: proving_ground::collide::CollisionWorld,
    from: Vec<f64>,
    goals: Vec<Vec<f64>>,
    stream: u64,
}

fn blocked_segments() -> Vec<Blocked> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = Vec::new();
    for design in ["ur5e", "modular-elbow"] {
        let model = load_model(&root.join(format!("designs/{design}.json")), &LoadOptions::default()).expect("shipped design loads");
        for task in 0..generate::CLUTTERED_TASKS {
            let scenario =
                proving_ground::scenario::load(&root.join(format!("scenarios/cluttered/task-{task:02}.json"))).expect("task loads");
            let placed = model.placed(&scenario.world_from_base);
            let world = collision_world(&placed, &scenario, &[]).expect("world builds");
            let solutions = solve_goals(&placed, &scenario, Some(&world), &IkOptions::default());
            let straight = TrajectoryOptions {
                planner: PlannerOptions {
                    kind: PlannerKind::Straight,
                    ..Default::default()
                },
                ..Default::default()
            };
            let trajectory = plan(&placed, &scenario, &world, &solutions, &straight).expect("plans");
            let mut previous = trajectory.home.clone();
            for step in &trajectory.steps {
                match step {
                    GoalStep::Reached { q, .. } => previous.clone_from(q),
                    GoalStep::NoPath { goal, .. } => {
                        let mut goals: Vec<Vec<f64>> = solutions[*goal]
                            .solutions
                            .iter()
                            .filter(|s| s.reached)
                            .map(|s| nearest_equivalent(&placed, &s.q, &previous))
                            .collect();
                        let firsts = goals.clone();
                        for q in &firsts {
                            goals.extend(whole_turn_equivalents(&placed, q, &previous).into_iter().filter(|e| e != q));
                        }
                        out.push(Blocked {
                            model: placed.clone(),
                            world: collision_world(&placed, &scenario, &[]).expect("world builds"),
                            from: previous.clone(),
                            goals,
                            stream: *goal as u64,
                        });
                    }
                    GoalStep::Unreachable { .. } => {}
                }
            }
        }
    }
    out
}

fn connect(segment: &Blocked) -> (bool, usize) {
    let mut checker = SegmentChecker::new(&segment.model, &segment.world, CertifyOptions::default());
    let mut rrt = RrtConnect {
        limits: segment.model.joints.iter().map(|j| j.limits).collect(),
        budget: DEFAULT_PLAN_BUDGET,
        straight_attempts: 0,
    };
    match rrt.connect(&mut checker, &segment.from, &segment.goals, segment.stream) {
        Ok(path) => (true, path.samples),
        Err(failure) => (false, failure.samples),
    }
}

fn blocked(c: &mut Criterion) {
    let segments = blocked_segments();
    // The distribution over segments, each timed once (criterion below times the whole set).
    let mut times: Vec<f64> = Vec::with_capacity(segments.len());
    let mut connected = Vec::new();
    for segment in &segments {
        let start = std::time::Instant::now();
        let (ok, _) = connect(segment);
        times.push(start.elapsed().as_secs_f64() * 1e3);
        if ok {
            connected.push(segment);
        }
    }
    times.sort_by(f64::total_cmp);
    let at = |p: f64| {
        times
            .get(((times.len() as f64 - 1.0) * p).round() as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    println!(
        "blocked segments: {} (ur5e, modular-elbow on 36 cluttered tasks), {} connected; per segment median {:.2} ms, p95 {:.2} ms, max {:.2} ms",
        segments.len(),
        connected.len(),
        at(0.5),
        at(0.95),
        at(1.0)
    );
    let mut group = c.benchmark_group("plan");
    group.sample_size(10);
    // The segments a path joins (one that exhausts its budget takes seconds and would dominate).
    group.bench_function("rrt-connect/connected-cluttered-segments", |b| {
        b.iter(|| black_box(connected.iter().map(|s| connect(s).1).sum::<usize>()))
    });
    group.finish();
}

criterion_group!(benches, course, blocked);
criterion_main!(benches);
