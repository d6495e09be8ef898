//! How far any point of a link can move when the joints move: the bound behind conservative
//! advancement (certified segments) and behind IK's certificates that a goal's tolerance cannot
//! reach a free configuration.

use super::Body;
use crate::model::{Collider, JointKind, Model, Shape};
use nalgebra::{Point3, Vector3};

/// The per-joint radius bounds of a model: `radius[j][k]` bounds the distance from joint `j`'s
/// axis line to any point of link `k` (0 for links joint `j` does not move), in every
/// configuration: for the link the joint turns, its collider points' largest distance from the
/// axis; for a later link, the next joint's origin's distance from the axis plus the offsets (and
/// prismatic travel) beyond it and the link's furthest collider point from its own origin.
#[derive(Debug, Clone)]
pub struct MotionBounds {
    radius: Vec<Vec<f64>>,
    prismatic: Vec<bool>,
    /// The last link's collider points' largest distance from the tool frame's origin: the link
    /// moves rigidly with the tool.
    tool_radius: f64,
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
        // A prismatic joint's travel (the largest of its limits' magnitudes).
        let travel: Vec<f64> = model
            .joints
            .iter()
            .map(|joint| match joint.kind {
                JointKind::Prismatic => joint.limits.map_or(f64::INFINITY, |[lo, hi]| lo.abs().max(hi.abs())),
                _ => 0.0,
            })
            .collect();
        // Link i + 1's origin is at most `reach[i]` from link i's origin: the joint offset, plus
        // the travel of a prismatic joint.
        let reach: Vec<f64> = model
            .joints
            .iter()
            .zip(&travel)
            .map(|(joint, travel)| joint.parent_from_joint.translation.vector.norm() + travel)
            .collect();
        let mut radius = vec![vec![0.0; links]; model.dof()];
        for (j, row) in radius.iter_mut().enumerate() {
            let joint = &model.joints[j];
            if joint.kind == JointKind::Prismatic {
                continue; // its points move at rate 1, whatever their place
            }
            // Joint j's axis passes through link j + 1's origin, along `axis` in that link's
            // frame, and keeps its place there: what counts is each point's distance from that
            // line, not from the origin. Link j + 1's own colliders are measured; a later link's
            // points lie within the chain's reach of link j + 2's origin.
            let axis = joint.axis.into_inner();
            let from_axis = |p: Vector3<f64>| (p - axis * p.dot(&axis)).norm();
            row[j + 1] = model.links[j + 1]
                .colliders
                .iter()
                .map(|c| collider_axis_distance(c, &from_axis))
                .fold(0.0, f64::max);
            let Some(next) = model.joints.get(j + 1) else { continue };
            let mut offset = from_axis(next.parent_from_joint.translation.vector) + travel[j + 1];
            for k in j + 2..links {
                if k > j + 2 {
                    offset += reach[k - 1];
                }
                row[k] = offset + extent[k];
            }
        }
        let tool = model.last_from_tool.translation.vector;
        let tool_radius = model.links.last().map_or(0.0, |link| {
            link.colliders
                .iter()
                .map(|c| collider_axis_distance(c, &|p: Vector3<f64>| (p - tool).norm()))
                .fold(0.0, f64::max)
        });
        Self {
            radius,
            prismatic: model.joints.iter().map(|j| j.kind == JointKind::Prismatic).collect(),
            tool_radius,
        }
    }

    /// Largest displacement of any point of the last link against an obstacle or the floor
    /// (`a`, `b` in either order) when the tool frame moves by at most `position` (m) and turns
    /// by at most `angle` (rad), whatever the joints do: the last link is rigid with the tool.
    /// `None` for any other pair.
    pub fn tool_rigid_motion(&self, a: Body, b: Body, position: f64, angle: f64) -> Option<f64> {
        let last = self.radius.len();
        match (a, b) {
            (Body::Link(_), Body::Link(_)) => None,
            (Body::Link(link), _) | (_, Body::Link(link)) if link == last && last > 0 => Some(position + self.tool_radius * angle),
            _ => None,
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

/// Largest distance `from_axis` (a convex function of the point, in the link frame) of any point
/// of the collider: at a vertex for a mesh or a box, at a cap centre plus the radius for the
/// round shapes (a cylinder lies inside the capsule of its radius and length).
fn collider_axis_distance(collider: &Collider, from_axis: &impl Fn(Vector3<f64>) -> f64) -> f64 {
    let at = |p: [f64; 3]| from_axis((collider.link_from_shape * Point3::from(p)).coords);
    let widest = |points: &mut dyn Iterator<Item = [f64; 3]>| points.map(at).fold(0.0, f64::max);
    match &collider.shape {
        Shape::Sphere { radius } => at([0.0; 3]) + radius,
        Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => {
            widest(&mut [-0.5, 0.5].into_iter().map(|end| [0.0, 0.0, end * length])) + radius
        }
        Shape::Box { half_extents: [x, y, z] } => widest(
            &mut (0..8)
                .map(|corner| [(corner & 1) as f64, (corner >> 1 & 1) as f64, (corner >> 2) as f64].map(|bit| 2.0 * bit - 1.0))
                .map(|[a, b, c]| [a * x, b * y, c * z]),
        ),
        Shape::Mesh(mesh) => widest(&mut mesh.vertices.iter().copied()),
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
