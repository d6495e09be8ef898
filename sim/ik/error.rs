//! Task-space errors per tolerance mode, in the form the solver and the verdict use.

use crate::scenario::{Goal, Tolerance};
use nalgebra::{Isometry3, Vector3, Vector6};

/// How far a tool pose is from a goal under the goal's tolerance mode.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct GoalError {
    /// `||p_goal - p||` (m).
    pub position_m: f64,
    /// `pose`: the rotation angle `arccos((tr(R_g^T R) - 1) / 2)`; `z_symmetric`: the angle
    /// between goal z and tool z; `position`: 0 (rad).
    pub orientation_rad: f64,
}

/// Position and orientation errors of `tool` against `goal`.
pub fn goal_error(goal: &Goal, tool: &Isometry3<f64>) -> GoalError {
    let position_m = (goal.position - tool.translation.vector).norm();
    let orientation_rad = match goal.tolerance {
        Tolerance::Pose => goal.rotation.angle_to(&tool.rotation),
        Tolerance::ZSymmetric => angle_between(&(goal.rotation * Vector3::z()), &(tool.rotation * Vector3::z())),
        Tolerance::Position => 0.0,
    };
    GoalError {
        position_m,
        orientation_rad,
    }
}

/// Angle between two unit vectors, accurate near 0 and pi (atan2 of cross and dot).
pub fn angle_between(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm().atan2(a.dot(b))
}

/// The world-frame task error the solver drives to zero: linear part `p_goal - p`, angular part
/// the rotation vector taking the tool to the goal (`pose`), the rotation taking tool z onto goal
/// z (`z_symmetric`, no component about tool z), or zero (`position`).
pub fn task_error(goal: &Goal, tool: &Isometry3<f64>) -> Vector6<f64> {
    let linear = goal.position - tool.translation.vector;
    let angular = match goal.tolerance {
        Tolerance::Pose => (goal.rotation * tool.rotation.inverse()).scaled_axis(),
        Tolerance::ZSymmetric => {
            let (tool_z, goal_z) = (tool.rotation * Vector3::z(), goal.rotation * Vector3::z());
            let axis = tool_z.cross(&goal_z);
            let sin = axis.norm();
            if sin < 1e-12 {
                // Parallel (done) or antiparallel: any axis perpendicular to z turns it over.
                if tool_z.dot(&goal_z) > 0.0 {
                    Vector3::zeros()
                } else {
                    (tool.rotation * Vector3::x()) * std::f64::consts::PI
                }
            } else {
                axis * (sin.atan2(tool_z.dot(&goal_z)) / sin)
            }
        }
        Tolerance::Position => Vector3::zeros(),
    };
    Vector6::new(linear.x, linear.y, linear.z, angular.x, angular.y, angular.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    fn goal(tolerance: Tolerance) -> Goal {
        Goal {
            name: "g".into(),
            position: Vector3::new(0.5, 0.0, 0.3),
            rotation: UnitQuaternion::from_euler_angles(0.3, 0.2, 0.1),
            tolerance,
            task: None,
        }
    }

    #[test]
    fn rotation_about_tool_z_is_free_only_for_z_symmetric() {
        let g = goal(Tolerance::ZSymmetric);
        let tool = Isometry3::from_parts(
            Translation3::from(g.position),
            g.rotation * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 1.0),
        );
        assert!(goal_error(&g, &tool).orientation_rad < 1e-12);
        assert!(task_error(&g, &tool).norm() < 1e-12);
        let pose = Goal {
            tolerance: Tolerance::Pose,
            ..g
        };
        assert!((goal_error(&pose, &tool).orientation_rad - 1.0).abs() < 1e-12);
    }

    #[test]
    fn pose_task_error_is_the_rotation_vector_to_the_goal() {
        let g = goal(Tolerance::Pose);
        let offset = UnitQuaternion::from_scaled_axis(Vector3::new(0.01, -0.02, 0.03));
        let tool = Isometry3::from_parts(Translation3::from(g.position), offset.inverse() * g.rotation);
        let e = task_error(&g, &tool);
        assert!((e.fixed_rows::<3>(3) - Vector3::new(0.01, -0.02, 0.03)).norm() < 1e-12, "{e}");
    }

    #[test]
    fn position_mode_ignores_orientation() {
        let g = goal(Tolerance::Position);
        let tool = Isometry3::from_parts(Translation3::from(g.position), UnitQuaternion::identity());
        assert_eq!(goal_error(&g, &tool).orientation_rad, 0.0);
    }
}
