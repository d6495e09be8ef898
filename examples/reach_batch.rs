//! The reach-only batch `proving_ground.reach` makes, called from Rust: the reference that
//! `python/bench.py` measures the binding's overhead against.
//!
//! `cargo run --release --example reach_batch -- TASK DESIGN.json...` reads the design files
//! once, then times (median of 5) parsing them and evaluating them all on TASK in parallel,
//! the work `reach` does after the Python layer hands the designs over as JSON text.

use proving_ground::pipeline::Loaded;
use proving_ground::sweep::record::evaluate_batch;
use proving_ground::sweep::SweepMode;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

const REPEATS: usize = 5;

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (task, designs) = args.split_first().ok_or("usage: reach_batch TASK DESIGN.json...")?;
    let scenario = proving_ground::pipeline::load_scenario(Path::new(task))?;
    let texts: Vec<(String, String)> = designs
        .iter()
        .map(|path| Ok((path.clone(), std::fs::read_to_string(path)?)))
        .collect::<Result<_, std::io::Error>>()?;
    // The sweep's defaults, as `reach` has them.
    let mode = SweepMode::ReachOnly {
        ik: proving_ground::ik::IkOptions {
            search_boxes: proving_ground::ik::SWEEP_SEARCH_BOXES,
            ..Default::default()
        },
    };
    let mut times = Vec::with_capacity(REPEATS);
    let mut solved = 0;
    for _ in 0..REPEATS {
        let start = Instant::now();
        let batch = texts
            .iter()
            .map(|(path, text)| {
                let design = proving_ground::design::parse(text, Path::new(path))?;
                let model = proving_ground::model::from_design(&design);
                Ok((
                    design.name.clone(),
                    Loaded {
                        model,
                        design: Some(design),
                    },
                ))
            })
            .collect::<Result<Vec<_>, proving_ground::design::DesignError>>()?;
        let records = evaluate_batch(batch, task, &scenario, &mode, &AtomicBool::new(false))?.ok_or("stopped")?;
        times.push(start.elapsed().as_secs_f64());
        solved = records.iter().map(|r| r.goals_solved).sum::<usize>();
    }
    // The first round decides every link pair's structural overlaps; later rounds find them
    // remembered (a training loop's new designs would not).
    let first = times[0];
    times.sort_by(f64::total_cmp);
    let median = times[REPEATS / 2];
    println!(
        "{} designs x 1 task, {} threads: {median:.3} s ({:.2} ms per pair, {solved} goals solved; first round {:.2} ms per pair)",
        texts.len(),
        rayon::current_num_threads(),
        1e3 * median / texts.len() as f64,
        1e3 * first / texts.len() as f64
    );
    Ok(())
}
