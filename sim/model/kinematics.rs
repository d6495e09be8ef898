//! Forward kinematics and the geometric Jacobian, in f64, without heap allocation per call.

use super::chain::FastChain;
use super::{JointKind, Model};
use nalgebra::{Isometry3, Matrix6xX, Rotation3, Translation3, UnitQuaternion, Vector3};

/// Buffers for [`Model::forward`] and [`Model::jacobian`]; make one per model and thread with
/// [`Model::workspace`] and reuse it.
#[derive(Debug, Clone)]
pub struct KinematicsWorkspace {
    /// World pose of every link frame, `links[i]` order.
    pub link_in_world: Vec<Isometry3<f64>>,
    /// World pose of the tool frame.
    pub tool_in_world: Isometry3<f64>,
    /// Geometric Jacobian of the tool frame origin, world frame: rows 0..3 linear velocity,
    /// rows 3..6 angular velocity, one column per joint.
    pub jacobian: Matrix6xX<f64>,
    /// Per-joint constants of the matrix form, and its scratch space.
    fast: FastChain,
}

impl Model {
    /// Buffers sized for this model.
    pub fn workspace(&self) -> KinematicsWorkspace {
        KinematicsWorkspace {
            link_in_world: vec![Isometry3::identity(); self.links.len()],
            tool_in_world: Isometry3::identity(),
            jacobian: Matrix6xX::zeros(self.dof()),
            fast: FastChain::new(self),
        }
    }

    /// Fills `ws.tool_in_world` and `ws.jacobian` (not `ws.link_in_world`) for `q`: the inner
    /// loop of IK, in rotation-matrix form (about twice as fast as [`Model::jacobian`]).
    ///
    /// # Panics
    /// When `q.len()` differs from [`Model::dof`] or `ws` was made for another model.
    pub fn tool_jacobian(&self, q: &[f64], ws: &mut KinematicsWorkspace) {
        assert_eq!(q.len(), self.dof(), "configuration length must equal the model's dof");
        let (tool_position, tool_rotation) = ws.fast.evaluate(q, &mut ws.jacobian);
        ws.tool_in_world = Isometry3::from_parts(
            Translation3::from(tool_position),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(tool_rotation)),
        );
    }

    /// Pose of the child link relative to the joint's parent link at joint position `q`.
    #[inline]
    pub fn joint_transform(&self, joint: usize, q: f64) -> Isometry3<f64> {
        let j = &self.joints[joint];
        match j.kind {
            JointKind::Revolute | JointKind::Continuous => {
                let (sin, cos) = super::trig::sin_cos(q / 2.0);
                let v = j.axis.into_inner() * sin;
                j.parent_from_joint * UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(cos, v.x, v.y, v.z))
            }
            JointKind::Prismatic => j.parent_from_joint * Translation3::from(j.axis.into_inner() * q),
        }
    }

    /// Fills `ws.link_in_world` and `ws.tool_in_world` for configuration `q` (rad or m).
    ///
    /// # Panics
    /// When `q.len()` differs from [`Model::dof`] or `ws` was made for another model.
    pub fn forward(&self, q: &[f64], ws: &mut KinematicsWorkspace) {
        self.forward_from(q, ws, 0);
    }

    /// [`Model::forward`] for a `q` that differs from the one `ws` holds only in joints `from`
    /// and after: the links before them are kept, the others recomputed with the same
    /// arithmetic, so the result is bit for bit [`Model::forward`]'s. A search that changes one
    /// angle of a box at a time pays only for the joints after it.
    ///
    /// # Panics
    /// As [`Model::forward`], and when `from` exceeds the dof.
    pub fn forward_from(&self, q: &[f64], ws: &mut KinematicsWorkspace, from: usize) {
        assert_eq!(q.len(), self.dof(), "configuration length must equal the model's dof");
        assert!(from <= self.dof(), "the first changed joint must be a joint of the model");
        if from == 0 {
            ws.link_in_world[0] = self.world_from_base;
        }
        for (i, &qi) in q.iter().enumerate().skip(from) {
            ws.link_in_world[i + 1] = ws.link_in_world[i] * self.joint_transform(i, qi);
        }
        ws.tool_in_world = ws.link_in_world[self.dof()] * self.last_from_tool;
    }

    /// World pose of the tool frame at `q`; allocation-free convenience over [`Model::forward`].
    ///
    /// # Panics
    /// When `q.len()` differs from [`Model::dof`].
    pub fn tool_pose(&self, q: &[f64]) -> Isometry3<f64> {
        assert_eq!(q.len(), self.dof(), "configuration length must equal the model's dof");
        let mut pose = self.world_from_base;
        for (i, &qi) in q.iter().enumerate() {
            pose *= self.joint_transform(i, qi);
        }
        pose * self.last_from_tool
    }

    /// Runs [`Model::forward`] and fills `ws.jacobian` with the tool frame's geometric Jacobian.
    ///
    /// # Panics
    /// As [`Model::forward`].
    pub fn jacobian(&self, q: &[f64], ws: &mut KinematicsWorkspace) {
        self.forward(q, ws);
        let tool = ws.tool_in_world.translation.vector;
        for (i, joint) in self.joints.iter().enumerate() {
            // The joint frame coincides with the child link frame (motion happens after the
            // fixed offset), so the axis and its origin are read from link i + 1.
            let frame = &ws.link_in_world[i + 1];
            let axis: Vector3<f64> = frame.rotation * joint.axis.into_inner();
            let mut column = ws.jacobian.column_mut(i);
            match joint.kind {
                JointKind::Revolute | JointKind::Continuous => {
                    let linear = axis.cross(&(tool - frame.translation.vector));
                    column.fixed_rows_mut::<3>(0).copy_from(&linear);
                    column.fixed_rows_mut::<3>(3).copy_from(&axis);
                }
                JointKind::Prismatic => {
                    column.fixed_rows_mut::<3>(0).copy_from(&axis);
                    column.fixed_rows_mut::<3>(3).fill(0.0);
                }
            }
        }
    }
}

impl Model {
    /// A configuration drawn uniformly within the joint limits (continuous joints in [-pi, pi]).
    pub fn random_configuration<R: rand::Rng>(&self, rng: &mut R) -> Vec<f64> {
        self.joints
            .iter()
            .map(|joint| {
                let [lower, upper] = joint.limits.unwrap_or([-std::f64::consts::PI, std::f64::consts::PI]);
                if upper > lower {
                    rng.random_range(lower..=upper)
                } else {
                    lower
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use crate::model::chain::tests::{configurations, kernel_models};

    /// Every kernel of the matrix form (identity, alpha-only, permutation and general fixed
    /// rotations; revolute about z and about other axes; prismatic; 4, 7 dof) against the
    /// isometry form.
    #[test]
    fn matrix_form_equals_isometry_form() {
        for model in kernel_models() {
            let (mut slow, mut fast) = (model.workspace(), model.workspace());
            for q in configurations(&model) {
                model.jacobian(&q, &mut slow);
                model.tool_jacobian(&q, &mut fast);
                let (dt, da) = crate::frames::pose_difference(&slow.tool_in_world, &fast.tool_in_world);
                assert!(dt < 1e-14 && da < 1e-14, "{} {dt} {da}", model.name);
                assert!((slow.jacobian.clone() - &fast.jacobian).abs().max() < 1e-14, "{}", model.name);
            }
        }
    }

    /// Changing one joint after another and recomputing from it gives every link and the tool
    /// bit for bit as the whole forward kinematics does.
    #[test]
    fn forward_from_the_first_changed_joint_is_forward_bit_for_bit() {
        for model in kernel_models() {
            let (mut whole, mut partial) = (model.workspace(), model.workspace());
            let mut q = vec![0.0; model.dof()];
            model.forward(&q, &mut partial);
            for (k, next) in configurations(&model).into_iter().enumerate() {
                let joint = k % model.dof();
                q[joint] = next[joint];
                model.forward_from(&q, &mut partial, joint);
                model.forward(&q, &mut whole);
                assert_eq!(whole.link_in_world, partial.link_in_world, "{} joint {joint}", model.name);
                assert_eq!(whole.tool_in_world, partial.tool_in_world, "{} joint {joint}", model.name);
            }
        }
    }
}
