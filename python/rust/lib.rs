//! The Python module `proving_ground._proving_ground`: a thin binding over the library. Each
//! function takes its inputs as the Python layer (`src/proving_ground/__init__.py`) hands them
//! over (a file path or JSON text, options as a JSON object), calls what `validate-design` calls
//! and gives back what it prints (the `--json` report) or numbers as NumPy arrays. Long work runs
//! with the GIL released; errors raise `ProvingGroundError` with the CLI's message.

use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2};
use proving_ground::design::Design;
use proving_ground::pipeline::{self, Loaded};
use proving_ground::scenario::Scenario;
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

create_exception!(
    _proving_ground,
    ProvingGroundError,
    PyException,
    "An input that cannot be used or a run that could not be made; the message names the file, the field or line, and what was expected."
);

fn error(e: impl std::fmt::Display) -> PyErr {
    ProvingGroundError::new_err(e.to_string())
}

/// A robot or scenario as the Python layer hands it over: `("path", path)` or
/// `("json", name, text)` with the name messages use.
#[derive(FromPyObject)]
enum Source {
    #[pyo3(transparent)]
    Path(String),
    Json(String, String),
}

fn load_robot(source: &Source, opts: &proving_ground::Options) -> PyResult<(std::path::PathBuf, Loaded)> {
    match source {
        Source::Path(path) => {
            let path = Path::new(path);
            Ok((path.to_path_buf(), pipeline::load(path, &opts.load).map_err(error)?))
        }
        Source::Json(name, text) => {
            let design = proving_ground::design::parse(text, Path::new(name)).map_err(error)?;
            Ok((name.into(), loaded(design)))
        }
    }
}

fn loaded(design: Design) -> Loaded {
    Loaded {
        model: proving_ground::model::from_design(&design),
        design: Some(design),
    }
}

fn load_scenario(source: Option<&Source>) -> PyResult<Scenario> {
    match source {
        None => pipeline::scenario_or_default(None).map_err(error),
        Some(Source::Path(path)) => pipeline::load_scenario(Path::new(path)).map_err(error),
        Some(Source::Json(name, text)) => proving_ground::scenario::parse(text, Path::new(name)).map_err(error),
    }
}

/// The `--json` report of the run `validate-design` makes of `design` on `scenario` with the
/// named options (a JSON object, names as on the command line with `_` for `-`).
#[pyfunction]
#[pyo3(signature = (design, scenario, options))]
fn validate(py: Python<'_>, design: Source, scenario: Option<Source>, options: &str) -> PyResult<String> {
    let named: proving_ground::run::Named = serde_json::from_str(options).map_err(|e| error(format!("options: {e}")))?;
    let opts = named.options().map_err(error)?;
    let (input, robot) = load_robot(&design, &opts)?;
    let scenario = load_scenario(scenario.as_ref())?;
    run_interruptibly(py, |stop| {
        let run = match proving_ground::run::validate_loaded(&input, robot, scenario, &opts, &Stoppable(stop)) {
            Ok(run) => run,
            Err(proving_ground::error::Error::Stopped) => return Ok(None),
            Err(e) => return Err(e.to_string()),
        };
        let report = run.report.ok_or_else(|| "the run stopped before the scenario".to_string())?;
        proving_ground::run::report_json(&report).map(Some).map_err(|e| e.to_string())
    })
}

/// Shows nothing and stops the run when its flag is set (by Ctrl-C, see [`run_interruptibly`]).
struct Stoppable<'a>(&'a AtomicBool);

impl proving_ground::progress::Progress for Stoppable<'_> {
    fn stage(&self, _name: &str, _total: Option<u64>) {}
    fn advance(&self) {}
    fn stopped(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// How often the caller's thread looks for Ctrl-C while a batch runs.
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(20);

/// Runs `work` on a thread of its own with the GIL released while the caller's thread checks for
/// Ctrl-C (Python handles signals on the main thread only); on Ctrl-C it sets the stop flag `work`
/// reads, waits for the designs already started and raises `KeyboardInterrupt`.
fn run_interruptibly<T: Send>(py: Python<'_>, work: impl FnOnce(&AtomicBool) -> Result<Option<T>, String> + Send) -> PyResult<T> {
    let stop = AtomicBool::new(false);
    let mut interrupt = None;
    let done = py.detach(|| {
        std::thread::scope(|scope| {
            // The worker says when it is done: waiting on that, not sleeping a whole poll,
            // returns the moment the batch ends (a sleep cost up to 20 ms a call).
            let (finished, wait) = std::sync::mpsc::channel();
            // The sender moves into the worker, so a panic drops it and ends the wait too.
            let stop = &stop;
            let worker = scope.spawn(move || {
                let result = work(stop);
                let _ = finished.send(());
                result
            });
            while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) = wait.recv_timeout(SIGNAL_POLL) {
                if interrupt.is_none() {
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
                        interrupt = Some(e);
                        stop.store(true, Ordering::Relaxed);
                    }
                }
            }
            worker.join()
        })
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    match done {
        Ok(Ok(Some(value))) => Ok(value),
        Ok(Ok(None)) => Err(error("the run was stopped")),
        Ok(Err(e)) => Err(error(e)),
        Err(_) => Err(error("the batch's worker thread panicked; please report this with the inputs")),
    }
}

/// The reach-only records `sweep` writes, one per design, in order, computed in parallel.
#[pyfunction]
#[pyo3(signature = (designs, scenario, ik_seeds, seed, search_boxes, threads))]
fn reach<'py>(
    py: Python<'py>,
    designs: Vec<Source>,
    scenario: Source,
    ik_seeds: usize,
    seed: u64,
    search_boxes: usize,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    if !(1..=proving_ground::limits::MAX_IK_SEEDS as usize).contains(&ik_seeds) {
        return Err(error(format!(
            "ik_seeds: {ik_seeds} is out of range; expected 1 to {}",
            proving_ground::limits::MAX_IK_SEEDS
        )));
    }
    let scenario_name = match &scenario {
        Source::Path(path) => path.clone(),
        Source::Json(name, _) => name.clone(),
    };
    let scenario = load_scenario(Some(&scenario))?;
    let opts = proving_ground::Options::default();
    let robots: Vec<(String, Loaded)> = designs
        .iter()
        .map(|source| {
            load_robot(source, &opts).map(|(path, loaded)| {
                let id = match source {
                    Source::Path(_) => path.display().to_string(),
                    Source::Json(..) => loaded.model.name.clone(),
                };
                (id, loaded)
            })
        })
        .collect::<PyResult<_>>()?;
    let mode = proving_ground::sweep::SweepMode::ReachOnly {
        ik: proving_ground::ik::IkOptions {
            seeds: ik_seeds,
            search_boxes,
            seed,
            ..Default::default()
        },
    };
    let pool = match threads {
        Some(n) => Some(rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build().map_err(error)?),
        None => None,
    };
    let records = run_interruptibly(py, |stop| {
        let evaluate =
            || proving_ground::sweep::record::evaluate_batch(robots, &scenario_name, &scenario, &mode, stop).map_err(|e| e.to_string());
        match &pool {
            Some(pool) => pool.install(evaluate),
            None => evaluate(),
        }
    })?;
    let out = PyDict::new(py);
    let column = |f: &dyn Fn(&proving_ground::sweep::record::Record) -> f64| records.iter().map(f).collect::<Vec<f64>>();
    let count = |f: &dyn Fn(&proving_ground::sweep::record::Record) -> usize| records.iter().map(|r| f(r) as i64).collect::<Vec<i64>>();
    out.set_item("goals", PyArray1::from_vec(py, count(&|r| r.goals)))?;
    out.set_item("solved", PyArray1::from_vec(py, count(&|r| r.goals_solved)))?;
    out.set_item("proven_unreachable", PyArray1::from_vec(py, count(&|r| r.goals_proven_unreachable)))?;
    out.set_item("undecided", PyArray1::from_vec(py, count(&|r| r.goals_undecided)))?;
    out.set_item(
        "task_solved",
        PyArray1::from_vec(py, records.iter().map(|r| r.task_solved).collect::<Vec<bool>>()),
    )?;
    out.set_item("task_loss", PyArray1::from_vec(py, column(&|r| r.task_loss.unwrap_or(f64::NAN))))?;
    out.set_item(
        "hardware_cost",
        PyArray1::from_vec(py, column(&|r| r.hardware_cost_m.unwrap_or(f64::NAN))),
    )?;
    out.set_item(
        "position_error_mm",
        PyArray1::from_vec(py, column(&|r| r.position_error_mm.unwrap_or(f64::NAN))),
    )?;
    out.set_item(
        "records",
        records
            .iter()
            .map(|r| serde_json::to_string(r).unwrap_or_default())
            .collect::<Vec<_>>(),
    )?;
    Ok(out)
}

/// The paper's differentiable objective per sample (design, goal, configuration) and its
/// gradients with respect to the configuration and the design's `d` and `a`.
#[pyfunction]
#[pyo3(signature = (designs, scenario, samples, q))]
fn loss_and_grad<'py>(
    py: Python<'py>,
    designs: Vec<Source>,
    scenario: Source,
    samples: Option<Vec<(usize, usize)>>,
    q: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyDict>> {
    use proving_ground::optimize::{Batch, Objective, Params, Sample};
    let scenario = load_scenario(Some(&scenario))?;
    let opts = proving_ground::Options::default();
    let designs: Vec<Design> = designs
        .iter()
        .map(|source| {
            load_robot(source, &opts)?.1.design.ok_or_else(|| {
                error("loss_and_grad needs designs with DH rows (free, economic, modular or preset), not URDF or MJCF robots")
            })
        })
        .collect::<PyResult<_>>()?;
    let q = q.as_array();
    // Default: every goal of every design, design-major.
    let samples = samples.unwrap_or_else(|| {
        (0..designs.len())
            .flat_map(|d| (0..scenario.goals.len()).map(move |g| (d, g)))
            .collect()
    });
    let samples: Vec<Sample> = samples.into_iter().map(|(design, goal)| Sample { design, goal }).collect();
    let batch = Batch::new(&designs, &scenario, samples).map_err(error)?;
    let n = batch.dof;
    if q.shape() != [batch.samples.len(), n] {
        return Err(error(format!(
            "q has shape {:?}; expected ({}, {n}): one row of joint values per sample",
            q.shape(),
            batch.samples.len()
        )));
    }
    if q.iter().any(|v| !v.is_finite()) {
        return Err(error("q holds a number that is not finite"));
    }
    let params = Params {
        q: q.iter().copied().collect(),
        d: designs.iter().flat_map(|d| d.joints.iter().map(|j| j.d)).collect(),
        a: designs.iter().flat_map(|d| d.joints.iter().map(|j| j.a)).collect(),
    };
    let evaluation = py
        .detach(|| proving_ground::optimize::Fused::cpu().evaluate(&batch, &params))
        .map_err(error)?;
    let count = batch.samples.len();
    let (objective, chosen) = proving_ground::optimize::design_objective(&batch, &params, &evaluation);
    // The design objective's gradient: its goals' chosen samples, plus w_c times the signs of d
    // and a (the hardware cost's subgradient; a zero offset stays zero and gets none).
    let designs_count = designs.len();
    let mut objective_d = vec![0.0; designs_count * n];
    let mut objective_a = vec![0.0; designs_count * n];
    for (b, sample) in batch.samples.iter().enumerate().filter(|(b, _)| chosen[*b]) {
        for j in 0..n {
            objective_d[sample.design * n + j] += evaluation.grad_d[b * n + j];
            objective_a[sample.design * n + j] += evaluation.grad_a[b * n + j];
        }
    }
    let weight = proving_ground::ik::HARDWARE_WEIGHT;
    for (k, (&d, &a)) in params.d.iter().zip(&params.a).enumerate() {
        objective_d[k] += weight * d.signum() * f64::from(u8::from(d != 0.0));
        objective_a[k] += weight * a.signum() * f64::from(u8::from(a != 0.0));
    }
    let out = PyDict::new(py);
    out.set_item("objective", PyArray1::from_vec(py, objective))?;
    out.set_item("chosen", PyArray1::from_vec(py, chosen))?;
    for (name, values) in [("objective_grad_d", objective_d), ("objective_grad_a", objective_a)] {
        let array: Bound<'py, PyArray2<f64>> = PyArray1::from_vec(py, values).reshape([designs_count, n])?;
        out.set_item(name, array)?;
    }
    out.set_item(
        "loss",
        PyArray1::from_vec(py, (0..count).map(|b| evaluation.loss(b)).collect::<Vec<f64>>()),
    )?;
    out.set_item("distance", PyArray1::from_vec(py, evaluation.distance.clone()))?;
    out.set_item("collision", PyArray1::from_vec(py, evaluation.collision.clone()))?;
    for (name, values) in [
        ("grad_q", &evaluation.grad_q),
        ("grad_d", &evaluation.grad_d),
        ("grad_a", &evaluation.grad_a),
    ] {
        let array: Bound<'py, PyArray2<f64>> = PyArray1::from_vec(py, values.clone()).reshape([count, n])?;
        out.set_item(name, array)?;
    }
    Ok(out)
}

/// A design file's text (the JSON `design::to_json` writes) of the catalog's `modular6` robot
/// number `index` (0 to 15 624), or of the DH rows `(d, a, alpha)` as a free or economic design.
#[pyfunction]
#[pyo3(signature = (index))]
fn modular6(index: usize) -> PyResult<String> {
    let count = modular6_count();
    if index >= count {
        return Err(error(format!(
            "modular6 index {index} is out of range; expected 0 to {}",
            count - 1
        )));
    }
    let slots = proving_ground::sweep::inputs::modular6_slots(index);
    let entry = proving_ground::sweep::inputs::catalog_entry(&slots);
    let design = Design::modular(&entry.id, &slots);
    Ok(proving_ground::design::to_json(&design, "the modular6 catalog"))
}

/// Robots in the `modular6` catalog: every option in each of its slots.
fn modular6_count() -> usize {
    let options = proving_ground::design::catalog::SlotOption::ALL.len();
    options.pow(proving_ground::sweep::inputs::CATALOG_SLOTS as u32)
}

/// The ids of the `modular6` catalog's robots, in catalog order.
#[pyfunction]
fn modular6_ids() -> Vec<String> {
    (0..modular6_count())
        .map(|k| proving_ground::sweep::inputs::catalog_entry(&proving_ground::sweep::inputs::modular6_slots(k)).id)
        .collect()
}

/// The defaults the Python layer shows: the sweeps' joint-space search budget.
#[pyfunction]
fn sweep_search_boxes() -> usize {
    proving_ground::ik::SWEEP_SEARCH_BOXES
}

/// A scenario file's text from a generator (`cluttered`, `workspace`, `course`).
#[pyfunction]
#[pyo3(signature = (generator, seed, task, count))]
fn generate(generator: &str, seed: Option<u64>, task: Option<usize>, count: Option<usize>) -> PyResult<String> {
    use proving_ground::scenario::generate::{outputs, Generator, Request};
    let generator = match generator {
        "cluttered" => Generator::Cluttered,
        "workspace" => Generator::Workspace,
        "course" => Generator::Course,
        other => {
            return Err(error(format!(
                "unknown generator `{other}`; expected cluttered, workspace or course"
            )))
        }
    };
    let request = Request {
        generator,
        seed,
        task,
        all: false,
        count,
        scale: None,
        tolerance: None,
        out: "scenario.json".into(),
        force: false,
    };
    let scenarios = outputs(&request).map_err(error)?;
    let (_, scenario) = scenarios.first().ok_or_else(|| error("the generator made no scenario"))?;
    Ok(proving_ground::scenario::to_json(scenario))
}

/// The module.
#[pymodule]
fn _proving_ground(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("ProvingGroundError", m.py().get_type::<ProvingGroundError>())?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(reach, m)?)?;
    m.add_function(wrap_pyfunction!(loss_and_grad, m)?)?;
    m.add_function(wrap_pyfunction!(modular6, m)?)?;
    m.add_function(wrap_pyfunction!(generate, m)?)?;
    m.add_function(wrap_pyfunction!(modular6_ids, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_search_boxes, m)?)?;
    Ok(())
}
