//! Sub-chains that stand in for the whole arm in the joint-space search ([`super::search`]).
//!
//! A point fixed both in link `k` and in the tool frame (where the axes of every joint after `k`
//! meet: a spherical wrist's centre, the crossing of the last two axes) must be, whenever the
//! tool is within the goal's tolerance, within the tolerance's position radius plus how far the
//! tolerance's turn moves it of where the goal puts it. The same holds for the line of the last
//! axis, fixed in the last link but one and in the tool frame: its point nearest the tool origin
//! and its direction. So when no configuration of the first `k` joints brings the point (or the
//! line) there, no configuration of the arm reaches the goal: a proof in `k` dimensions instead
//! of all of them, which is where the search's boxes run out (a 6-joint arm's goals just beyond
//! its reach need boxes of a milliradian along a fold of the six-dimensional joint space; its
//! wrist centre's fold is three-dimensional).

use super::search::Radii;
use super::{REACHED_ORIENTATION_RAD, REACHED_POSITION_M};
use crate::model::{JointKind, Model};
use crate::scenario::{Goal, Tolerance};
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

/// Largest distance (m) between the axes that should meet and their meeting point at which a
/// sub-chain is still used; the point's drift in the tool frame (at most 26 times this, see
/// [`drift`]) widens the radius. Designs meet exactly; URDFs within their rounding.
const MEET_M: f64 = 1e-6;

/// Parallel axes (sine of their angle below this) have no meeting point to stand in.
const PARALLEL: f64 = 1e-6;

/// A sub-chain of the first [`SubChain::joints`] joints whose tool is a point (and for the last
/// axis, a line) fixed in the full arm's tool frame.
#[derive(Debug, Clone)]
pub(super) struct SubChain {
    /// The first joints, their tool frame at the point, its z along the line.
    pub model: Model,
    /// Joints kept.
    pub joints: usize,
    /// The point in the full arm's tool frame (at zero joint values of the joints left out).
    point_in_tool: Vector3<f64>,
    /// The line's direction in the full arm's tool frame; `None` for a point alone.
    axis_in_tool: Option<Unit<Vector3<f64>>>,
    /// How far (m) the point can drift in the tool frame as the joints left out move.
    drift: f64,
    /// What stands in for the arm, for proofs.
    pub what: String,
}

/// The reduced goal of one sub-chain.
pub(super) struct Reduced {
    pub goal: Goal,
    pub radii: Radii,
}

/// The sub-chains of `model`, fewest joints first: where the axes of the last joints meet, then
/// the last axis. Empty when the last joint is not revolute.
pub(super) fn sub_chains(model: &Model) -> Vec<SubChain> {
    let dof = model.dof();
    let revolute = |j: usize| model.joints[j].kind != JointKind::Prismatic;
    if dof < 2 || !revolute(dof - 1) {
        return Vec::new();
    }
    let mut ws = model.workspace();
    model.forward(&vec![0.0; dof], &mut ws);
    let axis = |j: usize| {
        let frame = &ws.link_in_world[j + 1];
        (frame.translation.vector, frame.rotation * model.joints[j].axis.into_inner())
    };
    let tool = ws.tool_in_world;
    let mut chains = Vec::new();
    // The first joint left out: the longest run of revolute joints at the end whose axes meet.
    for first in 1..dof.saturating_sub(1) {
        if !(first..dof).all(revolute) {
            continue;
        }
        let Some(point) = meeting_point(axis(first), axis(first + 1)) else {
            continue;
        };
        let misses: Vec<f64> = (first..dof).map(|j| distance_to_line(&point, axis(j))).collect();
        if misses.iter().any(|&m| m > MEET_M) {
            continue;
        }
        let in_link = ws.link_in_world[first].inverse_transform_point(&point.into()).coords;
        let left_out = dof - first;
        let what = if left_out == 3 {
            format!("the wrist centre, where the axes of joints {} to {} meet", first + 1, dof)
        } else if left_out == 2 {
            format!("the point where the axes of joints {} and {} meet", first + 1, dof)
        } else {
            format!("the point where the axes of joints {} to {} meet", first + 1, dof)
        };
        chains.push(SubChain {
            model: truncated(
                model,
                first,
                Isometry3::from_parts(Translation3::from(in_link), UnitQuaternion::identity()),
            ),
            joints: first,
            point_in_tool: tool.inverse_transform_point(&point.into()).coords,
            axis_in_tool: None,
            drift: drift(&misses),
            what,
        });
        break;
    }
    // The last axis: its point nearest the tool origin, and its direction.
    let (origin, direction) = axis(dof - 1);
    let tool_origin = tool.translation.vector;
    let point = origin + direction * direction.dot(&(tool_origin - origin));
    let last = dof - 1;
    let in_link = ws.link_in_world[last].inverse_transform_point(&point.into()).coords;
    let direction_in_link = ws.link_in_world[last].inverse_transform_vector(&direction);
    let turn = UnitQuaternion::rotation_between(&Vector3::z(), &direction_in_link)
        .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI));
    chains.push(SubChain {
        model: truncated(model, last, Isometry3::from_parts(Translation3::from(in_link), turn)),
        joints: last,
        point_in_tool: tool.inverse_transform_point(&point.into()).coords,
        axis_in_tool: Some(Unit::new_normalize(tool.inverse_transform_vector(&direction))),
        drift: 0.0,
        what: format!("the axis of joint {dof}"),
    });
    chains
}

/// The closest point of the second line to the first, when the two are not parallel.
fn meeting_point(a: (Vector3<f64>, Vector3<f64>), b: (Vector3<f64>, Vector3<f64>)) -> Option<Vector3<f64>> {
    let (pa, da) = a;
    let (pb, db) = b;
    let normal = da.cross(&db);
    let sine2 = normal.norm_squared();
    if sine2 < PARALLEL * PARALLEL {
        return None;
    }
    // pb + t db closest to line a: (pb + t db - pa) . n_a = 0 with n_a = da x (da x db).
    let across = da.cross(&normal);
    let t = (pa - pb).dot(&across) / db.dot(&across);
    Some(pb + db * t)
}

fn distance_to_line(point: &Vector3<f64>, (origin, direction): (Vector3<f64>, Vector3<f64>)) -> f64 {
    let offset = point - origin;
    (offset - direction * direction.dot(&offset)).norm()
}

/// How far the point can move in the tool frame as the joints left out turn, when axis `i` of
/// them passes `misses[i]` from it: a turn moves a point by at most twice its distance from the
/// axis, and each earlier turn may have moved the point further from the next axis, so the
/// drifts compound as `D_i <= 3 D_(i-1) + 2 m_i` (26 times the largest miss for three joints).
fn drift(misses: &[f64]) -> f64 {
    misses.iter().fold(0.0, |drift, miss| 3.0 * drift + 2.0 * miss)
}

/// The first `joints` joints of `model`, without geometry, with their tool at `tool` in the last
/// link kept.
pub(super) fn truncated(model: &Model, joints: usize, tool: Isometry3<f64>) -> Model {
    let links = model.links[..=joints]
        .iter()
        .map(|link| crate::model::Link {
            name: link.name.clone(),
            merged: Vec::new(),
            colliders: Vec::new(),
            inertial: link.inertial.clone(),
            segments: Vec::new(),
        })
        .collect();
    Model {
        name: model.name.clone(),
        source: model.source.clone(),
        world_from_base: model.world_from_base,
        joints: model.joints[..joints].to_vec(),
        links,
        last_from_tool: tool,
        diagnostics: Vec::new(),
    }
}

impl SubChain {
    /// The goal the sub-chain must reach whenever the arm reaches `goal` within the harness's
    /// tolerance, and that goal's radii; `None` where the sub-chain says nothing of `goal`
    /// (a position-only goal, or a `z_symmetric` one whose free turn moves the point).
    pub(super) fn reduce(&self, goal: &Goal) -> Option<Reduced> {
        let z = Vector3::z();
        let off_z = self.point_in_tool.cross(&z).norm();
        match goal.tolerance {
            Tolerance::Position => return None,
            Tolerance::ZSymmetric => {
                let along = self.axis_in_tool.is_none_or(|axis| axis.cross(&z).norm() <= 1e-12);
                if off_z > 1e-12 || !along {
                    return None;
                }
            }
            Tolerance::Pose => {}
        }
        // The tolerance's turn moves a point at `lever` from the tool origin by at most this.
        let chord = 2.0 * (REACHED_ORIENTATION_RAD / 2.0).sin();
        let lever = self.point_in_tool.norm() + self.drift;
        let spin = if goal.tolerance == Tolerance::ZSymmetric {
            2.0 * self.drift
        } else {
            self.drift
        };
        let radii = Radii {
            position_m: REACHED_POSITION_M + chord * lever + spin,
            orientation_rad: REACHED_ORIENTATION_RAD,
        };
        let position = goal.position + goal.rotation * self.point_in_tool;
        let (rotation, tolerance) = match self.axis_in_tool {
            None => (UnitQuaternion::identity(), Tolerance::Position),
            Some(axis) => {
                // A z_symmetric goal constrains the tool z axis, which the last axis lies along.
                let wanted = if goal.tolerance == Tolerance::ZSymmetric {
                    goal.rotation * (z * axis.dot(&z).signum())
                } else {
                    goal.rotation * axis.into_inner()
                };
                let turn = UnitQuaternion::rotation_between(&z, &wanted)
                    .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI));
                (turn, Tolerance::ZSymmetric)
            }
        };
        Some(Reduced {
            goal: Goal {
                name: goal.name.clone(),
                position,
                rotation,
                tolerance,
                task: None,
            },
            radii,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::search::tests::preset;
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The oracle for every proof by a sub-chain: whatever configuration of the arm puts the
    /// tool within the tolerance of a goal, its first joints put the sub-chain's tool within
    /// the reduced radii of the reduced goal, near the tolerance's edge in every direction.
    #[test]
    fn every_configuration_within_the_tolerance_keeps_its_sub_chain_within_the_reduced_goal() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut checked = 0;
        for name in [
            "abb-irb-2600",
            "economic-spherical-wrist",
            "modular-elbow",
            "ur5e",
            "free-offset-6dof",
            "free-redundant-7dof",
            "paper-real-world",
        ] {
            let model = preset(name);
            let chains = sub_chains(&model);
            assert!(!chains.is_empty(), "{name}: the last axis always stands in");
            for chain in &chains {
                for tolerance in [Tolerance::Pose, Tolerance::ZSymmetric] {
                    for _ in 0..300 {
                        let q = model.random_configuration(&mut rng);
                        let tool = model.tool_pose(&q);
                        let shift = Vector3::new(
                            rng.random_range(-1.0..1.0),
                            rng.random_range(-1.0..1.0),
                            rng.random_range(-1.0..1.0),
                        );
                        let turn = Vector3::new(
                            rng.random_range(-1.0..1.0),
                            rng.random_range(-1.0..1.0),
                            rng.random_range(-1.0..1.0),
                        );
                        let spin = if tolerance == Tolerance::ZSymmetric {
                            rng.random_range(-3.0..3.0)
                        } else {
                            0.0
                        };
                        let rotation = UnitQuaternion::from_scaled_axis(turn.normalize() * 0.999 * REACHED_ORIENTATION_RAD)
                            * tool.rotation
                            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), spin);
                        let goal = Goal {
                            name: "g".into(),
                            position: tool.translation.vector + shift.normalize() * 0.999 * REACHED_POSITION_M,
                            rotation,
                            tolerance,
                            task: None,
                        };
                        let error = super::super::goal_error(&goal, &tool);
                        assert!(super::super::is_reached(&error), "{name}: the goal is within the tolerance");
                        let Some(reduced) = chain.reduce(&goal) else {
                            continue;
                        };
                        let sub = chain.model.tool_pose(&q[..chain.joints]);
                        let error = super::super::goal_error(&reduced.goal, &sub);
                        assert!(
                            error.position_m < reduced.radii.position_m && error.orientation_rad < reduced.radii.orientation_rad,
                            "{name} {tolerance:?}, {}: {error:?} outside {:?}",
                            chain.what,
                            reduced.radii
                        );
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 3000, "{checked} checks");
    }
}
