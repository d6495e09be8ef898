//! The golden snapshot regression suite: every shipped design against the course, six cluttered
//! tasks and a 100-pose workspace scenario, each report snapshotted with insta into
//! `golden/reports/` (YAML, numbers rounded to what is physically meaningful, see [`rounded`]).
//! Review a change with `cargo insta review`; in CI (`CI=true`) any difference fails.

mod common;

use common::repo;
use proving_ground::pipeline::{load, validate, LoadOptions, ValidateOptions};
use proving_ground::report;
use proving_ground::scenario::{generate, load as load_scenario, Scenario, Tolerance};
use rayon::prelude::*;
use serde_json::Value;
use std::path::PathBuf;

/// The cluttered tasks in the matrix: spread over the 36.
const CLUTTERED_TASKS: [usize; 6] = [0, 6, 12, 18, 24, 30];
/// Poses of the workspace scenario in the matrix (the generator's, seed `WORKSPACE_SEED`).
const WORKSPACE_POSES: usize = 100;

fn designs() -> Vec<PathBuf> {
    let mut designs: Vec<PathBuf> = std::fs::read_dir(repo().join("designs"))
        .expect("designs/ lists")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    designs.sort();
    designs
}

fn scenarios() -> Vec<(String, Scenario)> {
    let mut scenarios = vec![(
        "course".to_string(),
        load_scenario(&repo().join("scenarios/course.json")).expect("course loads"),
    )];
    for task in CLUTTERED_TASKS {
        let path = repo().join(format!("scenarios/cluttered/task-{task:02}.json"));
        scenarios.push((format!("cluttered-{task:02}"), load_scenario(&path).expect("task loads")));
    }
    let workspace = generate::workspace(WORKSPACE_POSES, 1.0, Tolerance::ZSymmetric, generate::WORKSPACE_SEED).expect("valid parameters");
    scenarios.push((format!("workspace-z_symmetric-{WORKSPACE_POSES}"), workspace));
    scenarios
}

/// Rounds every number of a report to the precision we claim, by the unit its field name ends
/// in: lengths (`_m`) to 0.1 mm, angles in degrees (`_deg`) to 0.01 degree, in radians (`_rad`,
/// and joint configurations) to 1e-4 rad, times (`_s`) to 1 ms; everything else to 4
/// significant digits; cross-check disagreements to the 1e-9 that makes a finding. Negative zero
/// becomes zero, so the sign of a rounding is not a change.
fn rounded(value: &mut Value, key: &str) {
    const CONFIGURATIONS: [&str; 5] = ["q", "chosen", "home", "from", "to"];
    match value {
        Value::Number(number) if number.is_f64() => {
            let x = number.as_f64().unwrap_or(f64::NAN);
            let step = if key.ends_with("disagreement") {
                // Cross-checks between two f64 computations: rounding noise below the 1e-9 that
                // makes a finding, so only that resolution is meaningful.
                Some(1e-9)
            } else if key.ends_with("_m") {
                Some(1e-4)
            } else if key.ends_with("_deg") {
                Some(1e-2)
            } else if key.ends_with("_rad") || CONFIGURATIONS.contains(&key) {
                Some(1e-4)
            } else if key.ends_with("_s") {
                Some(1e-3)
            } else {
                None
            };
            let r = match step {
                Some(step) => (x / step).round() * step,
                None if x == 0.0 || !x.is_finite() => x,
                None => {
                    let scale = 10f64.powi(3 - x.abs().log10().floor() as i32);
                    (x * scale).round() / scale
                }
            };
            let r = if r == 0.0 { 0.0 } else { r };
            // Printed through f32-free shortest decimal: parse the rounded text back.
            let text = match step {
                Some(step) => format!("{:.*}", (-step.log10()).round().max(0.0) as usize, r),
                None => format!("{r}"),
            };
            *value = serde_json::from_str(&text).unwrap_or(Value::Null);
        }
        Value::Array(items) => items.iter_mut().for_each(|item| rounded(item, key)),
        Value::Object(map) => map.iter_mut().for_each(|(k, v)| rounded(v, k)),
        _ => {}
    }
}

fn report_value(design: &std::path::Path, scenario: &Scenario) -> Value {
    let loaded = load(design, &LoadOptions::default()).expect("shipped design loads");
    let validation = validate(loaded, scenario.clone(), &ValidateOptions::default()).expect("runs");
    let mut value = serde_json::to_value(report::build(&validation)).expect("report serialises");
    rounded(&mut value, "");
    value
}

#[test]
fn golden_reports_of_every_design_on_the_matrix() {
    let designs = designs();
    let scenarios = scenarios();
    let pairs: Vec<(usize, usize)> = (0..designs.len()).flat_map(|d| (0..scenarios.len()).map(move |s| (d, s))).collect();
    let reports: Vec<Value> = pairs.par_iter().map(|&(d, s)| report_value(&designs[d], &scenarios[s].1)).collect();

    let mut failures = Vec::new();
    for (&(d, s), value) in pairs.iter().zip(reports) {
        let design = designs[d].file_stem().and_then(|s| s.to_str()).unwrap_or("design");
        let name = format!("{design}__{}", scenarios[s].0);
        let mut settings = insta::Settings::clone_current();
        settings.set_snapshot_path("../golden/reports");
        settings.set_snapshot_suffix(name.clone());
        settings.set_prepend_module_to_snapshot(false);
        settings.set_sort_maps(true);
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            settings.bind(|| insta::assert_yaml_snapshot!("report", value))
        }));
        if outcome.is_err() {
            failures.push(name);
        }
    }
    assert!(
        failures.is_empty(),
        "{} snapshots differ (cargo insta review): {failures:?}",
        failures.len()
    );
}

#[test]
fn the_same_run_gives_byte_identical_reports_on_one_and_on_two_threads() {
    let design = repo().join("designs/paper-real-world.json");
    let scenario = load_scenario(&repo().join("scenarios/course.json")).expect("course loads");
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        pool.install(|| {
            let loaded = load(&design, &LoadOptions::default()).expect("loads");
            let validation = validate(loaded, scenario.clone(), &ValidateOptions::default()).expect("runs");
            serde_json::to_string_pretty(&report::build(&validation)).expect("serialises")
        })
    };
    let first = run(1);
    assert_eq!(first, run(1), "two runs on one thread differ");
    assert_eq!(first, run(2), "one thread and two threads differ");
}

#[test]
fn rounding_keeps_what_is_physically_meaningful() {
    let mut value = serde_json::json!({
        "distance_m": 0.123456789, "angle_deg": -0.0012, "orientation_rad": 0.000123456,
        "q": [1.23456789, -0.00001], "time_s": 1.23456, "loss": 32.98623, "count": 7,
    });
    rounded(&mut value, "");
    assert_eq!(
        value,
        serde_json::json!({
            "distance_m": 0.1235, "angle_deg": 0.0, "orientation_rad": 0.0001,
            "q": [1.2346, 0.0], "time_s": 1.235, "loss": 32.99, "count": 7,
        })
    );
}
