//! How far any point of a link can move when the joints move: the bound behind conservative
//! advancement (certified segments) and behind IK's certificates that a goal's tolerance cannot
//! reach a free configuration.

use super::Body;
use crate::model::{JointKind, Model, Shape};

/// The per-joint radius bounds of a model: `radius[j][k]` bounds the distance from joint `j`'s
/// axis to any point of link `k` (0 for links joint `j` does not move).
#[derive(Debug, Clone)]
pub struct MotionBounds {
    radius: Vec<Vec<f64>>,
    prismatic: Vec<bool>,
}

impl MotionBounds {
    /// Bounds of `model` (configuration independent).
    pub fn of(model: &Model) -> Self {
        let links = model.links.len();
        let extent: Vec<f64> = model
            .links
            .iter()
            .map(|link| {
                link.colliders
                    .iter()
                    .map(|c| c.link_from_shape.translation.vector.norm() + shape_radius(&c.shape))
                    .fold(0.0, f64::max)
            })
            .collect();
        // Link i + 1's origin is at most `reach[i]` from link i's origin: the joint offset, plus
        // the travel of a prismatic joint.
        let reach: Vec<f64> = model
            .joints
            .iter()
            .map(|joint| {
                let travel = match joint.kind {
                    JointKind::Prismatic => joint.limits.map_or(f64::INFINITY, |[lo, hi]| lo.abs().max(hi.abs())),
                    _ => 0.0,
                };
                joint.parent_from_joint.translation.vector.norm() + travel
            })
            .collect();
        let mut radius = vec![vec![0.0; links]; model.dof()];
        for (j, row) in radius.iter_mut().enumerate() {
            // Joint j's axis passes through link j + 1's origin.
            let mut offset = 0.0;
            for k in j + 1..links {
                if k > j + 1 {
                    offset += reach[k - 1];
                }
                row[k] = offset + extent[k];
            }
        }
        Self {
            radius,
            prismatic: model.joints.iter().map(|j| j.kind == JointKind::Prismatic).collect(),
        }
    }

    /// Largest displacement per unit path parameter of any point of body `b` relative to body
    /// `a` (a link; `b` a later link, an obstacle or the floor), for joint deltas `delta`.
    pub fn relative_motion(&self, a: Body, b: Body, delta: &[f64]) -> f64 {
        let moving = |joints: std::ops::Range<usize>, link: usize| -> f64 {
            joints
                // A joint that does not move adds nothing, whatever its (possibly unbounded) radius.
                .filter(|&j| delta[j] != 0.0)
                .map(|j| {
                    let rate = if self.prismatic[j] { 1.0 } else { self.radius[j][link] };
                    delta[j].abs() * rate
                })
                .sum()
        };
        match (a, b) {
            (Body::Link(a), Body::Link(b)) => {
                let (low, high) = (a.min(b), a.max(b));
                moving(low..high.min(delta.len()), high)
            }
            (Body::Link(link), _) | (_, Body::Link(link)) => moving(0..link.min(delta.len()), link),
            _ => 0.0,
        }
    }
}

/// Radius of the smallest ball about the shape's origin containing it (m).
fn shape_radius(shape: &Shape) -> f64 {
    match shape {
        Shape::Sphere { radius } => *radius,
        Shape::Cylinder { radius, length } => radius.hypot(length / 2.0),
        Shape::Capsule { radius, length } => radius + length / 2.0,
        Shape::Box { half_extents } => half_extents.iter().map(|h| h * h).sum::<f64>().sqrt(),
        Shape::Mesh(mesh) => mesh
            .vertices
            .iter()
            .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
            .fold(0.0, f64::max),
    }
}
