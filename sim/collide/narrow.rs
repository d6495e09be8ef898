//! Narrow phase: the signed distance of two shapes, with witness points and normal, in f64.
//!
//! parry's dispatch is used throughout, with three corrections measured in `tests/collide.rs`:
//!
//! - parry's GJK stops early on curved shapes (cylinders, capsules): its distances were up to
//!   1.3e-5 m too large. A separated pair of support-map shapes (neither a ball, which parry
//!   measures by exact point projection) is polished by alternating projections onto the two
//!   shapes, which decreases the distance monotonically to the true one (Cheney-Goldstein), until
//!   the supporting planes across the gap certify it to 1e-10 m. The [`Polished`] dispatcher
//!   does this inside mesh traversals too, triangle by triangle;
//! - balls and capsules against balls and capsules are computed in closed form (closest points of
//!   two segments minus the radii), exact for depths too, where EPA only approximates. A capsule
//!   against any other shape is its axis segment against it, minus the radius: the signed
//!   distance of a convex set grown by `r` is its signed distance minus `r`, and a segment is a
//!   polytope, on which GJK and EPA are exact;
//! - parry 0.31's `contact` of a shape with a half-space given second passes the wrong relative
//!   pose; the floor is given first and the contact flipped.

use super::geometry::{BoundingCapsule, Geometry};
use super::primitives::{capsules, Measured};
use crate::frames::{closest_points_of_segments, parry_vector, vector_from_parry};
use parry3d_f64::math::{Pose, Real, Vector};
use parry3d_f64::query::details::{
    contact_composite_shape_shape, contact_shape_composite_shape, contact_support_map_support_map_with_params,
    distance_composite_shape_shape, distance_shape_composite_shape,
};
use parry3d_f64::query::gjk::{GJKResult, VoronoiSimplex};
use parry3d_f64::query::{
    self, ClosestPoints, Contact, DefaultQueryDispatcher, NonlinearRigidMotion, QueryDispatcher, ShapeCastHit, ShapeCastOptions,
    ShapeDistance, ShapeIntersection, Unsupported,
};
use parry3d_f64::shape::{Cylinder, HalfSpace, Shape};

/// Prediction given to `contact` when the distance is wanted whatever it is (m).
const UNBOUNDED_M: f64 = f64::MAX;
/// Most alternating-projection steps when polishing GJK's answer; the mean measured is 5, the
/// slowest (nearly tangent curved surfaces) reach 1e-13 m within 300.
const POLISH_STEPS: usize = 500;
/// Polishing stops once the gap between the witness points is within this of the lower bound
/// given by the supporting planes across the gap (m): the distance is then certified to it.
const CERTIFIED_M: f64 = 1e-10;
/// How much farther than asked parry's unpolished contact is looked for, relative and absolute
/// (m): its error on curved shapes was at most 1.3e-5 m at 0.5 m.
const PARRY_SLACK_RELATIVE: f64 = 0.01;
const PARRY_SLACK_M: f64 = 1e-4;

/// Signed distance between two shapes: closed form for balls and capsules, the mesh path when a
/// side is a mesh, parry's convex queries (polished) otherwise.
/// With `exact_depth` false, an overlap that would need EPA is estimated by the bounding capsules
/// (see `QueryOptions::exact_depth`).
pub(super) fn measure_shapes(pose_a: &Pose, a: &Geometry, pose_b: &Pose, b: &Geometry, exact_depth: bool) -> Measured {
    measure_shapes_hinted(pose_a, a, pose_b, b, exact_depth, &mut None)
}

/// [`measure_shapes`] with a two-mesh pair's nearest triangles at a nearby pose as a hint, kept
/// up to date: the same answer, found faster along a path (see `SphereTree::gap_to_tree`).
pub(super) fn measure_shapes_hinted(
    pose_a: &Pose,
    a: &Geometry,
    pose_b: &Pose,
    b: &Geometry,
    exact_depth: bool,
    hint: &mut Option<[u32; 2]>,
) -> Measured {
    if a.is_mesh() || b.is_mesh() {
        measure_mesh(pose_a, a, pose_b, b, hint)
    } else {
        measure_convex(pose_a, &*a.shape, pose_b, &*b.shape, exact_depth)
    }
}

/// Signed distance between a body and the floor (the half-space below `z = height`); a mesh by
/// its hull, whose lowest point is the mesh's lowest vertex.
pub(super) fn measure_floor(pose_a: &Pose, a: &Geometry, height: f64) -> Measured {
    let floor_pose = Pose::from_translation(Vector::new(0.0, 0.0, height));
    // The half-space goes first: parry 0.31 mishandles it as the second shape.
    match query::contact(&floor_pose, &HalfSpace::new(Vector::Z), pose_a, a.hull_or_shape(), UNBOUNDED_M) {
        Ok(Some(contact)) => Measured::from_contact(&contact.flipped()),
        _ => touching(pose_a, &floor_pose),
    }
}

/// Signed distance between convex shapes (through [`Polished`]).
pub(super) fn measure_convex(pose_a: &Pose, a: &dyn Shape, pose_b: &Pose, b: &dyn Shape, exact_depth: bool) -> Measured {
    let pose_ab = pose_a.inv_mul(pose_b);
    let overlapping = || query::intersection_test(&Pose::IDENTITY, a, &pose_ab, b).is_ok_and(|test| test.intersecting);
    if !exact_depth && Polished::needs_polish(a, b) && overlapping() {
        let (ca, cb) = (BoundingCapsule::of_shape(a), BoundingCapsule::of_shape(b));
        let mut contact = rounded_contact(&pose_ab, (ca.start, ca.end, ca.radius), (cb.start, cb.end, cb.radius));
        contact.dist = contact.dist.min(0.0);
        contact.transform_by_mut(pose_a, pose_b);
        return Measured::from_contact(&contact);
    }
    match (Polished { polish: exact_depth }).contact(&pose_ab, a, b, UNBOUNDED_M) {
        Ok(Some(mut contact)) => {
            contact.transform_by_mut(pose_a, pose_b);
            Measured::from_contact(&contact)
        }
        // Every pair of our shapes is supported and the prediction is unbounded, so parry answers
        // `None` only when EPA fails on an overlap: count it as touching.
        _ => touching(pose_a, pose_b),
    }
}

/// Signed distance when a side is a mesh: a gap by the sphere trees (see `mesh_tree`), else
/// parry's descent; the witnesses from the nearest triangle's contact; an overlap from the
/// deepest triangle; an enclosure by a containment test on closed meshes.
fn measure_mesh(pose_a: &Pose, a: &Geometry, pose_b: &Pose, b: &Geometry, hint: &mut Option<[u32; 2]>) -> Measured {
    let separated = match (&a.tree, &b.tree) {
        (Some(tree_a), Some(tree_b)) => tree_a.gap_to_tree(pose_a, tree_b, pose_b, leaf_contact, hint),
        (Some(tree), None) => tree.gap_to_shape(pose_a, &*b.shape, pose_b, leaf_contact),
        (None, Some(tree)) => tree.gap_to_shape(pose_b, &*a.shape, pose_a, leaf_contact).map(Measured::flipped),
        (None, None) => None,
    };
    match separated {
        Some(measured) => separated_mesh(measured, pose_a, a, pose_b, b),
        None => measure_mesh_descent(pose_a, a, pose_b, b),
    }
}

/// Whether a pair comes within `margin` (m) once its `allowance` is added: [`measure_shapes`]'
/// `distance + allowance <= margin`. A pair with a mesh side is not measured when its triangles
/// touch and `allowance <= margin` (any overlap depth then decides it): the overlap's depth is
/// where parry's descent spends its EPA runs.
pub(super) fn within(pose_a: &Pose, a: &Geometry, pose_b: &Pose, b: &Geometry, margin: f64, allowance: f64) -> bool {
    let measured = |measured: Measured| measured.distance + allowance <= margin;
    if allowance > margin || !(a.is_mesh() || b.is_mesh()) {
        return measured(measure_shapes(pose_a, a, pose_b, b, false));
    }
    let separated = match (&a.tree, &b.tree) {
        (Some(tree_a), Some(tree_b)) => {
            // A pair of triangles within the margin settles it; none, and only an enclosure
            // (a closed mesh holding the other body) can bring the pair within it.
            let reach = margin - allowance;
            if tree_a.any_pair_within(pose_a, tree_b, pose_b, reach, |gap| gap + allowance <= margin) {
                return true;
            }
            let enclosed = (a.closed && a.shape.contains_point(pose_a, pose_b * b.probe))
                || (b.closed && b.shape.contains_point(pose_b, pose_a * a.probe));
            return enclosed;
        }
        (Some(tree), None) => tree.gap_to_shape(pose_a, &*b.shape, pose_b, leaf_contact),
        (None, Some(tree)) => tree.gap_to_shape(pose_b, &*a.shape, pose_a, leaf_contact).map(Measured::flipped),
        (None, None) => return measured(measure_mesh(pose_a, a, pose_b, b, &mut None)),
    };
    separated.is_none_or(|gap| measured(separated_mesh(gap, pose_a, a, pose_b, b)))
}

/// [`measure_mesh`] by parry's descent of the meshes' AABB trees: for overlaps (the deepest
/// triangle), and the oracle the sphere trees are tested against.
pub(super) fn measure_mesh_descent(pose_a: &Pose, a: &Geometry, pose_b: &Pose, b: &Geometry) -> Measured {
    let pose_ab = pose_a.inv_mul(pose_b);
    let gap = Polished::EXACT.distance(&pose_ab, &*a.shape, &*b.shape).map_or(0.0, |d| d.distance);
    let prediction = if gap > 0.0 {
        gap * (1.0 + PARRY_SLACK_RELATIVE) + PARRY_SLACK_M
    } else {
        0.0
    };
    let Ok(Some(mut contact)) = Polished::EXACT.contact(&pose_ab, &*a.shape, &*b.shape, prediction) else {
        return touching(pose_a, pose_b);
    };
    contact.transform_by_mut(pose_a, pose_b);
    let measured = Measured::from_contact(&contact);
    if gap > 0.0 && measured.distance > 0.0 {
        separated_mesh(measured, pose_a, a, pose_b, b)
    } else {
        measured
    }
}

/// A mesh pair's positive gap: the normal along the witnesses, and the sign turned when one body
/// is enclosed by the other (a mesh is a surface: a body inside a closed mesh touches no triangle).
fn separated_mesh(mut measured: Measured, pose_a: &Pose, a: &Geometry, pose_b: &Pose, b: &Geometry) -> Measured {
    measured.normal = direction(measured.point_a, measured.point_b, pose_a, pose_b);
    let enclosed =
        (a.closed && a.shape.contains_point(pose_a, pose_b * b.probe)) || (b.closed && b.shape.contains_point(pose_b, pose_a * a.probe));
    if enclosed {
        measured.distance = -measured.distance;
        measured.normal = -measured.normal;
        measured.enclosed = true;
    }
    measured
}

/// The contact of one triangle of a mesh (first, in the mesh frame) with a shape at `pos12`, as
/// parry's mesh descent measures it through [`Polished`]; `None` unless they are apart.
fn leaf_contact(pos12: &Pose, triangle: &dyn Shape, shape: &dyn Shape) -> Option<Contact> {
    Polished::EXACT
        .contact(pos12, triangle, shape, UNBOUNDED_M)
        .ok()
        .flatten()
        .filter(|contact| contact.dist > 0.0)
}

/// Unit vector from `from` to `to`; from frame to frame when the points coincide.
fn direction(from: Vector, to: Vector, pose_from: &Pose, pose_to: &Pose) -> Vector {
    (to - from)
        .try_normalize()
        .or_else(|| (pose_to.translation - pose_from.translation).try_normalize())
        .unwrap_or(Vector::Z)
}

/// What is reported when parry cannot give a depth for an overlap: touching, between the frames.
fn touching(pose_a: &Pose, pose_b: &Pose) -> Measured {
    let (point_a, point_b) = (pose_a.translation, pose_b.translation);
    Measured {
        distance: 0.0,
        point_a,
        point_b,
        normal: direction(point_a, point_b, pose_a, pose_b),
        enclosed: false,
    }
}

/// Signed distance (m) within which a support-map pair's answer is taken as possibly degenerate
/// and asked again with one shape turned by [`TURN_RAD`] (about each axis).
const DEGENERATE_M: f64 = 1e-9;
const TURN_RAD: f64 = 1e-10;

/// parry's default dispatcher, with separated support-map pairs polished and meshes traversed
/// through this dispatcher, so each triangle's distance is polished too.
pub(super) struct Polished {
    /// Polish separated support-map pairs (else GJK's answer stands, up to 1.3e-5 m long).
    polish: bool,
}

impl Polished {
    /// Every answer polished: the exact narrow phase.
    pub(super) const EXACT: Self = Self { polish: true };
}

impl Polished {
    /// Whether GJK measures this pair (so it may stop early): support maps, neither a ball.
    fn needs_polish(g1: &dyn Shape, g2: &dyn Shape) -> bool {
        g1.as_ball().is_none() && g2.as_ball().is_none() && g1.as_support_map().is_some() && g2.as_support_map().is_some()
    }
}

impl QueryDispatcher for Polished {
    fn intersection_test(&self, pos12: &Pose, g1: &dyn Shape, g2: &dyn Shape) -> Result<ShapeIntersection, Unsupported> {
        DefaultQueryDispatcher.intersection_test(pos12, g1, g2)
    }

    fn distance(&self, pos12: &Pose, g1: &dyn Shape, g2: &dyn Shape) -> Result<ShapeDistance, Unsupported> {
        if let Some(mesh) = g1.as_trimesh() {
            return Ok(distance_composite_shape_shape(self, pos12, mesh, g2));
        }
        if let Some(mesh) = g2.as_trimesh() {
            return Ok(distance_shape_composite_shape(self, pos12, g1, mesh));
        }
        if Self::needs_polish(g1, g2) {
            if let Some(contact) = self.contact(pos12, g1, g2, UNBOUNDED_M)? {
                return Ok(ShapeDistance::new(contact.dist.max(0.0)));
            }
        }
        DefaultQueryDispatcher.distance(pos12, g1, g2)
    }

    fn contact(&self, pos12: &Pose, g1: &dyn Shape, g2: &dyn Shape, prediction: Real) -> Result<Option<Contact>, Unsupported> {
        if let Some(mesh) = g1.as_trimesh() {
            return Ok(contact_composite_shape_shape(self, pos12, mesh, g2, prediction));
        }
        if let Some(mesh) = g2.as_trimesh() {
            return Ok(contact_shape_composite_shape(self, pos12, g1, mesh, prediction));
        }
        if let (Some(a), Some(b)) = (rounded(g1), rounded(g2)) {
            let contact = rounded_contact(pos12, a, b);
            return Ok((contact.dist <= prediction).then_some(contact));
        }
        if let (Some(ball), Some(cylinder)) = (g1.as_ball(), g2.as_cylinder()) {
            let contact = ball_cylinder(&pos12.inverse(), ball.radius, cylinder).flipped();
            return Ok((contact.dist <= prediction).then_some(contact));
        }
        if let (Some(cylinder), Some(ball)) = (g1.as_cylinder(), g2.as_ball()) {
            let contact = ball_cylinder(pos12, ball.radius, cylinder);
            return Ok((contact.dist <= prediction).then_some(contact));
        }
        if let Some(capsule) = g1.as_capsule() {
            let grown = prediction + capsule.radius;
            let contact = self.contact(pos12, &capsule.segment, g2, grown)?.map(|mut contact| {
                contact.dist -= capsule.radius;
                contact.point1 += contact.normal1 * capsule.radius;
                contact
            });
            return Ok(contact.filter(|contact| contact.dist <= prediction));
        }
        if let Some(capsule) = g2.as_capsule() {
            let grown = prediction + capsule.radius;
            let contact = self.contact(pos12, g1, &capsule.segment, grown)?.map(|mut contact| {
                contact.dist -= capsule.radius;
                contact.point2 += contact.normal2 * capsule.radius;
                contact
            });
            return Ok(contact.filter(|contact| contact.dist <= prediction));
        }
        if !Self::needs_polish(g1, g2) {
            return DefaultQueryDispatcher.contact(pos12, g1, g2, prediction);
        }
        let wider = if prediction >= UNBOUNDED_M / 2.0 {
            prediction
        } else {
            prediction + prediction.abs() * PARRY_SLACK_RELATIVE + PARRY_SLACK_M
        };
        let Some(mut contact) = support_map_contact(pos12, g1, g2, wider) else {
            return Ok(None);
        };
        if contact.dist.abs() < DEGENERATE_M {
            // GJK and EPA answer "touching" on some exactly degenerate overlaps (found: a
            // cylinder's end face in a plane holding the other cylinder's axis, 60 mm deep,
            // at one configuration and not at its neighbours 1e-9 rad away): a true touch is
            // as rare, so ask again with the second shape turned by a tenth of a nanoradian
            // (moving its points by far less than a nanometre) and keep a deeper answer.
            let turned = *pos12 * Pose::new(Vector::ZERO, Vector::new(TURN_RAD, -TURN_RAD, TURN_RAD));
            if let Some(again) = support_map_contact(&turned, g1, g2, wider) {
                if again.dist < contact.dist - DEGENERATE_M {
                    contact = again;
                }
            }
        }
        if contact.dist > 0.0 && self.polish {
            polish(pos12, g1, g2, &mut contact);
        }
        Ok((contact.dist <= prediction).then_some(contact))
    }

    fn closest_points(&self, pos12: &Pose, g1: &dyn Shape, g2: &dyn Shape, max_dist: Real) -> Result<ClosestPoints, Unsupported> {
        DefaultQueryDispatcher.closest_points(pos12, g1, g2, max_dist)
    }

    fn cast_shapes(
        &self,
        pos12: &Pose,
        local_vel12: Vector,
        g1: &dyn Shape,
        g2: &dyn Shape,
        options: ShapeCastOptions,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        DefaultQueryDispatcher.cast_shapes(pos12, local_vel12, g1, g2, options)
    }

    fn cast_shapes_nonlinear(
        &self,
        motion1: &NonlinearRigidMotion,
        g1: &dyn Shape,
        motion2: &NonlinearRigidMotion,
        g2: &dyn Shape,
        start_time: Real,
        end_time: Real,
        stop_at_penetration: bool,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        DefaultQueryDispatcher.cast_shapes_nonlinear(motion1, g1, motion2, g2, start_time, end_time, stop_at_penetration)
    }
}

/// parry's GJK (and EPA on overlap) for two support-map shapes, started along the line between
/// the closest points of their axes (their bounding capsules): for tubes this is nearly the
/// answer, where parry's default start, the line between the shape origins, often is not.
fn support_map_contact(pos12: &Pose, g1: &dyn Shape, g2: &dyn Shape, prediction: Real) -> Option<Contact> {
    let (s1, s2) = (g1.as_support_map()?, g2.as_support_map()?);
    let (b1, b2) = (start_capsule(g1), start_capsule(g2));
    let in1 = |p: Vector| vector_from_parry(p);
    let (c1, c2) = closest_points_of_segments(in1(b1.start), in1(b1.end), in1(pos12 * b2.start), in1(pos12 * b2.end));
    let start = parry_vector(&(c2 - c1)).try_normalize();
    let mut simplex = VoronoiSimplex::new();
    match contact_support_map_support_map_with_params(pos12, s1, s2, prediction, &mut simplex, start) {
        GJKResult::ClosestPoints(point1, point2_in1, normal1) => {
            let dist = (point2_in1 - point1).dot(normal1);
            let point2 = pos12.inverse_transform_point(point2_in1);
            let normal2 = pos12.rotation.inverse() * -normal1;
            Some(Contact::new(point1, point2, normal1, normal2, dist))
        }
        _ => None,
    }
}

/// Where GJK starts from on a shape: its bounding capsule, but a hull's origin, whose bounding
/// sphere walks every vertex (a finely tessellated mesh's hull has hundreds of thousands).
fn start_capsule(shape: &dyn Shape) -> BoundingCapsule {
    if shape.as_convex_polyhedron().is_some() {
        BoundingCapsule {
            start: Vector::ZERO,
            end: Vector::ZERO,
            radius: 0.0,
        }
    } else {
        BoundingCapsule::of_shape(shape)
    }
}

/// The closed-form contact of a cylinder (first) and a ball at `pos12` in its frame: the signed
/// distance of the ball's centre to the solid cylinder minus the radius, exact for overlaps too
/// (a convex set grown by a ball), where EPA iterates. parry's cylinders have their axis along y.
fn ball_cylinder(pos12: &Pose, radius: f64, cylinder: &Cylinder) -> Contact {
    let centre = pos12.translation;
    let (half_height, rim) = (cylinder.half_height, cylinder.radius);
    let radial = Vector::new(centre.x, 0.0, centre.z);
    let from_axis = radial.length();
    let outward = radial.try_normalize().unwrap_or(Vector::X);
    let side = outward * rim + Vector::new(0.0, centre.y, 0.0);
    let cap_sign = if centre.y >= 0.0 { 1.0 } else { -1.0 };
    let cap = Vector::new(centre.x, cap_sign * half_height, centre.z);
    let (beyond_side, beyond_cap) = (from_axis - rim, centre.y.abs() - half_height);
    let (point1, normal1, signed) = if beyond_side > 0.0 && beyond_cap > 0.0 {
        let edge = outward * rim + Vector::new(0.0, cap_sign * half_height, 0.0);
        let gap = centre - edge;
        (edge, gap.normalize(), gap.length())
    } else if beyond_side >= beyond_cap {
        (side, outward, beyond_side)
    } else {
        (cap, Vector::new(0.0, cap_sign, 0.0), beyond_cap)
    };
    let point2 = pos12.inverse_transform_point(centre - normal1 * radius);
    Contact::new(point1, point2, normal1, pos12.rotation.inverse() * -normal1, signed - radius)
}

/// A ball or capsule as its segment (shape frame) and radius.
fn rounded(shape: &dyn Shape) -> Option<(Vector, Vector, f64)> {
    if let Some(ball) = shape.as_ball() {
        return Some((Vector::ZERO, Vector::ZERO, ball.radius));
    }
    shape.as_capsule().map(|c| (c.segment.a, c.segment.b, c.radius))
}

/// The closed-form contact of two rounded segments, in the local frames of the two shapes.
fn rounded_contact(
    pos12: &Pose,
    (start1, end1, radius1): (Vector, Vector, f64),
    (start2, end2, radius2): (Vector, Vector, f64),
) -> Contact {
    let in1 = |p: Vector| vector_from_parry(p);
    let closest = capsules(in1(start1), in1(end1), radius1, in1(pos12 * start2), in1(pos12 * end2), radius2);
    let normal1 = parry_vector(&closest.normal);
    Contact::new(
        parry_vector(&closest.point_a),
        pos12.inverse_transform_point(parry_vector(&closest.point_b)),
        normal1,
        pos12.rotation.inverse() * -normal1,
        closest.distance,
    )
}

/// Alternating projections from GJK's witnesses: project the point on `g2` onto `g1`, that onto
/// `g2`, while the distance decreases and is not yet certified to [`CERTIFIED_M`]. `contact` is
/// in the local frames of `g1` and `g2`, with `g2` at `pos12` in the frame of `g1`.
fn polish(pos12: &Pose, g1: &dyn Shape, g2: &dyn Shape, contact: &mut Contact) {
    let (Some(support1), Some(support2)) = (g1.as_support_map(), g2.as_support_map()) else {
        return;
    };
    let (mut point1, mut point2) = (contact.point1, pos12 * contact.point2);
    let start = (point2 - point1).length();
    let mut distance = start;
    for _ in 0..POLISH_STEPS {
        // The supporting planes across the gap bound the distance from below.
        if let Some(normal) = ((point2 - point1) / distance).try_normalize() {
            let far2 = pos12 * support2.local_support_point(pos12.rotation.inverse() * -normal);
            let lower = normal.dot(far2 - support1.local_support_point(normal));
            if distance - lower <= CERTIFIED_M {
                break;
            }
        }
        let next1 = g1.project_local_point(point2, false).point;
        let next2 = pos12 * g2.project_local_point(pos12.inverse_transform_point(next1), false).point;
        let next = (next2 - next1).length();
        // Stop when the step does not gain (NaN included).
        if next.partial_cmp(&distance) != Some(std::cmp::Ordering::Less) {
            break;
        }
        (point1, point2, distance) = (next1, next2, next);
    }
    if distance < start {
        let Some(normal1) = (point2 - point1).try_normalize() else {
            return;
        };
        contact.dist = distance;
        contact.point1 = point1;
        contact.point2 = pos12.inverse_transform_point(point2);
        contact.normal1 = normal1;
        contact.normal2 = pos12.rotation.inverse() * -normal1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d_f64::shape::{Capsule, Cuboid, Cylinder};

    const UR5_GRIPPER: &str = "tests/fixtures/urdf/example-robot-data/robots/ur_description/urdf/ur5_gripper.urdf";

    /// A robot of the repository (to `tip`) placed in a scenario's collision world.
    fn robot_world(robot: &str, tip: &str, scenario: &str) -> (crate::model::Model, crate::collide::CollisionWorld) {
        use crate::pipeline::{collision_world, load_model, LoadOptions};
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let opts = LoadOptions {
            tip_link: Some(tip.into()),
            ..Default::default()
        };
        let model = load_model(&root.join(robot), &opts).expect("robot loads");
        let scenario = crate::scenario::load(&root.join(scenario)).expect("shipped scenario loads");
        let model = model.placed(&scenario.world_from_base);
        let world = collision_world(&model, &scenario, &[]).expect("valid world");
        (model, world)
    }

    /// Every candidate of `world` but the floor's at the link poses `ws` holds: its index, then
    /// each side's pose and geometry.
    fn each_shape_pair(
        world: &crate::collide::CollisionWorld,
        ws: &crate::model::KinematicsWorkspace,
        mut visit: impl FnMut(usize, &Pose, &Geometry, &Pose, &Geometry),
    ) {
        use crate::collide::world::Other;
        let pose = |i: usize| crate::frames::parry_pose(&ws.link_in_world[world.colliders[i].link]) * world.colliders[i].link_from_shape;
        for (index, candidate) in world.candidates.iter().enumerate() {
            let (pose_b, b) = match candidate.b {
                Other::Link(j) => (pose(j), &world.colliders[j].geometry),
                Other::Obstacle(k) => (world.obstacles[k].world_from_shape, &world.obstacles[k].geometry),
                Other::Floor => continue,
            };
            visit(index, &pose(candidate.a), &world.colliders[candidate.a].geometry, &pose_b, b);
        }
    }

    /// The trees against parry's descent of every triangle (the oracle), on every mesh pair and
    /// mesh-obstacle pair of two real robots, at random configurations: same distances, and
    /// witnesses at that distance.
    #[test]
    fn trees_measure_what_parry_descent_measures_on_real_robots() {
        use rand::SeedableRng;
        let robots = [
            (
                "designs/urdf/example-robot-data/robots/panda_description/urdf/panda.urdf",
                "panda_hand",
                "scenarios/course.json",
            ),
            (
                "tests/fixtures/urdf/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf",
                "tool0",
                "scenarios/cluttered/task-00.json",
            ),
        ];
        let (mut separated, mut compared) = (0, 0);
        for (robot, tip, scenario) in robots {
            let (model, world) = robot_world(robot, tip, scenario);
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
            let mut ws = model.workspace();
            for _ in 0..16 {
                model.forward(&model.random_configuration(&mut rng), &mut ws);
                each_shape_pair(&world, &ws, |index, pose_a, a, pose_b, b| {
                    if !a.is_mesh() && !b.is_mesh() {
                        return;
                    }
                    let fast = measure_shapes(pose_a, a, pose_b, b, true);
                    let oracle = measure_mesh_descent(pose_a, a, pose_b, b);
                    compared += 1;
                    separated += usize::from(oracle.distance > 0.0);
                    assert!(
                        (fast.distance - oracle.distance).abs() < 1e-9,
                        "{robot}: candidate {index}: trees {} m, parry {} m",
                        fast.distance,
                        oracle.distance
                    );
                    let witnesses = (fast.point_b - fast.point_a).length();
                    assert!(
                        (witnesses - fast.distance.abs()).abs() < 1e-9,
                        "witnesses {witnesses} m apart, distance {}",
                        fast.distance
                    );
                });
            }
        }
        assert!(
            separated > 400 && compared > separated,
            "{separated} separated of {compared} compared"
        );
    }

    /// A mesh pair's hint (its nearest triangles at a nearby pose, any other pair, or indices of
    /// no triangle) changes nothing in the answer, bit for bit, along short paths of a real robot.
    #[test]
    fn a_hint_changes_no_answer() {
        use rand::{Rng, SeedableRng};
        let (model, world) = robot_world(UR5_GRIPPER, "tool0", "scenarios/cluttered/task-00.json");
        let bits = |m: &Measured| {
            let v = |x: Vector| x.to_array().map(f64::to_bits);
            (m.distance.to_bits(), v(m.point_a), v(m.point_b), v(m.normal), m.enclosed)
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut ws = model.workspace();
        let mut hints = vec![None; world.candidates.len()];
        let (mut compared, mut hinted) = (0, 0);
        for path in 0..12 {
            let mut q = model.random_configuration(&mut rng);
            let step: Vec<f64> = q.iter().map(|_| rng.random_range(-0.02..0.02)).collect();
            for _ in 0..8 {
                q.iter_mut().zip(&step).for_each(|(x, d)| *x += d);
                model.forward(&q, &mut ws);
                each_shape_pair(&world, &ws, |index, pose_a, a, pose_b, b| {
                    if !(a.is_mesh() && b.is_mesh()) {
                        return;
                    }
                    let plain = measure_shapes(pose_a, a, pose_b, b, true);
                    // Every third path: a random pair, or indices beyond the meshes.
                    if path % 3 == 1 {
                        hints[index] = Some([rng.random_range(0..400), rng.random_range(0..400)]);
                    } else if path % 3 == 2 {
                        hints[index] = Some([u32::MAX, 7]);
                    }
                    hinted += usize::from(hints[index].is_some());
                    let with_hint = measure_shapes_hinted(pose_a, a, pose_b, b, true, &mut hints[index]);
                    assert_eq!(bits(&plain), bits(&with_hint), "candidate {index} on path {path}");
                    compared += 1;
                });
            }
        }
        assert!(compared > 500 && hinted > compared / 2, "{hinted} hinted of {compared}");
    }

    /// `within` answers as the measured distance does, for every mesh pair and mesh-obstacle
    /// pair of a real robot at random configurations, margins and allowances (overlapping,
    /// touching within a margin, and apart).
    #[test]
    fn within_answers_as_the_measured_distance() {
        use rand::SeedableRng;
        let (model, world) = robot_world(UR5_GRIPPER, "tool0", "scenarios/cluttered/task-00.json");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let mut ws = model.workspace();
        let mut counts = [0usize; 2];
        for _ in 0..40 {
            model.forward(&model.random_configuration(&mut rng), &mut ws);
            each_shape_pair(&world, &ws, |index, pose_a, a, pose_b, b| {
                let distance = measure_shapes(pose_a, a, pose_b, b, false).distance;
                for (margin, allowance) in [(0.0, 0.0), (0.005, 0.0), (0.03, 0.01), (0.0, 0.02), (0.1, 0.0)] {
                    let expected = distance + allowance <= margin;
                    assert_eq!(
                        within(pose_a, a, pose_b, b, margin, allowance),
                        expected,
                        "candidate {index}: distance {distance} m, margin {margin}, allowance {allowance}"
                    );
                    counts[usize::from(expected)] += 1;
                }
            });
        }
        assert!(counts[0] > 200 && counts[1] > 200, "{counts:?} (apart, within)");
    }

    #[test]
    fn floor_contact_is_the_lowest_point_whichever_way_the_shape_is_turned() {
        let geometry = Geometry {
            shape: parry3d_f64::shape::SharedShape::new(Cuboid::new(Vector::new(0.1, 0.2, 0.3))),
            hull: None,
            tree: None,
            hull_bounds: true,
            closed: false,
            probe: Vector::ZERO,
            bounding: BoundingCapsule::of_shape(&Cuboid::new(Vector::new(0.1, 0.2, 0.3))),
        };
        // Turned a quarter turn about x, the 0.2 half extent points down; centre at z = 1.
        let pose = Pose::new(Vector::new(0.5, -0.5, 1.0), Vector::new(std::f64::consts::FRAC_PI_2, 0.0, 0.0));
        let measured = measure_floor(&pose, &geometry, 0.25);
        assert!((measured.distance - (1.0 - 0.2 - 0.25)).abs() < 1e-12, "{measured:?}");
        assert!((measured.normal + Vector::Z).length() < 1e-12, "{measured:?}");
        assert!((measured.point_b.z - 0.25).abs() < 1e-12, "{measured:?}");
    }

    #[test]
    fn polishing_brings_crossed_cylinders_to_the_closed_form() {
        // Cylinders along x and along y (parry's axis is y), 0.3 m apart between axes.
        let (a, b) = (Cylinder::new(0.3, 0.05), Cylinder::new(0.3, 0.07));
        let pose_a = Pose::new(Vector::ZERO, Vector::new(0.0, 0.0, std::f64::consts::FRAC_PI_2));
        let pose_b = Pose::from_translation(Vector::new(0.01, 0.02, 0.3));
        let expected = 0.3 - 0.05 - 0.07;
        let contact = Polished::EXACT
            .contact(&pose_a.inv_mul(&pose_b), &a, &b, UNBOUNDED_M)
            .expect("supported")
            .expect("unbounded");
        assert!((contact.dist - expected).abs() < CERTIFIED_M, "{} vs {expected}", contact.dist);
    }

    #[test]
    fn a_capsule_is_its_segment_grown_by_its_radius() {
        let capsule = Capsule::new_z(0.2, 0.05);
        let block = Cuboid::new(Vector::new(0.3, 0.3, 0.1));
        // Capsule axis from z = 0.4 to 0.8 above a box whose top is at z = 0.1.
        let measured = measure_convex(
            &Pose::from_translation(Vector::new(0.0, 0.0, 0.6)),
            &capsule,
            &Pose::IDENTITY,
            &block,
            true,
        );
        assert!((measured.distance - (0.4 - 0.05 - 0.1)).abs() < 1e-12, "{measured:?}");
        assert!((measured.point_a.z - 0.35).abs() < 1e-12 && (measured.point_b.z - 0.1).abs() < 1e-12);
        // Pushed down through the top face: a penetration of the segment itself.
        let measured = measure_convex(
            &Pose::from_translation(Vector::new(0.0, 0.0, 0.25)),
            &capsule,
            &Pose::IDENTITY,
            &block,
            true,
        );
        assert!((measured.distance + (0.1 - 0.05 + 0.05)).abs() < 1e-12, "{measured:?}");
    }

    #[test]
    fn ball_cylinder_closed_form_agrees_with_gjk_and_epa_in_both_orders() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let cylinder = Cylinder::new(0.2, 0.06);
        let (mut apart, mut overlapping) = (0, 0);
        for _ in 0..2000 {
            let ball = parry3d_f64::shape::Ball::new(rng.random_range(0.02..0.15));
            let centre = Vector::new(0.1, -0.2, 0.3)
                + Vector::new(
                    rng.random_range(-0.2..0.2),
                    rng.random_range(-0.2..0.2),
                    rng.random_range(-0.2..0.2),
                );
            let turn = Vector::new(
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
            );
            let (pose_c, pose_b) = (Pose::new(Vector::new(0.1, -0.2, 0.3), turn), Pose::from_translation(centre));
            let reference = match support_map_contact(&pose_c.inv_mul(&pose_b), &cylinder, &ball, UNBOUNDED_M) {
                Some(mut contact) if contact.dist > 0.0 => {
                    polish(&pose_c.inv_mul(&pose_b), &cylinder, &ball, &mut contact);
                    apart += 1;
                    contact.dist
                }
                Some(contact) => {
                    overlapping += 1;
                    contact.dist
                }
                None => continue,
            };
            let forward = measure_convex(&pose_c, &cylinder, &pose_b, &ball, true);
            let backward = measure_convex(&pose_b, &ball, &pose_c, &cylinder, true);
            // Polished GJK is certified to 1e-10 m; EPA stops on a polytope inside the curved
            // side, measured here up to 1.5e-6 m off.
            let tolerance = if reference > 0.0 { 1e-9 } else { 1e-5 };
            assert!(
                (forward.distance - reference).abs() < tolerance,
                "{} vs {reference}",
                forward.distance
            );
            assert_eq!(forward.distance, backward.distance);
            // Witnesses: on the surfaces, the gap between them the distance along the normal.
            let gap = forward.point_b - forward.point_a;
            assert!((gap.dot(forward.normal) - forward.distance).abs() < 1e-12);
            assert!(((forward.point_b - centre).length() - ball.radius).abs() < 1e-12);
            assert!((backward.normal + forward.normal).length() < 1e-12);
        }
        assert!(apart > 300 && overlapping > 300, "{apart} apart, {overlapping} overlapping");
    }
}
