//! Exact signed distances with parry3d-f64: AABB and bounding-capsule lower bounds, every
//! collider pair within the margin, then branch and bound for the closest pair; mesh hulls beside
//! the meshes.

use super::narrow::{measure_convex, measure_floor, measure_shapes_hinted, within};
use super::primitives::{order_key, Measured, BOUND_ROUNDING_M};

/// Below the hulls' unpolished GJK gap that is still a lower bound of the meshes' gap (m): GJK on
/// polytopes stops within its tolerance, far below this.
const HULL_SLACK_M: f64 = 1e-4;
use super::world::{CollisionWorld, Other};
use super::{effective_margin, Body, ClearanceByKind, CollisionFinding, Distances, PairDistance, PairEstimate, Part, QueryOptions, Stage};
use crate::frames::{parry_pose, vector_from_parry};
use nalgebra::Isometry3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Vector;
use std::cmp::Reverse;

/// Signed distances of every checked pair at one configuration, in the exact geometry.
///
/// `link_in_world[i]` is the world pose of link `i` (e.g. `KinematicsWorkspace::link_in_world`
/// after `Model::forward`). Fills `out` (see [`Distances`]): every pair within `query.margin`, the
/// closest pair, one estimate per pair, and hull disagreements. Reusing `out` across calls keeps its
/// buffers, so a call in steady state does not allocate.
///
/// # Panics
/// When `link_in_world.len()` differs from [`CollisionWorld::link_count`].
pub fn distances(world: &CollisionWorld, link_in_world: &[Isometry3<f64>], query: &QueryOptions, out: &mut Distances) {
    distances_among(world, link_in_world, query, None, out);
}

/// [`distances`] over some pairs, each measured only as far as it must be. `levels` has one
/// entry per pair ([`CollisionWorld::pairs`] order; `None` for the slice: every pair, as
/// [`distances`]): `None`, the pair is not looked at (its estimate infinite, not exact); a level,
/// the pair is measured when it could be below it (or within the margin), else its estimate is
/// the bound that showed it is not. `closest` is the closest pair measured, if any. A continuous
/// check re-measures only the pairs whose certified stretch has run out, and exactly only those
/// whose bound would not do.
///
/// # Panics
/// As [`distances`], and when `levels` has not one entry per pair.
pub fn distances_among(
    world: &CollisionWorld,
    link_in_world: &[Isometry3<f64>],
    query: &QueryOptions,
    levels: Option<&[Option<f64>]>,
    out: &mut Distances,
) {
    search(world, link_in_world, query, levels, false, out);
}

/// Each kind's smallest signed distance (obstacles, self, floor) at one configuration, in the
/// exact geometry with exact depths: what [`ClearanceByKind::of`] reads from a query with an
/// infinite margin, with every pair measured only when it could be closer than its kind's
/// closest so far. `out` lends its buffers.
///
/// # Panics
/// When `link_in_world.len()` differs from [`CollisionWorld::link_count`].
pub fn clearance_by_kind(world: &CollisionWorld, link_in_world: &[Isometry3<f64>], out: &mut Distances) -> ClearanceByKind {
    let query = QueryOptions {
        margin: 0.0,
        hulls: false,
        exact_depth: true,
        mesh_hulls: false,
    };
    search(world, link_in_world, &query, None, true, out);
    let mut by_kind = ClearanceByKind::default();
    for best in out.scratch.best.iter().flatten() {
        by_kind.lower(best.b.body, best.distance);
    }
    by_kind
}

/// The slot of a pair's kind in a search by kind: obstacles, self, floor.
fn kind_slot(other: Other) -> usize {
    match other {
        Other::Obstacle(_) => 0,
        Other::Link(_) => 1,
        Other::Floor => 2,
    }
}

/// [`distances_among`], or with `by_kind` the closest pair of each kind (see [`kind_slot`])
/// rather than the closest of all.
fn search(
    world: &CollisionWorld,
    link_in_world: &[Isometry3<f64>],
    query: &QueryOptions,
    levels: Option<&[Option<f64>]>,
    by_kind: bool,
    out: &mut Distances,
) {
    assert_eq!(
        link_in_world.len(),
        world.link_count(),
        "one pose per link of the model the collision world was built for"
    );
    if let Some(levels) = levels {
        assert_eq!(levels.len(), world.pairs.len(), "one level per checked pair");
    }
    let looked_at = |pair: usize| levels.is_none_or(|levels| levels[pair].is_some());
    // The whole query looks for the closest pair; a partial one for each pair's level.
    let level = |pair: usize| levels.and_then(|levels| levels[pair]).unwrap_or(f64::NEG_INFINITY);
    let highest_level = levels.map_or(f64::NEG_INFINITY, |levels| {
        levels.iter().flatten().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
    });
    let margin = effective_margin(query.margin);
    out.reset(margin, world.pairs.len());
    let Distances {
        scratch,
        findings,
        narrow_phase_calls,
        hull_calls,
        estimates,
        ..
    } = out;

    place(world, link_in_world, scratch);
    // Hints of another world's meshes are only wasted: every index is checked before use.
    scratch.hints.resize(world.candidates.len(), None);
    scratch.bounds.clear();
    scratch.stages.clear();
    for (index, candidate) in world.candidates.iter().enumerate() {
        // A pair not looked at is bounded by nothing: never queued, never measured.
        let bound = if looked_at(candidate.pair) {
            box_bound(world, index, scratch)
        } else {
            f64::INFINITY
        };
        scratch.bounds.push(bound);
        scratch.stages.push(Stage::Boxed);
    }

    // Collider pairs by bound, smallest first; each is measured only if it can change an answer:
    // a pair's distance within the margin (it could be below the pair's best so far), the
    // closest pair (it could be below the closest so far), or a hull finding. Its bounding
    // capsules are tried before its shapes.
    let mut closest = [if levels.is_some() { f64::NEG_INFINITY } else { f64::INFINITY }; 3];
    let slot = |other: Other| if by_kind { kind_slot(other) } else { 0 };
    let slots = if by_kind { 3 } else { 1 };
    scratch.queue.clear();
    scratch.queue.extend(
        scratch
            .bounds
            .iter()
            .enumerate()
            .filter(|&(index, _)| looked_at(world.candidates[index].pair))
            .map(|(index, &bound)| Reverse((order_key(bound), index))),
    );
    while let Some(Reverse((_, index))) = scratch.queue.pop() {
        let bound = scratch.bounds[index];
        let farthest = closest[..slots].iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        if bound > margin && bound >= farthest.max(highest_level) {
            break;
        }
        let candidate = &world.candidates[index];
        let kind = slot(candidate.b);
        let pair_best = scratch.best[candidate.pair].map_or(f64::INFINITY, |best| best.distance);
        let by_hulls = query.mesh_hulls && world.has_mesh(candidate);
        let hulls = query.hulls && !by_hulls && bound <= margin && world.has_mesh(candidate);
        if !(bound < closest[kind].max(level(candidate.pair)) || (bound <= margin && (bound < pair_best || hulls))) {
            continue;
        }
        if scratch.stages[index] == Stage::Boxed && candidate.b != Other::Floor {
            let bound = tighten(world, index, scratch);
            scratch.queue.push(Reverse((order_key(bound), index)));
            continue;
        }
        // A mesh pair's narrow phase walks triangle pairs; its hulls' distance, one convex query,
        // bounds it from below first (a mesh lies inside its hull).
        if scratch.stages[index] == Stage::Capsuled && world.has_mesh(candidate) && !by_hulls {
            let bound = hull_bound(world, index, scratch);
            scratch.queue.push(Reverse((order_key(bound), index)));
            continue;
        }
        *narrow_phase_calls += 1;
        let (distance, hull_measured) = measure(world, index, scratch, findings, hulls, query.exact_depth, by_hulls);
        closest[kind] = closest[kind].min(distance);
        *hull_calls += usize::from(hull_measured);
    }

    // A pair's estimate is exact when no unmeasured collider pair of it could be closer.
    estimates.extend(
        world
            .pairs
            .iter()
            .zip(&scratch.best)
            .enumerate()
            .map(|(index, (pair, best))| PairEstimate {
                a: pair.a,
                b: pair.b,
                distance: best.map_or(f64::INFINITY, |best| best.distance),
                exact: looked_at(index),
            }),
    );
    for (index, candidate) in world.candidates.iter().enumerate() {
        let estimate = &mut estimates[candidate.pair];
        if scratch.stages[index] != Stage::Measured && scratch.bounds[index] < estimate.distance {
            estimate.distance = scratch.bounds[index];
            estimate.exact = false;
        }
    }
    out.collect();
}

/// Whether every checked pair is farther apart than `margin` (m; NaN and negative count as 0) at
/// one configuration: the comparison of [`distances`]' closest pair with the margin, with
/// `exact_depth` false and no hulls, decided without looking for the closest pair. Each pair is
/// bounded by its boxes and bounding capsules, and measured only when those cannot clear it; the
/// first pair within the margin ends the search. `out` lends its buffers; its answer fields are
/// left as they were.
///
/// # Panics
/// When `link_in_world.len()` differs from [`CollisionWorld::link_count`].
pub fn clear(world: &CollisionWorld, link_in_world: &[Isometry3<f64>], margin: f64, out: &mut Distances) -> bool {
    assert_eq!(
        link_in_world.len(),
        world.link_count(),
        "one pose per link of the model the collision world was built for"
    );
    let margin = effective_margin(margin);
    let scratch = &mut out.scratch;
    place(world, link_in_world, scratch);
    for (index, candidate) in world.candidates.iter().enumerate() {
        if box_bound(world, index, scratch) > margin || capsule_bound(world, index, scratch).is_some_and(|bound| bound > margin) {
            continue;
        }
        let a = &world.colliders[candidate.a];
        let pose_a = &scratch.poses[candidate.a];
        // As `measure`: the allowance applies to pairs of links, the floor has none.
        let allowance = candidate.allowance;
        let near = match candidate.b {
            Other::Floor => {
                measure_floor(pose_a, &a.geometry, world.floor.expect("floor pairs exist only with a floor")).distance <= margin
            }
            Other::Link(j) => within(
                pose_a,
                &a.geometry,
                &scratch.poses[j],
                &world.colliders[j].geometry,
                margin,
                allowance,
            ),
            Other::Obstacle(k) => {
                let obstacle = &world.obstacles[k];
                within(
                    pose_a,
                    &a.geometry,
                    &obstacle.world_from_shape,
                    &obstacle.geometry,
                    margin,
                    allowance,
                )
            }
        };
        if near {
            return false;
        }
    }
    true
}

/// Fills `scratch` with every link's and collider's world pose, every collider's world AABB and
/// its bounding capsule's segment.
fn place(world: &CollisionWorld, link_in_world: &[Isometry3<f64>], scratch: &mut super::Scratch) {
    scratch.link_poses.clear();
    scratch.link_poses.extend(link_in_world.iter().map(parry_pose));
    scratch.poses.clear();
    scratch.aabbs.clear();
    scratch.segments.clear();
    for collider in &world.colliders {
        let pose = scratch.link_poses[collider.link] * collider.link_from_shape;
        let bounding = &collider.geometry.bounding;
        scratch.aabbs.push(aabb_of(&*collider.geometry.shape, &pose));
        scratch
            .segments
            .push([bounding.start, bounding.end].map(|end| vector_from_parry(pose * end)));
        scratch.poses.push(pose);
    }
}

/// Candidate `index`'s lower bound from the boxes (the floor's is exact for the lowest point).
fn box_bound(world: &CollisionWorld, index: usize, scratch: &super::Scratch) -> f64 {
    let candidate = &world.candidates[index];
    let a = &scratch.aabbs[candidate.a];
    let bound = match candidate.b {
        Other::Link(b) => aabb_bound(a, &scratch.aabbs[b]),
        Other::Obstacle(k) => aabb_bound(a, &world.obstacles[k].aabb),
        Other::Floor => a.mins.z - world.floor.expect("floor pairs exist only with a floor"),
    };
    bound + candidate.allowance - BOUND_ROUNDING_M
}

/// Candidate `index`'s lower bound from the bounding capsules; `None` for the floor.
fn capsule_bound(world: &CollisionWorld, index: usize, scratch: &super::Scratch) -> Option<f64> {
    let candidate = &world.candidates[index];
    let [start, end] = scratch.segments[candidate.a];
    let radius = world.colliders[candidate.a].geometry.bounding.radius;
    let ([other_start, other_end], other_radius) = match candidate.b {
        Other::Link(b) => (scratch.segments[b], world.colliders[b].geometry.bounding.radius),
        Other::Obstacle(k) => (world.obstacles[k].bounding, world.obstacles[k].geometry.bounding.radius),
        Other::Floor => return None,
    };
    let capsules = super::primitives::capsules(start, end, radius, other_start, other_end, other_radius).distance;
    Some(capsules + candidate.allowance - BOUND_ROUNDING_M)
}

/// Measures candidate `index` (and its hulls when `with_hulls` and a side is a mesh), records it
/// in `scratch`, and returns its signed distance and whether hulls were measured.
fn measure(
    world: &CollisionWorld,
    index: usize,
    scratch: &mut super::Scratch,
    findings: &mut Vec<CollisionFinding>,
    with_hulls: bool,
    exact_depth: bool,
    by_hulls: bool,
) -> (f64, bool) {
    let candidate = &world.candidates[index];
    let a = &world.colliders[candidate.a];
    let pose_a = &scratch.poses[candidate.a];
    let part_a = Part {
        body: Body::Link(a.link),
        element: a.element,
    };
    let (pose_b, b, part_b) = match candidate.b {
        Other::Floor => {
            let height = world.floor.expect("floor pairs exist only with a floor");
            let measured = measure_floor(pose_a, &a.geometry, height);
            record(scratch, index, candidate.pair, measured, part_a, Part::floor());
            return (measured.distance, false);
        }
        Other::Link(j) => {
            let b = &world.colliders[j];
            let part = Part {
                body: Body::Link(b.link),
                element: b.element,
            };
            (&scratch.poses[j], &b.geometry, part)
        }
        Other::Obstacle(k) => {
            let part = Part {
                body: Body::Obstacle(k),
                element: 0,
            };
            (&world.obstacles[k].world_from_shape, &world.obstacles[k].geometry, part)
        }
    };
    let measured = if by_hulls {
        measure_convex(pose_a, a.geometry.hull_or_shape(), pose_b, b.hull_or_shape(), exact_depth)
    } else {
        measure_shapes_hinted(pose_a, &a.geometry, pose_b, b, exact_depth, &mut scratch.hints[index])
    };
    let with_hulls = with_hulls && (a.geometry.is_mesh() || b.is_mesh());
    if with_hulls {
        let hull_distance = measure_convex(pose_a, a.geometry.hull_or_shape(), pose_b, b.hull_or_shape(), true).distance;
        if hull_distance <= 0.0 && measured.distance > 0.0 {
            findings.push(CollisionFinding::HullDisagreement {
                pair: candidate.pair,
                a: part_a,
                b: part_b,
                exact_distance: measured.distance,
                hull_distance,
            });
        }
    }
    // A shape pair of two links that overlap by construction counts only beyond that overlap.
    let measured = Measured {
        distance: measured.distance + candidate.allowance,
        ..measured
    };
    record(scratch, index, candidate.pair, measured, part_a, part_b);
    (measured.distance, with_hulls)
}

/// Raises candidate `index`'s bound to its bounding capsules' signed distance (the floor keeps
/// its AABB bound, which is exact for the lowest point) and returns the bound.
fn tighten(world: &CollisionWorld, index: usize, scratch: &mut super::Scratch) -> f64 {
    if let Some(capsules) = capsule_bound(world, index, scratch) {
        let bound = &mut scratch.bounds[index];
        *bound = bound.max(capsules);
    }
    scratch.stages[index] = Stage::Capsuled;
    scratch.bounds[index]
}

/// Raises candidate `index`'s bound (a pair with a mesh side) to its convex hulls' distance when
/// the hulls are apart, and returns the bound. The hulls' gap is GJK's on polytopes, lowered by
/// [`HULL_SLACK_M`] so rounding cannot make it exceed the meshes' gap.
fn hull_bound(world: &CollisionWorld, index: usize, scratch: &mut super::Scratch) -> f64 {
    let candidate = &world.candidates[index];
    let a = &world.colliders[candidate.a].geometry;
    let (pose_b, b) = match candidate.b {
        Other::Link(j) => (&scratch.poses[j], &world.colliders[j].geometry),
        Other::Obstacle(k) => (&world.obstacles[k].world_from_shape, &world.obstacles[k].geometry),
        Other::Floor => {
            scratch.stages[index] = Stage::Hulled;
            return scratch.bounds[index];
        }
    };
    // A hull of many vertices costs a scan of them all per GJK step, more than the mesh's tree
    // descent it would spare.
    if !a.hull_bounds || !b.hull_bounds {
        scratch.stages[index] = Stage::Hulled;
        return scratch.bounds[index];
    }
    let gap = measure_convex(&scratch.poses[candidate.a], a.hull_or_shape(), pose_b, b.hull_or_shape(), false).distance - HULL_SLACK_M;
    let bound = &mut scratch.bounds[index];
    if gap > 0.0 {
        *bound = bound.max(gap + candidate.allowance);
    }
    scratch.stages[index] = Stage::Hulled;
    *bound
}

/// Stores a measured candidate: its bound becomes its distance, and its pair's best improves.
fn record(scratch: &mut super::Scratch, index: usize, pair: usize, measured: Measured, a: Part, b: Part) {
    scratch.bounds[index] = measured.distance;
    scratch.stages[index] = Stage::Measured;
    let best = &mut scratch.best[pair];
    if best.is_none_or(|best| measured.distance < best.distance) {
        *best = Some(measured.into_pair_distance(pair, a, b));
    }
}

/// The world AABB of a shape at `pose`: closed form for cylinders (parry asks their support
/// function six times), parry's otherwise.
fn aabb_of(shape: &dyn parry3d_f64::shape::Shape, pose: &parry3d_f64::math::Pose) -> Aabb {
    let Some(cylinder) = shape.as_cylinder() else {
        return shape.compute_aabb(pose);
    };
    // Along each world axis: half the axis's projection plus the radius times the sine.
    let axis = pose.rotation * Vector::Y;
    let reach = |a: f64| a.abs() * cylinder.half_height + (1.0 - a * a).max(0.0).sqrt() * cylinder.radius;
    let half = Vector::new(reach(axis.x), reach(axis.y), reach(axis.z));
    Aabb::new(pose.translation - half, pose.translation + half)
}

/// A lower bound on the signed distance of two bodies inside these boxes (m): the gap between
/// the boxes, or, when they overlap, minus their smallest overlap along an axis (moving one body
/// that far along that axis separates the boxes, hence the bodies).
pub(super) fn aabb_bound(a: &Aabb, b: &Aabb) -> f64 {
    let gap = (b.mins - a.maxs).max(a.mins - b.maxs);
    let outside = gap.max(Vector::ZERO);
    if outside == Vector::ZERO {
        gap.max_element()
    } else {
        outside.length()
    }
}

impl Measured {
    fn into_pair_distance(self, pair: usize, a: Part, b: Part) -> PairDistance {
        PairDistance {
            pair,
            a,
            b,
            distance: self.distance,
            point_a: vector_from_parry(self.point_a),
            point_b: vector_from_parry(self.point_b),
            normal: vector_from_parry(self.normal),
            enclosed: self.enclosed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn aabb(mins: [f64; 3], maxs: [f64; 3]) -> Aabb {
        Aabb::new(Vector::from_array(mins), Vector::from_array(maxs))
    }

    #[test]
    fn aabb_bound_is_the_gap_or_minus_the_smallest_overlap() {
        let unit = aabb([0.0; 3], [1.0; 3]);
        assert_eq!(aabb_bound(&unit, &aabb([4.0, 5.0, 0.0], [5.0, 6.0, 1.0])), 5.0);
        assert_eq!(aabb_bound(&unit, &aabb([0.5, 0.9, -1.0], [2.0, 2.0, 2.0])), -0.09999999999999998);
        assert_eq!(aabb_bound(&aabb([4.0, 5.0, 0.0], [5.0, 6.0, 1.0]), &unit), 5.0);
    }

    #[test]
    fn cylinder_aabb_matches_parry() {
        let cylinder = parry3d_f64::shape::Cylinder::new(0.3, 0.1);
        let pose = parry3d_f64::math::Pose::new(Vector::new(0.1, -0.2, 0.3), Vector::new(0.4, -1.1, 0.7));
        let (ours, parry) = (aabb_of(&cylinder, &pose), parry3d_f64::shape::Shape::compute_aabb(&cylinder, &pose));
        assert!(
            (ours.mins - parry.mins).length() < 1e-15 && (ours.maxs - parry.maxs).length() < 1e-15,
            "{ours:?} {parry:?}"
        );
    }

    #[test]
    fn order_keys_sort_like_the_numbers() {
        let values = [f64::NEG_INFINITY, -2.0, -1e-300, -0.0, 0.0, 1e-300, 3.0, f64::INFINITY];
        let keys: Vec<u64> = values.iter().map(|&v| order_key(v)).collect();
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "{keys:?}");
    }
}
