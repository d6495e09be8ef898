//! Consumes a design, a scenario and starting configurations (IK's solutions plus seeded random
//! starts). Produces the design and configurations after the paper's Adam fine-tuning of its
//! differentiable objective. Fails with [`OptimizeError`] when the batch cannot be built or a
//! tensor operation fails.
//!
//! The objective per sample (one design, one goal, one start) is the paper's
//! `w_d d(g, q) + w_col c_col(q)` in the capsule model (`ik::paper_loss_terms`), plus
//! `w_c c_h` per design. Each start descends its own sample's loss (learning rate 0.1); the
//! design's `d` and `a` (learning rate 0.01) descend `sum over goals of min over starts + w_c c_h`,
//! the loss the design is scored by. `alpha` stays (discrete); a zero `d` or `a` stays zero
//! (it decides the capsule structure); economic values are projected back into their sets after
//! each step; modular and preset designs only move `q`. The best iterate is kept, so the result
//! never scores worse than the start.

pub mod analytic;
mod fused;
mod fused_cpu;
mod gaps;
mod portable;
pub mod problem;
pub mod tensor;
mod tune;

pub use analytic::Analytic;
pub use fused::Fused;
pub use problem::{Batch, Evaluation, Params, Sample};
pub use tensor::Tensors;
pub use tune::{
    batches, before_and_after, best_module_swap, choose, lost_ground, module_swaps, nothing_to_tune, tune, validation, Choice, Tuned,
};

use crate::design::{Design, DesignMode};
use crate::ik::HARDWARE_WEIGHT;
use crate::scenario::Scenario;
use rand::SeedableRng;
use rayon::prelude::*;

/// One way to evaluate the objective and its gradients over a batch.
pub trait Objective {
    /// The paper's terms and the gradients of each sample's loss at `params`.
    ///
    /// # Errors
    /// [`OptimizeError::Tensor`] when a backend's operation fails.
    fn evaluate(&mut self, batch: &Batch, params: &Params) -> Result<Evaluation, OptimizeError>;

    /// The whole of [`optimize`], where the backend runs it itself, with the same result (a GPU
    /// keeps every step on the device); `None` where [`optimize`] steps it.
    ///
    /// # Errors
    /// The backend's errors.
    fn optimize_whole(
        &mut self,
        _batch: &Batch,
        _designs: &[Design],
        _start: &Params,
        _opts: &OptimizeOptions,
    ) -> Option<Result<Optimized, OptimizeError>> {
        None
    }
}

/// Why an optimization could not run.
#[derive(Debug, thiserror::Error)]
pub enum OptimizeError {
    /// The designs do not form one batch.
    #[error("cannot batch the designs: {0}")]
    Batch(String),
    /// An input the command cannot use (which file or argument, and why).
    #[error("{0}")]
    Input(String),
    /// A tensor operation failed (candle's message).
    #[error("tensor backend: {0}")]
    Tensor(#[from] candle_core::Error),
    /// Building the collision world failed.
    #[error(transparent)]
    Pipeline(#[from] Box<crate::error::Error>),
}

/// The paper's refinement settings (Table A); every default is the paper's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptimizeOptions {
    /// Adam steps (default 200).
    pub steps: usize,
    /// Learning rate of the joint positions (default 0.1).
    pub joint_rate: f64,
    /// Learning rate of the design parameters `d` and `a` (default 0.01).
    pub design_rate: f64,
    /// Starts per goal (default 4, the paper's IK guesses).
    pub seeds: usize,
    /// Seed of the random starts (default 0).
    pub seed: u64,
}

impl Default for OptimizeOptions {
    fn default() -> Self {
        Self {
            steps: 200,
            joint_rate: 0.1,
            design_rate: 0.01,
            seeds: 4,
            seed: 0,
        }
    }
}

/// Pose distances (m for the position, rad for the rotation angle) below which a sample's
/// distance counts as zero, its gradient too. The norm's gradient is the direction of the
/// residual, and an exact IK solution (the starts are) leaves a residual of rounding alone:
/// that gradient was noise, and Adam's first step, which moves every parameter whose gradient
/// is not exactly zero by the whole rate, turned it into a kick of 0.1 rad per joint in a
/// random direction. One ulp of one DH parameter changed the design gradient at step 1 by up to
/// 4.3 and the tuned design by 0.1 after 200 steps; a CUDA run, whose rounding differs, diverged
/// the same way. Zero is the norm's own subgradient at zero; the value moves by less than this.
pub(crate) const POSE_DEAD_ZONE: f64 = 1e-9;

/// `distance` beyond [`POSE_DEAD_ZONE`], else 0.
pub(crate) fn beyond_dead_zone(distance: f64) -> f64 {
    if distance > POSE_DEAD_ZONE {
        distance
    } else {
        0.0
    }
}

/// The range of an economic design's non-zero `d` and `|a|` (m).
pub(crate) const ECONOMIC_RANGE_M: (f64, f64) = (0.1, 0.4);

/// Which `d` and `a` entries Adam moves: a free or economic design's non-zero ones (a zero
/// decides the capsule structure and stays).
pub(crate) fn free_lengths(designs: &[Design], n: usize, start: &Params) -> (Vec<bool>, Vec<bool>) {
    let movable = |design: &Design, value: f64| matches!(design.mode, DesignMode::Free | DesignMode::Economic) && value != 0.0;
    let free_d = (0..designs.len() * n).map(|i| movable(&designs[i / n], start.d[i])).collect();
    let free_a = (0..designs.len() * n).map(|i| movable(&designs[i / n], start.a[i])).collect();
    (free_d, free_a)
}

/// Adam's moment decay rates and denominator floor (Kingma and Ba's defaults, as the paper's
/// PyTorch optimizer).
pub(crate) const BETA1: f64 = 0.9;
pub(crate) const BETA2: f64 = 0.999;
pub(crate) const EPSILON: f64 = 1e-8;

/// Adam's state for one flat parameter vector.
#[derive(Debug, Clone)]
struct Adam {
    rate: f64,
    first: Vec<f64>,
    second: Vec<f64>,
}

impl Adam {
    fn new(rate: f64, len: usize) -> Self {
        Self {
            rate,
            first: vec![0.0; len],
            second: vec![0.0; len],
        }
    }

    /// One step (`step` counts from 1) on the entries `free` allows.
    fn step(&mut self, step: usize, values: &mut [f64], gradient: &[f64], free: &[bool]) {
        let (bias1, bias2) = (1.0 - BETA1.powi(step as i32), 1.0 - BETA2.powi(step as i32));
        for i in 0..values.len() {
            if !free[i] {
                continue;
            }
            self.first[i] = BETA1 * self.first[i] + (1.0 - BETA1) * gradient[i];
            self.second[i] = BETA2 * self.second[i] + (1.0 - BETA2) * gradient[i] * gradient[i];
            let (m, v) = (self.first[i] / bias1, self.second[i] / bias2);
            values[i] -= self.rate * m / (v.sqrt() + EPSILON);
        }
    }
}

/// The result of [`optimize`].
#[derive(Debug, Clone)]
pub struct Optimized {
    /// Per design, the best parameters seen (its rows of `d`, `a` and its samples' `q`).
    pub params: Params,
    /// The objective at the start and at [`Optimized::params`], per design.
    pub objective: (Vec<f64>, Vec<f64>),
    /// The objective's evaluation at [`Optimized::params`].
    pub evaluation: Evaluation,
    /// Per design, the step its best parameters come from (0: the start).
    pub best_step: Vec<usize>,
}

/// Per design, `sum over goals of min over its starts (w_d d + w_col c_col) + w_c c_h`, and per
/// sample whether it is its goal's best start (the lowest index among equals).
pub fn design_objective(batch: &Batch, params: &Params, evaluation: &Evaluation) -> (Vec<f64>, Vec<bool>) {
    let designs = batch.designs.len();
    let goals = batch.targets.len();
    // Per (design, goal), in that order: the sums below run in it, whatever the sample order.
    let mut best: Vec<Option<usize>> = vec![None; designs * goals];
    for (b, sample) in batch.samples.iter().enumerate() {
        let slot = &mut best[sample.design * goals + sample.goal];
        if slot.is_none_or(|kept| evaluation.loss(b) < evaluation.loss(kept)) {
            *slot = Some(b);
        }
    }
    let mut objective: Vec<f64> = (0..designs)
        .map(|design| {
            let (d, a) = batch.rows(params, design);
            HARDWARE_WEIGHT * d.iter().chain(a).map(|v| v.abs()).sum::<f64>()
        })
        .collect();
    let mut chosen = vec![false; batch.samples.len()];
    for (slot, b) in best.into_iter().enumerate() {
        if let Some(b) = b {
            objective[slot / goals] += evaluation.loss(b);
            chosen[b] = true;
        }
    }
    (objective, chosen)
}

/// Fine-tunes `start` for `batch` with Adam (see the module docs); `designs` gives each design's
/// mode (what may move and the economic sets) and joint limits.
///
/// # Errors
/// The objective's errors.
pub fn optimize(
    objective: &mut dyn Objective,
    batch: &Batch,
    designs: &[Design],
    start: Params,
    opts: &OptimizeOptions,
) -> Result<Optimized, OptimizeError> {
    if let Some(done) = objective.optimize_whole(batch, designs, &start, opts) {
        return done;
    }
    let n = batch.dof;
    let (free_d, free_a) = free_lengths(designs, n, &start);
    let free_q = vec![true; start.q.len()];
    let mut adam_q = Adam::new(opts.joint_rate, start.q.len());
    let mut adam_d = Adam::new(opts.design_rate, start.d.len());
    let mut adam_a = Adam::new(opts.design_rate, start.a.len());

    let mut samples_of = vec![Vec::new(); designs.len()];
    for (b, sample) in batch.samples.iter().enumerate() {
        samples_of[sample.design].push(b);
    }
    let mut params = start;
    let mut evaluation = objective.evaluate(batch, &params)?;
    let (initial, mut chosen) = design_objective(batch, &params, &evaluation);
    // Each design keeps its own best iterate: designs share a batch, not a fate.
    let mut best = Best {
        params: params.clone(),
        evaluation: evaluation.clone(),
        objective: initial.clone(),
        step: vec![0; designs.len()],
    };
    for step in 1..=opts.steps {
        // The design's gradient: its goals' best starts, and the hardware cost.
        let mut grad_d = vec![0.0; params.d.len()];
        let mut grad_a = vec![0.0; params.a.len()];
        for (b, sample) in batch.samples.iter().enumerate() {
            if !chosen[b] {
                continue;
            }
            for j in 0..n {
                grad_d[sample.design * n + j] += evaluation.grad_d[b * n + j];
                grad_a[sample.design * n + j] += evaluation.grad_a[b * n + j];
            }
        }
        for (gradient, values) in [(&mut grad_d, &params.d), (&mut grad_a, &params.a)] {
            for (g, v) in gradient.iter_mut().zip(values) {
                *g += HARDWARE_WEIGHT * v.signum();
            }
        }
        adam_q.step(step, &mut params.q, &evaluation.grad_q, &free_q);
        adam_d.step(step, &mut params.d, &grad_d, &free_d);
        adam_a.step(step, &mut params.a, &grad_a, &free_a);
        project(batch, designs, &mut params);

        evaluation = objective.evaluate(batch, &params)?;
        let (value, now_chosen) = design_objective(batch, &params, &evaluation);
        chosen = now_chosen;
        best.keep(batch, &samples_of, &params, &evaluation, &value, step);
    }
    Ok(Optimized {
        params: best.params,
        objective: (initial, best.objective),
        evaluation: best.evaluation,
        best_step: best.step,
    })
}

/// Per design, the best iterate so far.
struct Best {
    params: Params,
    evaluation: Evaluation,
    objective: Vec<f64>,
    step: Vec<usize>,
}

impl Best {
    /// Takes the rows of every design whose objective `value` beats its best.
    /// `samples_of` lists each design's samples.
    fn keep(&mut self, batch: &Batch, samples_of: &[Vec<usize>], params: &Params, evaluation: &Evaluation, value: &[f64], step: usize) {
        let n = batch.dof;
        for (design, &v) in value.iter().enumerate() {
            // A NaN objective (a diverged step) never replaces a number; a number replaces a NaN.
            let kept = self.objective[design];
            let better = v < kept || (kept.is_nan() && !v.is_nan());
            if !better {
                continue;
            }
            self.objective[design] = v;
            self.step[design] = step;
            let rows = design * n..(design + 1) * n;
            self.params.d[rows.clone()].copy_from_slice(&params.d[rows.clone()]);
            self.params.a[rows.clone()].copy_from_slice(&params.a[rows]);
            for &b in &samples_of[design] {
                let rows = b * n..(b + 1) * n;
                self.params.q[rows.clone()].copy_from_slice(&params.q[rows.clone()]);
                for (to, from) in [
                    (&mut self.evaluation.grad_q, &evaluation.grad_q),
                    (&mut self.evaluation.grad_d, &evaluation.grad_d),
                    (&mut self.evaluation.grad_a, &evaluation.grad_a),
                ] {
                    to[rows.clone()].copy_from_slice(&from[rows.clone()]);
                }
                self.evaluation.distance[b] = evaluation.distance[b];
                self.evaluation.collision[b] = evaluation.collision[b];
            }
        }
    }
}

/// Joint positions into their limits; economic `d` into [0.1, 0.4] m and `|a|` into
/// [0.1, 0.4] m with its sign (zeros never move); free values within the length limit.
fn project(batch: &Batch, designs: &[Design], params: &mut Params) {
    let n = batch.dof;
    for (b, sample) in batch.samples.iter().enumerate() {
        for (j, joint) in designs[sample.design].joints.iter().enumerate() {
            let q = &mut params.q[b * n + j];
            *q = q.clamp(joint.limits[0], joint.limits[1]);
        }
    }
    let (lower, upper) = ECONOMIC_RANGE_M;
    for (design_index, design) in designs.iter().enumerate() {
        for j in 0..n {
            for value in [&mut params.d[design_index * n + j], &mut params.a[design_index * n + j]] {
                *value = match design.mode {
                    DesignMode::Economic if *value != 0.0 => value.signum() * value.abs().clamp(lower, upper),
                    _ => value.clamp(-crate::limits::MAX_LENGTH_M, crate::limits::MAX_LENGTH_M),
                };
            }
        }
    }
}

/// The starting batch of one design on a scenario: per goal up to `opts.seeds` of IK's
/// solutions (the paper starts from its IK network's guesses), the rest random configurations
/// within the joint limits from a ChaCha8 stream seeded by `opts.seed` and the goal's index.
///
/// # Errors
/// [`OptimizeError::Pipeline`] when the collision world cannot be built.
pub fn starts(design: &Design, scenario: &Scenario, opts: &OptimizeOptions) -> Result<(Batch, Params), OptimizeError> {
    starts_of(std::slice::from_ref(design), scenario, opts)
}

/// The starting batch of several designs of one dof count and capsule structure (the paper
/// tunes its batch of generated robots together): each design's samples as [`starts`] makes
/// them, design after design. Each design's samples and result are the same as alone.
///
/// # Errors
/// [`OptimizeError::Batch`] for designs that cannot share a batch, [`OptimizeError::Pipeline`]
/// when a collision world cannot be built.
pub fn starts_of(designs: &[Design], scenario: &Scenario, opts: &OptimizeOptions) -> Result<(Batch, Params), OptimizeError> {
    // Starts only: what the joint-space search decides adds none.
    let ik = crate::ik::IkOptions {
        seed: opts.seed,
        search_boxes: 0,
        ..Default::default()
    };
    // Each design's starts depend on it alone: solved in parallel, joined in design order.
    let per_design = designs
        .par_iter()
        .map(|design| -> Result<Vec<f64>, OptimizeError> {
            let model = crate::model::from_design(design).placed(&scenario.world_from_base);
            let world = crate::pipeline::collision_world(&model, scenario, &[]).map_err(Box::new)?;
            let solutions = crate::ik::solve_goals(&model, scenario, Some(&world), &ik);
            let mut q = Vec::new();
            for (goal, found) in solutions.iter().enumerate() {
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ goal as u64);
                for k in 0..opts.seeds {
                    match found.solutions.get(k) {
                        Some(solution) => q.extend_from_slice(&solution.q),
                        None => q.extend(model.random_configuration(&mut rng)),
                    }
                }
            }
            Ok(q)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let q = per_design.concat();
    let samples = (0..designs.len())
        .flat_map(|design| (0..scenario.goals.len()).flat_map(move |goal| (0..opts.seeds).map(move |_| Sample { design, goal })))
        .collect();
    let batch = Batch::new(designs, scenario, samples)?;
    let params = Params {
        q,
        d: designs.iter().flat_map(|d| d.joints.iter().map(|j| j.d)).collect(),
        a: designs.iter().flat_map(|d| d.joints.iter().map(|j| j.a)).collect(),
    };
    Ok((batch, params))
}

/// `design` with the DH rows of design `index` of `params`; `name` names it.
pub fn tuned_design(design: &Design, batch: &Batch, params: &Params, index: usize, name: &str) -> Design {
    let (d, a) = batch.rows(params, index);
    let mut tuned = design.clone();
    tuned.name = name.to_string();
    tuned.snapped.clear();
    for (joint, (&d, &a)) in tuned.joints.iter_mut().zip(d.iter().zip(a)) {
        joint.d = d;
        joint.a = a;
    }
    tuned
}
