//! Consecutive revolute joints on one axis turn the tool as one joint by their sum (or
//! difference, for opposite directions): such an arm is rank-deficient, its solutions of a pose
//! form continua, and a search over its joints splits boxes along a direction that moves
//! nothing. The arm with each such pair merged into one joint reaches exactly the tool poses the
//! arm reaches (the merged joint's range is the sum of the two ranges, an interval), so a proof
//! that the merged arm cannot bring its tool within a goal's tolerance is one for the arm, in
//! one dimension fewer per pair. Collisions are not merged: the link between the two joints
//! turns with the first alone, so the merged arm has no geometry and proves only out of reach.
//!
//! The two frames commute: where joint `j + 1`'s axis line, carried by its parent transform
//! `A`, is joint `j`'s, a turn of joint `j` by `t` composed with `A` is `A` composed with a turn
//! of joint `j + 1` by `+-t`, so `A_j R_j(q_j) A_(j+1) R_(j+1)(q_(j+1)) = A_j A_(j+1)
//! R_(j+1)(q_(j+1) +- q_j)`.

use super::reduce;
use crate::model::{Joint, JointKind, Link, Model};
use nalgebra::{Isometry3, Vector3};

/// Largest distance (m) between the two axis lines, and sine of their angle, at which two
/// joints count as one axis: designs are exact, URDFs within their rounding.
const SAME_AXIS: f64 = 1e-9;

/// An arm with its coaxial consecutive joints merged.
#[derive(Debug, Clone)]
pub(super) struct Merged {
    /// The merged arm, without geometry.
    pub model: Model,
    /// Its sub-chains ([`reduce`]).
    pub sub_chains: Vec<reduce::SubChain>,
    /// Per joint of the merged arm, the arm's joints it stands for (from 1).
    pub groups: Vec<Vec<usize>>,
    /// Per joint of the merged arm, how it reads: "3+4" (a sum), "5-6" (joint 6 turning the
    /// other way), for proofs.
    pub names: Vec<String>,
}

impl Merged {
    /// The arm `model` with every run of coaxial revolute joints merged; `None` when it has none.
    pub(super) fn of(model: &Model) -> Option<Merged> {
        let mut merged = reduce::truncated(model, model.dof(), model.last_from_tool);
        // Original joint numbers of the merged model's joints.
        let mut groups: Vec<Vec<usize>> = (1..=model.dof()).map(|j| vec![j]).collect();
        let mut names: Vec<String> = (1..=model.dof()).map(|j| j.to_string()).collect();
        while let Some((j, sign)) = coaxial_pair(&merged) {
            merge(&mut merged, j, sign);
            let first = groups.remove(j);
            groups[j].splice(0..0, first);
            let first = names.remove(j);
            names[j] = format!("{first}{}{}", if sign > 0.0 { "+" } else { "-" }, names[j]);
        }
        if groups.iter().all(|group| group.len() == 1) {
            return None;
        }
        let sub_chains = reduce::sub_chains(&merged);
        Some(Merged {
            model: merged,
            sub_chains,
            groups,
            names,
        })
    }

    /// "joints 2 and 3 turn the tool about one axis ...; the arm so merged has joints 1, 2+3,
    /// 4, ...", for proofs (the merged arm's sub-chains are named by its own joint numbers).
    pub(super) fn describe(&self) -> String {
        let each: Vec<String> = self
            .groups
            .iter()
            .filter(|group| group.len() > 1)
            .map(|group| {
                let (last, rest) = group.split_last().expect("a group of two or more");
                let rest: Vec<String> = rest.iter().map(ToString::to_string).collect();
                format!("joints {} and {last}", rest.join(", "))
            })
            .collect();
        let verb = if each.len() == 1 { "turn" } else { "each turn" };
        format!(
            "{} {verb} the tool about one axis, as one joint by their sum (or difference); the arm so merged has joints {}",
            each.join("; "),
            self.names.join(", ")
        )
    }
}

impl Merged {
    /// The merged arm as a 6R arm, for the all-solutions methods: a merged arm of six joints as
    /// it is; one of five with a sixth, virtual, revolute joint about the tool's z axis, held at
    /// 0 by its limits `[0, 0]`. Either reaches exactly the tool poses the arm reaches (the
    /// virtual joint turns the tool only where it is 0), and its pose has finitely many
    /// solutions where the arm's form continua: the five joints' solutions bring the tool's
    /// position and z axis to the goal's, the virtual angle says how far about z the tool
    /// stays off. `None` for other joint counts.
    pub(super) fn six_joints(&self) -> Option<Model> {
        let mut model = self.model.clone();
        match model.dof() {
            6 => {}
            5 => {
                let tool = model.last_from_tool;
                model.joints.push(Joint {
                    name: "virtual joint about the tool's z axis".into(),
                    kind: JointKind::Revolute,
                    parent_from_joint: tool,
                    axis: Vector3::z_axis(),
                    limits: Some([0.0, 0.0]),
                    max_velocity: None,
                    max_effort: None,
                });
                model.links.push(Link {
                    name: "virtual".into(),
                    merged: Vec::new(),
                    colliders: Vec::new(),
                    inertial: None,
                    segments: Vec::new(),
                });
                model.last_from_tool = Isometry3::identity();
            }
            _ => return None,
        }
        Some(model)
    }

    /// How the arm of [`Self::six_joints`] reads, for proofs: [`Self::describe`], and the virtual
    /// joint where there is one.
    pub(super) fn describe_six(&self) -> String {
        let virtual_joint = if self.model.dof() == 5 {
            ", and a sixth, virtual, about the tool's z axis held at 0 (the five reach the goal's position and z axis, the sixth says how far about z the tool stays off)"
        } else {
            ""
        };
        format!("{}{virtual_joint}", self.describe())
    }
}

/// The first consecutive pair of revolute joints of `model` on one axis line, and whether their
/// directions agree (+1) or are opposite (-1).
fn coaxial_pair(model: &Model) -> Option<(usize, f64)> {
    let revolute = |j: usize| model.joints[j].kind != JointKind::Prismatic;
    (0..model.dof().saturating_sub(1)).find_map(|j| {
        if !(revolute(j) && revolute(j + 1)) {
            return None;
        }
        // Joint j + 1's axis line in joint j's frame (the frame joint j turns).
        let next = &model.joints[j + 1];
        let (point, direction) = (
            next.parent_from_joint.translation.vector,
            next.parent_from_joint.rotation * next.axis.into_inner(),
        );
        let axis = model.joints[j].axis.into_inner();
        let off_line = (point - axis * axis.dot(&point)).norm();
        let parallel = axis.cross(&direction).norm();
        (off_line <= SAME_AXIS && parallel <= SAME_AXIS).then(|| (j, axis.dot(&direction).signum()))
    })
}

/// Merges joint `j` into joint `j + 1` (`sign` as [`coaxial_pair`]): the merged joint keeps
/// joint `j + 1`'s axis, gets both parent transforms and the two ranges' sum; the link between
/// them goes.
fn merge(model: &mut Model, j: usize, sign: f64) {
    let first = model.joints.remove(j);
    let next = &mut model.joints[j];
    next.parent_from_joint = first.parent_from_joint * next.parent_from_joint;
    next.name = format!("{}+{}", first.name, next.name);
    next.limits = match (first.limits, next.limits) {
        (Some([low_a, high_a]), Some([low_b, high_b])) if sign > 0.0 => Some([low_b + low_a, high_b + high_a]),
        (Some([low_a, high_a]), Some([low_b, high_b])) => Some([low_b - high_a, high_b - low_a]),
        _ => None,
    };
    if next.limits.is_none() {
        next.kind = JointKind::Continuous;
    }
    model.links.remove(j + 1);
}

/// What the merged arm's searches ask: nothing beyond their bounds (no collisions, no local
/// solves: a configuration of the merged arm within the tolerance ends a search unproven).
pub(super) struct BoundsAlone;

impl super::search::Oracle for BoundsAlone {
    fn local(&mut self, _: &mut [f64]) -> bool {
        false
    }
    fn clear(&mut self, _: &[f64], _: &[f64]) -> super::search::Clear {
        super::search::Clear::Free
    }
    fn collisions(&self) -> bool {
        false
    }
}

/// Joint values of the merged arm for a configuration `q` of the arm: what the tool pose says
/// they are (for tests).
#[cfg(test)]
fn merged_configuration(model: &Model, q: &[f64]) -> Vec<f64> {
    let mut q = q.to_vec();
    let mut merged = reduce::truncated(model, model.dof(), model.last_from_tool);
    while let Some((j, sign)) = coaxial_pair(&merged) {
        let first = q.remove(j);
        q[j] += sign * first;
        merge(&mut merged, j, sign);
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn design(text: &str) -> Model {
        let design = crate::design::parse(text, std::path::Path::new("coaxial.json")).expect("design");
        crate::model::from_design(&design)
    }

    fn free(rows: &[(f64, f64, f64)]) -> Model {
        let joints: Vec<String> = rows
            .iter()
            .map(|(d, a, alpha)| format!(r#"{{"d": {d}, "a": {a}, "alpha": {alpha}}}"#))
            .collect();
        design(&format!(r#"{{"name": "c", "mode": "free", "joints": [{}]}}"#, joints.join(",")))
    }

    /// The merged arm's tool is the arm's at every configuration (FK: sums, a difference, three
    /// joints in a row), and arms without a shared axis are left alone.
    #[test]
    fn the_merged_arm_puts_the_tool_where_the_arm_does() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        // Joints 2 and 3 share an axis (a = 0, alpha = 0 between them), and 5 and 6 (alpha = pi:
        // opposite directions); in the second arm joints 3, 4 and 5.
        let pairs = free(&[
            (0.3, 0.0, FRAC_PI_2),
            (0.1, 0.0, 0.0),
            (0.2, 0.4, -FRAC_PI_2),
            (0.3, 0.0, FRAC_PI_2),
            (0.0, 0.0, PI),
            (0.1, 0.0, 0.0),
        ]);
        let run = free(&[
            (0.2, 0.2, -FRAC_PI_2),
            (0.2, 0.4, -FRAC_PI_2),
            (0.3, 0.0, 0.0),
            (0.2, 0.0, 0.0),
            (0.3, 0.3, 0.0),
            (0.3, 0.2, FRAC_PI_2),
        ]);
        for (model, groups, names) in [
            (&pairs, vec![vec![1], vec![2, 3], vec![4], vec![5, 6]], vec!["1", "2+3", "4", "5-6"]),
            (&run, vec![vec![1], vec![2], vec![3, 4, 5], vec![6]], vec!["1", "2", "3+4+5", "6"]),
        ] {
            let merged = Merged::of(model).expect("coaxial joints");
            assert_eq!(merged.groups, groups, "{}", merged.describe());
            assert_eq!(merged.names, names);
            for _ in 0..200 {
                let q = model.random_configuration(&mut rng);
                let m = merged_configuration(model, &q);
                let (a, b) = (model.tool_pose(&q), merged.model.tool_pose(&m));
                assert!((a.translation.vector - b.translation.vector).norm() < 1e-12, "{q:?}");
                assert!(a.rotation.angle_to(&b.rotation) < 1e-12, "{q:?}");
                for (value, joint) in m.iter().zip(&merged.model.joints) {
                    if let Some([low, high]) = joint.limits {
                        assert!(*value >= low - 1e-12 && *value <= high + 1e-12, "{value} outside [{low}, {high}]");
                    }
                }
            }
        }
        assert!(Merged::of(&pairs)
            .expect("coaxial joints")
            .describe()
            .starts_with("joints 2 and 3; joints 5 and 6 each turn the tool about one axis"));
        assert!(Merged::of(&run)
            .expect("coaxial joints")
            .describe()
            .starts_with("joints 3, 4 and 5 turn the tool"));
        let general = free(&[
            (0.3, 0.05, 1.3),
            (-0.08, 0.47, 0.12),
            (0.03, 0.36, -0.2),
            (0.19, 0.0, 1.57),
            (0.11, -0.02, -1.4),
            (0.1, 0.0, 0.0),
        ]);
        assert!(Merged::of(&general).is_none());
    }
}
