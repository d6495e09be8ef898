//! The paper's objective summed over a scenario, as the design tool would score the design.

use super::Validation;
use crate::ik::{COLLISION_WEIGHT, DISTANCE_WEIGHT, HARDWARE_WEIGHT};
use serde::Serialize;

/// `L = sum_i (w_d d_i + w_col c_col,i) + w_c c_h`, at the configurations the report chose
/// (the regularisation term is a training device and left out).
#[derive(Debug, Clone, Serialize)]
pub struct PaperLoss {
    /// The whole loss; `None` when a goal has no configuration at all.
    pub total: Option<f64>,
    /// `sum w_d d_i`.
    pub distance: f64,
    /// `sum w_col c_col,i`.
    pub collision: f64,
    /// `w_c c_h` (designs only; 0 for URDF robots).
    pub hardware: f64,
    /// Weights used: w_d, w_r (per rad), w_col, w_c.
    pub weights: [f64; 4],
}

pub(super) fn paper_loss(validation: &Validation) -> PaperLoss {
    let distance: f64 = validation.loss_terms.iter().flatten().map(|t| DISTANCE_WEIGHT * t.distance).sum();
    let collision: f64 = validation.loss_terms.iter().flatten().map(|t| COLLISION_WEIGHT * t.collision).sum();
    let hardware = validation.design.as_ref().map_or(0.0, |d| HARDWARE_WEIGHT * d.hardware_cost());
    let complete = validation.loss_terms.iter().all(Option::is_some);
    PaperLoss {
        total: complete.then_some(distance + collision + hardware),
        distance,
        collision,
        hardware,
        weights: [DISTANCE_WEIGHT, crate::ik::ROTATION_WEIGHT, COLLISION_WEIGHT, HARDWARE_WEIGHT],
    }
}
