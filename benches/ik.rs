//! IK for one goal without obstacles. Targets (issue 11): the numeric solver, 4 seeds on a 6-dof
//! arm, <= 10 us per goal (`ik-4-seeds`, closed form and branch restarts off; with the default
//! branch restarts that find every branch: `ik-4-seeds-branches`); the closed form of a UR-type arm a few
//! microseconds per goal, every solution found, polished and judged (`ik-closed-form`), of
//! which the bare closed form (`closed-form-bare`) is a fraction.
//!
//! Issue 22: every solution of a pose, bare (`all-solutions-bare`: the general 6R elimination on
//! `free-offset-6dof`, target median <= 20 us; the spherical wrist on `abb-irb-2600` and
//! `economic-spherical-wrist`, target <= 3 us) and polished, deduplicated and judged
//! (`ik-all-solutions`); the same bare on catalog arms (`all-solutions-bare/modular6/...`: the
//! elimination keeping joints 2 to 4, and three parallel axes). The joint-space search proving a
//! goal out of the tolerance by its bounds alone (`search/...`: the first goal each design's
//! search proves, on the course for `economic-scara`, on the `z_symmetric` workspace task for
//! `paper-real-world`; no target: its cost is the boxes it needs, reported in proofs).
#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, Criterion};
use proving_ground::ik::{Ik, IkOptions};
use proving_ground::pipeline::{load_model, LoadOptions};
use proving_ground::scenario::{Goal, Tolerance};
use rand::SeedableRng;
use std::hint::black_box;
use std::path::Path;

fn ik(c: &mut Criterion) {
    for design in [
        "designs/ur5e.json",
        "designs/modular-elbow.json",
        "designs/paper-real-world.json",
        "designs/free-offset-6dof.json",
        "designs/abb-irb-2600.json",
        "designs/economic-spherical-wrist.json",
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(design);
        let model = load_model(&path, &LoadOptions::default()).expect("shipped design loads");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        let goals: Vec<Goal> = (0..256)
            .map(|i| {
                let tool = model.tool_pose(&model.random_configuration(&mut rng));
                Goal {
                    name: format!("goal {i}"),
                    position: tool.translation.vector,
                    rotation: tool.rotation,
                    tolerance: Tolerance::Pose,
                    task: None,
                }
            })
            .collect();
        let numeric = IkOptions {
            analytic: false,
            ..Default::default()
        };
        let plain = IkOptions {
            branch_starts: 0,
            ..numeric.clone()
        };
        let mut i = 0;
        for (name, opts) in [("ik-4-seeds", plain), ("ik-4-seeds-branches", numeric)] {
            let mut solver = Ik::new(&model, opts);
            c.bench_function(&format!("{name}/{}", model.name), |b| {
                b.iter(|| {
                    i = (i + 1) % goals.len();
                    black_box(solver.solve(black_box(&goals[i]), i, None).reached())
                })
            });
        }
        let mut solver = Ik::new(&model, IkOptions::default());
        if let Some(method) = solver.all_solutions().cloned() {
            let poses: Vec<nalgebra::Isometry3<f64>> = goals
                .iter()
                .map(|g| nalgebra::Isometry3::from_parts(g.position.into(), g.rotation))
                .collect();
            c.bench_function(&format!("ik-all-solutions/{}", model.name), |b| {
                b.iter(|| {
                    i = (i + 1) % goals.len();
                    black_box(solver.solve(black_box(&goals[i]), i, None).reached())
                })
            });
            c.bench_function(&format!("all-solutions-bare/{}", model.name), |b| {
                b.iter(|| {
                    i = (i + 1) % poses.len();
                    black_box(method.solve(black_box(&poses[i])).configurations.len())
                })
            });
        }
        let Some(arm) = solver.closed_form().cloned() else { continue };
        c.bench_function(&format!("ik-closed-form/{}", model.name), |b| {
            b.iter(|| {
                i = (i + 1) % goals.len();
                black_box(solver.solve(black_box(&goals[i]), i, None).reached())
            })
        });
        let poses: Vec<nalgebra::Isometry3<f64>> = goals
            .iter()
            .map(|g| nalgebra::Isometry3::from_parts(g.position.into(), g.rotation))
            .collect();
        c.bench_function(&format!("closed-form-bare/{}", model.name), |b| {
            b.iter(|| {
                i = (i + 1) % poses.len();
                black_box(arm.solve(black_box(&poses[i])).configurations.len())
            })
        });
    }
}

/// The all-solutions methods of modular catalog arms, bare: the elimination keeping joints 2 to
/// 4 (catalog index 12 019) and three parallel axes (index 370, `D-D-Il-Ll-Ll-D`).
fn catalog(c: &mut Criterion) {
    use proving_ground::ik::solvers::AllSolutions;
    use proving_ground::sweep::inputs::{catalog_entry, modular6_slots};
    for index in [12_019, 370] {
        let entry = catalog_entry(&modular6_slots(index));
        let model = entry.load().model;
        let Some((method, _)) = AllSolutions::of(&model) else { continue };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        let poses: Vec<nalgebra::Isometry3<f64>> = (0..256).map(|_| model.tool_pose(&model.random_configuration(&mut rng))).collect();
        let mut i = 0;
        c.bench_function(&format!("all-solutions-bare/{}", entry.id), |b| {
            b.iter(|| {
                i = (i + 1) % poses.len();
                black_box(method.solve(black_box(&poses[i])).configurations.len())
            })
        });
    }
}

/// Every goal of a scenario, collision-aware, with exact verification of each solution; the
/// scenarios come from the same generators as the committed files.
fn scenarios(c: &mut Criterion) {
    use proving_ground::scenario::generate;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut group = c.benchmark_group("scenario");
    group.sample_size(10);
    let task = generate::cluttered(0, generate::CLUTTERED_MASTER_SEED);
    let workspace =
        generate::workspace(generate::WORKSPACE_GOALS, 1.0, Tolerance::Pose, generate::WORKSPACE_SEED).expect("valid parameters");
    let course = generate::course(generate::COURSE_SEED);
    for (design, scenario) in [
        ("designs/modular-elbow.json", &task),
        ("designs/ur20.json", &task),
        ("designs/ur20.json", &workspace),
        ("designs/paper-real-world.json", &course),
    ] {
        let model = load_model(&root.join(design), &LoadOptions::default()).expect("shipped design loads");
        let placed = model.placed(&scenario.world_from_base);
        let structural = proving_ground::collide::structural_overlaps(&placed, &Default::default()).expect("geometry builds");
        let opts = proving_ground::collide::CollideOptions {
            excluded_pairs: structural.pairs,
            excluded_shapes: structural.shapes,
            structural_allowances: structural.allowances,
        };
        let world = proving_ground::collide::world(&placed, scenario, &opts).expect("world builds");
        group.bench_function(format!("{}/{}", model.name, scenario.name), |b| {
            b.iter(|| black_box(proving_ground::ik::solve_goals(&placed, scenario, Some(&world), &IkOptions::default()).len()))
        });
    }
    group.finish();
}

/// The joint-space search to a proof, by the bounds alone (no local solves).
fn search(c: &mut Criterion) {
    use proving_ground::ik::search::{search, Search};
    use proving_ground::scenario::generate;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut group = c.benchmark_group("search");
    group.sample_size(10);
    let course = generate::course(generate::COURSE_SEED);
    let workspace = generate::workspace(100, 1.0, Tolerance::ZSymmetric, generate::WORKSPACE_SEED).expect("valid parameters");
    for (design, scenario) in [
        ("designs/economic-scara.json", &course),
        ("designs/paper-real-world.json", &workspace),
    ] {
        let model = load_model(&root.join(design), &LoadOptions::default())
            .expect("shipped design loads")
            .placed(&scenario.world_from_base);
        let proven = scenario
            .goals
            .iter()
            .enumerate()
            .find_map(|(index, goal)| match search(&model, goal, 300_000, |_| false) {
                Some(Search::Proven { boxes, .. }) => Some((index, goal, boxes)),
                _ => None,
            });
        let Some((index, goal, boxes)) = proven else { continue };
        group.bench_function(format!("{}/{} goal {index} ({boxes} boxes)", model.name, scenario.name), |b| {
            b.iter(|| black_box(search(&model, black_box(goal), 300_000, |_| false)))
        });
    }
    group.finish();
}

criterion_group!(benches, ik, catalog, scenarios, search);
criterion_main!(benches);
