//! Certificates that a known solution proves nothing about the goal's tolerance, or does: the
//! configurations within 1 mm and 1 degree of a pose lie near its exact solutions (the inverse
//! Jacobian's rows against the tolerance, doubled for the curvature), so a colliding solution
//! counts only when its closest pair stays colliding throughout that neighbourhood, and a
//! solution outside the limits only when it stays outside. A colliding branch that no
//! certificate covers is searched for a free configuration within the tolerance first. First
//! order (doubled), not interval arithmetic: docs/ik.md says so.

use super::{refine, Ik, IkSolution, EXACT, REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use crate::model::JointKind;
use crate::scenario::{Goal, Tolerance};
use std::f64::consts::TAU;

impl Ik<'_> {
    /// The joint step that removes task error `e` at `q` to first order, over the directions
    /// the goal constrains (six for `pose`; five for `z_symmetric`: no turn about goal z); `None`
    /// when they are not as many as the joints, or the Jacobian is singular there.
    pub(super) fn newton_step(&mut self, goal: &Goal, q: &[f64], e: &nalgebra::Vector6<f64>) -> Option<Vec<f64>> {
        let inverse = self.constrained_inverse(goal, q)?;
        let constrained = constrained_rows(goal) * e;
        Some(
            (0..q.len())
                .map(|i| (0..6).map(|k| inverse[(i, k)] * constrained[k]).sum())
                .collect(),
        )
    }

    /// The inverse of the Jacobian's constrained rows at `q` (joints by 6, the unconstrained
    /// rows' columns zero, and the held joint's row, see [`Ik::held`]); `None` as in
    /// [`Self::newton_step`]. Leaves the Jacobian at `q` in the workspace.
    fn constrained_inverse(&mut self, goal: &Goal, q: &[f64]) -> Option<nalgebra::DMatrix<f64>> {
        self.model.tool_jacobian(q, &mut self.ws);
        let dof = q.len();
        let held = self.held.filter(|&h| h < dof);
        let moving: Vec<usize> = (0..dof).filter(|&i| Some(i) != held).collect();
        let rows = constrained_rows(goal);
        let constrained = match goal.tolerance {
            Tolerance::Pose => 6,
            Tolerance::ZSymmetric => 5,
            Tolerance::Position => 3,
        };
        if constrained != moving.len() {
            return None;
        }
        let projected = rows * &self.ws.jacobian;
        let square = nalgebra::DMatrix::from_fn(constrained, constrained, |r, c| projected[(r, moving[c])]);
        let inverse = square.try_inverse()?;
        let mut out = nalgebra::DMatrix::zeros(dof, 6);
        for (k, &i) in moving.iter().enumerate() {
            for r in 0..constrained {
                out[(i, r)] = inverse[(k, r)];
            }
        }
        Some(out)
    }

    /// The joints' rates along the self-motion through `q` per unit of its parameter: the held
    /// joint's turn (the others follow to keep the pose), else the free turn about goal z.
    /// `inverse` is [`Self::constrained_inverse`] at `q`, whose Jacobian the workspace holds.
    fn branch_rate(&self, goal: &Goal, inverse: &nalgebra::DMatrix<f64>) -> Vec<f64> {
        let dof = inverse.nrows();
        match self.held.filter(|&h| h < dof) {
            Some(h) => {
                let rows = constrained_rows(goal);
                let column: Vec<f64> = (0..6)
                    .map(|r| (0..6).map(|k| rows[(r, k)] * self.ws.jacobian[(k, h)]).sum())
                    .collect();
                (0..dof)
                    .map(|i| {
                        if i == h {
                            1.0
                        } else {
                            -(0..6).map(|k| inverse[(i, k)] * column[k]).sum::<f64>()
                        }
                    })
                    .collect()
            }
            None => {
                let z = goal.rotation * nalgebra::Vector3::z();
                (0..dof).map(|i| (0..3).map(|k| inverse[(i, 3 + k)] * z[k]).sum()).collect()
            }
        }
    }

    /// How far each joint may be from solution `q` while the tool stays within the goal's
    /// tolerance: the inverse Jacobian's rows against 1 mm and 1 degree, doubled for the
    /// curvature; with `turn` > 0 also the branch's motion over that much of the self-motion's
    /// parameter (see [`Self::branch_rate`]); `None` near a singularity, where that is no bound.
    fn neighbourhood(&mut self, goal: &Goal, q: &[f64], turn: f64) -> Option<Vec<f64>> {
        self.neighbourhood_within(goal, q, turn, Region::WHOLE)
    }

    /// [`Self::neighbourhood`] of a part of the tolerance around the pose `q` reaches: the poses
    /// within `region` of it.
    pub(super) fn neighbourhood_within(&mut self, goal: &Goal, q: &[f64], turn: f64, region: Region) -> Option<Vec<f64>> {
        // Columns: constrained rows (position first); the rotation rows' error is at most the
        // tolerance angle in whichever directions are constrained.
        let inverse = self.constrained_inverse(goal, q)?;
        let along = self.branch_rate(goal, &inverse);
        let reach: Vec<f64> = (0..q.len())
            .map(|i| TOLERANCE_CURVATURE * (region.spread(|k| inverse[(i, k)]) + along[i].abs() * turn))
            .collect();
        reach.iter().all(|r| r.is_finite() && *r <= LINEAR_REACH_RAD).then_some(reach)
    }

    /// The colliding pair that stays colliding throughout the tolerance neighbourhood of
    /// `solution` (the checker's last query), named with its depth; else why not.
    ///
    /// With `turn` > 0 the solution is a sample of a self-motion (a 6R arm on a `z_symmetric`
    /// goal, see [`selfmotion`]) and the neighbourhood also covers the branch over `turn` (rad)
    /// of the free turn about tool z either side.
    pub(super) fn collision_certificate(&mut self, goal: &Goal, solution: &IkSolution, margin: f64, turn: f64) -> Result<String, String> {
        let clearance = solution.clearance.map_or(f64::INFINITY, |c| c.exact_m);
        let pair = self.checker.as_ref().and_then(|c| c.closest_pair());
        let Some(pair) = pair else {
            return Err("a solution's collision was not measured".into());
        };
        let name = &pair.name;
        match self.collision_bound(goal, &solution.q, &pair, turn, Region::WHOLE) {
            Some(motion) if clearance + motion <= margin => Ok(format!("{name} {:.1} mm", clearance * 1e3)),
            Some(motion) => Err(format!(
                "a solution's {name} are at {:.1} mm, within the {:.1} mm the goal's tolerance can move them",
                clearance * 1e3,
                motion * 1e3
            )),
            None => Err(format!(
                "a solution near a singularity has {name} at {:.1} mm, and the goal's tolerance may move them far",
                clearance * 1e3
            )),
        }
    }

    /// How far `pair`'s distance at `q` may change over the poses within `region` of the one `q`
    /// reaches (and `turn` of a self-motion): the whole-body bound or the pair's distance
    /// gradient (first order, doubled for the curvature like the reach), the smaller; `None`
    /// near a singularity.
    pub(super) fn collision_bound(&mut self, goal: &Goal, q: &[f64], pair: &refine::ClosestPair, turn: f64, region: Region) -> Option<f64> {
        let reach = self.neighbourhood_within(goal, q, turn, region);
        let gradient = match reach {
            Some(_) => self.distance_gradient(goal, q, pair),
            None => None,
        };
        self.pair_motion(pair, turn, region, reach.as_deref(), gradient.as_ref())
    }

    /// [`Self::collision_bound`] from the neighbourhood (`reach`, `None` near a singularity) and
    /// the pair's distance gradient ([`Self::distance_gradient`]) already at hand.
    pub(super) fn pair_motion(
        &self,
        pair: &refine::ClosestPair,
        turn: f64,
        region: Region,
        reach: Option<&[f64]>,
        gradient: Option<&(nalgebra::Vector6<f64>, f64)>,
    ) -> Option<f64> {
        // The last link against the world moves with the tool, singular or not (a turn about
        // tool z, or a held joint's, turns it by at most `turn` more).
        let (position, rotation) = region.extent();
        let rigid = self
            .bounds
            .tool_rigid_motion(pair.bodies[0], pair.bodies[1], position, rotation + turn);
        let Some(reach) = reach else {
            return rigid;
        };
        let whole = self.bounds.relative_motion(pair.bodies[0], pair.bodies[1], reach);
        let first_order = gradient.map_or(f64::INFINITY, |(h, along)| {
            TOLERANCE_CURVATURE * (region.spread(|k| h[k]) + along.abs() * turn)
        });
        Some(whole.min(first_order).min(rigid.unwrap_or(f64::INFINITY)))
    }

    /// The pair's distance gradient at `q` in task space: `h` with `d(q + dq) ~ d(q) + h . J dq`
    /// over the goal's constrained directions (position first), from the witness points'
    /// velocities along the normal, and the distance's rate along the self-motion (see
    /// [`Self::branch_rate`]); `None` where the Jacobian is singular.
    pub(super) fn distance_gradient(
        &mut self,
        goal: &Goal,
        q: &[f64],
        pair: &refine::ClosestPair,
    ) -> Option<(nalgebra::Vector6<f64>, f64)> {
        let inverse = self.constrained_inverse(goal, q)?;
        let branch = self.branch_rate(goal, &inverse);
        self.model.forward(q, &mut self.ws);
        let mut h = nalgebra::Vector6::zeros();
        let mut along = 0.0;
        for (i, joint) in self.model.joints.iter().enumerate() {
            let frame = &self.ws.link_in_world[i + 1];
            let axis = frame.rotation * joint.axis.into_inner();
            // Joint i moves links i + 1 onwards; obstacles and the floor stay.
            let velocity = |body: crate::collide::Body, point: &nalgebra::Vector3<f64>| match body {
                crate::collide::Body::Link(k) if k > i => match joint.kind {
                    JointKind::Prismatic => axis,
                    _ => axis.cross(&(point - frame.translation.vector)),
                },
                _ => nalgebra::Vector3::zeros(),
            };
            let rate = pair
                .normal
                .dot(&(velocity(pair.bodies[1], &pair.points[1]) - velocity(pair.bodies[0], &pair.points[0])));
            for k in 0..6 {
                h[k] += inverse[(i, k)] * rate;
            }
            along += branch[i] * rate;
        }
        Some((h, along))
    }

    /// A collision-free configuration within the goal's tolerance near colliding exact solution
    /// `q`, when moving the tool within 90 % of the tolerance along the closest pair's
    /// separating direction finds one (a few steps, each re-measured exactly).
    pub(super) fn free_within_tolerance(&mut self, goal: &Goal, q: &[f64], margin: f64) -> Option<IkSolution> {
        if goal.tolerance != Tolerance::Pose {
            return None;
        }
        let mut current = q.to_vec();
        for _ in 0..TOLERANCE_SEARCH_STEPS {
            let pair = self.checker.as_mut().map(|c| {
                c.clearance(&current, true);
                c.closest_pair()
            })??;
            let (h, _) = self.distance_gradient(goal, &current, &pair)?;
            let (position, rotation) = (h.fixed_rows::<3>(0).into_owned(), h.fixed_rows::<3>(3).into_owned());
            let towards = |v: nalgebra::Vector3<f64>, size: f64| {
                let norm = v.norm();
                if norm > 0.0 {
                    v * (TOLERANCE_USED * size / norm)
                } else {
                    v
                }
            };
            let shifted = Goal {
                position: goal.position + towards(position, REACHED_POSITION_M),
                rotation: nalgebra::UnitQuaternion::from_scaled_axis(towards(rotation, REACHED_ORIENTATION_RAD)) * goal.rotation,
                ..goal.clone()
            };
            let mut next = current.clone();
            let (_, size, _) = self.polish(&shifted, &mut next);
            if size > EXACT {
                return None;
            }
            let solution = self.judge(goal, next.clone(), None, margin);
            if solution.reached {
                return Some(solution);
            }
            current = next;
        }
        None
    }

    /// Whether solution `q`, none of whose whole-turn equivalents is within the limits, proves
    /// nothing reachable throughout the goal's tolerance (and `turn` of a self-motion): it stays
    /// outside the limits (`Ok(None)`), or where the limits certificate fails it collides
    /// throughout, so any neighbour within the limits collides too (`Ok(Some(pair))`); else why
    /// not.
    pub(super) fn outside_limits_certificate(&mut self, goal: &Goal, q: &[f64], turn: f64) -> Result<Option<String>, String> {
        let why = match self.limits_certificate(goal, q, turn) {
            Ok(()) => return Ok(None),
            Err(why) => why,
        };
        if self.checker.is_none() {
            return Err(why);
        }
        // Collision geometry repeats with every whole turn: the configuration as it is will do.
        let margin = self.margin();
        let solution = self.judge(goal, q.to_vec(), None, margin);
        if solution.clearance.is_none_or(|c| c.exact_m > margin) {
            return Err(why);
        }
        self.collision_certificate(goal, &solution, margin, turn).map(Some).map_err(|_| why)
    }

    /// Whether solution `q`, none of whose whole-turn equivalents is within the limits, stays
    /// outside them throughout the goal's tolerance; else why not.
    pub(super) fn limits_certificate(&mut self, goal: &Goal, q: &[f64], turn: f64) -> Result<(), String> {
        let Some(reach) = self.neighbourhood(goal, q, turn) else {
            return Err("a solution outside the joint limits is near a singularity".into());
        };
        let mut closest: Option<(usize, f64)> = None;
        for (i, (joint, value)) in self.model.joints.iter().zip(q).enumerate() {
            let gap = limit_gap(joint, *value);
            if gap > reach[i] {
                return Ok(());
            }
            if gap > 0.0 && closest.is_none_or(|(_, g)| gap < g) {
                closest = Some((i, gap));
            }
        }
        Err(match closest {
            Some((i, gap)) => format!(
                "a solution is {:.2} deg outside joint {}'s limits, within what the goal's tolerance allows",
                gap.to_degrees(),
                i + 1
            ),
            None => "a solution is at the joint limits".into(),
        })
    }
}

/// A part of a goal's tolerance about a pose, in the goal's constrained task-space rows
/// (position first, see [`constrained_rows`]).
#[derive(Debug, Clone, Copy)]
pub(super) enum Region {
    /// The poses within `position_m` of its position and `rotation_rad` of its rotation.
    Ball { position_m: f64, rotation_rad: f64 },
    /// The poses whose offset in each row is within its half-width (m, then rad).
    Box([f64; 6]),
}

impl Region {
    /// The whole tolerance.
    pub(super) const WHOLE: Region = Region::Ball {
        position_m: REACHED_POSITION_M,
        rotation_rad: REACHED_ORIENTATION_RAD,
    };

    /// The most a linear function of the task-space offset with coefficients `row` (position
    /// first) reaches over the region.
    fn spread(&self, row: impl Fn(usize) -> f64) -> f64 {
        match self {
            Region::Ball { position_m, rotation_rad } => {
                let norm = |first: usize| (first..first + 3).map(|k| row(k).powi(2)).sum::<f64>().sqrt();
                norm(0) * position_m + norm(3) * rotation_rad
            }
            Region::Box(half) => half.iter().enumerate().map(|(k, w)| row(k).abs() * w).sum(),
        }
    }

    /// The farthest the region's poses are from its centre: in position (m) and in rotation
    /// (rad).
    fn extent(&self) -> (f64, f64) {
        match self {
            Region::Ball { position_m, rotation_rad } => (*position_m, *rotation_rad),
            Region::Box(half) => {
                let norm = |first: usize| half[first..first + 3].iter().map(|w| w * w).sum::<f64>().sqrt();
                (norm(0), norm(3))
            }
        }
    }
}

/// Doubles the linearised tolerance neighbourhood of a solution: the pose error is not linear
/// in the joints, and a certificate must hold for all of it.
pub(super) const TOLERANCE_CURVATURE: f64 = 2.0;
/// Steps of the search for a free configuration within a colliding solution's tolerance.
const TOLERANCE_SEARCH_STEPS: usize = 4;
/// The part of the tolerance that search may use: the configuration it finds must stay within
/// the tolerance after rounding.
const TOLERANCE_USED: f64 = 0.9;
/// Joint motions (rad) beyond which the linearised neighbourhood is no bound (near a
/// singularity the tolerance may reach a different branch).
pub(super) const LINEAR_REACH_RAD: f64 = 0.5;

/// The rows of the task error a goal constrains, first: all six for `pose`; for `z_symmetric`
/// the position and the two turns across goal z (the last row zero); the position alone for
/// `position`.
pub(super) fn constrained_rows(goal: &Goal) -> nalgebra::Matrix6<f64> {
    let mut rows = nalgebra::Matrix6::identity();
    match goal.tolerance {
        Tolerance::Pose => {}
        Tolerance::ZSymmetric => {
            let x = goal.rotation * nalgebra::Vector3::x();
            let y = goal.rotation * nalgebra::Vector3::y();
            rows.fixed_view_mut::<3, 3>(3, 3).fill(0.0);
            rows.fixed_view_mut::<1, 3>(3, 3).copy_from(&x.transpose());
            rows.fixed_view_mut::<1, 3>(4, 3).copy_from(&y.transpose());
        }
        Tolerance::Position => rows.fixed_view_mut::<3, 3>(3, 3).fill(0.0),
    }
    rows
}

/// How far (rad or m) joint value `value` is outside the joint's limits, over its whole-turn
/// equivalents for a revolute joint; 0 when within them or unlimited.
pub(super) fn limit_gap(joint: &crate::model::Joint, value: f64) -> f64 {
    let Some([lower, upper]) = joint.limits else { return 0.0 };
    // Within rounding of a limit is at it (see [`super::LIMIT_ROUNDING`]).
    let outside = |v: f64| {
        let gap = (lower - v).max(v - upper);
        if gap <= super::LIMIT_ROUNDING {
            0.0
        } else {
            gap
        }
    };
    if joint.kind == JointKind::Prismatic {
        return outside(value);
    }
    let turns = [((lower - value) / TAU).floor(), ((upper - value) / TAU).ceil()];
    (turns[0] as i64..=turns[1] as i64)
        .map(|k| outside(value + k as f64 * TAU))
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sample at a joint's limit that was wrapped into (-pi, pi] and back (the Kinova Gen3's
    /// joint 7, limits [-1.4915, 4.6315] rad: -1.4915 comes back as -1.4915000000000003) is at
    /// the limit, not outside it; a value a micro-radian past it is outside.
    #[test]
    fn a_value_at_a_limit_stays_at_it_through_a_wrap() {
        let mut model = super::super::search::tests::preset("ur5e");
        let (lower, upper) = (-1.4915, 4.6315);
        model.joints[5].limits = Some([lower, upper]);
        let ik = Ik::new(&model, Default::default());
        for limit in [lower, upper] {
            let wrapped = super::super::wrap_angle(limit);
            assert_eq!(limit_gap(&model.joints[5], wrapped), 0.0, "{limit} wrapped to {wrapped}");
            let mut q = vec![0.0, 0.0, 0.0, 0.0, 0.0, wrapped];
            assert!(ik.shift_into_limits(&mut q, None), "{limit} wrapped to {wrapped}");
            assert_eq!(q[5], limit);
        }
        let past = lower - 1e-6;
        assert!(limit_gap(&model.joints[5], past) > 0.0);
        let mut q = vec![0.0, 0.0, 0.0, 0.0, 0.0, past];
        assert!(!ik.shift_into_limits(&mut q, None));
    }
}
