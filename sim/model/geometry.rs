//! Exact collision shapes attached to links.

use super::mesh::TriMesh;
use nalgebra::Isometry3;
use serde::Serialize;

/// One exact collision shape and where it sits on its link.
#[derive(Debug, Clone, Serialize)]
pub struct Collider {
    /// Shape frame in the link frame.
    pub link_from_shape: Isometry3<f64>,
    /// The shape, in its own frame.
    pub shape: Shape,
    /// What the shape stands for (`d tube of joint 2`, `<collision> 0 of link panda_hand`).
    pub label: String,
}

/// An exact collision shape in its own frame.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Shape {
    /// Sphere centred at the origin.
    Sphere {
        /// Radius in metres.
        radius: f64,
    },
    /// Solid cylinder centred at the origin, axis along z (the URDF and MJCF convention).
    Cylinder {
        /// Radius in metres.
        radius: f64,
        /// Full length along z in metres.
        length: f64,
    },
    /// Capsule centred at the origin: a cylinder along z capped by two hemispheres.
    Capsule {
        /// Radius in metres.
        radius: f64,
        /// Length of the cylindrical part (distance between the cap centres) in metres.
        length: f64,
    },
    /// Box centred at the origin.
    Box {
        /// Half the edge lengths along x, y, z in metres.
        half_extents: [f64; 3],
    },
    /// Triangle mesh, checked as it is (not as its convex hull).
    Mesh(TriMesh),
}

impl Shape {
    /// Short name of the shape type, as used in messages and reports.
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Sphere { .. } => "sphere",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Capsule { .. } => "capsule",
            Shape::Box { .. } => "box",
            Shape::Mesh(_) => "mesh",
        }
    }

    /// Distance from the shape origin to its furthest point (metres): bounds how far any point
    /// of the shape can be from its frame.
    pub fn bounding_radius(&self) -> f64 {
        match self {
            Shape::Sphere { radius } => *radius,
            Shape::Cylinder { radius, length } => radius.hypot(length / 2.0),
            Shape::Capsule { radius, length } => radius + length / 2.0,
            Shape::Box { half_extents } => {
                let [x, y, z] = *half_extents;
                (x * x + y * y + z * z).sqrt()
            }
            Shape::Mesh(mesh) => mesh
                .vertices
                .iter()
                .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
                .fold(0.0, f64::max),
        }
    }
}
