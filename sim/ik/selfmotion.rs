//! Goals whose solutions form curves (the self-motion), one pose problem per value of a
//! parameter: a 6R arm on a `z_symmetric` goal (any turn about tool z is allowed), or a 7R arm
//! on a `pose` goal (joint 7 held at each angle of its range, the six others solved exactly).
//! Sampled [`TURNS`] to the turn, each sample solved exactly by the closed form or the
//! all-solutions method: a sample that is collision-free within the limits reaches the goal.
//! Otherwise the goal is proven unreachable interval by interval: both ends' solutions certified
//! over their neighbourhood (the goal's tolerance plus half the interval of their branch, from
//! the inverse Jacobian applied to the parameter's motion, doubled like the tolerance's, within
//! the linear bound) with the same count at both ends (no branch starts or ends inside), or both
//! ends without solutions and proven out of reach with half the interval added to the slack. An
//! interval that fails is halved while that may help; what still falls short stays `undecided`,
//! with the first reason.

use super::cells::Cells;
use super::{summary, GoalSolutions, Ik, EXACT};
use crate::scenario::{Goal, Tolerance};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::collections::hash_map::{Entry, HashMap};
use std::f64::consts::TAU;

/// Samples per whole turn of the parameter (5 degrees apart).
pub(super) const TURNS: usize = 72;

/// What a self-motion is swept by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Parameter {
    /// The free turn about tool z of a `z_symmetric` goal (0 for a plain `pose` goal).
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
            _ => Samples {
                values: (0..TURNS).map(|k| k as f64 * TAU / TURNS as f64).collect(),
                step: TAU / TURNS as f64,
                periodic: true,
            },
        }
    }

    /// The goal as one pose problem at parameter value `value`, every solution of it (as many
    /// joints as the model has), and whether they are all listed (no continuum); `None` when no
    /// exact method applies.
    fn sample(&self, goal: &Goal, parameter: Parameter, value: f64) -> Option<(Goal, Vec<Vec<f64>>, bool)> {
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
                Some((sample, configurations, exact.finite))
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
                Some((goal.clone(), configurations, found.resolved))
            }
        }
    }

    /// A configuration reaching the goal found by solving exactly the poses up to 0.9 mm and
    /// 0.9 degrees off the sample's (the tool moved along and turned about each axis, alone and
    /// combined): where the sample has no exact solution but the tolerance is not ruled out,
    /// one of these may have solutions, and a free one within the limits reaches the goal.
    pub(super) fn reach_nearby(&mut self, goal: &Goal, parameter: Parameter, value: f64) -> Option<super::IkSolution> {
        let margin = self.margin();
        let axes = [
            Vector3::zeros(),
            Vector3::x(),
            -Vector3::x(),
            Vector3::y(),
            -Vector3::y(),
            Vector3::z(),
            -Vector3::z(),
        ];
        for shift in &axes {
            for turn in &axes {
                if shift.norm() == 0.0 && turn.norm() == 0.0 {
                    continue;
                }
                let nearby = Goal {
                    position: goal.position + shift * (NEARBY * super::REACHED_POSITION_M),
                    rotation: UnitQuaternion::from_scaled_axis(turn * (NEARBY * super::REACHED_ORIENTATION_RAD)) * goal.rotation,
                    ..goal.clone()
                };
                let (sample, configurations, _) = self.sample(&nearby, parameter, value)?;
                for mut q in configurations {
                    let (_, size, _) = self.polish(&sample, &mut q);
                    if size > EXACT || !self.shift_into_limits(&mut q, None) {
                        continue;
                    }
                    let solution = self.judge(goal, q, None, margin);
                    if solution.reached {
                        return Some(solution);
                    }
                }
            }
        }
        None
    }

    /// Why no configuration reaches the goal with the parameter within `slack` of `value`,
    /// when the method proves it; with `cut` (no shorter interval follows) a proof that fails
    /// over the whole tolerance is tried part by part ([`super::parts`]).
    /// The proof comes with whether the tolerance was cut for it.
    fn sample_out_of_reach(&mut self, goal: &Goal, parameter: Parameter, value: f64, slack: f64, cut: bool) -> (Option<String>, bool) {
        let whole = self.part_out_of_reach(goal, parameter, value, slack, super::search::Radii::REACHED, self.cap_evaluations());
        // The closed form's proofs cost a microsecond; a spherical wrist's bound of its centre's
        // approach (a search over joints 2 and 3) a thousand times that, per part: on the
        // golden matrix its parts took the run from 3 minutes past 10.
        let cheap = parameter == Parameter::Turn && self.analytic.is_some();
        if whole.is_some() || !cut || !cheap || self.opts.search_boxes < super::search::FIRST_ORDER_BUDGET {
            return (whole, false);
        }
        let mut budget = self.reach_parts_left;
        let proof = super::parts::out_of_reach_by_parts(
            goal,
            &mut budget,
            super::parts::LEVER_M,
            // The ball bounds alone: a cap's evaluations per part would cost seconds a goal.
            |part, extent| self.part_out_of_reach(part, parameter, value, slack, extent.radii, 0).ok_or(None),
            |part| self.sample(part, parameter, value).is_some_and(|(_, found, _)| !found.is_empty()),
        );
        self.reach_parts_left = budget;
        let proven = proof.is_some();
        (proof, proven)
    }

    /// Why no configuration reaches `goal`'s pose within `radii`, the parameter within `slack`
    /// of `value`, when the method proves it (a spherical wrist's within `evaluations` of its
    /// cap).
    fn part_out_of_reach(
        &self,
        goal: &Goal,
        parameter: Parameter,
        value: f64,
        slack: f64,
        radii: super::search::Radii,
        evaluations: usize,
    ) -> Option<String> {
        let pose = Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
        match parameter {
            Parameter::Turn => {
                let turned = pose * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), value);
                self.exact_out_of_reach_within(&turned, radii, slack, evaluations)
            }
            Parameter::Held => {
                let held = self.redundant.as_ref()?;
                // Joint 7 turns the six's virtual tool about its own z.
                held.method
                    .out_of_reach_within(&held.pose_of_six(&pose, value), radii, slack, evaluations)
            }
        }
    }

    /// The sample at `value` judged over `half` of the parameter either side: its solutions
    /// counted and certified, or reached; `None` when no exact method applies. With `cut` (no
    /// shorter interval will be tried), a colliding solution whose certificate fails has the
    /// tolerance cut into parts ([`super::cells`]).
    fn judge_sample(&mut self, goal: &Goal, parameter: Parameter, value: f64, half: f64, cut: bool, words: &Words) -> Option<Judged> {
        let margin = self.margin();
        let (sample, configurations, finite) = self.sample(goal, parameter, value)?;
        let mut judged = Judged {
            count: 0,
            reached: None,
            collisions: Vec::new(),
            failure: None,
            refinable: true,
        };
        if !finite {
            judged.fail(format!("{}{} is a singular pose", words.at(value), words.place), false);
        }
        let mut distinct: Vec<Vec<f64>> = Vec::with_capacity(configurations.len());
        for mut q in configurations {
            let (_, size, _) = self.polish(&sample, &mut q);
            if size > EXACT {
                judged.fail(format!("a solution at {} does not verify", words.at(value)), false);
                continue;
            }
            if distinct.iter().any(|d| self.same_configuration(d, &q)) {
                continue;
            }
            distinct.push(q.clone());
            if self.shift_into_limits(&mut q, None) {
                let solution = self.judge(goal, q, None, margin);
                if solution.reached {
                    judged.reached = Some(solution);
                    return Some(judged);
                }
                match self.collision_certificate(&sample, &solution, margin, half) {
                    Ok(pair) => judged.collisions.push(pair),
                    Err(why) if cut => match self.cut_tolerance(&sample, goal, &solution.q.clone(), margin, half) {
                        Cells::Settled(pair) => judged.collisions.push(pair),
                        Cells::Free(solution) => {
                            judged.reached = Some(solution);
                            return Some(judged);
                        }
                        Cells::Open(cut) => judged.fail(format!("{why}; cut into parts, {cut}"), true),
                        Cells::Untried => judged.fail(why, true),
                    },
                    Err(why) => judged.fail(why, true),
                }
            } else {
                match self.outside_limits_certificate(&sample, &q, half) {
                    Ok(pair) => judged.collisions.extend(pair),
                    Err(why) => judged.fail(why, true),
                }
            }
        }
        judged.count = distinct.len();
        Some(judged)
    }

    /// Sweeps the parameter interval by interval: an interval is decided when its two ends are
    /// certified over half its length with the same count of solutions, or both have none and
    /// are proven out of reach; one whose certificates fail is halved (down to a sixteenth of
    /// the first step, within a budget of samples), since the branch's motion over a shorter
    /// step is smaller.
    fn sweep(&mut self, goal: &Goal, result: &mut GoalSolutions, parameter: Parameter) {
        let samples = self.samples(parameter);
        let method = self.method();
        let words = Words::of(parameter, samples.step);
        let mut grid = samples.values.clone();
        if samples.periodic {
            grid.extend(samples.values.first().map(|first| first + TAU));
        }
        let mut intervals: Vec<(f64, f64)> = grid.windows(2).rev().map(|w| (w[0], w[1])).collect();
        let shortest = samples.step / REFINEMENTS as f64;
        let budget = REFINEMENT_BUDGET * samples.values.len();
        let mut judged: HashMap<(u64, u64), Judged> = HashMap::new();
        let mut proofs: HashMap<(u64, u64), Option<String>> = HashMap::new();
        // Samples whose proof needed the tolerance cut into parts.
        let mut cut_samples = 0;
        let mut seen: Vec<f64> = Vec::new();
        let mut finest = samples.step;
        let mut collisions: Vec<String> = Vec::new();
        let mut out_of_reach: Option<String> = None;
        let mut open: Option<String> = None;
        let mut each: Option<usize> = None;
        while let Some((a, b)) = intervals.pop() {
            let half = (b - a) / 2.0;
            // Cutting the tolerance is costly: only where no shorter interval will follow, and
            // while the goal may still be proven.
            let cut = open.is_none() && (half <= shortest || judged.len() + 2 >= budget);
            let keys = [a, b].map(|value| (value.to_bits(), half.to_bits()));
            for (value, key) in [a, b].into_iter().zip(keys) {
                if let Entry::Vacant(slot) = judged.entry(key) {
                    let Some(sample) = self.judge_sample(goal, parameter, value, half, cut, &words) else {
                        return;
                    };
                    if let Some(solution) = sample.reached {
                        result.solutions.insert(0, solution);
                        result.undecided = None;
                        return;
                    }
                    if !seen.iter().any(|v| words.same(*v, value)) {
                        seen.push(value);
                    }
                    slot.insert(sample);
                }
            }
            if open.is_some() {
                // Undecided already: only a reached sample can change that.
                continue;
            }
            let (first, second) = (&judged[&keys[0]], &judged[&keys[1]]);
            each.get_or_insert(first.count);
            let mut failure = first.failure.clone().or_else(|| second.failure.clone());
            let mut refinable = first.refinable && second.refinable && first.count == second.count;
            if failure.is_none() && first.count != second.count {
                failure = Some(format!(
                    "the number of solutions changes between {} of {:.1} and {:.1} deg (a branch turns there)",
                    words.values,
                    a.to_degrees(),
                    b.to_degrees()
                ));
            }
            if failure.is_none() && first.count == 0 {
                // No solution at either end: proven when both are out of reach with half the
                // interval added to their slack.
                for (value, key) in [a, b].into_iter().zip(keys) {
                    if let Entry::Vacant(slot) = proofs.entry(key) {
                        let (proof, cut) = self.sample_out_of_reach(goal, parameter, value, half, half <= shortest);
                        cut_samples += usize::from(cut);
                        slot.insert(proof);
                    }
                    match &proofs[&key] {
                        Some(proof) => {
                            out_of_reach.get_or_insert_with(|| proof.clone());
                        }
                        None => {
                            if let Some(solution) = self.reach_nearby(goal, parameter, value) {
                                result.solutions.insert(0, solution);
                                result.undecided = None;
                                return;
                            }
                            failure = Some(format!(
                                "no {} sampled has an exact solution, but {} is not proven out of reach, so a configuration within the goal's tolerance is not ruled out",
                                words.one,
                                words.at(value)
                            ));
                            break;
                        }
                    }
                }
                // The slack grows with the interval: a shorter one may prove it.
                refinable = true;
            }
            match failure {
                None if first.count == 0 => {}
                None => {
                    for pair in first.collisions.iter().chain(&second.collisions) {
                        if !collisions.contains(pair) {
                            collisions.push(pair.clone());
                        }
                    }
                }
                Some(why) => {
                    if refinable && half > shortest && judged.len() < budget {
                        let middle = a + half;
                        finest = finest.min(half);
                        intervals.push((middle, b));
                        intervals.push((a, middle));
                    } else {
                        open = Some(why);
                    }
                }
            }
        }
        let n = seen.len();
        let over = words.over(finest);
        match open {
            Some(why) => {
                result.undecided = Some(format!("{method} {over} ({n} {}): {why}", words.many));
            }
            None => {
                let (sampled, of_step) = (words.sampled, words.of_step);
                let each = each.unwrap_or(0);
                result.complete = true;
                result.undecided = None;
                result.proof = Some(if let Some(proof) = out_of_reach {
                    let cut = if cut_samples > 0 {
                        format!(", {cut_samples} of them with the goal's tolerance cut into parts")
                    } else {
                        String::new()
                    };
                    format!("{method} {over}: every one of the {n} {sampled} is out of reach, each with half a sample step {of_step} added to its slack{cut} (the first: {proof})")
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

/// How much of the tolerance the poses tried around a sample use.
const NEARBY: f64 = 0.9;
/// A sweep's intervals are halved where certificates fail down to its first step over this.
const REFINEMENTS: usize = 16;
/// Samples a sweep may judge, per sample of its first grid.
const REFINEMENT_BUDGET: usize = 4;

/// One sample judged over half an interval either side.
#[derive(Debug, Clone)]
struct Judged {
    /// Distinct solutions of the sample's pose.
    count: usize,
    /// A solution within the limits and collision-free: the goal is reached.
    reached: Option<super::IkSolution>,
    /// The colliding pairs certified.
    collisions: Vec<String>,
    /// The first reason the sample proves nothing.
    failure: Option<String>,
    /// Every failure is a certificate a shorter interval may pass.
    refinable: bool,
}

impl Judged {
    fn fail(&mut self, why: String, refinable: bool) {
        self.failure.get_or_insert(why);
        self.refinable &= refinable;
    }
}

/// How a sweep's parameter reads in proofs and reasons.
struct Words {
    parameter: Parameter,
    step: f64,
    /// One sample, many samples, pairs of values, a step of it, its samples, where it turns.
    one: &'static str,
    many: &'static str,
    values: &'static str,
    of_step: &'static str,
    sampled: &'static str,
    place: &'static str,
}

impl Words {
    fn of(parameter: Parameter, step: f64) -> Self {
        match parameter {
            Parameter::Turn => Words {
                parameter,
                step,
                one: "turn",
                many: "turns",
                values: "the turns",
                of_step: "of the turn",
                sampled: "turns sampled",
                place: " about tool z",
            },
            Parameter::Held => Words {
                parameter,
                step,
                one: "angle of joint 7",
                many: "angles",
                values: "joint 7's angles",
                of_step: "of joint 7",
                sampled: "angles of joint 7 sampled",
                place: "",
            },
        }
    }

    /// The sample at `value`.
    fn at(&self, value: f64) -> String {
        match self.parameter {
            Parameter::Turn => format!("the turn of {:.0} deg", value.to_degrees()),
            Parameter::Held => format!("joint 7 at {:.1} deg", value.to_degrees()),
        }
    }

    /// What was swept, with the finest step used where it was refined.
    fn over(&self, finest: f64) -> String {
        let refined = if finest < self.step * 0.99 {
            format!(", down to {:.2} deg where needed", finest.to_degrees())
        } else {
            String::new()
        };
        match self.parameter {
            Parameter::Turn if refined.is_empty() => "over the free turn about tool z".into(),
            Parameter::Turn => format!("over the free turn about tool z ({:.0} deg apart{refined})", self.step.to_degrees()),
            Parameter::Held => format!(
                "with joint 7 held, over its range ({:.1} deg apart{refined})",
                self.step.to_degrees()
            ),
        }
    }

    /// Whether two values are one sample (a whole turn apart).
    fn same(&self, a: f64, b: f64) -> bool {
        super::wrap_angle(a - b).abs() < 1e-12
    }
}
