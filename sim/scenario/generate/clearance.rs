//! A conservative clearance model the generators build their scenarios with, independent of the
//! collision stage: the paper's capsules (`Link::segments`, radius [`PAPER_CAPSULE_RADIUS_M`])
//! plus a bounding sphere for every exact collider they do not already cover (the joint module
//! housings), against exact obstacle shapes, the floor, and the robot itself.

use crate::model::{KinematicsWorkspace, Model, Shape, PAPER_CAPSULE_RADIUS_M};
use crate::scenario::Obstacle;
use nalgebra::{Isometry3, Point3, Vector3};

/// Spacing of the points at which a capsule axis is compared with a box or cylinder obstacle (m);
/// half of it is subtracted from the result, since distance is 1-Lipschitz.
pub(crate) const SEGMENT_SAMPLE_M: f64 = 0.005;

/// Slack when deciding whether a paper capsule covers an exact collider (m): float noise only.
const COVER_SLACK_M: f64 = 1e-9;

/// A capsule fixed to a link: axis from `start` to `end` in the link frame, `radius` in metres.
#[derive(Debug, Clone, Copy)]
struct LinkCapsule {
    link: usize,
    start: Vector3<f64>,
    end: Vector3<f64>,
    radius: f64,
    /// One of the paper's capsules, not a bounding sphere added for an uncovered collider.
    paper: bool,
}

/// The same capsule in the world at the current configuration.
#[derive(Debug, Clone, Copy)]
struct WorldCapsule {
    link: usize,
    start: Vector3<f64>,
    end: Vector3<f64>,
    radius: f64,
    paper: bool,
}

/// An exact collider of a link as a parry shape, for the exact self-collision check.
struct ExactPart {
    link: usize,
    /// Pose of the parry shape in the link frame (parry's cylinders run along y, ours along z).
    link_from_part: Isometry3<f64>,
    shape: Box<dyn parry3d_f64::shape::Shape>,
}

impl std::fmt::Debug for ExactPart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ExactPart {{ link: {}, link_from_part: {:?} }}", self.link, self.link_from_part)
    }
}

/// A model's conservative capsule geometry, posed at one configuration at a time.
#[derive(Debug)]
pub(crate) struct CapsuleRobot<'a> {
    model: &'a Model,
    ws: KinematicsWorkspace,
    capsules: Vec<LinkCapsule>,
    world: Vec<WorldCapsule>,
    exact: Vec<ExactPart>,
    self_pairs: Vec<(usize, usize)>,
    reach: Vec<Vec<f64>>,
}

impl<'a> CapsuleRobot<'a> {
    /// The capsules of `model`, posed at `q = 0` until [`CapsuleRobot::set`] is called.
    pub(crate) fn new(model: &'a Model) -> Self {
        let mut capsules = Vec::new();
        for (link_index, link) in model.links.iter().enumerate() {
            let paper: Vec<LinkCapsule> = link
                .segments
                .iter()
                .map(|s| LinkCapsule {
                    link: link_index,
                    start: s.start,
                    end: s.end,
                    radius: PAPER_CAPSULE_RADIUS_M,
                    paper: true,
                })
                .collect();
            for collider in &link.colliders {
                if !covered(&collider.shape, &collider.link_from_shape, &paper) {
                    let centre = collider.link_from_shape.translation.vector;
                    capsules.push(LinkCapsule {
                        link: link_index,
                        start: centre,
                        end: centre,
                        radius: collider.shape.bounding_radius(),
                        paper: false,
                    });
                }
            }
            capsules.extend(paper);
        }

        // Self-collision pairs: the paper leaves out pairs on one body and consecutive bodies.
        // For a design, link i ends where link i + 1 begins, so when link i + 1 spans less than
        // two capsule radii, the capsules of links i and i + 2 touch in every configuration; such
        // pairs are left to the joint design as well.
        let links_with_capsules: Vec<usize> = (0..model.links.len()).filter(|&i| !model.links[i].segments.is_empty()).collect();
        let mut self_pairs = Vec::new();
        for &i in &links_with_capsules {
            for &j in &links_with_capsules {
                let always_touching =
                    j == i + 2 && model.joints[i + 1].parent_from_joint.translation.vector.norm() < 2.0 * PAPER_CAPSULE_RADIUS_M;
                if j >= i + 2 && !always_touching {
                    self_pairs.push((i, j));
                }
            }
        }

        // reach[j][link]: how far any axis point of `link` can be from joint j's origin (and so
        // from its axis), whatever the other joints do: the joint-to-joint hops along the chain
        // from the link joint j moves, plus the furthest axis point of `link` from its own origin.
        // A capsule is its axis grown by its radius, so bounding the axis motion bounds the capsule's.
        let extent = |link: usize| {
            capsules
                .iter()
                .filter(|c| c.link == link)
                .map(|c| c.start.norm().max(c.end.norm()))
                .fold(0.0, f64::max)
        };
        let reach = (0..model.dof())
            .map(|j| {
                let mut hops = 0.0;
                (0..model.links.len())
                    .map(|link| {
                        if link <= j {
                            return 0.0;
                        }
                        let bound = hops + extent(link);
                        if link < model.dof() {
                            hops += model.joints[link].parent_from_joint.translation.vector.norm();
                        }
                        bound
                    })
                    .collect()
            })
            .collect();

        let exact = model
            .links
            .iter()
            .enumerate()
            .flat_map(|(link, l)| l.colliders.iter().map(move |c| (link, c)))
            .map(|(link, collider)| {
                let (shape_from_part, shape) = parry_shape(&collider.shape);
                ExactPart {
                    link,
                    link_from_part: collider.link_from_shape * shape_from_part,
                    shape,
                }
            })
            .collect();
        let mut robot = CapsuleRobot {
            model,
            ws: model.workspace(),
            world: Vec::with_capacity(capsules.len()),
            capsules,
            exact,
            self_pairs,
            reach,
        };
        robot.set(&vec![0.0; model.dof()]);
        robot
    }

    /// Poses the capsules at configuration `q` (rad).
    ///
    /// # Panics
    /// When `q.len()` differs from the model's dof.
    pub(crate) fn set(&mut self, q: &[f64]) {
        self.model.forward(q, &mut self.ws);
        self.world.clear();
        for c in &self.capsules {
            let frame = &self.ws.link_in_world[c.link];
            self.world.push(WorldCapsule {
                link: c.link,
                start: frame.transform_point(&Point3::from(c.start)).coords,
                end: frame.transform_point(&Point3::from(c.end)).coords,
                radius: c.radius,
                paper: c.paper,
            });
        }
    }

    /// Smallest distance between the robot's capsules and spheres and any obstacle (m; negative
    /// when they overlap), each capsule's less `slack[link]` (see [`CapsuleRobot::motion_bounds`]).
    pub(crate) fn obstacle_clearance(&self, obstacles: &[Obstacle], slack: &[f64]) -> f64 {
        let mut clearance = f64::INFINITY;
        for obstacle in obstacles {
            for c in &self.world {
                clearance = clearance.min(segment_to_shape(&c.start, &c.end, obstacle) - c.radius - slack[c.link]);
            }
        }
        clearance
    }

    /// Height of the robot's lowest point above the floor at `height` (m), each capsule's less
    /// `slack[link]`.
    pub(crate) fn floor_clearance(&self, height: f64, slack: &[f64]) -> f64 {
        self.world
            .iter()
            .map(|c| c.start.z.min(c.end.z) - c.radius - height - slack[c.link])
            .fold(f64::INFINITY, f64::min)
    }

    /// No slack: one zero per link, for clearances at a configuration.
    pub(crate) fn exact(&self) -> Vec<f64> {
        vec![0.0; self.model.links.len()]
    }

    /// Smallest distance between the paper capsules of two links that may collide (m; negative
    /// in self-collision); see [`CapsuleRobot::new`] for the pairs.
    pub(crate) fn self_clearance(&self) -> f64 {
        let mut clearance = f64::INFINITY;
        for &(i, j) in &self.self_pairs {
            for a in self.world.iter().filter(|c| c.paper && c.link == i) {
                for b in self.world.iter().filter(|c| c.paper && c.link == j) {
                    clearance = clearance.min(segment_distance(&a.start, &a.end, &b.start, &b.end) - a.radius - b.radius);
                }
            }
        }
        clearance
    }

    /// Smallest distance between the exact colliders (tubes, housings) of two links that may
    /// collide (m; 0 when they touch or overlap), by parry3d; the same pairs as
    /// [`CapsuleRobot::self_clearance`]. The capsules do not cover the joint module housings, and
    /// bounding spheres around the housings would make links that are always close (2 and 5 of
    /// the paper robot, 0.14 m apart through two 0.1 m modules) collide in every configuration.
    pub(crate) fn exact_self_clearance(&self) -> f64 {
        let pose = |part: &ExactPart| crate::frames::parry_pose(&(self.ws.link_in_world[part.link] * part.link_from_part));
        let mut clearance = f64::INFINITY;
        for &(i, j) in &self.self_pairs {
            for a in self.exact.iter().filter(|p| p.link == i) {
                for b in self.exact.iter().filter(|p| p.link == j) {
                    let distance = parry3d_f64::query::distance(&pose(a), a.shape.as_ref(), &pose(b), b.shape.as_ref())
                        .map_or(f64::NEG_INFINITY, |d| d.distance);
                    clearance = clearance.min(distance);
                }
            }
        }
        clearance
    }

    /// Per link, an upper bound on how far any capsule axis point of the link moves when the
    /// joints change by `dq` (rad): `sum_j reach_j |dq_j|` over the joints before it, since a
    /// rotation by `t` about an axis moves a point at distance `r` by at most `r t`.
    pub(crate) fn motion_bounds(&self, dq: &[f64]) -> Vec<f64> {
        (0..self.model.links.len())
            .map(|link| self.reach.iter().zip(dq).map(|(r, d)| r[link] * d.abs()).sum())
            .collect()
    }
}

/// A model shape as a parry shape, with the pose of the parry shape in the model shape's frame.
/// Meshes become their bounding sphere (catalog robots have none).
fn parry_shape(shape: &Shape) -> (Isometry3<f64>, Box<dyn parry3d_f64::shape::Shape>) {
    use parry3d_f64::shape::{Ball, Capsule, Cuboid, Cylinder};
    // parry's cylinders and capsules run along y; turning y onto z lays them along our z.
    let y_to_z = Isometry3::rotation(Vector3::x() * std::f64::consts::FRAC_PI_2);
    match shape {
        Shape::Sphere { radius } => (Isometry3::identity(), Box::new(Ball::new(*radius))),
        Shape::Cylinder { radius, length } => (y_to_z, Box::new(Cylinder::new(length / 2.0, *radius))),
        Shape::Capsule { radius, length } => (y_to_z, Box::new(Capsule::new_y(length / 2.0, *radius))),
        Shape::Box { half_extents } => (
            Isometry3::identity(),
            Box::new(Cuboid::new(parry3d_f64::math::Vector::new(
                half_extents[0],
                half_extents[1],
                half_extents[2],
            ))),
        ),
        Shape::Mesh(_) => (Isometry3::identity(), Box::new(Ball::new(shape.bounding_radius()))),
    }
}

/// True when a paper capsule of the same link contains the collider.
fn covered(shape: &Shape, link_from_shape: &Isometry3<f64>, paper: &[LinkCapsule]) -> bool {
    let on_axis = |p: &Vector3<f64>, c: &LinkCapsule| point_segment_distance(p, &c.start, &c.end) <= COVER_SLACK_M;
    match shape {
        Shape::Sphere { radius } => {
            let centre = link_from_shape.translation.vector;
            paper.iter().any(|c| on_axis(&centre, c) && *radius <= c.radius + COVER_SLACK_M)
        }
        // A capsule contains a cylinder of no larger radius whose axis lies on its own axis.
        Shape::Cylinder { radius, length } => {
            let a = link_from_shape.transform_point(&Point3::new(0.0, 0.0, -length / 2.0)).coords;
            let b = link_from_shape.transform_point(&Point3::new(0.0, 0.0, length / 2.0)).coords;
            paper
                .iter()
                .any(|c| on_axis(&a, c) && on_axis(&b, c) && *radius <= c.radius + COVER_SLACK_M)
        }
        _ => false,
    }
}

/// Signed distance from the segment `a`-`b` to an obstacle (m): exact for spheres and capsules;
/// for boxes and cylinders the minimum over points every [`SEGMENT_SAMPLE_M`] minus half the
/// spacing, a lower bound; for meshes the distance to their bounding sphere, a lower bound.
pub(crate) fn segment_to_shape(a: &Vector3<f64>, b: &Vector3<f64>, obstacle: &Obstacle) -> f64 {
    let pose = &obstacle.world_from_shape;
    let centre = pose.translation.vector;
    match &obstacle.shape {
        Shape::Sphere { radius } => point_segment_distance(&centre, a, b) - radius,
        Shape::Capsule { radius, length } => {
            let p = pose.transform_point(&Point3::new(0.0, 0.0, -length / 2.0)).coords;
            let q = pose.transform_point(&Point3::new(0.0, 0.0, length / 2.0)).coords;
            segment_distance(a, b, &p, &q) - radius
        }
        Shape::Mesh(_) => point_segment_distance(&centre, a, b) - obstacle.shape.bounding_radius(),
        Shape::Box { .. } | Shape::Cylinder { .. } => {
            let length = (b - a).norm();
            let steps = (length / SEGMENT_SAMPLE_M).ceil().max(1.0) as usize;
            let mut nearest = f64::INFINITY;
            for i in 0..=steps {
                let point = a + (b - a) * (i as f64 / steps as f64);
                let local = pose.inverse_transform_point(&Point3::from(point)).coords;
                nearest = nearest.min(point_to_shape(&local, &obstacle.shape));
            }
            nearest - 0.5 * length / steps as f64
        }
    }
}

/// Signed distance from a point in the shape frame to a box or cylinder (m; negative inside).
fn point_to_shape(p: &Vector3<f64>, shape: &Shape) -> f64 {
    let outside_inside = |excess: &[f64]| {
        let outside: f64 = excess.iter().map(|e| e.max(0.0).powi(2)).sum::<f64>().sqrt();
        let inside = excess.iter().copied().fold(f64::NEG_INFINITY, f64::max).min(0.0);
        outside + inside
    };
    match shape {
        Shape::Box { half_extents } => outside_inside(&[
            p.x.abs() - half_extents[0],
            p.y.abs() - half_extents[1],
            p.z.abs() - half_extents[2],
        ]),
        Shape::Cylinder { radius, length } => outside_inside(&[p.x.hypot(p.y) - radius, p.z.abs() - length / 2.0]),
        _ => unreachable!("point_to_shape is only called for boxes and cylinders"),
    }
}

/// Distance from point `p` to the segment `a`-`b` (m).
pub(crate) fn point_segment_distance(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let length_squared = ab.norm_squared();
    let t = if length_squared > 0.0 {
        ((p - a).dot(&ab) / length_squared).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

/// Distance between the segments `p1`-`q1` and `p2`-`q2` (m).
pub(crate) fn segment_distance(p1: &Vector3<f64>, q1: &Vector3<f64>, p2: &Vector3<f64>, q2: &Vector3<f64>) -> f64 {
    let (a, b) = crate::frames::closest_points_of_segments(*p1, *q1, *p2, *q2);
    (a - b).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design;
    use crate::model::from_design;
    use std::path::Path;

    #[test]
    fn segment_distance_matches_brute_force() {
        let cases = [
            ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, 2.0, 0.0], 1.0),
            ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 1.0], [3.0, 0.0, 1.0], 2f64.sqrt()),
            ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0], 1.0),
            ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, -1.0], [0.0, 1.0, 1.0], 1.0),
        ];
        for (p1, q1, p2, q2, expected) in cases {
            let d = segment_distance(&Vector3::from(p1), &Vector3::from(q1), &Vector3::from(p2), &Vector3::from(q2));
            assert!((d - expected).abs() < 1e-12, "{p1:?} {q1:?} {p2:?} {q2:?}: {d}");
        }
    }

    #[test]
    fn paper_robot_housings_get_bounding_spheres_and_short_links_skip_pairs() {
        let text = r#"{"mode": "modular", "modules": ["direct", "L-short", "direct", "direct", "I-long"]}"#;
        let model = from_design(&design::parse(text, Path::new("paper.json")).expect("valid"));
        let robot = CapsuleRobot::new(&model);
        let housings = robot
            .capsules
            .iter()
            .filter(|c| c.start == c.end && c.radius > PAPER_CAPSULE_RADIUS_M)
            .count();
        assert_eq!(housings, 5, "one joint module housing per joint; the tubes are inside the capsules");
        assert_eq!(robot.self_pairs, vec![(1, 3), (1, 4), (1, 5), (2, 5)]);
        // Joint 1 reaches the tool end of the 0.4 m tube through hops 0.1, |(0.2, 0, 0.1)|, 0.1, 0.1.
        let expected = 0.1 + 0.05f64.sqrt() + 0.1 + 0.1 + 0.4;
        assert!((robot.reach[0][5] - expected).abs() < 1e-12, "{:?}", robot.reach);
        // The first link's axis runs up joint 1's own axis from its origin: 0.1 m at most.
        assert!((robot.reach[0][1] - 0.1).abs() < 1e-12, "{:?}", robot.reach);
        let bounds = robot.motion_bounds(&[0.0, 0.01, 0.0, 0.0, 0.0]);
        assert_eq!(bounds[1], 0.0, "joint 2 does not move link 1");
    }
}
