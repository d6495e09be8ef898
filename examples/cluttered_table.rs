//! The table of cluttered-benchmark goals reached per shipped design (issue 3), and a diagnosis
//! of every goal no shipped design reaches.
//!
//! `cargo run --release --example cluttered_table` prints Markdown: per design the goals reached
//! out of 288 and the tasks with all 8 goals reached; then, per unreached goal, what stands in the
//! way for the design that came closest: out of reach (no design gets within 1 mm / 1 degree even
//! ignoring obstacles), or blocked (some design reaches the pose, but every solution found collides).
//! The last column is each task's own catalog robot (the one whose joint angles made the goals).

use proving_ground::collide::{self, structural_overlaps, CollideOptions, StructuralOptions};
use proving_ground::ik::{solve_goals, GoalSolutions, IkOptions};
use proving_ground::model::{self, Model};
use proving_ground::pipeline::{load_model, LoadOptions};
use proving_ground::scenario::{generate, load as load_scenario, Scenario};
use rayon::prelude::*;
use std::path::Path;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut designs: Vec<_> = std::fs::read_dir(root.join("designs"))?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    designs.sort();
    let tasks: Vec<Scenario> = (0..generate::CLUTTERED_TASKS)
        .map(|t| load_scenario(&root.join(format!("scenarios/cluttered/task-{t:02}.json"))))
        .collect::<Result<_, _>>()?;
    let models: Vec<Model> = designs
        .iter()
        .map(|d| load_model(d, &LoadOptions::default()))
        .collect::<Result<_, _>>()?;

    let started = Instant::now();
    // results[design][task]
    let results: Vec<Vec<Vec<GoalSolutions>>> = models.par_iter().map(|model| solve_all(model, &tasks)).collect::<Result<_, _>>()?;
    let elapsed = started.elapsed();

    let witnesses: Vec<Vec<GoalSolutions>> = (0..generate::CLUTTERED_TASKS)
        .into_par_iter()
        .map(|t| {
            let witness = generate::cluttered_witness(t, generate::CLUTTERED_MASTER_SEED);
            let names: Vec<String> = witness.modules.iter().map(|m| format!("\"{}\"", m.name())).collect();
            let text = format!(r#"{{"mode": "modular", "modules": [{}]}}"#, names.join(", "));
            let robot = model::from_design(&proving_ground::design::parse(&text, Path::new("witness.json"))?);
            Ok::<_, Box<dyn std::error::Error + Send + Sync>>(solve_all(&robot, std::slice::from_ref(&tasks[t]))?.remove(0))
        })
        .collect::<Result<_, _>>()?;

    let kinematic: Vec<usize> = models
        .par_iter()
        .map(|model| tasks.iter().map(|task| kinematically_reached(model, task)).sum())
        .collect();

    println!("| design | goals reached (of 288) | tasks fully solved (of 36) | reached ignoring collisions |");
    println!("|---|---:|---:|---:|");
    for ((model, per_task), kinematic) in models.iter().zip(&results).zip(&kinematic) {
        let reached: usize = per_task.iter().map(|goals| goals.iter().filter(|g| g.reached()).count()).sum();
        let full = per_task.iter().filter(|goals| goals.iter().all(GoalSolutions::reached)).count();
        println!("| {} | {reached} | {full} | {kinematic} |", model.name);
    }
    let reached: usize = witnesses.iter().map(|goals| goals.iter().filter(|g| g.reached()).count()).sum();
    let full = witnesses.iter().filter(|goals| goals.iter().all(GoalSolutions::reached)).count();
    println!("| each task's own catalog robot | {reached} | {full} | 288 by construction |");

    println!("\n| task | goal | closest design | position error (mm) | orientation error (deg) | exact clearance (mm) | diagnosis | own catalog robot |");
    println!("|---|---|---|---:|---:|---:|---|---|");
    let mut unreached = 0;
    let mut union = 0;
    for (t, task) in tasks.iter().enumerate() {
        for (g, goal) in task.goals.iter().enumerate() {
            if results.iter().any(|per_task| per_task[t][g].reached()) {
                union += 1;
                continue;
            }
            unreached += 1;
            // The design whose best solution is closest: pose reached first, then smallest error.
            let mut best: Option<(usize, &proving_ground::ik::IkSolution)> = None;
            for (d, per_task) in results.iter().enumerate() {
                if let Some(s) = per_task[t][g].solutions.first() {
                    let key = |s: &proving_ground::ik::IkSolution| (!s.pose_reached, s.error.position_m + 0.5 * s.error.orientation_rad);
                    if best.is_none_or(|(_, b)| key(s) < key(b)) {
                        best = Some((d, s));
                    }
                }
            }
            let own = if witnesses[t][g].reached() { "reaches it" } else { "does not" };
            if let Some((d, s)) = best {
                let clearance = s.clearance.map_or(f64::NAN, |c| c.exact_m * 1e3);
                let diagnosis = if s.pose_reached {
                    "blocked: every solution collides"
                } else {
                    "out of reach of every design"
                };
                println!(
                    "| {t:02} | {} | {} | {:.1} | {:.2} | {clearance:.1} | {diagnosis} | {own} |",
                    goal.name,
                    models[d].name,
                    s.error.position_m * 1e3,
                    s.error.orientation_rad.to_degrees(),
                )
            }
        }
    }
    println!("\n{union} of 288 goals reached by at least one shipped design; {unreached} by none.");
    eprintln!(
        "{} designs x 36 tasks in {:.2} s on {} threads ({:.2} ms per design and task)",
        models.len(),
        elapsed.as_secs_f64(),
        rayon::current_num_threads(),
        elapsed.as_secs_f64() * 1e3 / (models.len() * 36) as f64 * rayon::current_num_threads() as f64
    );
    Ok(())
}

/// Goals of `task` reached by `model` when the obstacles, the floor and self-collision are ignored.
fn kinematically_reached(model: &Model, task: &Scenario) -> usize {
    let placed = model.placed(&task.world_from_base);
    solve_goals(&placed, task, None, &IkOptions::default())
        .iter()
        .filter(|g| g.reached())
        .count()
}

fn solve_all(model: &Model, tasks: &[Scenario]) -> Result<Vec<Vec<GoalSolutions>>, Box<dyn std::error::Error + Send + Sync>> {
    // Self pairs do not depend on where the robot stands: sampled once per design.
    let structural = structural_overlaps(model, &StructuralOptions::default())?;
    tasks
        .iter()
        .map(|task| {
            let placed = model.placed(&task.world_from_base);
            let opts = CollideOptions {
                excluded_pairs: structural.pairs.clone(),
                excluded_shapes: structural.shapes.clone(),
                structural_allowances: structural.allowances.clone(),
            };
            let world = collide::world(&placed, task, &opts)?;
            Ok(solve_goals(&placed, task, Some(&world), &IkOptions::default()))
        })
        .collect()
}
