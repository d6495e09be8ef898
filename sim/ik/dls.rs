//! Damped least squares (Levenberg-Marquardt) on the tolerance-projected task error, with the
//! analytic Jacobian and joint limits.

use super::error::task_error;
use super::spd6::Cholesky6;
use crate::model::{JointKind, KinematicsWorkspace, Model};
use crate::scenario::{Goal, Tolerance};
use nalgebra::{DVector, Isometry3, Matrix3, Matrix6, Matrix6xX, Vector3, Vector6};
use std::f64::consts::PI;

/// Weight of the angular rows against the linear ones (m per rad): a 1 m arm turning by 1 rad
/// moves its tool by about 0.5 m, so errors of both kinds count alike.
const ANGULAR_WEIGHT_M_PER_RAD: f64 = 0.5;
/// Damping at the start of a solve; adapted by factors below.
const INITIAL_DAMPING: f64 = 1e-2;
const MIN_DAMPING: f64 = 1e-9;
const MAX_DAMPING: f64 = 1e3;
/// Largest change of one joint per step (rad or m): keeps a step inside the region where the
/// linearisation holds.
const MAX_STEP: f64 = 1.2;
/// Iterations without a 20% cost reduction after which a start is stuck in a local minimum and
/// jumps to a fresh random configuration (within the same iteration budget).
const STALL_ITERATIONS: usize = 6;
const STALL_IMPROVEMENT: f64 = 0.8;
/// Damping of the null-space projector: small, so the projection is close to exact away from
/// singularities.
const NULL_SPACE_DAMPING: f64 = 1e-3;

/// Convergence thresholds of the solver, far tighter than "reached" (1 mm, 1 degree) so that a
/// converged solution is reached with margin; Levenberg-Marquardt converges quadratically, so the
/// tighter threshold costs one or two iterations.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Convergence {
    pub(crate) position_m: f64,
    pub(crate) orientation_rad: f64,
}

/// Scratch space for one model; reused across solves.
pub(crate) struct Solver<'a> {
    model: &'a Model,
    ws: KinematicsWorkspace,
    limits: Vec<[f64; 2]>,
    /// Revolute joints whose range spans a full turn: a step past one limit re-enters a turn
    /// earlier instead of stopping at the wall (the same pose, still within the limits).
    wraps: Vec<bool>,
    previous: Vec<f64>,
    best: Vec<f64>,
    /// The Jacobian's columns with their rows weighted and projected.
    projected: Vec<Vector6<f64>>,
    /// The Jacobian and tool pose of `previous`, restored when a step is rejected.
    previous_jacobian: Matrix6xX<f64>,
    previous_tool: Isometry3<f64>,
    /// Weight of the angular rows (m per rad), [`ANGULAR_WEIGHT_M_PER_RAD`] unless a caller
    /// weighs the two kinds of error its own way.
    pub(crate) angular_weight: f64,
}

impl<'a> Solver<'a> {
    pub(crate) fn new(model: &'a Model) -> Self {
        let limits: Vec<[f64; 2]> = model.joints.iter().map(|j| j.limits.unwrap_or([-PI, PI])).collect();
        let wraps = model
            .joints
            .iter()
            .zip(&limits)
            .map(|(j, [lower, upper])| j.kind != JointKind::Prismatic && upper - lower >= 2.0 * PI)
            .collect();
        let dof = model.dof();
        Self {
            model,
            ws: model.workspace(),
            limits,
            wraps,
            previous: vec![0.0; dof],
            best: vec![0.0; dof],
            projected: vec![Vector6::zeros(); dof],
            previous_jacobian: Matrix6xX::zeros(dof),
            previous_tool: Isometry3::identity(),
            angular_weight: ANGULAR_WEIGHT_M_PER_RAD,
        }
    }

    /// Puts `q` inside the joint limits: full-turn revolute joints by whole turns, others by
    /// clamping.
    fn limit(&self, q: &mut [f64]) {
        for ((value, [lower, upper]), wraps) in q.iter_mut().zip(&self.limits).zip(&self.wraps) {
            if *wraps {
                while *value > *upper {
                    *value -= 2.0 * PI;
                }
                while *value < *lower {
                    *value += 2.0 * PI;
                }
            } else {
                *value = value.clamp(*lower, *upper);
            }
        }
    }

    /// Drives `q` (in place) towards `goal` for at most `max_iterations` Jacobian evaluations,
    /// restarting from a random configuration drawn from `rng` when stuck in a local minimum.
    /// Leaves the best configuration seen in `q`; returns the iterations used.
    pub(crate) fn solve<R: rand::Rng>(
        &mut self,
        goal: &Goal,
        q: &mut [f64],
        max_iterations: usize,
        done: Convergence,
        rng: &mut R,
    ) -> usize {
        self.limit(q);
        let mut damping = INITIAL_DAMPING;
        self.model.tool_jacobian(q, &mut self.ws);
        let (mut error, mut cost) = self.weighted_error(goal);
        self.best.copy_from_slice(q);
        let (mut best_cost, mut start_best, mut since_improvement) = (cost, cost, 0);
        let mut used = max_iterations;
        for iteration in 0..max_iterations {
            if self.converged(goal, &error, done) {
                used = iteration;
                break;
            }
            if since_improvement >= STALL_ITERATIONS {
                q.copy_from_slice(&self.model.random_configuration(rng));
                self.limit(q);
                self.model.tool_jacobian(q, &mut self.ws);
                (error, cost) = self.weighted_error(goal);
                (damping, start_best, since_improvement) = (INITIAL_DAMPING, cost, 0);
                continue;
            }
            let projection = self.projection(goal);
            let mut normal = Matrix6::<f64>::identity() * (damping * damping);
            self.project_columns(&projection, &mut normal);
            let Some(cholesky) = Cholesky6::new(&normal) else {
                damping = (damping * 10.0).min(MAX_DAMPING);
                since_improvement += 1;
                continue;
            };
            let y = cholesky.solve(&error);
            self.previous.copy_from_slice(q);
            self.previous_jacobian.copy_from(&self.ws.jacobian);
            self.previous_tool = self.ws.tool_in_world;
            let mut largest: f64 = 0.0;
            for (j, column) in self.projected.iter().enumerate() {
                let delta = column.dot(&y);
                q[j] = self.previous[j] + delta;
                largest = largest.max(delta.abs());
            }
            if largest > MAX_STEP {
                let scale = MAX_STEP / largest;
                for (value, previous) in q.iter_mut().zip(&self.previous) {
                    *value = previous + (*value - previous) * scale;
                }
            }
            self.limit(q);
            self.model.tool_jacobian(q, &mut self.ws);
            let (new_error, new_cost) = self.weighted_error(goal);
            if new_cost < cost {
                error = new_error;
                cost = new_cost;
                damping = (damping / 3.0).max(MIN_DAMPING);
            } else {
                q.copy_from_slice(&self.previous);
                self.ws.jacobian.copy_from(&self.previous_jacobian);
                self.ws.tool_in_world = self.previous_tool;
                damping = (damping * 5.0).min(MAX_DAMPING);
            }
            if cost < best_cost {
                best_cost = cost;
                self.best.copy_from_slice(q);
            }
            if cost < STALL_IMPROVEMENT * start_best {
                (start_best, since_improvement) = (cost, 0);
            } else {
                since_improvement += 1;
            }
        }
        if cost > best_cost {
            q.copy_from_slice(&self.best);
        }
        used
    }

    /// Whether `q` meets the convergence thresholds for `goal`.
    pub(crate) fn converged_at(&mut self, goal: &Goal, q: &[f64], done: Convergence) -> bool {
        self.model.tool_jacobian(q, &mut self.ws);
        let (error, _) = self.weighted_error(goal);
        self.converged(goal, &error, done)
    }

    /// Moves `q` by `scale * direction` projected onto the null space of the (weighted,
    /// projected) task Jacobian at `q`: a motion that leaves the tool's task error unchanged to
    /// first order.
    pub(crate) fn null_space_step(&mut self, goal: &Goal, q: &mut [f64], direction: &DVector<f64>, scale: f64) {
        self.model.tool_jacobian(q, &mut self.ws);
        let projection = self.projection(goal);
        let mut normal = Matrix6::<f64>::identity() * (NULL_SPACE_DAMPING * NULL_SPACE_DAMPING);
        self.project_columns(&projection, &mut normal);
        let Some(cholesky) = Cholesky6::new(&normal) else { return };
        // v - P^T (P P^T + l^2 I)^-1 P v, with P the projected Jacobian (rows of `projected` are
        // its columns).
        let mut p_v = Vector6::<f64>::zeros();
        for (j, column) in self.projected.iter().enumerate() {
            p_v += column * direction[j];
        }
        let y = cholesky.solve(&p_v);
        for (j, column) in self.projected.iter().enumerate() {
            q[j] += scale * (direction[j] - column.dot(&y));
        }
        self.limit(q);
    }

    /// Fills `self.projected` with the projected Jacobian columns and adds their outer products
    /// to the lower triangle of `normal`, the part [`Cholesky6`] reads (fixed-size arithmetic: the
    /// generic GEMM was a quarter of the solve time).
    fn project_columns(&mut self, projection: &Matrix6<f64>, normal: &mut Matrix6<f64>) {
        let angular = projection.fixed_view::<3, 3>(3, 3).into_owned();
        for (column, projected) in self.ws.jacobian.column_iter().zip(self.projected.iter_mut()) {
            let linear = Vector3::new(column[0], column[1], column[2]);
            let rotated = angular * Vector3::new(column[3], column[4], column[5]);
            *projected = Vector6::new(linear.x, linear.y, linear.z, rotated.x, rotated.y, rotated.z);
            // The lower triangle only: all the factorisation reads.
            for c in 0..6 {
                for r in c..6 {
                    normal[(r, c)] += projected[r] * projected[c];
                }
            }
        }
    }

    /// Task error with angular rows weighted and projected, and its squared norm.
    fn weighted_error(&self, goal: &Goal) -> (Vector6<f64>, f64) {
        let e = self.projection(goal) * task_error(goal, &self.ws.tool_in_world);
        (e, e.norm_squared())
    }

    /// Row weighting and projection for the goal's tolerance mode: identity on the linear rows;
    /// on the angular rows the weight, times the projection onto the plane orthogonal to tool z
    /// for `z_symmetric` (rotation about tool z is free), or zero for `position`.
    fn projection(&self, goal: &Goal) -> Matrix6<f64> {
        let mut t = Matrix6::identity();
        let angular: Matrix3<f64> = match goal.tolerance {
            Tolerance::Pose => Matrix3::identity() * self.angular_weight,
            Tolerance::ZSymmetric => {
                let z: Vector3<f64> = self.ws.tool_in_world.rotation * Vector3::z();
                (Matrix3::identity() - z * z.transpose()) * self.angular_weight
            }
            Tolerance::Position => Matrix3::zeros(),
        };
        t.fixed_view_mut::<3, 3>(3, 3).copy_from(&angular);
        t
    }

    fn converged(&self, goal: &Goal, weighted: &Vector6<f64>, done: Convergence) -> bool {
        let position = weighted.fixed_rows::<3>(0).norm();
        let angular = weighted.fixed_rows::<3>(3).norm() / self.angular_weight;
        position <= done.position_m && (goal.tolerance == Tolerance::Position || angular <= done.orientation_rad)
    }
}
