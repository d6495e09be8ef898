//! Goals whose solutions form curves (the self-motion), one pose problem per value of a
//! parameter: a 6R arm on a `z_symmetric` goal (any turn about tool z is allowed), or a 7R arm
//! on a `pose` goal (joint 7 held at each angle of its range, the six others solved exactly).
//! Sampled [`TURNS`] to the turn, each sample solved exactly by the closed form or the
//! all-solutions method: a sample that is collision-free within the limits reaches the goal;
//! otherwise the goal is proven unreachable when every sample solution is certified over its
//! neighbourhood (the goal's tolerance plus half a sample step of its branch, from the inverse
//! Jacobian applied to the parameter's motion, doubled like the tolerance's), the count of
//! solutions is the same at every sample (no branch starts or ends between samples), and no
//! branch moves a joint by more than the linear bound between samples; or when every sample is
//! proven out of reach with half a step of the parameter added to its slack. What falls short
//! stays `undecided`, with the first reason.

use super::analytic::AnalyticSolutions;
use super::{summary, GoalSolutions, Ik, EXACT};
use crate::scenario::{Goal, Tolerance};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::f64::consts::TAU;

/// Samples per whole turn of the parameter (5 degrees apart).
pub(super) const TURNS: usize = 72;

/// What a self-motion is swept by.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Parameter {
    /// The free turn about tool z of a `z_symmetric` goal.
    Turn,
    /// The last joint's angle of a 7R arm, over its range.
    Held,
}

/// The parameter's sampled values.
struct Samples {
    values: Vec<f64>,
    step: f64,
    /// The last sample is followed by the first (a whole turn).
    periodic: bool,
}

impl Ik<'_> {
    /// Decides a `z_symmetric` goal of a 6R arm that the numeric search did not reach: a reached
    /// sample becomes the first solution; else `result` gets the proof or the reason it is
    /// undecided.
    pub(super) fn sweep_free_turn(&mut self, goal: &Goal, result: &mut GoalSolutions) {
        self.sweep(goal, result, Parameter::Turn);
    }

    /// Decides a `pose` goal of a 7R arm that the numeric search did not reach, joint 7 held at
    /// each sample of its range, as [`Self::sweep_free_turn`] does.
    pub(super) fn sweep_held_joint(&mut self, goal: &Goal, result: &mut GoalSolutions) {
        self.held = Some(self.model.dof() - 1);
        self.sweep(goal, result, Parameter::Held);
        self.held = None;
    }

    /// The values of `parameter` sampled: a whole turn, or the held joint's limits when they
    /// span less (both ends sampled).
    fn samples(&self, parameter: Parameter) -> Samples {
        let whole = || Samples {
            values: (0..TURNS).map(|k| k as f64 * TAU / TURNS as f64).collect(),
            step: TAU / TURNS as f64,
            periodic: true,
        };
        let limits = match parameter {
            Parameter::Turn => None,
            Parameter::Held => self.model.joints.last().and_then(|j| j.limits),
        };
        match limits {
            Some([lower, upper]) if lower.is_finite() && upper.is_finite() && upper > lower && upper - lower < TAU => {
                let intervals = ((upper - lower) / (TAU / TURNS as f64)).ceil().max(1.0) as usize;
                let step = (upper - lower) / intervals as f64;
                let mut values: Vec<f64> = (0..intervals).map(|k| lower + k as f64 * step).collect();
                // Exactly the upper limit, not a rounding past it.
                values.push(upper);
                Samples {
                    values,
                    step,
                    periodic: false,
                }
            }
            _ => whole(),
        }
    }

    /// The goal as one pose problem at parameter value `value`, and every solution of it (as
    /// many joints as the model has); `None` when no exact method applies.
    fn sample(&self, goal: &Goal, parameter: Parameter, value: f64) -> Option<(Goal, AnalyticSolutions, Vec<Vec<f64>>)> {
        match parameter {
            Parameter::Turn => {
                let rotation = goal.rotation * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), value);
                let sample = Goal {
                    rotation,
                    tolerance: Tolerance::Pose,
                    ..goal.clone()
                };
                let exact = self.exact_pose(&Isometry3::from_parts(Translation3::from(goal.position), rotation))?;
                let configurations = exact.configurations.iter().map(|q| q.to_vec()).collect();
                Some((sample, exact, configurations))
            }
            Parameter::Held => {
                let held = self.redundant.as_ref()?;
                let pose = held.pose_of_six(&Isometry3::from_parts(Translation3::from(goal.position), goal.rotation), value);
                let found = held.method.solve(&pose);
                let configurations = found
                    .configurations
                    .iter()
                    .map(|q| q.iter().copied().chain([value]).collect())
                    .collect();
                let exact = AnalyticSolutions {
                    configurations: found.configurations,
                    finite: found.resolved,
                    out_of_reach: found.out_of_reach,
                };
                Some((goal.clone(), exact, configurations))
            }
        }
    }

    /// Why no configuration reaches the goal with the parameter within `slack` of `value`,
    /// when the method proves it.
    fn sample_out_of_reach(&self, goal: &Goal, parameter: Parameter, value: f64, slack: f64) -> Option<String> {
        let pose = Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
        match parameter {
            Parameter::Turn => {
                let turned = pose * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), value);
                self.exact_out_of_reach(&turned, slack)
            }
            Parameter::Held => {
                let held = self.redundant.as_ref()?;
                // Joint 7 turns the six's virtual tool about its own z.
                held.method.out_of_reach_over_turn(&held.pose_of_six(&pose, value), slack)
            }
        }
    }

    fn sweep(&mut self, goal: &Goal, result: &mut GoalSolutions, parameter: Parameter) {
        let margin = self.margin();
        let samples = self.samples(parameter);
        let step = samples.step;
        let method = self.method();
        let at = |value: f64| match parameter {
            Parameter::Turn => format!("the turn of {:.0} deg", value.to_degrees()),
            Parameter::Held => format!("joint 7 at {:.1} deg", value.to_degrees()),
        };
        // Words for the parameter: its samples (one, many), its pairs of values, its step.
        let (one, many, values, of_step) = match parameter {
            Parameter::Turn => ("turn", "turns", "the turns", "of the turn"),
            Parameter::Held => ("angle of joint 7", "angles", "joint 7's angles", "of joint 7"),
        };
        let n = samples.values.len();
        // What was swept, and what its samples are called.
        let (over, sampled) = match parameter {
            Parameter::Turn => ("over the free turn about tool z".to_string(), "turns sampled"),
            Parameter::Held => (
                format!("with joint 7 held, over its range ({:.1} deg apart)", step.to_degrees()),
                "angles of joint 7 sampled",
            ),
        };
        let mut counts: Vec<usize> = Vec::with_capacity(samples.values.len());
        let mut collisions: Vec<String> = Vec::new();
        let mut open: Option<String> = None;
        for &value in &samples.values {
            let Some((sample, exact, configurations)) = self.sample(goal, parameter, value) else {
                return;
            };
            if !exact.finite {
                let place = if parameter == Parameter::Turn { " about tool z" } else { "" };
                open.get_or_insert_with(|| format!("{}{place} is a singular pose", at(value)));
            }
            let mut distinct: Vec<Vec<f64>> = Vec::with_capacity(configurations.len());
            for mut q in configurations {
                let (_, size, _) = self.polish(&sample, &mut q);
                if size > EXACT {
                    open.get_or_insert_with(|| format!("a solution at {} does not verify", at(value)));
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
        let pairs = if samples.periodic {
            counts.len()
        } else {
            counts.len().saturating_sub(1)
        };
        if let Some(k) = (1..=pairs).find(|&k| counts[k % counts.len()] != counts[k - 1]) {
            open.get_or_insert_with(|| {
                format!(
                    "the number of solutions changes between {values} of {:.0} and {:.0} deg (a branch turns there)",
                    samples.values[k - 1].to_degrees(),
                    samples.values[k % counts.len()].to_degrees()
                )
            });
        }
        let mut out_of_reach: Option<String> = None;
        if counts.iter().all(|&c| c == 0) && open.is_none() {
            // No solution at any sample: proven when every sample is out of reach with half a
            // step of the parameter added to its slack.
            for &value in &samples.values {
                match self.sample_out_of_reach(goal, parameter, value, step / 2.0) {
                    Some(proof) => {
                        out_of_reach.get_or_insert(proof);
                    }
                    None => {
                        open = Some(format!(
                            "no {one} sampled has an exact solution, but {} is not proven out of reach, so a configuration within the goal's tolerance is not ruled out",
                            at(value)
                        ));
                        break;
                    }
                }
            }
        }
        match open {
            Some(why) => {
                result.undecided = Some(format!("{method} {over} ({n} {many}): {why}"));
            }
            None => {
                let each = counts.first().copied().unwrap_or(0);
                result.complete = true;
                result.undecided = None;
                result.proof = Some(if let Some(proof) = out_of_reach {
                    format!("{method} {over}: every one of the {n} {sampled} is out of reach, each with half a sample step {of_step} added to its slack (the first: {proof})")
                } else if collisions.is_empty() {
                    format!("{method} {over}: every solution of the {n} {sampled} ({each} each) is outside the joint limits, certified between samples")
                } else {
                    format!(
                        "{method} {over}: every solution of the {n} {sampled} ({each} each) is outside the joint limits or collides, certified between samples ({})",
                        summary(&collisions)
                    )
                });
            }
        }
    }
}
