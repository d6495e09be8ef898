//! The shapes the queries measure: a parry shape per collider with its hull, sphere tree,
//! bounding capsule and probe point ([`Geometry`]), built from the model's exact shapes.

use super::mesh_tree::SphereTree;
use super::CollideError;
use crate::frames::{parry_pose, vector_from_parry};
use crate::model::{Shape, TriMesh};
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::shape::{Ball, Capsule, ConvexPolyhedron, Cuboid, Cylinder, SharedShape, TriMeshFlags};
use std::collections::HashMap;

/// Most vertices of a mesh hull used as a lower bound before the mesh itself (see
/// `exact::hull_bound`); robot link hulls have a few hundred.
pub(super) const HULL_BOUND_VERTICES: usize = 2048;

/// A parry shape and what the queries need to know about it.
pub(super) struct Geometry {
    pub(super) shape: SharedShape,
    /// Convex hull, for meshes only.
    pub(super) hull: Option<SharedShape>,
    /// Sphere tree over the triangles, for meshes only.
    pub(super) tree: Option<SphereTree>,
    /// The hull (or the convex shape itself) is cheap enough to bound the mesh's distances:
    /// at most [`HULL_BOUND_VERTICES`] vertices.
    pub(super) hull_bounds: bool,
    /// A mesh whose every edge is shared by exactly two triangles, oriented outwards.
    pub(super) closed: bool,
    /// A point of the body in the shape frame (the middle of its axis, or a mesh vertex), for
    /// enclosure tests.
    pub(super) probe: Vector,
    /// A capsule containing the shape, in the shape frame: a cheap lower bound on distances.
    pub(super) bounding: BoundingCapsule,
}

/// A capsule (segment ends and radius, m) that contains a shape.
#[derive(Debug, Clone, Copy)]
pub(super) struct BoundingCapsule {
    pub(super) start: Vector,
    pub(super) end: Vector,
    pub(super) radius: f64,
}

impl BoundingCapsule {
    /// The smallest capsule along a shape's own axis: the shape itself for balls and capsules,
    /// the axis and radius of a cylinder, a box's longest axis with the radius of its cross
    /// section's corner.
    pub(super) fn of(shape: &SharedShape) -> Self {
        Self::of_shape(&**shape)
    }

    /// As [`BoundingCapsule::of`], for any parry shape.
    pub(super) fn of_shape(shape: &dyn parry3d_f64::shape::Shape) -> Self {
        let along = |axis: Vector, half: f64, radius: f64| Self {
            start: -axis * half,
            end: axis * half,
            radius,
        };
        if let Some(ball) = shape.as_ball() {
            along(Vector::Z, 0.0, ball.radius)
        } else if let Some(capsule) = shape.as_capsule() {
            Self {
                start: capsule.segment.a,
                end: capsule.segment.b,
                radius: capsule.radius,
            }
        } else if let Some(cylinder) = shape.as_cylinder() {
            along(Vector::Y, cylinder.half_height, cylinder.radius)
        } else if let Some(cuboid) = shape.as_cuboid() {
            let h = cuboid.half_extents;
            if h.x >= h.y && h.x >= h.z {
                along(Vector::X, h.x, h.y.hypot(h.z))
            } else if h.y >= h.z {
                along(Vector::Y, h.y, h.x.hypot(h.z))
            } else {
                along(Vector::Z, h.z, h.x.hypot(h.y))
            }
        } else {
            let sphere = shape.compute_local_bounding_sphere();
            Self {
                start: sphere.center,
                end: sphere.center,
                radius: sphere.radius,
            }
        }
    }
}

impl Geometry {
    pub(super) fn is_mesh(&self) -> bool {
        self.hull.is_some()
    }

    /// The convex hull of a mesh, or the convex shape itself.
    pub(super) fn hull_or_shape(&self) -> &dyn parry3d_f64::shape::Shape {
        &**self.hull.as_ref().unwrap_or(&self.shape)
    }

    pub(super) fn convex(shape: SharedShape) -> Self {
        let bounding = BoundingCapsule::of(&shape);
        Self {
            // The middle of a convex shape's own axis is inside it.
            probe: (bounding.start + bounding.end) / 2.0,
            bounding,
            shape,
            hull: None,
            tree: None,
            hull_bounds: true,
            closed: false,
        }
    }

    /// A ball or capsule as a segment and radius in the frame `world_from_shape`.
    pub(super) fn rounded(&self, world_from_shape: &Pose) -> Option<RoundedSegment> {
        let (start, end, radius) = if let Some(ball) = self.shape.as_ball() {
            (Vector::ZERO, Vector::ZERO, ball.radius)
        } else {
            let capsule = self.shape.as_capsule()?;
            (capsule.segment.a, capsule.segment.b, capsule.radius)
        };
        Some(RoundedSegment {
            start: vector_from_parry(world_from_shape * start),
            end: vector_from_parry(world_from_shape * end),
            radius,
        })
    }
}

/// A sphere (zero-length segment) or capsule in the world frame.
#[derive(Debug, Clone, Copy)]
pub(super) struct RoundedSegment {
    pub(super) start: Vector3<f64>,
    pub(super) end: Vector3<f64>,
    pub(super) radius: f64,
}

/// The parry shape of a model shape, and its pose: `parent_from_shape` for every shape but the
/// cylinder, which parry lays along y and ours along z.
pub(super) fn geometry(owner: &str, parent_from_shape: &Isometry3<f64>, shape: &Shape) -> Result<(Pose, Geometry), CollideError> {
    let invalid = |message: String| CollideError::InvalidShape {
        owner: owner.into(),
        message,
    };
    let positive = |name: &str, value: f64| {
        if value > 0.0 && value.is_finite() {
            Ok(value)
        } else {
            Err(invalid(format!("{} {name} {value} m must be positive and finite", shape.kind())))
        }
    };
    let translation = parent_from_shape.translation.vector;
    if !translation
        .iter()
        .chain(parent_from_shape.rotation.coords.iter())
        .all(|v| v.is_finite())
    {
        return Err(invalid(format!("pose {parent_from_shape} must be finite")));
    }
    let mut pose = parry_pose(parent_from_shape);
    let geometry = match shape {
        Shape::Sphere { radius } => Geometry::convex(SharedShape::new(Ball::new(positive("radius", *radius)?))),
        Shape::Cylinder { radius, length } => {
            // Turning by +90 degrees about x takes parry's y axis onto our z axis.
            let y_to_z = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2);
            pose = parry_pose(&(parent_from_shape * y_to_z));
            let cylinder = Cylinder::new(positive("length", *length)? / 2.0, positive("radius", *radius)?);
            Geometry::convex(SharedShape::new(cylinder))
        }
        Shape::Capsule { radius, length } => {
            if !(*length >= 0.0 && length.is_finite()) {
                return Err(invalid(format!("capsule length {length} m must be zero or positive and finite")));
            }
            Geometry::convex(SharedShape::new(Capsule::new_z(length / 2.0, positive("radius", *radius)?)))
        }
        Shape::Box { half_extents } => {
            let [x, y, z] = *half_extents;
            let half = Vector::new(
                positive("half extent x", x)?,
                positive("half extent y", y)?,
                positive("half extent z", z)?,
            );
            Geometry::convex(SharedShape::new(Cuboid::new(half)))
        }
        Shape::Mesh(mesh) => mesh_geometry(owner, mesh)?,
    };
    Ok((pose, geometry))
}

/// A mesh as a parry `TriMesh` (checked as it is) with its convex hull.
///
/// Vertices at identical positions are welded and triangles with a repeated vertex (no area)
/// dropped, which does not change the surface. A closed mesh (every directed edge once, its
/// reverse once) is oriented outwards (flipped when its signed volume is negative) and gets
/// parry's pseudo-normals, so containment can be tested.
pub(super) fn mesh_geometry(owner: &str, mesh: &TriMesh) -> Result<Geometry, CollideError> {
    let bad = |message: String| CollideError::Mesh {
        owner: owner.into(),
        uri: mesh.uri.clone(),
        message,
    };
    if let Some(v) = mesh.vertices.iter().find(|v| !v.iter().all(|c| c.is_finite())) {
        return Err(bad(format!("vertex {v:?} is not finite")));
    }
    let count = mesh.vertices.len();
    if let Some(t) = mesh.triangles.iter().find(|t| t.iter().any(|&i| i as usize >= count)) {
        return Err(bad(format!("triangle {t:?} refers to a vertex beyond the {count} it has")));
    }
    let mut welded_index: HashMap<[u64; 3], u32> = HashMap::with_capacity(count);
    let mut vertices: Vec<Vector> = Vec::with_capacity(count);
    let remap: Vec<u32> = mesh
        .vertices
        .iter()
        .map(|v| {
            // +0.0 and -0.0 are the same point.
            let key = v.map(|c| (c + 0.0).to_bits());
            *welded_index.entry(key).or_insert_with(|| {
                vertices.push(Vector::new(v[0], v[1], v[2]));
                (vertices.len() - 1) as u32
            })
        })
        .collect();
    let mut triangles: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| remap[i as usize]))
        .filter(|[a, b, c]| a != b && b != c && a != c)
        .collect();
    if triangles.is_empty() {
        return Err(bad("it has no triangle with three distinct vertices".into()));
    }

    let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(triangles.len() * 3);
    for &[a, b, c] in &triangles {
        for edge in [(a, b), (b, c), (c, a)] {
            *edges.entry(edge).or_insert(0) += 1;
        }
    }
    let volume: f64 = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    let closed = volume != 0.0 && edges.iter().all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1));
    if closed && volume < 0.0 {
        for t in &mut triangles {
            t.swap(1, 2);
        }
    }
    let hull = ConvexPolyhedron::from_convex_hull(&vertices)
        .ok_or_else(|| bad("parry cannot build its convex hull (fewer than three distinct vertices, or all on one line)".into()))?;
    let probe = vertices[0];
    let tree = SphereTree::new(&vertices, &triangles);
    let flags = if closed { TriMeshFlags::ORIENTED } else { TriMeshFlags::empty() };
    let trimesh = parry3d_f64::shape::TriMesh::with_flags(vertices, triangles, flags).map_err(|e| bad(format!("parry: {e}")))?;
    let shape = SharedShape::new(trimesh);
    Ok(Geometry {
        bounding: BoundingCapsule::of(&shape),
        shape,
        hull_bounds: hull.points().len() <= HULL_BOUND_VERTICES,
        hull: Some(SharedShape::new(hull)),
        tree: Some(tree),
        closed,
        probe,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn mesh(vertices: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> TriMesh {
        TriMesh {
            uri: "m.stl".into(),
            file: PathBuf::from("m.stl"),
            scale: [1.0; 3],
            vertices,
            triangles,
        }
    }

    /// A unit tetrahedron, as STL stores it: three vertices per triangle.
    fn tetrahedron(inward: bool) -> TriMesh {
        let corners = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let mut faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        if inward {
            faces.iter_mut().for_each(|f| f.swap(1, 2));
        }
        let vertices = faces.iter().flat_map(|f| f.map(|i| corners[i])).collect();
        mesh(vertices, (0..4).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect())
    }

    #[test]
    fn closed_mesh_is_welded_oriented_and_contains_its_inside() {
        for inward in [false, true] {
            let geometry = mesh_geometry("t", &tetrahedron(inward)).expect("valid mesh");
            assert!(geometry.closed, "inward {inward}");
            let inside = Vector::new(0.1, 0.1, 0.1);
            assert!(geometry.shape.contains_point(&Pose::IDENTITY, inside), "inward {inward}");
            assert!(!geometry.shape.contains_point(&Pose::IDENTITY, Vector::new(1.0, 1.0, 1.0)));
        }
    }

    #[test]
    fn open_mesh_is_not_closed_and_flat_mesh_is_an_error() {
        let mut open = tetrahedron(false);
        open.triangles.pop();
        assert!(!mesh_geometry("t", &open).expect("valid mesh").closed);
        let flat = mesh(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]]);
        let flat = mesh_geometry("link `a` collider 0", &flat).expect("a flat mesh has a flat hull");
        assert!(!flat.closed && flat.hull.is_some());
        let broken = mesh(vec![[0.0; 3]], vec![[0, 1, 2]]);
        let error = mesh_geometry("t", &broken).err().expect("bad index");
        assert!(error.to_string().contains("beyond the 1"), "{error}");
    }

    #[test]
    fn cylinder_axis_is_z() {
        let shape = Shape::Cylinder { radius: 0.1, length: 1.0 };
        let (pose, geometry) = geometry("t", &Isometry3::identity(), &shape).expect("valid");
        let aabb = geometry.shape.compute_aabb(&pose);
        assert!((aabb.maxs.z - 0.5).abs() < 1e-15 && (aabb.maxs.y - 0.1).abs() < 1e-15, "{aabb:?}");
    }

    #[test]
    fn non_positive_dimensions_are_errors() {
        let error = geometry("obstacle `b`", &Isometry3::identity(), &Shape::Sphere { radius: -1.0 })
            .err()
            .expect("negative radius");
        assert_eq!(error.to_string(), "obstacle `b`: sphere radius -1 m must be positive and finite");
    }
}
