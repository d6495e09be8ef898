//! The paper's approximate model: capsules of radius 0.06 m on each link's segments, closed-form
//! signed distances to other capsules, spheres, capsule obstacles and the floor plane.

use super::narrow::measure_shapes;
use super::primitives::{capsules, Closest};
use super::world::{CollisionWorld, Other};
use super::{effective_margin, Body, Distances, PairDistance, PairEstimate, Part, QueryOptions};
use crate::frames::{parry_pose, vector_from_parry};
use crate::model::PAPER_CAPSULE_RADIUS_M;
use nalgebra::{Isometry3, Point3, Vector3};

/// Signed distances of every checked pair at one configuration, in the paper's capsule model.
///
/// Same pairs, output and reuse as [`distances`](super::distances); `Part::element` is the
/// segment's index in `Link::segments`. Every capsule pair is measured (the closed forms are
/// cheaper than bounds), so every estimate is exact; there are no hull findings.
///
/// # Panics
/// When `link_in_world.len()` differs from [`CollisionWorld::link_count`].
pub fn approximate_distances(world: &CollisionWorld, link_in_world: &[Isometry3<f64>], query: &QueryOptions, out: &mut Distances) {
    assert_eq!(
        link_in_world.len(),
        world.link_count(),
        "one pose per link of the model the collision world was built for"
    );
    out.reset(effective_margin(query.margin), world.pairs.len());
    let Distances {
        scratch,
        narrow_phase_calls,
        estimates,
        ..
    } = out;
    scratch.segments.clear();
    for capsule in &world.capsules {
        let pose = &link_in_world[capsule.link];
        let ends = [pose * Point3::from(capsule.start), pose * Point3::from(capsule.end)];
        scratch.segments.push(ends.map(|p| p.coords));
    }

    let radius = PAPER_CAPSULE_RADIUS_M;
    for candidate in &world.capsule_candidates {
        let capsule = &world.capsules[candidate.a];
        let a = Part {
            body: Body::Link(capsule.link),
            element: capsule.element,
        };
        let [start, end] = scratch.segments[candidate.a];
        let (closest, b, enclosed) = match candidate.b {
            Other::Link(j) => {
                let other = &world.capsules[j];
                let [other_start, other_end] = scratch.segments[j];
                let b = Part {
                    body: Body::Link(other.link),
                    element: other.element,
                };
                (capsules(start, end, radius, other_start, other_end, radius), b, false)
            }
            Other::Obstacle(k) => {
                let obstacle = &world.obstacles[k];
                let b = Part {
                    body: Body::Obstacle(k),
                    element: 0,
                };
                match obstacle.rounded {
                    Some(rounded) => (capsules(start, end, radius, rounded.start, rounded.end, rounded.radius), b, false),
                    // Boxes, cylinders and meshes have no closed form against a capsule: the
                    // exact model's narrow phase measures the same capsule as a `Capsule` shape.
                    None => {
                        let pose = parry_pose(&link_in_world[capsule.link]);
                        let measured = measure_shapes(&pose, &capsule.geometry, &obstacle.world_from_shape, &obstacle.geometry, true);
                        let closest = Closest {
                            distance: measured.distance,
                            point_a: vector_from_parry(measured.point_a),
                            point_b: vector_from_parry(measured.point_b),
                            normal: vector_from_parry(measured.normal),
                        };
                        (closest, b, measured.enclosed)
                    }
                }
            }
            Other::Floor => {
                let height = world.floor.expect("floor pairs exist only with a floor");
                (capsule_floor(start, end, radius, height), Part::floor(), false)
            }
        };
        *narrow_phase_calls += 1;
        let best = &mut scratch.best[candidate.pair];
        if best.is_none_or(|best| closest.distance < best.distance) {
            *best = Some(PairDistance {
                pair: candidate.pair,
                a,
                b,
                distance: closest.distance,
                point_a: closest.point_a,
                point_b: closest.point_b,
                normal: closest.normal,
                enclosed,
            });
        }
    }
    estimates.extend(world.pairs.iter().zip(&scratch.best).map(|(pair, best)| PairEstimate {
        a: pair.a,
        b: pair.b,
        distance: best.map_or(f64::INFINITY, |best| best.distance),
        exact: true,
    }));
    out.collect();
}

/// Signed distance between a capsule and the floor, the half-space below `z = height` (m).
pub(crate) fn capsule_floor(start: Vector3<f64>, end: Vector3<f64>, radius: f64, height: f64) -> Closest {
    let lowest = if end.z < start.z { end } else { start };
    Closest {
        distance: lowest.z - radius - height,
        point_a: lowest - Vector3::z() * radius,
        point_b: Vector3::new(lowest.x, lowest.y, height),
        normal: -Vector3::z(),
    }
}

/// The capsule model's structure as plain data, for a solver that evaluates the same distances
/// its own way (the optimize stage's tensors): every capsule, and every measured capsule pair in
/// the order [`approximate_distances`] measures them.
#[derive(Debug, Clone)]
pub(crate) struct CapsuleModel {
    /// `(link, start, end)` per capsule, segment ends in the link frame (m).
    pub(crate) capsules: Vec<(usize, Vector3<f64>, Vector3<f64>)>,
    /// `(checked pair, capsule, other)` per measured capsule pair.
    pub(crate) candidates: Vec<(usize, usize, CapsuleOther)>,
    /// Number of checked pairs.
    pub(crate) pair_count: usize,
}

/// What a capsule is measured against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum CapsuleOther {
    /// Another capsule of the robot, by index.
    Capsule(usize),
    /// A sphere or capsule obstacle: segment ends in the world and radius (m).
    Rounded {
        start: Vector3<f64>,
        end: Vector3<f64>,
        radius: f64,
    },
    /// A box, cylinder or mesh obstacle (no closed form), by index: see [`capsule_shape_distance`].
    Shape(usize),
    /// The floor at this height (m).
    Floor(f64),
}

/// The structure of `world`'s capsule model.
pub(crate) fn capsule_model(world: &CollisionWorld) -> CapsuleModel {
    CapsuleModel {
        capsules: world.capsules.iter().map(|c| (c.link, c.start, c.end)).collect(),
        candidates: world
            .capsule_candidates
            .iter()
            .map(|candidate| {
                let other = match candidate.b {
                    Other::Link(j) => CapsuleOther::Capsule(j),
                    Other::Obstacle(k) => match world.obstacles[k].rounded {
                        Some(r) => CapsuleOther::Rounded {
                            start: r.start,
                            end: r.end,
                            radius: r.radius,
                        },
                        None => CapsuleOther::Shape(k),
                    },
                    Other::Floor => CapsuleOther::Floor(world.floor.expect("floor pairs exist only with a floor")),
                };
                (candidate.pair, candidate.a, other)
            })
            .collect(),
        pair_count: world.pairs.len(),
    }
}

/// The signed distance between the capsule of segment `start`..`end` (link frame, m) on a link
/// at `link_in_world` and obstacle `obstacle` without a closed form, measured exactly as
/// [`approximate_distances`] measures it (parry's narrow phase on a `Capsule` shape).
pub(crate) fn capsule_shape_distance(
    world: &CollisionWorld,
    obstacle: usize,
    link_in_world: &Isometry3<f64>,
    start: Vector3<f64>,
    end: Vector3<f64>,
) -> Closest {
    let capsule = parry3d_f64::shape::Capsule::new(
        crate::frames::parry_vector(&start),
        crate::frames::parry_vector(&end),
        PAPER_CAPSULE_RADIUS_M,
    );
    let geometry = super::geometry::Geometry::convex(parry3d_f64::shape::SharedShape::new(capsule));
    let obstacle = &world.obstacles[obstacle];
    let measured = measure_shapes(
        &parry_pose(link_in_world),
        &geometry,
        &obstacle.world_from_shape,
        &obstacle.geometry,
        true,
    );
    Closest {
        distance: measured.distance,
        point_a: vector_from_parry(measured.point_a),
        point_b: vector_from_parry(measured.point_b),
        normal: vector_from_parry(measured.normal),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_distance_uses_the_lower_end() {
        let closest = capsule_floor(Vector3::new(0.0, 0.0, 1.0), Vector3::new(1.0, 0.0, 0.1), 0.06, 0.0);
        assert!((closest.distance - 0.04).abs() < 1e-15);
        assert_eq!(closest.point_b, Vector3::new(1.0, 0.0, 0.0));
    }
}
