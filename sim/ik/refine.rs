//! Collision-aware refinement: damped least squares on the goal with the gradient of the paper's
//! exponential collision loss in the null space of the task, and random restarts when stuck.
//!
//! The loss of one pair at signed distance `d` (threshold `t = 0.12 m`) is
//! `L(d) = (exp(-d / t) - e^-1) / (1 - e^-1)` for `d <= t`, else 0. Its gradient in joint space is
//! `L'(d) * dd/dq`, with `dd/dq = n . (J_b(p_b) - J_a(p_a))` from the witness points `p_a`, `p_b`
//! and the normal `n` (from `a` to `b`); `J_x(p)` is the linear Jacobian of point `p` on link `x`.
//! The gradient only steers: its distances are cheap stand-ins (bounding capsules for depths,
//! convex hulls for mesh links), while whether a configuration is free is always the exact sign
//! of its clearance.
//!
//! Without redundancy (no more joints than the goal constrains: a 6-joint arm on a `pose` goal)
//! the task has no null space: a solution is an isolated point, and a colliding one stays in
//! collision however the loss is descended. There the gradient is not computed, only the sign of
//! the clearance (remembered while the configuration stays the same), and the search waits out
//! the same steps before a fresh start.

use super::dls::{Convergence, Solver};
use crate::collide::{self, Body, CollisionWorld, Distances, QueryOptions};
use crate::model::{JointKind, KinematicsWorkspace, Model};
use crate::scenario::{Goal, Tolerance};
use nalgebra::{DVector, Isometry3, Vector3};

/// The paper's collision loss threshold `t` (m).
pub const COLLISION_THRESHOLD_M: f64 = 0.12;
/// The paper's weight of the collision loss against the pose distance.
pub const COLLISION_WEIGHT: f64 = 0.6;
/// Largest joint change the collision term may ask for in one step (rad or m).
const MAX_AVOIDANCE_STEP: f64 = 0.05;
/// Steps without getting out of contact after which the refinement jumps to a fresh start.
const STUCK_STEPS: usize = 20;

/// Clearance of one configuration in both geometric models.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Clearance {
    /// Smallest signed distance over all checked pairs, exact geometry (m).
    pub exact_m: f64,
    /// Smallest signed distance over all checked pairs, the paper's capsule model (m).
    pub approximate_m: f64,
}

/// The closest pair of a query: what a certificate needs of it.
pub(crate) struct ClosestPair {
    pub(crate) bodies: [Body; 2],
    pub(crate) points: [Vector3<f64>; 2],
    /// From `a` to `b`: moving `b` along it separates the pair.
    pub(crate) normal: Vector3<f64>,
    pub(crate) name: String,
}

/// The exact model's query at `q` (no margin, no hulls), with exact overlap depths or not.
fn exact_query(exact_depth: bool) -> QueryOptions {
    QueryOptions {
        margin: 0.0,
        hulls: false,
        exact_depth,
        mesh_hulls: false,
    }
}

/// Collision queries for IK, with their buffers.
pub(crate) struct Checker<'a> {
    world: &'a CollisionWorld,
    model: &'a Model,
    ws: KinematicsWorkspace,
    exact: Distances,
    approximate: Distances,
    gradient: DVector<f64>,
    /// The last configuration [`Self::keeps_margin`] measured, at which margin, and its answer.
    kept_q: Vec<f64>,
    kept_margin: f64,
    kept_clear: bool,
    /// Clearance a configuration must keep to count as free (m).
    pub(crate) margin: f64,
}

impl<'a> Checker<'a> {
    pub(crate) fn new(model: &'a Model, world: &'a CollisionWorld) -> Self {
        Self {
            world,
            model,
            ws: model.workspace(),
            exact: Distances::new(),
            approximate: Distances::new(),
            gradient: DVector::zeros(model.dof()),
            kept_q: Vec::new(),
            kept_margin: f64::NAN,
            kept_clear: false,
            margin: 0.0,
        }
    }

    /// Exact and approximate clearance at `q`; with `exact_depth` false an overlap's depth is the
    /// bounding capsules' estimate (the sign, which decides the verdict, is exact either way).
    pub(crate) fn clearance(&mut self, q: &[f64], exact_depth: bool) -> Clearance {
        self.model.forward(q, &mut self.ws);
        let query = exact_query(exact_depth);
        collide::distances(self.world, &self.ws.link_in_world, &query, &mut self.exact);
        collide::approximate_distances(self.world, &self.ws.link_in_world, &query, &mut self.approximate);
        let smallest = |d: &Distances| d.closest.map_or(f64::INFINITY, |c| c.distance);
        Clearance {
            exact_m: smallest(&self.exact),
            approximate_m: smallest(&self.approximate),
        }
    }

    /// Which pairs involve no link beyond `links` (obstacles and the floor count): the levels
    /// [`Self::clearance_among`] measures them at.
    pub(crate) fn pairs_up_to(&self, links: usize) -> Vec<Option<f64>> {
        let within = |body: Body| !matches!(body, Body::Link(link) if link > links);
        self.world
            .pairs()
            .iter()
            .map(|pair| (within(pair.a) && within(pair.b)).then_some(f64::INFINITY))
            .collect()
    }

    /// The exact clearance at `q` over the pairs `levels` measures (see [`Self::pairs_up_to`]),
    /// overlaps by their exact depth where `exact_depth` (else the sign alone is exact);
    /// [`Self::closest_pair`] names the closest of them.
    pub(crate) fn clearance_among(&mut self, q: &[f64], levels: &[Option<f64>], exact_depth: bool) -> f64 {
        self.model.forward(q, &mut self.ws);
        let query = exact_query(exact_depth);
        collide::distances_among(self.world, &self.ws.link_in_world, &query, Some(levels), &mut self.exact);
        self.exact.closest.map_or(f64::INFINITY, |c| c.distance)
    }

    /// Levels for [`Self::clearance_among`] that measure `pair` alone; `None` where the world
    /// does not check it.
    pub(crate) fn pair_levels(&self, pair: [Body; 2]) -> Option<Vec<Option<f64>>> {
        let pairs = self.world.pairs();
        let index = pairs.iter().position(|p| [p.a, p.b] == pair)?;
        Some((0..pairs.len()).map(|i| (i == index).then_some(f64::INFINITY)).collect())
    }

    /// The pairs in collision at the last [`Self::clearance`] query, with their signed
    /// distances.
    pub(crate) fn colliding_pairs(&self) -> impl Iterator<Item = ([Body; 2], f64)> + '_ {
        self.exact
            .within_margin
            .iter()
            .map(|pair| ([pair.a.body, pair.b.body], pair.distance))
    }

    /// A pair's names, as [`Self::closest_pair`] gives them.
    pub(crate) fn pair_name(&self, pair: [Body; 2]) -> String {
        format!("{} and {}", self.world.body_name(pair[0]), self.world.body_name(pair[1]))
    }

    /// The pair that was closest at the last [`Self::clearance`] query: its bodies, their
    /// witness points (world) and their names.
    pub(crate) fn closest_pair(&self) -> Option<ClosestPair> {
        let pair = self.exact.closest.as_ref()?;
        Some(ClosestPair {
            bodies: [pair.a.body, pair.b.body],
            points: [pair.point_a, pair.point_b],
            normal: pair.normal,
            name: format!("{} and {}", self.world.body_name(pair.a.body), self.world.body_name(pair.b.body)),
        })
    }

    /// Whether `q` keeps the margin in exact geometry (the sign of the clearance against it).
    fn keeps_margin(&mut self, q: &[f64]) -> bool {
        let same = self.kept_q.len() == q.len() && self.kept_q.iter().zip(q).all(|(a, b)| a.to_bits() == b.to_bits());
        if !same || self.kept_margin.to_bits() != self.margin.to_bits() {
            self.model.forward(q, &mut self.ws);
            self.kept_clear = collide::clear(self.world, &self.ws.link_in_world, self.margin, &mut self.exact);
            self.kept_q.clear();
            self.kept_q.extend_from_slice(q);
            self.kept_margin = self.margin;
        }
        self.kept_clear
    }

    /// The gradient of the weighted collision loss at `q`, in `self.gradient`.
    fn loss_gradient(&mut self, q: &[f64]) {
        self.model.forward(q, &mut self.ws);
        let query = QueryOptions {
            margin: COLLISION_THRESHOLD_M,
            hulls: false,
            // The loss only steers the search, whose every answer is judged by the exact sign of
            // the clearance ([`Self::keeps_margin`]): bounding capsules for depths, not EPA, and
            // mesh links by their hulls, not their triangles.
            exact_depth: false,
            mesh_hulls: true,
        };
        collide::distances(self.world, &self.ws.link_in_world, &query, &mut self.exact);
        self.gradient.fill(0.0);
        let scale = 1.0 / (1.0 - (-1.0f64).exp());
        for pair in &self.exact.within_margin {
            let slope = -COLLISION_WEIGHT * scale * (-pair.distance / COLLISION_THRESHOLD_M).exp() / COLLISION_THRESHOLD_M;
            if let Body::Link(link) = pair.a.body {
                add_point_gradient(
                    self.model,
                    &self.ws.link_in_world,
                    &mut self.gradient,
                    link,
                    &pair.point_a,
                    &(-pair.normal),
                    slope,
                );
            }
            if let Body::Link(link) = pair.b.body {
                add_point_gradient(
                    self.model,
                    &self.ws.link_in_world,
                    &mut self.gradient,
                    link,
                    &pair.point_b,
                    &pair.normal,
                    slope,
                );
            }
        }
    }
}

/// Adds `slope * direction . J(link, point)` to `gradient`, `J` the linear Jacobian of a point
/// fixed to `link`.
fn add_point_gradient(
    model: &Model,
    link_in_world: &[Isometry3<f64>],
    gradient: &mut DVector<f64>,
    link: usize,
    point: &Vector3<f64>,
    direction: &Vector3<f64>,
    slope: f64,
) {
    // Joint j moves links j + 1 and beyond; its frame is the frame of link j + 1.
    for j in 0..link.min(model.dof()) {
        let frame = &link_in_world[j + 1];
        let axis = frame.rotation * model.joints[j].axis.into_inner();
        let velocity = match model.joints[j].kind {
            JointKind::Prismatic => axis,
            _ => axis.cross(&(point - frame.translation.vector)),
        };
        gradient[j] += slope * direction.dot(&velocity);
    }
}

/// Refines `q` towards a pose-reaching configuration keeping the checker's margin within `steps`
/// steps.
/// Returns true when it got there.
pub(crate) fn refine<R: rand::Rng>(
    solver: &mut Solver,
    checker: &mut Checker,
    goal: &Goal,
    q: &mut [f64],
    steps: usize,
    done: Convergence,
    rng: &mut R,
) -> bool {
    let redundant = checker.model.dof() > constrained_dimensions(goal.tolerance);
    let mut stuck = 0;
    let mut step = 0;
    while step < steps {
        let is_free = checker.keeps_margin(q);
        let pose_ok = solver.converged_at(goal, q, done);
        if is_free {
            if pose_ok {
                return true;
            }
            // Free but not at the goal: a plain solve (which restarts itself when stuck).
            stuck = 0;
            step += 1 + solver.solve(goal, q, (steps - step).min(50), done, rng);
            continue;
        }
        stuck += 1;
        if stuck >= STUCK_STEPS {
            // A collision the null space cannot resolve (a 6-dof pose goal has none): this
            // branch of solutions is blocked, try another.
            q.copy_from_slice(&checker.model.random_configuration(rng));
            step += 1 + solver.solve(goal, q, (steps - step).min(50), done, rng);
            stuck = 0;
            continue;
        }
        // Descend the loss inside the task's null space, then restore the task.
        if redundant {
            checker.loss_gradient(q);
        }
        let largest = checker.gradient.amax();
        if redundant && largest > 0.0 {
            let scale = (MAX_AVOIDANCE_STEP / largest).min(1.0);
            solver.null_space_step(goal, q, &checker.gradient, -scale);
        }
        step += 1 + solver.solve(goal, q, 3, done, rng);
    }
    checker.keeps_margin(q) && solver.converged_at(goal, q, done)
}

/// Dimensions of the tool pose a goal of this tolerance constrains.
pub(super) fn constrained_dimensions(tolerance: Tolerance) -> usize {
    match tolerance {
        Tolerance::Pose => 6,
        // Free about the tool's z axis.
        Tolerance::ZSymmetric => 5,
        Tolerance::Position => 3,
    }
}
