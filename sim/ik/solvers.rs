//! Which all-solutions method serves a model: chosen once, from its axis lines.
//!
//! UR-type arms have their own closed form ([`super::analytic`]). Otherwise, for a 6R arm on
//! `pose` goals or a 5R arm on `z_symmetric` goals (a virtual sixth joint about tool z): Pieper's
//! decomposition where three consecutive axes meet at either end ([`super::wrist`]), else the
//! general elimination ([`super::general`]) where it holds for the geometry, else three
//! consecutive parallel axes ([`super::parallel`]).

use super::general::General6R;
use super::lines::Arm;
use super::parallel::ParallelTriple;
use super::solutions::Solutions;
use super::wrist::SphericalWrist;
use crate::model::Model;
use crate::scenario::Tolerance;
use nalgebra::{Isometry3, UnitQuaternion, Vector3};

/// Configurations closer than this in every joint (rad) are one root found twice.
const SAME_RAD: f64 = 1e-6;

/// An all-solutions method of one model.
#[derive(Debug, Clone)]
pub enum AllSolutions {
    /// Three consecutive axes meet at the wrist or at the base (boxed, like the other: both
    /// carry the arm's lines and tables).
    Wrist(Box<SphericalWrist>),
    /// Any other 6R geometry the elimination holds for (boxed: its coefficient tables are
    /// large).
    General(Box<General6R>),
    /// Three consecutive parallel axes where the elimination degenerates.
    Parallel(Box<ParallelTriple>),
}

impl AllSolutions {
    /// The method for `model`, and the goal mode it decides (`pose` for six joints,
    /// `z_symmetric` for five); `None` when no method applies.
    pub fn of(model: &Model) -> Option<(AllSolutions, Tolerance)> {
        let (arm, tolerance) = match model.dof() {
            6 => (Arm::of(model)?, Tolerance::Pose),
            5 => (Arm::with_virtual_tool_joint(model)?, Tolerance::ZSymmetric),
            _ => return None,
        };
        Self::of_arm(arm).map(|method| (method, tolerance))
    }

    /// The method for a chain's lines: the wrist where it holds, else the elimination.
    fn of_arm(arm: Arm) -> Option<AllSolutions> {
        if let Some(wrist) = SphericalWrist::of_arm(arm.clone()) {
            return Some(AllSolutions::Wrist(Box::new(wrist)));
        }
        // With two joints on one line the pose's solutions are continua, which the elimination
        // and the parallel triple cannot list: their probes would fail, after two whole solves
        // per variant tried (about 0.2 ms an arm).
        if arm.forward.has_coaxial_pair() {
            return None;
        }
        if let Some(general) = General6R::of_arm(arm.clone()) {
            return Some(AllSolutions::General(Box::new(general)));
        }
        ParallelTriple::of_arm(arm).map(|parallel| AllSolutions::Parallel(Box::new(parallel)))
    }

    /// The method's name, for proofs.
    pub fn name(&self) -> &'static str {
        match self {
            AllSolutions::Wrist(_) => "all-solutions IK (spherical wrist)",
            AllSolutions::General(_) => "all-solutions IK (general 6R)",
            AllSolutions::Parallel(_) => "all-solutions IK (three parallel axes)",
        }
    }

    /// Every configuration reaching world pose `goal`, each once: a double root (two branches
    /// meeting) or a complex pair just off the real line gives one configuration twice.
    pub fn solve(&self, goal: &Isometry3<f64>) -> Solutions {
        self.solve_proving(goal, 0)
    }

    /// [`Self::solve`], a spherical wrist's out-of-reach proof spending up to `evaluations` on
    /// the tolerance's cap (see [`SphericalWrist::solve_proving`]).
    pub fn solve_proving(&self, goal: &Isometry3<f64>, evaluations: usize) -> Solutions {
        let mut found = self.solve_raw(goal, evaluations);
        let mut kept: Vec<[f64; 6]> = Vec::with_capacity(found.configurations.len());
        for q in found.configurations.drain(..) {
            let known = kept.iter().any(|k| k.iter().zip(&q).all(|(a, b)| same_angle(*a, *b)));
            if !known {
                kept.push(q);
            }
        }
        found.configurations = kept;
        found
    }

    /// Why no configuration reaches `goal`, turned by up to `turn` about tool z, within the
    /// tolerance, when the method proves it (within `evaluations`, see
    /// [`SphericalWrist::out_of_reach_over_turn`]).
    pub fn out_of_reach_over_turn(&self, goal: &Isometry3<f64>, turn: f64, evaluations: usize) -> Option<String> {
        self.out_of_reach_within(goal, super::search::Radii::REACHED, turn, evaluations)
    }

    /// [`Self::out_of_reach_over_turn`] for the poses within `radii` of `goal` (a part of the
    /// tolerance).
    pub fn out_of_reach_within(&self, goal: &Isometry3<f64>, radii: super::search::Radii, turn: f64, evaluations: usize) -> Option<String> {
        match self {
            AllSolutions::Wrist(wrist) => wrist.out_of_reach_within(goal, radii, turn, evaluations),
            AllSolutions::General(general) => general.out_of_reach_within(goal, radii, turn),
            AllSolutions::Parallel(_) => None,
        }
    }

    fn solve_raw(&self, goal: &Isometry3<f64>, evaluations: usize) -> Solutions {
        match self {
            AllSolutions::Wrist(wrist) => {
                let found = wrist.solve_proving(goal, evaluations);
                Solutions {
                    configurations: found.configurations,
                    resolved: found.resolved,
                    out_of_reach: found.out_of_reach,
                }
            }
            AllSolutions::General(general) => {
                let found = general.solve(goal);
                Solutions {
                    configurations: found.configurations,
                    resolved: found.resolved,
                    out_of_reach: None,
                }
            }
            AllSolutions::Parallel(parallel) => parallel.solve(goal),
        }
    }
}

/// A 7R arm's pose goals with joint 7 held at each angle in turn: the six others are a 6R arm
/// with the method for their lines, its tool a virtual frame on joint 7's axis (its z the axis),
/// so turning joint 7 turns that frame about its own z.
#[derive(Debug, Clone)]
pub struct HeldJoint {
    /// The six others' method; its tool is the virtual frame on joint 7's axis.
    pub method: AllSolutions,
    /// The real tool in the virtual frame at `q7 = 0`.
    offset: Isometry3<f64>,
}

impl HeldJoint {
    /// The method of a 7R `model` with its last joint held, when one holds for the six others.
    pub fn of(model: &Model) -> Option<HeldJoint> {
        let (arm, offset) = Arm::holding_last_joint(model)?;
        AllSolutions::of_arm(arm).map(|method| HeldJoint { method, offset })
    }

    /// The pose the six others must reach to put the tool at `goal` with joint 7 at `angle`.
    pub fn pose_of_six(&self, goal: &Isometry3<f64>, angle: f64) -> Isometry3<f64> {
        goal * self.offset.inverse() * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), -angle)
    }
}

/// Whether two angles are one within [`SAME_RAD`], a whole turn apart or not.
fn same_angle(a: f64, b: f64) -> bool {
    super::wrapped(a - b).abs() <= SAME_RAD
}
