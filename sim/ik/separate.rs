//! The separating test of the joint-space search ([`super::search`]): rules a box out when no
//! joint motion within it can bring the tool's residual (position, and the tool's axes) into
//! the tolerance, judged in every direction at once rather than along the error alone.
//!
//! The residual `E(q)` stacks the position offset and the offsets of the tool axes the
//! tolerance constrains, each block scaled by what the tolerance allows it: the position by the
//! reached radius, the whole rotation matrix by `2 sqrt 2 sin(tol / 2)` (its Frobenius distance
//! from the goal's at exactly the tolerance angle), the z axis alone by `2 sin(tol / 2)`.
//! Within the tolerance every block has norm at most 1, so for any direction `u`,
//! `u . E(q) <= sum |u_b|`. Over a box, `E(c + d) = E(c) + G d + r` with `G` the Jacobian of
//! the residual at the centre and `r` bounded per block by the search's remainders, so the box
//! is out when `u . E(c) - sum_j |u . G_j| h_j - sum_b |u_b| (1 + r_b) > 0` for some `u`.
//! The `u` tried is the residual the linear model cannot remove within the box (a
//! box-constrained least-squares fit): where the linear model misses the tolerance, that
//! direction shows it with the largest margin. Any `u` keeps the test rigorous; the fit only
//! chooses a good one.

use super::search::Radii;
use crate::model::KinematicsWorkspace;
use crate::scenario::{Goal, Tolerance};
use nalgebra::{Matrix3, Vector3};

/// Sweeps of the coordinate descent that fits the box-constrained least squares.
const SWEEPS: usize = 24;

/// Largest change of a sweep, relative to the box, below which the fit has converged.
const CONVERGED: f64 = 1e-6;

/// Largest residual: 3 position rows and 9 rotation rows.
const ROWS: usize = 12;

/// Scratch space for one model's boxes.
pub(super) struct Separator {
    /// Residual rows per joint (column `j` is `G_j`), `rows` used.
    columns: Vec<[f64; ROWS]>,
    residual: [f64; ROWS],
    fit: Vec<f64>,
}

/// Per-box inputs the search has already computed.
pub(super) struct BoxBounds<'a> {
    pub half: &'a [f64],
    pub revolute: &'a [bool],
    /// Remainder of the tool position over the box (m), per joint.
    pub position_rest: &'a [f64],
    /// Remainder of one tool axis over the box (a unit vector's displacement), per joint.
    pub axis_rest: &'a [f64],
}

impl Separator {
    pub(super) fn new(dof: usize) -> Self {
        Self {
            columns: vec![[0.0; ROWS]; dof],
            residual: [0.0; ROWS],
            fit: vec![0.0; dof],
        }
    }

    /// Whether the box whose centre's kinematics `ws` holds is ruled out for `goal` (`None`),
    /// else the joint whose motion within the box keeps it most from being ruled out.
    pub(super) fn rules_out(&mut self, goal: &Goal, radii: Radii, ws: &KinematicsWorkspace, bounds: &BoxBounds) -> Option<usize> {
        let dof = bounds.half.len();
        let tool = &ws.tool_in_world;
        let rotation: Matrix3<f64> = *tool.rotation.to_rotation_matrix().matrix();
        let target: Matrix3<f64> = *goal.rotation.to_rotation_matrix().matrix();
        let position_scale = 1.0 / radii.position_m;
        let half_chord = 2.0 * (radii.orientation_rad / 2.0).sin();
        // The rotation block: which axes, and its scale and remainder (per axis, then the
        // block's norm: the Frobenius norm of three vectors each within the bound).
        let (axes, axis_scale, block_rest): (&[usize], f64, f64) = match goal.tolerance {
            Tolerance::Pose => (&[0, 1, 2], 1.0 / (2.0_f64.sqrt() * half_chord), 3.0_f64.sqrt()),
            Tolerance::ZSymmetric => (&[2], 1.0 / half_chord, 1.0),
            Tolerance::Position => (&[], 0.0, 0.0),
        };
        let rows = 3 + 3 * axes.len();
        let offset = (tool.translation.vector - goal.position) * position_scale;
        self.residual[..3].copy_from_slice(offset.as_slice());
        for (k, &axis) in axes.iter().enumerate() {
            let gap = (rotation.column(axis) - target.column(axis)) * axis_scale;
            self.residual[3 + 3 * k..6 + 3 * k].copy_from_slice(gap.as_slice());
        }
        for j in 0..dof {
            let column = ws.jacobian.column(j);
            let linear = Vector3::new(column[0], column[1], column[2]) * position_scale;
            let turn = Vector3::new(column[3], column[4], column[5]);
            let g = &mut self.columns[j];
            g[..3].copy_from_slice(linear.as_slice());
            for (k, &axis) in axes.iter().enumerate() {
                let rate = if bounds.revolute[j] {
                    turn.cross(&rotation.column(axis).into_owned()) * axis_scale
                } else {
                    Vector3::zeros()
                };
                g[3 + 3 * k..6 + 3 * k].copy_from_slice(rate.as_slice());
            }
        }
        self.fit_within(bounds.half, rows);
        // u: the residual left by the fit.
        let mut u = self.residual;
        for j in 0..dof {
            let d = self.fit[j];
            for (value, g) in u[..rows].iter_mut().zip(&self.columns[j][..rows]) {
                *value += g * d;
            }
        }
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let norm = |a: &[f64]| dot(a, a).sqrt();
        let (u_position, u_rotation) = (norm(&u[..3]), norm(&u[3..rows]));
        let mut value = dot(&u[..rows], &self.residual[..rows]) - u_position - u_rotation;
        let (mut split, mut largest) = (0, f64::NEG_INFINITY);
        for j in 0..dof {
            let share = dot(&u[..rows], &self.columns[j][..rows]).abs() * bounds.half[j]
                + u_position * bounds.position_rest[j] * position_scale
                + u_rotation * bounds.axis_rest[j] * block_rest * axis_scale;
            value -= share;
            if share > largest {
                (split, largest) = (j, share);
            }
        }
        if value > super::search::ROUNDING * norm(&u[..rows]).max(1.0) {
            None
        } else {
            Some(split)
        }
    }

    /// Box-constrained least squares `min |E + G d|` over `|d_j| <= h_j` by projected
    /// coordinate descent, into `fit`.
    fn fit_within(&mut self, half: &[f64], rows: usize) {
        let mut left = self.residual;
        self.fit.iter_mut().for_each(|d| *d = 0.0);
        for _ in 0..SWEEPS {
            let mut moved = 0.0_f64;
            for (j, &h) in half.iter().enumerate() {
                let g = &self.columns[j][..rows];
                let weight: f64 = g.iter().map(|x| x * x).sum();
                if weight < 1e-24 {
                    continue;
                }
                let slope: f64 = g.iter().zip(&left[..rows]).map(|(x, y)| x * y).sum();
                let old = self.fit[j];
                let new = (old - slope / weight).clamp(-h, h);
                if new != old {
                    for (value, x) in left[..rows].iter_mut().zip(g) {
                        *value += x * (new - old);
                    }
                    self.fit[j] = new;
                    moved = moved.max((new - old).abs() / h);
                }
            }
            // Converged: another sweep would not move the direction the test uses.
            if moved < CONVERGED {
                break;
            }
        }
    }
}
