//! The bottom of `collide/`: closed forms (capsule and triangle distances), the constants every
//! query shares, and [`Measured`], the one measured distance with witnesses. Everything else in
//! the stage builds on it; it imports nothing of the stage.
//!
//! Two triangles apart are nearest at a vertex of one against the other or at two edges
//! (Ericson, Real-Time Collision Detection, 5.1): about 15 closed forms where GJK iterates, for
//! ranking triangle pairs in a mesh descent.

use crate::frames::closest_points_of_segments;
use nalgebra::Vector3;
use parry3d_f64::math::Vector;
use parry3d_f64::query::Contact;

/// Subtracted from every AABB bound (m): the bound and a narrow phase round differently, and a
/// bound a rounding error above the distance it bounds could skip the closest pair.
pub(super) const BOUND_ROUNDING_M: f64 = 1e-9;

/// A key whose unsigned order is the total order of `value`.
pub(super) fn order_key(value: f64) -> u64 {
    let bits = value.to_bits();
    if bits >> 63 == 1 {
        !bits
    } else {
        bits | 1 << 63
    }
}

/// A measured signed distance in parry's types, world frame.
#[derive(Debug, Clone, Copy)]
pub(super) struct Measured {
    pub(super) distance: f64,
    pub(super) point_a: Vector,
    pub(super) point_b: Vector,
    /// Unit, from `a` to `b`.
    pub(super) normal: Vector,
    pub(super) enclosed: bool,
}

impl Measured {
    /// The same measurement with the bodies swapped.
    pub(super) fn flipped(self) -> Self {
        Self {
            point_a: self.point_b,
            point_b: self.point_a,
            normal: -self.normal,
            ..self
        }
    }

    pub(super) fn from_contact(contact: &Contact) -> Self {
        Self {
            distance: contact.dist,
            point_a: contact.point1,
            point_b: contact.point2,
            normal: contact.normal1,
            enclosed: false,
        }
    }
}

/// A signed distance with witness points and the unit normal from `a` to `b` (world frame, m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Closest {
    pub(crate) distance: f64,
    pub(crate) point_a: Vector3<f64>,
    pub(crate) point_b: Vector3<f64>,
    pub(crate) normal: Vector3<f64>,
}

/// Signed distance between capsules (segment ends in the world, radii in m); a zero-length
/// segment is a sphere.
pub(crate) fn capsules(
    start_a: Vector3<f64>,
    end_a: Vector3<f64>,
    radius_a: f64,
    start_b: Vector3<f64>,
    end_b: Vector3<f64>,
    radius_b: f64,
) -> Closest {
    let (centre_a, centre_b) = closest_points_of_segments(start_a, end_a, start_b, end_b);
    let between = centre_b - centre_a;
    let length = between.norm();
    let normal = if length > 0.0 {
        between / length
    } else {
        // The axes cross: any direction across axis a separates them.
        perpendicular(end_a - start_a)
            .or_else(|| perpendicular(end_b - start_b))
            .unwrap_or(Vector3::z())
    };
    Closest {
        distance: length - radius_a - radius_b,
        point_a: centre_a + normal * radius_a,
        point_b: centre_b - normal * radius_b,
        normal,
    }
}

/// A unit vector perpendicular to `axis`, if `axis` is not zero.
fn perpendicular(axis: Vector3<f64>) -> Option<Vector3<f64>> {
    let axis = axis.try_normalize(0.0)?;
    let helper = if axis.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    Some(axis.cross(&helper).normalize())
}

/// The distance between two triangles (m), or `None` when they intersect: an edge of one
/// crosses the other (two triangles that meet always do, or touch at distance 0).
pub(super) fn triangle_distance(a: &[Vector; 3], b: &[Vector; 3]) -> Option<f64> {
    if edges_cross(a, b) || edges_cross(b, a) {
        return None;
    }
    let mut best = f64::INFINITY;
    for i in 0..3 {
        let (p, q) = (a[i], a[(i + 1) % 3]);
        for j in 0..3 {
            best = best.min(segment_segment(p, q, b[j], b[(j + 1) % 3]));
        }
        best = best.min((closest_on_triangle(a[i], b) - a[i]).length_squared());
        best = best.min((closest_on_triangle(b[i], a) - b[i]).length_squared());
    }
    Some(best.sqrt())
}

/// Whether an edge of `a` crosses the plane of `b` inside `b` (Moeller-Trumbore); an edge in
/// the plane of `b` is not tested: a crossing then shows as a zero distance between edges.
fn edges_cross(a: &[Vector; 3], b: &[Vector; 3]) -> bool {
    let (e1, e2) = (b[1] - b[0], b[2] - b[0]);
    (0..3).any(|i| {
        let (start, end) = (a[i], a[(i + 1) % 3]);
        let dir = end - start;
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() <= f64::EPSILON * e1.length() * e2.length() * dir.length() {
            return false;
        }
        let inv = 1.0 / det;
        let t = start - b[0];
        let u = t.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return false;
        }
        let qv = t.cross(e1);
        let v = dir.dot(qv) * inv;
        if v < 0.0 || u + v > 1.0 {
            return false;
        }
        let s = e2.dot(qv) * inv;
        (0.0..=1.0).contains(&s)
    })
}

/// Squared distance between segments `p1 q1` and `p2 q2` (Ericson 5.1.9).
pub(super) fn segment_segment(p1: Vector, q1: Vector, p2: Vector, q2: Vector) -> f64 {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    let (s, t) = if a <= f64::EPSILON && e <= f64::EPSILON {
        (0.0, 0.0)
    } else if a <= f64::EPSILON {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= f64::EPSILON {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    ((p1 + d1 * s) - (p2 + d2 * t)).length_squared()
}

/// The point of triangle `t` closest to `p` (Ericson 5.1.5).
fn closest_on_triangle(p: Vector, t: &[Vector; 3]) -> Vector {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d_f64::math::Pose;
    use parry3d_f64::query;
    use parry3d_f64::shape::Triangle;
    use rand::{Rng, SeedableRng};

    #[test]
    fn skew_segments_meet_at_their_common_perpendicular() {
        let (a, b) = closest_points_of_segments(
            Vector3::new(-1.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.3, -1.0, 2.0),
            Vector3::new(0.3, 1.0, 2.0),
        );
        assert!((a - Vector3::new(0.3, 0.0, 0.0)).norm() < 1e-15, "{a}");
        assert!((b - Vector3::new(0.3, 0.0, 2.0)).norm() < 1e-15, "{b}");
    }

    #[test]
    fn parallel_and_point_segments_are_handled() {
        let (a, b) = closest_points_of_segments(
            Vector3::zeros(),
            Vector3::x(),
            Vector3::new(0.5, 1.0, 0.0),
            Vector3::new(3.0, 1.0, 0.0),
        );
        assert!(((b - a).norm() - 1.0).abs() < 1e-15, "{a} {b}");
        let point = Vector3::new(0.2, 0.3, 0.4);
        let (a, b) = closest_points_of_segments(point, point, Vector3::zeros(), Vector3::z());
        assert_eq!((a, b), (point, Vector3::new(0.0, 0.0, 0.4)));
        let (a, b) = closest_points_of_segments(Vector3::zeros(), Vector3::z(), point, point);
        assert_eq!((a, b), (Vector3::new(0.0, 0.0, 0.4), point));
    }

    #[test]
    fn crossing_capsules_penetrate_by_both_radii() {
        let closest = capsules(-Vector3::x(), Vector3::x(), 0.1, -Vector3::y(), Vector3::y(), 0.2);
        assert!((closest.distance + 0.3).abs() < 1e-15);
        assert!((closest.normal.norm() - 1.0).abs() < 1e-15);
        assert!(closest.normal.x.abs() < 1e-15);
    }

    /// Against parry's GJK (exact on polytopes) on random triangle pairs, apart and crossing.
    #[test]
    fn agrees_with_gjk_and_finds_every_crossing() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut point = |spread: f64| {
            Vector::new(
                rng.random_range(-spread..spread),
                rng.random_range(-spread..spread),
                rng.random_range(-spread..spread),
            )
        };
        let (mut apart, mut crossing) = (0, 0);
        for _ in 0..20_000 {
            let a = [point(0.1), point(0.1), point(0.1)];
            let offset = point(0.15);
            let b = [offset + point(0.1), offset + point(0.1), offset + point(0.1)];
            let gjk = query::distance(
                &Pose::IDENTITY,
                &Triangle::new(a[0], a[1], a[2]),
                &Pose::IDENTITY,
                &Triangle::new(b[0], b[1], b[2]),
            )
            .expect("triangles are supported")
            .distance;
            match triangle_distance(&a, &b) {
                Some(distance) => {
                    apart += 1;
                    assert!((distance - gjk).abs() < 1e-9, "closed form {distance}, GJK {gjk}");
                }
                None => {
                    crossing += 1;
                    assert!(gjk < 1e-9, "reported crossing, GJK says {gjk} apart");
                }
            }
        }
        assert!(
            apart > 1000 && crossing > 500,
            "both cases drawn: {apart} apart, {crossing} crossing"
        );
    }
}
