//! Pose and unit helpers shared by every stage.
//!
//! Transforms are `nalgebra::Isometry3<f64>` named `a_from_b` (maps coordinates in frame `b` to
//! frame `a`). URDF and designs give orientations as roll-pitch-yaw (fixed X, then Y, then Z);
//! MJCF wants quaternions `w x y z`.

use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// A pose as written in design files: position in metres and roll-pitch-yaw in radians.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseSpec {
    /// Translation in metres.
    #[serde(default)]
    pub position: [f64; 3],
    /// Roll, pitch, yaw in radians (rotation about fixed X, then Y, then Z).
    #[serde(default)]
    pub rpy: [f64; 3],
}

impl PoseSpec {
    /// The isometry this pose describes.
    pub fn isometry(&self) -> Isometry3<f64> {
        isometry_from_xyz_rpy(self.position, self.rpy)
    }

    /// True when every number is finite.
    pub fn is_finite(&self) -> bool {
        self.position.iter().chain(self.rpy.iter()).all(|v| v.is_finite())
    }
}

/// The isometry `Trans(xyz) * Rz(yaw) * Ry(pitch) * Rx(roll)`, the URDF `<origin>` convention.
pub fn isometry_from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}

/// Roll, pitch, yaw of a rotation, the inverse of [`isometry_from_xyz_rpy`] up to angle wrapping.
///
/// Pitch and yaw come from the first column; roll from what remains after undoing them. Unlike
/// `UnitQuaternion::euler_angles`, this stays exact (<= 1e-15 rad) near pitch = +-pi/2.
pub fn rpy_of(rotation: &UnitQuaternion<f64>) -> [f64; 3] {
    let world_from_frame = rotation.to_rotation_matrix();
    let m = world_from_frame.matrix();
    let pitch = (-m[(2, 0)]).atan2(m[(0, 0)].hypot(m[(1, 0)]));
    let yaw = m[(1, 0)].atan2(m[(0, 0)]);
    let roll_only =
        Rotation3::from_axis_angle(&Vector3::y_axis(), -pitch) * Rotation3::from_axis_angle(&Vector3::z_axis(), -yaw) * world_from_frame;
    let r = roll_only.matrix();
    // `atan2(-0.0, x)` is `-0.0`; write it as plain `0`.
    [r[(2, 1)].atan2(r[(2, 2)]), pitch, yaw].map(|angle| if angle == 0.0 { 0.0 } else { angle })
}

/// A quaternion as `[w, x, y, z]`, the MJCF order.
pub fn wxyz(rotation: &UnitQuaternion<f64>) -> [f64; 4] {
    let q = rotation.quaternion();
    [q.w, q.i, q.j, q.k]
}

/// Components of a vector as an array.
pub fn xyz(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// The largest translation and rotation-angle difference between two poses (metres, radians).
pub fn pose_difference(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let translation = (a.translation.vector - b.translation.vector).norm();
    let angle = a.rotation.angle_to(&b.rotation);
    (translation, angle)
}

/// A nalgebra isometry as a parry pose (glam `f64` types). Conversions between nalgebra and
/// parry's glam types live here and nowhere else.
pub fn parry_pose(isometry: &Isometry3<f64>) -> parry3d_f64::math::Pose {
    let q = isometry.rotation.quaternion();
    parry3d_f64::math::Pose::from_parts(
        parry_vector(&isometry.translation.vector),
        parry3d_f64::math::Rotation::from_xyzw(q.i, q.j, q.k, q.w),
    )
}

/// A parry pose as a nalgebra isometry; the inverse of [`parry_pose`].
pub fn isometry_from_parry(pose: &parry3d_f64::math::Pose) -> Isometry3<f64> {
    let q = pose.rotation;
    Isometry3::from_parts(
        Translation3::from(vector_from_parry(pose.translation)),
        UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(q.w, q.x, q.y, q.z)),
    )
}

/// A nalgebra vector (or point coordinates) as a parry vector.
pub fn parry_vector(v: &Vector3<f64>) -> parry3d_f64::math::Vector {
    parry3d_f64::math::Vector::new(v.x, v.y, v.z)
}

/// A parry vector as a nalgebra vector; the inverse of [`parry_vector`].
pub fn vector_from_parry(v: parry3d_f64::math::Vector) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

/// A segment whose squared length is at most this (m^2) is a point.
pub(crate) const POINT_SEGMENT_M2: f64 = 1e-24;

/// The closest points of segments `[p1, q1]` and `[p2, q2]`, one on each (Ericson, Real-Time
/// Collision Detection, 5.1.9, with point segments and parallel segments handled).
pub fn closest_points_of_segments(p1: Vector3<f64>, q1: Vector3<f64>, p2: Vector3<f64>, q2: Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let (s, t) = closest_parameters_of_segments(p1, q1, p2, q2);
    (p1 + (q1 - p1) * s, p2 + (q2 - p2) * t)
}

/// The parameters `(s, t)` in `[0, 1]` of [`closest_points_of_segments`]' points along
/// `p1 -> q1` and `p2 -> q2`.
pub fn closest_parameters_of_segments(p1: Vector3<f64>, q1: Vector3<f64>, p2: Vector3<f64>, q2: Vector3<f64>) -> (f64, f64) {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.norm_squared(), d2.norm_squared(), d2.dot(&r));
    if a <= POINT_SEGMENT_M2 && e <= POINT_SEGMENT_M2 {
        (0.0, 0.0)
    } else if a <= POINT_SEGMENT_M2 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= POINT_SEGMENT_M2 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denominator = a * e - b * b;
            // Parallel segments: any s works; start from 0 and let the clamping below fix t, s.
            let s = if denominator > 0.0 {
                ((b * f - c * e) / denominator).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t = (b * s + f) / e;
            if t < 0.0 {
                ((-c / a).clamp(0.0, 1.0), 0.0)
            } else if t > 1.0 {
                (((b - c) / a).clamp(0.0, 1.0), 1.0)
            } else {
                (s, t)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_round_trips_through_isometry() {
        let rpy = [0.3, -1.1, 2.5];
        let pose = isometry_from_xyz_rpy([1.0, 2.0, 3.0], rpy);
        let back = isometry_from_xyz_rpy([1.0, 2.0, 3.0], rpy_of(&pose.rotation));
        let (dt, da) = pose_difference(&pose, &back);
        assert!(dt < 1e-15 && da < 1e-12, "{dt} {da}");
    }

    #[test]
    fn rpy_is_exact_near_gimbal_lock() {
        for pitch in [
            -std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_2 - 1e-8,
            -std::f64::consts::FRAC_PI_2 + 3e-8,
        ] {
            let pose = isometry_from_xyz_rpy([0.0; 3], [0.3, pitch, 0.4]);
            let back = isometry_from_xyz_rpy([0.0; 3], rpy_of(&pose.rotation));
            assert!(pose.rotation.angle_to(&back.rotation) < 1e-14, "pitch {pitch}");
        }
    }

    #[test]
    fn rpy_matches_urdf_fixed_axis_order() {
        // URDF: R = Rz(yaw) * Ry(pitch) * Rx(roll)
        let (r, p, y) = (0.2, 0.4, -0.7);
        let expected = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), y)
            * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), p)
            * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), r);
        let got = isometry_from_xyz_rpy([0.0; 3], [r, p, y]).rotation;
        assert!(got.angle_to(&expected) < 1e-14);
    }

    #[test]
    fn parry_pose_round_trips_and_transforms_like_nalgebra() {
        let pose = isometry_from_xyz_rpy([0.3, -0.2, 1.1], [0.7, -1.2, 2.9]);
        let back = isometry_from_parry(&parry_pose(&pose));
        let (dt, da) = pose_difference(&pose, &back);
        assert!(dt == 0.0 && da < 1e-15, "{dt} {da}");
        let point = Vector3::new(0.4, 0.5, -0.6);
        let ours = pose * nalgebra::Point3::from(point);
        let theirs = vector_from_parry(parry_pose(&pose) * parry_vector(&point));
        assert!((ours.coords - theirs).norm() < 1e-15, "{ours} {theirs}");
    }
}
