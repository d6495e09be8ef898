//! The optimize stage: loss + gradient per sample on a batch of 4096 (the fused objective, the
//! product's, against the candle graph and the hand-written f64 gradient), and the whole
//! fine-tuning of 8 goals x 4 starts x 200 steps, for one design and for a batch of 8; on a CUDA
//! GPU the fused kernel (4096 designs: target 10 s on one H100 or H200).

#![allow(missing_docs)] // criterion_group! generates undocumented items

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use proving_ground::optimize::{self, Analytic, Batch, Fused, Objective, OptimizeOptions, Params, Sample, Tensors};
use rand::SeedableRng;
use std::path::Path;

fn inputs() -> (proving_ground::design::Design, proving_ground::scenario::Scenario) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let design = proving_ground::design::load(&root.join("designs/free-offset-6dof.json")).expect("design");
    let scenario = proving_ground::scenario::load(&root.join("scenarios/cluttered/task-03.json")).expect("scenario");
    (design, scenario)
}

fn batch_of(size: usize) -> (Batch, Params) {
    let (design, scenario) = inputs();
    let model = proving_ground::model::from_design(&design);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let goals = scenario.goals.len();
    let samples: Vec<Sample> = (0..size)
        .map(|b| Sample {
            design: 0,
            goal: b % goals,
        })
        .collect();
    let q: Vec<f64> = (0..size)
        .flat_map(|_| model.random_configuration(&mut rng).into_iter().map(|v| v * 0.5))
        .collect();
    let batch = Batch::new(std::slice::from_ref(&design), &scenario, samples).expect("batch");
    let params = Params {
        q,
        d: design.joints.iter().map(|j| j.d).collect(),
        a: design.joints.iter().map(|j| j.a).collect(),
    };
    (batch, params)
}

fn per_sample(c: &mut Criterion) {
    let size = 4096;
    let (batch, params) = batch_of(size);
    let mut group = c.benchmark_group("optimize/loss+gradient, batch 4096");
    group.sample_size(10);
    group.throughput(Throughput::Elements(size as u64));
    group.bench_function("candle tensors (cpu)", |b| {
        let mut objective = Tensors::default();
        b.iter(|| objective.evaluate(&batch, &params).expect("tensors"))
    });
    group.bench_function("hand-written f64", |b| {
        b.iter(|| Analytic.evaluate(&batch, &params).expect("analytic"))
    });
    group.bench_function("fused (cpu)", |b| b.iter(|| Fused::cpu().evaluate(&batch, &params).expect("fused")));
    group.finish();
}

fn whole(c: &mut Criterion) {
    let (design, scenario) = inputs();
    let opts = OptimizeOptions::default();
    let (batch, start) = optimize::starts(&design, &scenario, &opts).expect("starts");
    let mut group = c.benchmark_group("optimize/8 goals x 4 starts x 200 steps");
    group.sample_size(10);
    group.bench_function("candle tensors (cpu)", |b| {
        b.iter(|| {
            optimize::optimize(&mut Tensors::default(), &batch, std::slice::from_ref(&design), start.clone(), &opts).expect("optimize")
        })
    });
    group.bench_function("hand-written f64", |b| {
        b.iter(|| optimize::optimize(&mut Analytic, &batch, std::slice::from_ref(&design), start.clone(), &opts).expect("optimize"))
    });
    group.bench_function("fused (cpu)", |b| {
        b.iter(|| optimize::optimize(&mut Fused::cpu(), &batch, std::slice::from_ref(&design), start.clone(), &opts).expect("optimize"))
    });
    group.finish();
}

/// `count` variants of the free 6-dof design, its non-zero `d` and `a` scaled by 0.85 .. 1.2: one
/// dof count and capsule structure.
fn variants(count: usize) -> Vec<proving_ground::design::Design> {
    let (design, _) = inputs();
    (0..count)
        .map(|k| {
            let factor = 0.85 + 0.35 * k as f64 / count.saturating_sub(1).max(1) as f64;
            let mut variant = design.clone();
            variant.name = format!("scaled-{k}");
            for joint in &mut variant.joints {
                joint.d *= factor;
                joint.a *= factor;
            }
            variant
        })
        .collect()
}

/// The paper's batch: 8 robots tuned together (9.31 s on its GPU). Here 8 variants of the free
/// 6-dof design.
fn eight_designs(c: &mut Criterion) {
    let (_, scenario) = inputs();
    let designs = variants(8);
    let opts = OptimizeOptions::default();
    let (batch, start) = optimize::starts_of(&designs, &scenario, &opts).expect("starts");
    let mut group = c.benchmark_group("optimize/8 designs x 8 goals x 4 starts x 200 steps");
    group.sample_size(10);
    group.bench_function("candle tensors (cpu)", |b| {
        b.iter(|| optimize::optimize(&mut Tensors::default(), &batch, &designs, start.clone(), &opts).expect("optimize"))
    });
    group.bench_function("hand-written f64", |b| {
        b.iter(|| optimize::optimize(&mut Analytic, &batch, &designs, start.clone(), &opts).expect("optimize"))
    });
    group.bench_function("fused (cpu)", |b| {
        b.iter(|| optimize::optimize(&mut Fused::cpu(), &batch, &designs, start.clone(), &opts).expect("optimize"))
    });
    group.finish();
}

/// The same on a CUDA GPU, the fused kernel (issue 25's target on one H100 or H200: 4 096 designs x 8 goals x 4
/// starts x 200 steps in at most 10 s, and faster than the CPU from 8 designs up), where the
/// crate is built with `--features cuda` and a GPU is present; elsewhere it says why it skips.
/// `scripts/gpu-check.sh` builds and runs it.
fn gpu(c: &mut Criterion) {
    let mut cuda = match Fused::cuda(0) {
        Ok(cuda) => cuda.gpu_always(),
        Err(why) => {
            eprintln!("optimize/cuda: skipped, no CUDA device ({why})");
            return;
        }
    };
    let size = 4096;
    let (batch, params) = batch_of(size);
    let mut group = c.benchmark_group("optimize/loss+gradient, batch 4096");
    group.sample_size(10);
    group.throughput(Throughput::Elements(size as u64));
    group.bench_function("fused kernel (cuda)", |b| b.iter(|| cuda.evaluate(&batch, &params).expect("cuda")));
    group.finish();
    let (_, scenario) = inputs();
    let opts = OptimizeOptions::default();
    for count in [8, 4096] {
        let designs = variants(count);
        let (batch, start) = optimize::starts_of(&designs, &scenario, &opts).expect("starts");
        let mut group = c.benchmark_group(format!("optimize/{count} designs x 8 goals x 4 starts x 200 steps"));
        group.sample_size(10);
        group.bench_function("fused kernel (cuda)", |b| {
            b.iter(|| optimize::optimize(&mut cuda, &batch, &designs, start.clone(), &opts).expect("optimize"))
        });
        group.finish();
    }
}

criterion_group!(benches, per_sample, whole, eight_designs, gpu);
criterion_main!(benches);
