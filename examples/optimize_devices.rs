//! Issue 25's timing table: `optimize` of a batch of free designs (variants of
//! `free-offset-6dof`, its non-zero `d` and `a` scaled by 0.85 .. 1.2) on cluttered task 03, 8 goals
//! x 4 starts x 200 steps, with the fused objective on the CPU (all its cores) and on CUDA GPU 0,
//! as a Markdown table; the last column is the largest difference between the two tuned batches
//! (0: bit for bit the same).
//!
//! `cargo run --release --features cuda --example optimize_devices -- [SIZES...]` (default
//! `1 8 64 256 4096`). `scripts/gpu-check.sh` runs it. The
//! IK starts are computed before the clock starts; the GPU is warmed up by one untimed run.

use proving_ground::optimize::{self, Fused, OptimizeOptions};
use std::path::Path;
use std::time::Instant;

/// Above this many designs the CPU is not timed.
const CPU_UP_TO: usize = 4096;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let sizes: Vec<usize> = std::env::args().skip(1).map(|a| a.parse()).collect::<Result<_, _>>()?;
    let sizes = if sizes.is_empty() { vec![1, 8, 64, 256, 4096] } else { sizes };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let design = proving_ground::design::load(&root.join("designs/free-offset-6dof.json"))?;
    let scenario = proving_ground::scenario::load(&root.join("scenarios/cluttered/task-03.json"))?;
    let opts = OptimizeOptions::default();
    // The kernels themselves, however small the batch (`optimize --device cuda` runs a batch of
    // fewer than 64 samples per CPU thread on the CPU, where it is done sooner).
    let mut cuda = match Fused::cuda(0) {
        Ok(cuda) => Some(cuda.gpu_always()),
        Err(why) => {
            eprintln!("no CUDA device ({why}): the CPU alone is timed");
            None
        }
    };
    if let Some(cuda) = cuda.as_mut() {
        let (batch, start) = optimize::starts(&design, &scenario, &opts)?;
        optimize::optimize(cuda, &batch, std::slice::from_ref(&design), start, &opts)?;
    }
    println!("| designs in the batch | CPU | CUDA | objective summed | CPU and CUDA tuned designs apart |");
    println!("| --- | --- | --- | --- | --- |");
    for count in sizes {
        let designs: Vec<_> = (0..count)
            .map(|k| {
                let factor = 0.85 + 0.35 * k as f64 / count.saturating_sub(1).max(1) as f64;
                let mut variant = design.clone();
                variant.name = format!("scaled-{k}");
                variant.joints.iter_mut().for_each(|j| (j.d, j.a) = (j.d * factor, j.a * factor));
                variant
            })
            .collect();
        let (batch, start) = optimize::starts_of(&designs, &scenario, &opts)?;
        let run = |objective: &mut Fused| -> Result<(f64, f64, Vec<f64>), Box<dyn std::error::Error>> {
            let clock = Instant::now();
            let tuned = optimize::optimize(objective, &batch, &designs, start.clone(), &opts)?;
            let rows = tuned.params.d.iter().chain(&tuned.params.a).copied().collect();
            Ok((clock.elapsed().as_secs_f64(), tuned.objective.1.iter().sum(), rows))
        };
        let cpu = if count <= CPU_UP_TO { Some(run(&mut Fused::cpu())?) } else { None };
        let gpu = match cuda.as_mut() {
            Some(cuda) => Some(run(cuda)?),
            None => None,
        };
        let time = |r: &Option<(f64, f64, Vec<f64>)>| r.as_ref().map_or("-".to_string(), |(t, _, _)| format!("{t:.2} s"));
        let objective = cpu.as_ref().or(gpu.as_ref()).map_or("-".to_string(), |(_, o, _)| format!("{o:.6}"));
        let apart = match (&cpu, &gpu) {
            (Some((_, _, a)), Some((_, _, b))) => format!("{:e}", a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)),
            _ => "-".to_string(),
        };
        println!("| {count} | {} | {} | {objective} | {apart} |", time(&cpu), time(&gpu));
    }
    Ok(())
}
