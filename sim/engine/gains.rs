//! Position-control gains for a robot following a [`TimedPath`], shared by both engines so that
//! rapier and MuJoCo run the same control law `tau = kp (q_ref - q) + kd (qd_ref - qd)`.
//!
//! Per joint `j`, over configurations along the path (every waypoint and 7 points between
//! consecutive waypoints on the straight joint-space segment):
//!
//! - `I_j`: the largest reflected inertia ([`Model::reflected_inertia`], kg m^2 or kg);
//! - `G_j`: the largest gravity torque magnitude ([`Model::gravity_torques`], N m or N);
//! - `r_j`: the largest distance from the joint axis to the tool origin (m).
//!
//! Then
//!
//! - bandwidth: `kp_j >= I_j w^2` with `w =` [`GainOptions::bandwidth_rad_s`] (default 50 rad/s,
//!   8 Hz): a critically damped joint settles to `e^{-w t} (1 + w t)` of an error, 4e-10 after
//!   the 0.5 s dwell, and lags a 2 pi rad/s^2 reference acceleration by `a / w^2` = 2.5 mrad;
//! - static sag: with no gravity feedforward the joint sags by `G_j / kp_j` at rest. That sag
//!   must stay within [`GainOptions::sag_fraction`] (default 0.1) of the hold tolerance at the
//!   tool: `G_j / kp_j <= 0.1 min(1 mm / r_j, 1 deg)` for a revolute joint, `<= 0.1 mm` for a
//!   prismatic one. Five joints all sagging the worst way stay at half the tolerance;
//! - damping: critical, `kd_j = 2 sqrt(kp_j I_j)`.
//!
//! Stability at a 1 ms step: the stiffest joint's natural frequency `sqrt(kp_j / I_j(q))` with
//! the smallest inertia along the path is what an explicit integrator must resolve (semi-implicit
//! Euler needs `w h < 2`). For the paper's robot on the course it is a few hundred rad/s
//! (`tests/dynamics.rs` prints and bounds it), `w h` well below 1. The damping is large in the
//! stiff joints (`kd / I = 2 w`); MuJoCo integrates it implicitly (`implicitfast`, the position
//! actuators' velocity gain), and rapier's joint motors are implicit springs, so neither engine
//! is limited by it.

use super::Gains;
use crate::model::{JointKind, Model};
use crate::plan::TimedPath;
use serde::Serialize;

/// Points sampled strictly between two consecutive waypoints of the path.
const POINTS_BETWEEN_WAYPOINTS: usize = 7;

/// Settings of [`gains`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GainOptions {
    /// Closed-loop bandwidth every joint reaches at least (rad/s); default 50.
    pub bandwidth_rad_s: f64,
    /// Tool position tolerance of a goal hold (m); default 0.001 (the paper's 1 mm).
    pub position_tolerance_m: f64,
    /// Tool orientation tolerance of a goal hold (rad); default 1 degree (the paper's).
    pub orientation_tolerance_rad: f64,
    /// Share of the tolerance one joint's static gravity sag may use; default 0.1.
    pub sag_fraction: f64,
    /// Gravity along world -z (m/s^2); default 9.81.
    pub gravity_m_s2: f64,
}

impl Default for GainOptions {
    fn default() -> Self {
        Self {
            bandwidth_rad_s: 50.0,
            position_tolerance_m: 0.001,
            orientation_tolerance_rad: 1f64.to_radians(),
            sag_fraction: 0.1,
            gravity_m_s2: 9.81,
        }
    }
}

/// Stiffness and damping per joint for following `path` (see the module docs for the formula).
/// An empty path is judged at the zero configuration.
///
/// # Panics
/// When the path's configurations do not have one value per joint of `model`.
pub fn gains(model: &Model, path: &TimedPath, opts: &GainOptions) -> Gains {
    let dof = model.dof();
    let configurations = along(path, dof);
    let mut inertia = vec![0.0_f64; dof];
    let mut gravity = vec![0.0_f64; dof];
    let mut reach = vec![0.0_f64; dof];
    let mut ws = model.workspace();
    for q in &configurations {
        let reflected = model.reflected_inertia(q);
        let torques = model.gravity_torques(q, opts.gravity_m_s2);
        model.forward(q, &mut ws);
        let tool = ws.tool_in_world.translation.vector;
        for j in 0..dof {
            inertia[j] = inertia[j].max(reflected[j]);
            gravity[j] = gravity[j].max(torques[j].abs());
            let frame = &ws.link_in_world[j + 1];
            let axis = frame.rotation * model.joints[j].axis.into_inner();
            reach[j] = reach[j].max(axis.cross(&(tool - frame.translation.vector)).norm());
        }
    }
    let mut stiffness = Vec::with_capacity(dof);
    let mut damping = Vec::with_capacity(dof);
    for (j, joint) in model.joints.iter().enumerate() {
        let allowed_sag = match joint.kind {
            JointKind::Prismatic => opts.sag_fraction * opts.position_tolerance_m,
            JointKind::Revolute | JointKind::Continuous => {
                let through_reach = if reach[j] > 0.0 {
                    opts.position_tolerance_m / reach[j]
                } else {
                    f64::INFINITY
                };
                opts.sag_fraction * through_reach.min(opts.orientation_tolerance_rad)
            }
        };
        let kp = (inertia[j] * opts.bandwidth_rad_s.powi(2)).max(gravity[j] / allowed_sag);
        stiffness.push(kp);
        damping.push(2.0 * (kp * inertia[j]).sqrt());
    }
    Gains { stiffness, damping }
}

/// The path's waypoints and points on the straight segments between them.
fn along(path: &TimedPath, dof: usize) -> Vec<Vec<f64>> {
    let Some(first) = path.segments.first() else {
        return vec![vec![0.0; dof]];
    };
    let mut configurations = vec![first.from.clone()];
    for segment in &path.segments {
        for k in 1..=POINTS_BETWEEN_WAYPOINTS + 1 {
            let s = k as f64 / (POINTS_BETWEEN_WAYPOINTS + 1) as f64;
            let q = segment.from.iter().zip(&segment.to).map(|(a, b)| a + s * (b - a)).collect();
            configurations.push(q);
        }
    }
    configurations
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::TimingLimits;

    fn paper_robot() -> Model {
        let text = r#"{"mode": "modular", "modules": ["direct", "L-short", "direct", "direct", "I-long"]}"#;
        let design = crate::design::parse(text, std::path::Path::new("paper.json")).expect("valid design");
        crate::model::from_design(&design)
    }

    #[test]
    fn gains_are_critically_damped_and_hold_the_sag_inside_the_tolerance() {
        let model = paper_robot();
        let waypoints = vec![vec![0.0; 5], vec![0.3, 0.8, -0.5, 0.4, 1.0]];
        let path = TimedPath::through(&waypoints, &[Some(0)], &TimingLimits::of(&model));
        let opts = GainOptions::default();
        let gains = gains(&model, &path, &opts);
        for q in along(&path, model.dof()) {
            let inertia = model.reflected_inertia(&q);
            let torques = model.gravity_torques(&q, opts.gravity_m_s2);
            for j in 0..model.dof() {
                let sag = torques[j].abs() / gains.stiffness[j];
                assert!(sag <= 0.1 * opts.orientation_tolerance_rad + 1e-15, "joint {j}: sag {sag}");
                assert!(gains.stiffness[j] >= inertia[j] * 2500.0 * (1.0 - 1e-12), "joint {j}");
            }
        }
        // Critical damping for the largest inertia along the path: kd = 2 sqrt(kp I_max).
        let configurations = along(&path, model.dof());
        for j in 0..model.dof() {
            let (kp, kd) = (gains.stiffness[j], gains.damping[j]);
            let largest = configurations.iter().map(|q| model.reflected_inertia(q)[j]).fold(0.0, f64::max);
            assert!(largest > 0.0, "joint {j} moves mass");
            assert!(
                (kd - 2.0 * (kp * largest).sqrt()).abs() <= 1e-12 * kd,
                "joint {j}: kp {kp} kd {kd} I {largest}"
            );
        }
    }

    #[test]
    fn an_empty_path_is_judged_at_zero() {
        let model = paper_robot();
        let path = TimedPath { segments: vec![] };
        let gains = gains(&model, &path, &GainOptions::default());
        assert_eq!(gains.stiffness.len(), 5);
        assert!(gains.stiffness.iter().all(|k| k.is_finite() && *k > 0.0));
    }
}
