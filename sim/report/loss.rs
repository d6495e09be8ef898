//! The paper's objective summed over a scenario, as the design tool would score the design.

use super::Validation;
use crate::ik::{LossTerms, COLLISION_WEIGHT, DISTANCE_WEIGHT, HARDWARE_WEIGHT};
use serde::Serialize;

/// `L = sum_i (w_d d_i + w_col c_col,i) + w_c c_h` as the paper defines it: minimized over the
/// configurations, here each goal's term at the IK solution that minimizes it (the regularisation
/// term is a training device and left out). `validate-design optimize` lowers it further by
/// gradient descent; this is the value before any fine-tuning.
#[derive(Debug, Clone, Serialize)]
pub struct PaperLoss {
    /// The whole loss, minimized over each goal's IK solutions; `None` when a goal has no
    /// configuration at all.
    pub total: Option<f64>,
    /// `sum w_d d_i`, of the minimizing solutions.
    pub distance: f64,
    /// `sum w_col c_col,i`, of the minimizing solutions.
    pub collision: f64,
    /// `w_c c_h` (designs only; 0 for URDF robots).
    pub hardware: f64,
    /// The whole loss at the configurations the report chose (the trajectory's, else IK's best);
    /// `None` when a goal has no configuration at all.
    pub at_chosen: Option<f64>,
    /// Weights used: w_d, w_r (per rad), w_col, w_c.
    pub weights: [f64; 4],
}

/// `(sum w_d d, sum w_col c_col, complete)` of per-goal terms.
fn sums(terms: &[Option<LossTerms>]) -> (f64, f64, bool) {
    let distance = terms.iter().flatten().map(|t| DISTANCE_WEIGHT * t.distance).sum();
    let collision = terms.iter().flatten().map(|t| COLLISION_WEIGHT * t.collision).sum();
    (distance, collision, terms.iter().all(Option::is_some))
}

pub(super) fn paper_loss(validation: &Validation) -> PaperLoss {
    let hardware = validation.design.as_ref().map_or(0.0, |d| HARDWARE_WEIGHT * d.hardware_cost());
    let (distance, collision, complete) = sums(&validation.task_loss_terms);
    let (chosen_distance, chosen_collision, chosen_complete) = sums(&validation.loss_terms);
    PaperLoss {
        total: complete.then_some(distance + collision + hardware),
        distance,
        collision,
        hardware,
        at_chosen: chosen_complete.then_some(chosen_distance + chosen_collision + hardware),
        weights: [DISTANCE_WEIGHT, crate::ik::ROTATION_WEIGHT, COLLISION_WEIGHT, HARDWARE_WEIGHT],
    }
}
