//! A 6R arm on a `z_symmetric` goal: any turn `psi` about tool z is allowed, so the solutions
//! form curves (the self-motion), one pose problem per turn. Sampled at [`TURNS`] turns, each
//! solved exactly by the closed form or the all-solutions method: a sample that is collision-free
//! within the limits reaches the goal; otherwise the goal is proven unreachable when every
//! sample solution is certified over its neighbourhood (the goal's tolerance plus half a sample
//! step of its branch, from the inverse Jacobian applied to a turn about tool z, doubled like
//! the tolerance's), the count of solutions is the same at every sample (no branch starts or
//! ends between samples), and no branch moves a joint by more than the linear bound between
//! samples. What falls short stays `undecided`, with the first reason.

use super::{summary, GoalSolutions, Ik, EXACT};
use crate::scenario::{Goal, Tolerance};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::f64::consts::TAU;

/// Turns about tool z sampled (5 degrees apart).
pub(super) const TURNS: usize = 72;

impl Ik<'_> {
    /// Decides a `z_symmetric` goal of a 6R arm that the numeric search did not reach: a reached
    /// sample becomes the first solution; else `result` gets the proof or the reason it is
    /// undecided.
    pub(super) fn sweep_free_turn(&mut self, goal: &Goal, result: &mut GoalSolutions) {
        let margin = self.margin();
        let step = TAU / TURNS as f64;
        let method = self.method();
        let mut counts: Vec<usize> = Vec::with_capacity(TURNS);
        let mut collisions: Vec<String> = Vec::new();
        let mut open: Option<String> = None;
        for k in 0..TURNS {
            let turn = k as f64 * step;
            let rotation = goal.rotation * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn);
            let sample = Goal {
                rotation,
                tolerance: Tolerance::Pose,
                ..goal.clone()
            };
            let Some(exact) = self.exact_pose(&Isometry3::from_parts(Translation3::from(goal.position), rotation)) else {
                return;
            };
            if !exact.finite {
                open.get_or_insert_with(|| format!("the turn of {:.0} deg about tool z is a singular pose", turn.to_degrees()));
            }
            let mut distinct: Vec<Vec<f64>> = Vec::with_capacity(exact.configurations.len());
            for configuration in &exact.configurations {
                let mut q = configuration.to_vec();
                let (_, size, _) = self.polish(&sample, &mut q);
                if size > EXACT {
                    open.get_or_insert_with(|| format!("a solution at the turn of {:.0} deg does not verify", turn.to_degrees()));
                    continue;
                }
                if distinct.iter().any(|d| self.same_configuration(d, &q)) {
                    continue;
                }
                distinct.push(q.clone());
                if self.shift_into_limits(&mut q, None) {
                    let solution = self.judge(goal, q, None, margin);
                    if solution.reached {
                        result.solutions.insert(0, solution);
                        result.undecided = None;
                        return;
                    }
                    match self.collision_certificate(&sample, &solution, margin, step / 2.0) {
                        Ok(pair) => collisions.push(pair),
                        Err(why) => {
                            open.get_or_insert(why);
                        }
                    }
                } else if let Err(why) = self.limits_certificate(&sample, &q, step / 2.0) {
                    open.get_or_insert(why);
                }
            }
            counts.push(distinct.len());
        }
        if let Some(k) = (1..=counts.len()).find(|&k| counts[k % counts.len()] != counts[k - 1]) {
            open.get_or_insert_with(|| {
                format!(
                    "the number of solutions changes between the turns of {:.0} and {:.0} deg (a branch turns there)",
                    ((k - 1) as f64 * step).to_degrees(),
                    ((k % counts.len()) as f64 * step).to_degrees()
                )
            });
        }
        let mut out_of_reach: Option<String> = None;
        if counts.iter().all(|&c| c == 0) && open.is_none() {
            // No solution at any turn: proven when every turn is out of reach with half a step
            // of the turn added to its slack.
            for k in 0..TURNS {
                let rotation = goal.rotation * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), k as f64 * step);
                let pose = Isometry3::from_parts(Translation3::from(goal.position), rotation);
                match self.exact_out_of_reach(&pose, step / 2.0) {
                    Some(proof) => {
                        out_of_reach.get_or_insert(proof);
                    }
                    None => {
                        open = Some(format!(
                            "no turn sampled has an exact solution, but the turn of {:.0} deg is not proven out of reach, so a configuration within the goal's tolerance is not ruled out",
                            (k as f64 * step).to_degrees()
                        ));
                        break;
                    }
                }
            }
        }
        match open {
            Some(why) => {
                result.undecided = Some(format!("{method} over the free turn about tool z ({TURNS} turns): {why}"));
            }
            None => {
                let each = counts.first().copied().unwrap_or(0);
                result.complete = true;
                result.undecided = None;
                result.proof = Some(if let Some(proof) = out_of_reach {
                    format!("{method} over the free turn about tool z: every one of the {TURNS} turns sampled is out of reach, each with half a sample step of the turn added to its slack (the first: {proof})")
                } else if collisions.is_empty() {
                    format!("{method} over the free turn about tool z: every solution of the {TURNS} turns sampled ({each} each) is outside the joint limits, certified between samples")
                } else {
                    format!(
                        "{method} over the free turn about tool z: every solution of the {TURNS} turns sampled ({each} each) is outside the joint limits or collides, certified between samples ({})",
                        summary(&collisions)
                    )
                });
            }
        }
    }
}
