//! Reaching a goal's tolerance rather than its pose: alternating projections between the
//! tolerance and what the arm reaches.
//!
//! The numeric solver aims at the goal's pose itself. Just beyond the arm's reach it ends on the
//! workspace boundary at the pose nearest the goal in its own metric, and that pose can lie
//! outside the tolerance (1.6 mm off, 0.02 degrees turned) while another pose within it is
//! reachable (0.8 mm off, turned 0.9 degrees: trading turn for distance, which the metric does
//! not). Here the target is moved instead: to the pose within the tolerance nearest where the
//! arm ended, the arm solved toward it, and again; where the two sets meet, the arm ends within
//! the tolerance. The projections start from the numeric solver's closest distinct misses; where
//! the pose they end at collides and the arm has a closed form, its other solutions at that pose
//! (the other branches, within the tolerance too) are judged as well.

use super::{goal_error, is_reached, Ik, IkSolution, CONVERGED};
use crate::scenario::{Goal, Tolerance};
use nalgebra::{Isometry3, UnitQuaternion};

/// Rounds of projection and solving per start.
const ROUNDS: usize = 40;
/// Solver iterations per round.
const STEPS: usize = 10;
/// Misses the projections start from (the closest distinct ones first).
pub(super) const STARTS: usize = 4;
/// A round that leaves more than this share of the excess over the tolerance ends the start.
const STALLED: f64 = 0.99;
/// Fraction of the tolerance the projected target stays within, so that an arm reaching it is
/// within the tolerance after rounding.
const INSIDE: f64 = 0.98;

/// The pose within `INSIDE` of `goal`'s tolerance nearest `tool` (position and rotation each
/// moved the shortest way; a `z_symmetric` goal's free turn kept from `tool`).
fn project(goal: &Goal, tool: &Isometry3<f64>) -> Goal {
    let (position_radius, orientation_radius) = (INSIDE * super::REACHED_POSITION_M, INSIDE * super::REACHED_ORIENTATION_RAD);
    let offset = tool.translation.vector - goal.position;
    let position = goal.position + offset * (position_radius / offset.norm().max(position_radius));
    let rotation = match goal.tolerance {
        Tolerance::Pose => {
            let turn = (tool.rotation * goal.rotation.inverse()).scaled_axis();
            let turn = turn * (orientation_radius / turn.norm().max(orientation_radius));
            UnitQuaternion::from_scaled_axis(turn) * goal.rotation
        }
        Tolerance::ZSymmetric => {
            let (at, wanted) = (tool.rotation * nalgebra::Vector3::z(), goal.rotation * nalgebra::Vector3::z());
            let tilt = UnitQuaternion::rotation_between(&wanted, &at).map_or(nalgebra::Vector3::zeros(), |r| r.scaled_axis());
            let tilt = tilt * (orientation_radius / tilt.norm().max(orientation_radius));
            let target_z = UnitQuaternion::from_scaled_axis(tilt) * wanted;
            UnitQuaternion::rotation_between(&at, &target_z).unwrap_or_else(UnitQuaternion::identity) * tool.rotation
        }
        Tolerance::Position => tool.rotation,
    };
    Goal {
        position,
        rotation,
        ..goal.clone()
    }
}

impl Ik<'_> {
    /// A configuration within `goal`'s tolerance and the joint limits, by alternating
    /// projections from the closest misses in `misses`; judged against collisions (it may
    /// collide). `None` when no projection lands within the tolerance.
    pub(super) fn reach_tolerance(&mut self, goal: &Goal, goal_index: usize, misses: &[IkSolution]) -> Option<IkSolution> {
        let mut rng = self.rng(goal_index);
        // A miss far beyond the tolerance is not one the tolerance's own trade of turn for
        // distance can close: only those within ten times it (the brute force's undecided goals
        // are mostly far misses, and each start here costs 400 solver iterations).
        let near = |s: &&IkSolution| s.error.position_m < super::NEARBY_MISS_M && s.error.orientation_rad < super::NEARBY_MISS_RAD;
        let mut misses: Vec<&IkSolution> = misses.iter().filter(|s| !s.pose_reached).filter(near).collect();
        misses.sort_by(|a, b| super::rank(&a.error).total_cmp(&super::rank(&b.error)));
        misses.dedup_by(|a, b| self.same_configuration(&a.q, &b.q));
        // Errors weighed as the tolerance weighs them: the solver's own weighting (0.5 m per
        // rad) keeps the turn small where the tolerance would rather spend it.
        let weight = self.solver.angular_weight;
        self.solver.angular_weight = super::REACHED_POSITION_M / super::REACHED_ORIENTATION_RAD;
        let mut within = Vec::new();
        for miss in misses.into_iter().take(STARTS) {
            let mut q = miss.q.clone();
            let mut last = f64::INFINITY;
            for _ in 0..ROUNDS {
                let tool = self.model.tool_pose(&q);
                let error = goal_error(goal, &tool);
                if is_reached(&error) {
                    within.push(q);
                    break;
                }
                // The excess over the tolerance, in units of it: where a round no longer cuts it,
                // the two sets are apart (or meet too slowly to be worth the rounds).
                let excess = (error.position_m / super::REACHED_POSITION_M).max(error.orientation_rad / super::REACHED_ORIENTATION_RAD);
                if excess > STALLED * last {
                    break;
                }
                last = excess;
                let target = project(goal, &tool);
                self.solver.solve(&target, &mut q, STEPS, CONVERGED, &mut rng);
            }
        }
        self.solver.angular_weight = weight;
        let margin = self.margin();
        let mut colliding: Option<IkSolution> = None;
        for q in &within {
            let mut q = q.clone();
            if !self.shift_into_limits(&mut q, None) {
                continue;
            }
            let solution = self.judge(goal, q, None, margin);
            if solution.reached {
                return Some(solution);
            }
            colliding.get_or_insert(solution);
        }
        // A pose within the tolerance that the arm reaches has every solution in closed form
        // where the arm has one: the other branches at the same pose, which may be free.
        for q in &within {
            let pose = self.model.tool_pose(q);
            let at_pose = Goal {
                position: pose.translation.vector,
                rotation: pose.rotation,
                ..goal.clone()
            };
            for configuration in self.exact_pose(&pose).map(|e| e.configurations).unwrap_or_default() {
                let mut q = configuration[..self.model.dof()].to_vec();
                self.polish(&at_pose, &mut q);
                if !is_reached(&goal_error(goal, &self.model.tool_pose(&q))) || !self.shift_into_limits(&mut q, None) {
                    continue;
                }
                let solution = self.judge(goal, q, None, margin);
                if solution.reached {
                    return Some(solution);
                }
            }
        }
        colliding
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, Vector3};

    /// The projection lands within the tolerance, and leaves a pose already within it alone.
    #[test]
    fn the_projection_is_within_the_tolerance() {
        let goal_pose = Isometry3::from_parts(Translation3::new(0.3, -0.2, 0.5), UnitQuaternion::from_euler_angles(0.3, -0.4, 1.2));
        for tolerance in [Tolerance::Pose, Tolerance::ZSymmetric, Tolerance::Position] {
            let goal = Goal {
                name: "g".into(),
                position: goal_pose.translation.vector,
                rotation: goal_pose.rotation,
                tolerance,
                task: None,
            };
            for k in 0..50 {
                let s = f64::from(k) / 10.0;
                let tool = Isometry3::from_parts(
                    Translation3::from(goal.position + Vector3::new(0.01 * s, -0.004 * s, 0.002)),
                    UnitQuaternion::from_scaled_axis(Vector3::new(0.1 * s, 0.02, -0.3 * s)) * goal.rotation,
                );
                let target = project(&goal, &tool);
                let target_pose = Isometry3::from_parts(Translation3::from(target.position), target.rotation);
                assert!(is_reached(&goal_error(&goal, &target_pose)), "{tolerance:?} {k}");
                let tool_error = goal_error(&goal, &tool);
                if is_reached(&tool_error) {
                    let unchanged = goal_error(&target, &tool);
                    assert!(
                        unchanged.position_m < 1e-12 && unchanged.orientation_rad < 1e-9,
                        "{tolerance:?} {k}"
                    );
                }
            }
        }
    }
}
