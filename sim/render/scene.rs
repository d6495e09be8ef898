//! Exact geometry as world triangles: the robot's colliders at a configuration and the obstacles,
//! each triangle tagged with the body it belongs to. Spheres, cylinders and capsules are
//! surfaces of revolution sampled at [`AROUND`] steps (the chord error is stated in the picture);
//! boxes and meshes are exact.

use crate::model::{Model, Shape};
use crate::scenario::Scenario;
use nalgebra::{Isometry3, Point3, Vector3};

/// Steps around the axis of a sphere, cylinder or capsule: a chord error of
/// `r (1 - cos(pi / AROUND))`, 0.5 % of the radius.
pub const AROUND: usize = 32;
/// Steps from pole to pole of a sphere (half of it per capsule cap).
const RINGS: usize = 16;

/// A shape as triangles in its own frame.
#[derive(Debug, Clone, Default)]
pub struct Surface {
    /// Vertex positions (m).
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Every triangle is wound counter-clockwise seen from outside (a closed primitive), so a
    /// triangle facing away from the viewer can be skipped; a mesh file promises no winding.
    pub outward: bool,
}

/// Which body a triangle belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Part {
    /// Robot link, by index in [`Model::links`].
    Link(usize),
    /// Obstacle, by index in [`Scenario::obstacles`].
    Obstacle(usize),
}

/// One triangle in the world.
#[derive(Debug, Clone, Copy)]
pub(super) struct Triangle {
    /// Corners (m, world frame).
    pub(super) corners: [Point3<f64>; 3],
    /// The body it belongs to.
    pub(super) part: Part,
    /// Wound outward (see [`Surface::outward`]).
    pub(super) outward: bool,
}

/// The triangles of a shape in its own frame.
pub fn surface(shape: &Shape) -> Surface {
    match shape {
        Shape::Sphere { radius } => {
            let profile = (0..=RINGS)
                .map(|i| {
                    let polar = std::f64::consts::PI * i as f64 / RINGS as f64;
                    (radius * polar.sin(), radius * polar.cos())
                })
                .collect::<Vec<_>>();
            lathe(&profile)
        }
        Shape::Cylinder { radius, length } => {
            let half = length / 2.0;
            lathe(&[(0.0, half), (*radius, half), (*radius, -half), (0.0, -half)])
        }
        Shape::Capsule { radius, length } => {
            let half = length / 2.0;
            let cap = |from: usize, to: usize, offset: f64| {
                (from..=to).map(move |i| {
                    let polar = std::f64::consts::PI * i as f64 / RINGS as f64;
                    (radius * polar.sin(), radius * polar.cos() + offset)
                })
            };
            let profile: Vec<_> = cap(0, RINGS / 2, half).chain(cap(RINGS / 2, RINGS, -half)).collect();
            lathe(&profile)
        }
        Shape::Box { half_extents } => cuboid(*half_extents),
        Shape::Mesh(mesh) => Surface {
            vertices: mesh.vertices.clone(),
            triangles: mesh.triangles.clone(),
            outward: false,
        },
    }
}

/// A surface of revolution about z: `profile` is `(radius, z)` from the top pole to the bottom.
fn lathe(profile: &[(f64, f64)]) -> Surface {
    let mut vertices = Vec::with_capacity(profile.len() * AROUND);
    for &(radius, z) in profile {
        for j in 0..AROUND {
            let angle = std::f64::consts::TAU * j as f64 / AROUND as f64;
            vertices.push([radius * angle.cos(), radius * angle.sin(), z]);
        }
    }
    let index = |i: usize, j: usize| (i * AROUND + j % AROUND) as u32;
    let mut triangles = Vec::new();
    for i in 0..profile.len() - 1 {
        for j in 0..AROUND {
            // (profile step) x (angle step) points outward for a profile running top to bottom.
            let (a, b, c, d) = (index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1));
            if profile[i + 1].0 > 0.0 || profile[i].0 > 0.0 {
                if profile[i + 1].0 > 0.0 {
                    triangles.push([a, b, c]);
                }
                if profile[i].0 > 0.0 {
                    triangles.push([a, c, d]);
                }
            }
        }
    }
    Surface {
        vertices,
        triangles,
        outward: true,
    }
}

/// A box centred at the origin, two outward triangles per face.
fn cuboid(half: [f64; 3]) -> Surface {
    let mut vertices = Vec::with_capacity(24);
    let mut triangles = Vec::with_capacity(12);
    for axis in 0..3 {
        for sign in [1.0, -1.0] {
            let mut centre = [0.0; 3];
            centre[axis] = sign * half[axis];
            let (mut u, mut v) = ([0.0; 3], [0.0; 3]);
            u[(axis + 1) % 3] = half[(axis + 1) % 3];
            v[(axis + 2) % 3] = half[(axis + 2) % 3];
            // u x v is +axis; on the negative face swap them so the face still winds outward.
            if sign < 0.0 {
                std::mem::swap(&mut u, &mut v);
            }
            let base = vertices.len() as u32;
            for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                vertices.push(std::array::from_fn(|k| centre[k] + su * u[k] + sv * v[k]));
            }
            triangles.push([base, base + 1, base + 2]);
            triangles.push([base, base + 2, base + 3]);
        }
    }
    Surface {
        vertices,
        triangles,
        outward: true,
    }
}

/// Every link collider's surface, per link, in its link frame: computed once per model.
#[derive(Debug, Clone)]
pub(super) struct RobotSurfaces {
    /// `links[i]`: `(link_from_shape, surface)` per collider of link `i`.
    pub(super) links: Vec<Vec<(Isometry3<f64>, Surface)>>,
    /// Obstacle surfaces, each in the world.
    pub(super) obstacles: Vec<(Isometry3<f64>, Surface)>,
}

impl RobotSurfaces {
    /// The surfaces of a model's colliders and of a scenario's obstacles.
    pub(super) fn of(model: &Model, scenario: &Scenario) -> Self {
        Self {
            links: model
                .links
                .iter()
                .map(|link| link.colliders.iter().map(|c| (c.link_from_shape, surface(&c.shape))).collect())
                .collect(),
            obstacles: scenario.obstacles.iter().map(|o| (o.world_from_shape, surface(&o.shape))).collect(),
        }
    }

    /// The robot's triangles in the world at configuration `q` (`q.len()` is the model's dof).
    pub(super) fn robot(&self, model: &Model, q: &[f64]) -> Vec<Triangle> {
        let mut ws = model.workspace();
        model.forward(q, &mut ws);
        let mut out = Vec::new();
        for (i, colliders) in self.links.iter().enumerate() {
            for (link_from_shape, surface) in colliders {
                place(&mut out, &(ws.link_in_world[i] * link_from_shape), surface, Part::Link(i));
            }
        }
        out
    }

    /// The obstacles' triangles in the world.
    pub(super) fn obstacles(&self) -> Vec<Triangle> {
        let mut out = Vec::new();
        for (k, (world_from_shape, surface)) in self.obstacles.iter().enumerate() {
            place(&mut out, world_from_shape, surface, Part::Obstacle(k));
        }
        out
    }
}

fn place(out: &mut Vec<Triangle>, world_from_shape: &Isometry3<f64>, surface: &Surface, part: Part) {
    let points: Vec<Point3<f64>> = surface
        .vertices
        .iter()
        .map(|v| world_from_shape * Point3::from(Vector3::from(*v)))
        .collect();
    for triangle in &surface.triangles {
        let corner = |k: usize| points.get(triangle[k] as usize).copied();
        // A mesh index outside its vertices was refused by the loader; skip rather than panic.
        if let (Some(a), Some(b), Some(c)) = (corner(0), corner(1), corner(2)) {
            out.push(Triangle {
                corners: [a, b, c],
                part,
                outward: surface.outward,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The divergence theorem: the enclosed volume of an outward-wound closed surface is
    /// `sum (a . (b x c)) / 6`, positive, and close to the shape's own volume.
    fn volume(surface: &Surface) -> f64 {
        surface
            .triangles
            .iter()
            .map(|t| {
                let p = |k: usize| Vector3::from(surface.vertices[t[k] as usize]);
                p(0).dot(&p(1).cross(&p(2))) / 6.0
            })
            .sum()
    }

    #[test]
    fn primitives_are_closed_outward_and_have_their_volume() {
        let pi = std::f64::consts::PI;
        let cases = [
            (Shape::Sphere { radius: 0.2 }, 4.0 / 3.0 * pi * 0.008),
            (Shape::Cylinder { radius: 0.1, length: 0.5 }, pi * 0.01 * 0.5),
            (
                Shape::Capsule { radius: 0.1, length: 0.3 },
                pi * 0.01 * 0.3 + 4.0 / 3.0 * pi * 0.001,
            ),
            (
                Shape::Box {
                    half_extents: [0.1, 0.2, 0.3],
                },
                0.2 * 0.4 * 0.6,
            ),
        ];
        for (shape, exact) in cases {
            let got = volume(&surface(&shape));
            // The inscribed polyhedron loses at most about 2 % at 32 steps around, 16 rings.
            assert!(
                got > 0.0 && got <= exact * (1.0 + 1e-12) && got > 0.97 * exact,
                "{} volume {got} against {exact}",
                shape.kind()
            );
        }
    }
}
