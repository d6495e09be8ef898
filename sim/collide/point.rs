//! Signed distances of single points to the world's bodies: what a proof that a goal cannot be
//! reached rests on (a tool point that has to sit inside an obstacle).

use super::{Body, CollisionWorld};
use crate::frames::parry_vector;
use nalgebra::Vector3;
use parry3d_f64::math::Pose;
use parry3d_f64::shape::SharedShape;

/// Signed distance from `point` (in the shape's parent frame) to a convex shape at `pose`:
/// negative inside. Meshes are skipped (`None`): inside and outside of a surface mesh is not
/// decided by a projection.
fn signed(shape: &SharedShape, pose: &Pose, point: &Vector3<f64>) -> Option<f64> {
    if shape.as_trimesh().is_some() {
        return None;
    }
    let p = parry_vector(point);
    let projection = shape.project_point(pose, p, false);
    let gap = (projection.point - p).length();
    Some(if projection.is_inside { -gap } else { gap })
}

impl CollisionWorld {
    /// Signed distance (m) from a world point to every obstacle with a convex shape and to the
    /// floor, negative inside; mesh obstacles are left out.
    pub fn point_depths(&self, point_in_world: &Vector3<f64>) -> Vec<(Body, f64)> {
        let mut out: Vec<(Body, f64)> = self
            .obstacles
            .iter()
            .enumerate()
            .filter_map(|(k, o)| signed(&o.geometry.shape, &o.world_from_shape, point_in_world).map(|d| (Body::Obstacle(k), d)))
            .collect();
        if let Some(height) = self.floor {
            out.push((Body::Floor, point_in_world.z - height));
        }
        out
    }

    /// Signed distance (m) from a point in link `link`'s frame to the nearest of the link's
    /// convex colliders, negative inside; `None` when the link has none.
    pub fn point_to_link(&self, link: usize, point_in_link: &Vector3<f64>) -> Option<f64> {
        self.colliders
            .iter()
            .filter(|c| c.link == link)
            .filter_map(|c| signed(&c.geometry.shape, &c.link_from_shape, point_in_link))
            .reduce(f64::min)
    }

    /// Whether the world checks link `link` against `body`.
    pub fn checks(&self, link: usize, body: Body) -> bool {
        self.pairs
            .iter()
            .any(|p| (p.a == Body::Link(link) && p.b == body) || (p.b == Body::Link(link) && p.a == body))
    }
}
