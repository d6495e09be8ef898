//! Bounding-sphere trees over a mesh's triangles, for the exact gap between a mesh and another
//! shape without visiting most of its triangles.
//!
//! parry measures a mesh against a shape by descending the mesh's AABB tree against the shape's
//! AABB in the mesh frame, and a mesh against a mesh by running that whole descent once per
//! triangle of the first mesh. Both bounds are loose for turned shapes (an AABB of a turned box
//! or of a whole mesh), so most triangles of two links 15 mm apart end in GJK. A sphere does not
//! grow when turned, and a dual descent of two trees bounds a pair of nodes by the gap between
//! their spheres; a node against a convex shape is bounded by the exact distance from the
//! sphere's centre to the shape minus the radius. Leaves are measured with the same narrow phase
//! as before, triangle by triangle, so the gap and its witnesses are the same as parry's descent
//! gives (the minimum over the same triangle contacts); only the number of triangles measured
//! changes.
//!
//! Only separated pairs are answered here: when a measured triangle touches or overlaps the
//! other shape, the caller falls back to parry's descent, which gives the deepest triangle.

use super::primitives::{order_key, segment_segment, triangle_distance, Measured, BOUND_ROUNDING_M};
use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::query::Contact;
use parry3d_f64::shape::{Shape, SupportMap, Triangle};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Triangles per leaf: two measured leaves cost up to this squared in triangle contacts.
const LEAF_TRIANGLES: usize = 4;

/// A sphere tree over the triangles of one mesh, in the mesh's frame.
#[derive(Debug, Clone)]
pub(super) struct SphereTree {
    nodes: Vec<Node>,
    /// The mesh's triangles, ordered so that each leaf holds a contiguous range.
    triangles: Vec<Triangle>,
    /// Each triangle's bounding sphere (centre, radius), in the same order.
    spheres: Vec<(Vector, f64)>,
    /// Each triangle's unit normal (zero for a degenerate one), in the same order.
    normals: Vec<Vector>,
}

#[derive(Debug, Clone, Copy)]
struct Node {
    center: Vector,
    radius: f64,
    /// A capsule containing the node: a segment along its vertices' principal axis and the
    /// largest distance of a vertex from it; far tighter than the sphere for the long strips of
    /// a tube's surface.
    axis: [Vector; 2],
    axis_radius: f64,
    /// Children (inner node), or `None` for a leaf.
    children: Option<(u32, u32)>,
    /// The node's triangles: `triangles[first..first + count]`.
    first: u32,
    count: u32,
}

impl SphereTree {
    /// The tree of a mesh given by its vertices and triangles (indices checked by the caller).
    pub(super) fn new(vertices: &[Vector], indices: &[[u32; 3]]) -> Self {
        let triangles: Vec<Triangle> = indices
            .iter()
            .map(|t| Triangle::new(vertices[t[0] as usize], vertices[t[1] as usize], vertices[t[2] as usize]))
            .collect();
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * triangles.len() / LEAF_TRIANGLES + 1);
        build(&triangles, &mut order, 0, &mut nodes);
        let triangles: Vec<Triangle> = order.iter().map(|&i| triangles[i as usize]).collect();
        let spheres = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = *t.vertices();
                let centre = (a.min(b).min(c) + a.max(b).max(c)) / 2.0;
                (centre, t.vertices().iter().map(|v| (v - centre).length()).fold(0.0, f64::max))
            })
            .collect();
        let normals = triangles.iter().map(normal).collect();
        Self {
            nodes,
            triangles,
            spheres,
            normals,
        }
    }

    /// The exact gap between this mesh at `pose` and a convex (non-mesh) `shape` at `pose_other`,
    /// with witnesses; `None` when a triangle touches or overlaps the shape.
    ///
    /// `leaf` measures one triangle (first, mesh frame) against the shape at a relative pose,
    /// `None` unless they are apart: the narrow phase's query.
    pub(super) fn gap_to_shape(
        &self,
        pose: &Pose,
        shape: &dyn Shape,
        pose_other: &Pose,
        leaf: impl Fn(&Pose, &dyn Shape, &dyn Shape) -> Option<Contact>,
    ) -> Option<Measured> {
        // Everything in the mesh frame; the shape at `pos12` there.
        let pos12 = pose.inv_mul(pose_other);
        let bound = |node: &Node| {
            let centre = pos12.inverse_transform_point(node.center);
            shape.distance_to_local_point(centre, true) - node.radius - BOUND_ROUNDING_M
        };
        let support = shape.as_support_map();
        let mut best: Option<Contact> = None;
        let mut queue = BinaryHeap::with_capacity(32);
        queue.push(Reverse((order_key(bound(&self.nodes[0])), 0u32)));
        while let Some(Reverse((key, index))) = queue.pop() {
            if best.is_some_and(|best| key >= order_key(best.dist)) {
                break;
            }
            let node = &self.nodes[index as usize];
            match node.children {
                Some((left, right)) => {
                    for child in [left, right] {
                        let key = order_key(bound(&self.nodes[child as usize]));
                        if best.is_none_or(|best| key < order_key(best.dist)) {
                            queue.push(Reverse((key, child)));
                        }
                    }
                }
                None => {
                    for (triangle, (_, placed)) in self.leaf(node).iter().zip(self.leaf_bounds(node)) {
                        // A triangle's own sphere, then the shape's extent across the triangle's
                        // plane, before its contact (GJK).
                        if let Some(best) = &best {
                            let centre = pos12.inverse_transform_point(placed.centre);
                            let sphere = shape.distance_to_local_point(centre, true) - placed.radius - BOUND_ROUNDING_M;
                            if sphere >= best.dist || support.is_some_and(|support| plane_gap(&placed, support, &pos12) >= best.dist) {
                                continue;
                            }
                        }
                        let contact = leaf(&pos12, triangle, shape)?;
                        if best.is_none_or(|best| contact.dist < best.dist) {
                            best = Some(contact);
                        }
                    }
                }
            }
        }
        best.map(|mut contact| {
            contact.transform_by_mut(pose, pose_other);
            Measured::from_contact(&contact)
        })
    }

    /// The exact gap between this mesh at `pose` and `other` at `pose_other`, with witnesses;
    /// `None` when two triangles touch or overlap.
    ///
    /// `leaf` measures two triangles as in [`SphereTree::gap_to_shape`]. `hint` is a triangle
    /// pair (this mesh's, `other`'s) that was nearest at a nearby pose, and becomes the nearest
    /// pair of this one. Its gap here starts the search's bound, so that along a path most nodes
    /// are pruned at once; the answer does not depend on it (see the comment at its use).
    pub(super) fn gap_to_tree(
        &self,
        pose: &Pose,
        other: &SphereTree,
        pose_other: &Pose,
        leaf: impl Fn(&Pose, &dyn Shape, &dyn Shape) -> Option<Contact>,
        hint: &mut Option<[u32; 2]>,
    ) -> Option<Measured> {
        let pos12 = pose.inv_mul(pose_other);
        let bound = |a: &Node, b: &Node, best: f64| node_pair_bound(a, b, &pos12, best);
        // Triangle pairs are ranked by the closed form; the nearest is then measured as parry's
        // descent measures it, so its witnesses are the same.
        let mut best_distance = f64::INFINITY;
        let mut nearest: Option<(u32, u32)> = None;
        // The hinted pair's gap `c`, computed exactly as the search computes it, is at least the
        // smallest gap `m`. Starting the bound just above `c` prunes only nodes and pairs whose
        // bounds exceed `m`; the first pair at `m` in the queue's order is still visited and still
        // replaces the bound (strictly below it), and later ties still do not: the same pair wins
        // as without a hint. A touching hinted pair means touching meshes, which the search
        // would find anyway.
        if let Some([ia, ib]) = *hint {
            if let (Some(ta), Some(tb)) = (self.triangles.get(ia as usize), other.triangles.get(ib as usize)) {
                let moved = tb.vertices().map(|v| pos12 * v);
                best_distance = triangle_distance(ta.vertices(), &moved)?.next_up();
            }
        }
        let mut queue = BinaryHeap::with_capacity(64);
        queue.push(Reverse((
            order_key(bound(&self.nodes[0], &other.nodes[0], f64::INFINITY)),
            0u32,
            0u32,
        )));
        while let Some(Reverse((key, ia, ib))) = queue.pop() {
            if key >= order_key(best_distance) {
                break;
            }
            let (a, b) = (&self.nodes[ia as usize], &other.nodes[ib as usize]);
            let Some(split_a) = split_first(a, b) else {
                let moved = other.moved_leaf(b, &pos12);
                for (index_a, ta) in self.leaf_bounds(a) {
                    for (index_b, tb) in (b.first..).zip(&moved[..b.count as usize]) {
                        if apart(&ta, tb, best_distance) {
                            continue;
                        }
                        let distance = triangle_distance(&ta.vertices, &tb.vertices)?;
                        if distance < best_distance {
                            best_distance = distance;
                            nearest = Some((index_a, index_b));
                        }
                    }
                }
                continue;
            };
            let (left, right) = if split_a { a.children } else { b.children }.expect("the split node is inner");
            for child in [left, right] {
                let (ca, cb) = if split_a { (child, ib) } else { (ia, child) };
                let key = order_key(bound(&self.nodes[ca as usize], &other.nodes[cb as usize], best_distance));
                if key < order_key(best_distance) {
                    queue.push(Reverse((key, ca, cb)));
                }
            }
        }
        let (ia, ib) = nearest?;
        *hint = Some([ia, ib]);
        let mut contact = leaf(&pos12, &self.triangles[ia as usize], &other.triangles[ib as usize])?;
        contact.transform_by_mut(pose, pose_other);
        Some(Measured::from_contact(&contact))
    }

    /// Whether some triangle pair of this mesh at `pose` and `other` at `pose_other` touches or
    /// has a gap `d` with `accept(d)`, looking only where a gap can be at most `reach` (m): the
    /// question [`SphereTree::gap_to_tree`] answers through the smallest gap, decided at the
    /// first pair that settles it. `accept` must hold only for gaps up to `reach`.
    pub(super) fn any_pair_within(
        &self,
        pose: &Pose,
        other: &SphereTree,
        pose_other: &Pose,
        reach: f64,
        accept: impl Fn(f64) -> bool,
    ) -> bool {
        let pos12 = pose.inv_mul(pose_other);
        // A bound beyond `reach` prunes: at least the next number above it.
        let cutoff = (reach + BOUND_ROUNDING_M).next_up();
        let bound = |a: &Node, b: &Node| node_pair_bound(a, b, &pos12, cutoff);
        let mut stack = Vec::with_capacity(64);
        if bound(&self.nodes[0], &other.nodes[0]) < cutoff {
            stack.push((0u32, 0u32));
        }
        while let Some((ia, ib)) = stack.pop() {
            let (a, b) = (&self.nodes[ia as usize], &other.nodes[ib as usize]);
            let Some(split_a) = split_first(a, b) else {
                let moved = other.moved_leaf(b, &pos12);
                for (_, ta) in self.leaf_bounds(a) {
                    for tb in &moved[..b.count as usize] {
                        if !apart(&ta, tb, cutoff) && triangle_distance(&ta.vertices, &tb.vertices).is_none_or(&accept) {
                            return true;
                        }
                    }
                }
                continue;
            };
            let (left, right) = if split_a { a.children } else { b.children }.expect("the split node is inner");
            for child in [left, right] {
                let (ca, cb) = if split_a { (child, ib) } else { (ia, child) };
                if bound(&self.nodes[ca as usize], &other.nodes[cb as usize]) < cutoff {
                    stack.push((ca, cb));
                }
            }
        }
        false
    }

    /// Leaf `node`'s triangles with their indices, bounding spheres and normals, in this mesh's
    /// frame.
    fn leaf_bounds(&self, node: &Node) -> impl Iterator<Item = (u32, Placed)> + '_ {
        (node.first..node.first + node.count).map(|index| {
            let i = index as usize;
            let (centre, radius) = self.spheres[i];
            let placed = Placed {
                vertices: *self.triangles[i].vertices(),
                centre,
                radius,
                normal: self.normals[i],
            };
            (index, placed)
        })
    }

    /// [`Self::leaf_bounds`] moved by `pos12` (into the other mesh's frame), once for a whole
    /// leaf pair; the first `node.count` entries are filled.
    fn moved_leaf(&self, node: &Node, pos12: &Pose) -> [Placed; LEAF_TRIANGLES] {
        let mut moved = [Placed::default(); LEAF_TRIANGLES];
        for (slot, (_, placed)) in moved.iter_mut().zip(self.leaf_bounds(node)) {
            *slot = Placed {
                vertices: placed.vertices.map(|v| pos12 * v),
                centre: pos12 * placed.centre,
                radius: placed.radius,
                normal: pos12.rotation * placed.normal,
            };
        }
        moved
    }

    fn leaf(&self, node: &Node) -> &[Triangle] {
        &self.triangles[node.first as usize..(node.first + node.count) as usize]
    }
}

/// A triangle with its bounding sphere and unit normal, in some mesh's frame.
#[derive(Debug, Clone, Copy, Default)]
struct Placed {
    vertices: [Vector; 3],
    centre: Vector,
    radius: f64,
    normal: Vector,
}

/// A lower bound on the gap between two nodes' triangles (`b` at `pos12` in `a`'s frame): the
/// spheres' gap (cheap), and the capsules' only when the spheres' stays below `cutoff`.
fn node_pair_bound(a: &Node, b: &Node, pos12: &Pose, cutoff: f64) -> f64 {
    let spheres = (pos12 * b.center - a.center).length() - a.radius - b.radius - BOUND_ROUNDING_M;
    if spheres >= cutoff {
        return spheres;
    }
    let axis = segment_segment(a.axis[0], a.axis[1], pos12 * b.axis[0], pos12 * b.axis[1]).sqrt();
    spheres.max(axis - a.axis_radius - b.axis_radius - BOUND_ROUNDING_M)
}

/// Which node of a pair to split: `a` (true), `b`, or `None` for two leaves. The larger one,
/// so both sides shrink at the same pace.
fn split_first(a: &Node, b: &Node) -> Option<bool> {
    match (a.children, b.children) {
        (None, None) => None,
        (Some(_), None) => Some(true),
        (None, Some(_)) => Some(false),
        (Some(_), Some(_)) => Some(a.radius >= b.radius),
    }
}

/// Whether triangles `a` and `b` (in one frame) are at least `cutoff` apart by their spheres or
/// by their projections, without measuring them.
fn apart(a: &Placed, b: &Placed, cutoff: f64) -> bool {
    let between = b.centre - a.centre;
    between.length() - a.radius - b.radius - BOUND_ROUNDING_M >= cutoff || separation(a, b, between) >= cutoff
}

/// A lower bound on the distance between a triangle and a convex shape at `pos12` (the
/// triangle's frame): how far the shape lies beyond the triangle's plane, on either side.
fn plane_gap(triangle: &Placed, support: &dyn SupportMap, pos12: &Pose) -> f64 {
    let (a, normal) = (triangle.vertices[0], triangle.normal);
    let extreme = |direction: Vector| pos12 * support.local_support_point(pos12.rotation.inverse() * direction);
    let above = normal.dot(extreme(-normal) - a);
    let below = normal.dot(a - extreme(normal));
    above.max(below) - BOUND_ROUNDING_M
}

/// A lower bound on the distance between two triangles: the gap between their projections on
/// the line through their spheres' centres and on each one's normal (a gap along any axis is).
fn separation(a: &Placed, b: &Placed, centres: Vector) -> f64 {
    let gap = |axis: Vector| {
        let (pa, pb) = (a.vertices.map(|v| v.dot(axis)), b.vertices.map(|v| v.dot(axis)));
        let (lo_a, hi_a) = (pa[0].min(pa[1]).min(pa[2]), pa[0].max(pa[1]).max(pa[2]));
        let (lo_b, hi_b) = (pb[0].min(pb[1]).min(pb[2]), pb[0].max(pb[1]).max(pb[2]));
        (lo_b - hi_a).max(lo_a - hi_b)
    };
    let along = centres.normalize_or_zero();
    gap(along).max(gap(a.normal)).max(gap(b.normal)) - BOUND_ROUNDING_M
}

/// A triangle's unit normal, zero when it is degenerate.
fn normal(triangle: &Triangle) -> Vector {
    let [a, b, c] = *triangle.vertices();
    (b - a).cross(c - a).normalize_or_zero()
}

/// Builds the subtree over `order` (a range of triangle indices starting at `first` in the final
/// order) and returns its index. Splits at the median of the triangle centres along the longest
/// axis of their box, so the tree is balanced whatever the mesh.
fn build(triangles: &[Triangle], order: &mut [u32], first: u32, nodes: &mut Vec<Node>) -> u32 {
    let (mut lo, mut hi) = (Vector::splat(f64::INFINITY), Vector::splat(f64::NEG_INFINITY));
    for &i in order.iter() {
        for v in triangles[i as usize].vertices() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
    }
    let center = (lo + hi) / 2.0;
    let radius = order
        .iter()
        .flat_map(|&i| triangles[i as usize].vertices().map(|v| (v - center).length()))
        .fold(0.0, f64::max);
    let (axis, axis_radius) = principal_capsule(order.iter().flat_map(|&i| *triangles[i as usize].vertices()));
    let index = nodes.len() as u32;
    nodes.push(Node {
        center,
        radius,
        axis,
        axis_radius,
        children: None,
        first,
        count: order.len() as u32,
    });
    if order.len() > LEAF_TRIANGLES {
        let centre_of = |i: u32| triangles[i as usize].center();
        let (mut clo, mut chi) = (Vector::splat(f64::INFINITY), Vector::splat(f64::NEG_INFINITY));
        for &i in order.iter() {
            clo = clo.min(centre_of(i));
            chi = chi.max(centre_of(i));
        }
        let extent = chi - clo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let half = order.len() / 2;
        // Ties broken by index, so the tree does not depend on the sort's internals.
        order.select_nth_unstable_by(half, |&i, &j| centre_of(i)[axis].total_cmp(&centre_of(j)[axis]).then(i.cmp(&j)));
        let (left, right) = order.split_at_mut(half);
        let left = build(triangles, left, first, nodes);
        let right = build(triangles, right, first + half as u32, nodes);
        nodes[index as usize].children = Some((left, right));
    }
    index
}

/// A capsule containing `points`: the segment spanned by their projections on their principal
/// axis (the covariance's largest eigenvector), and the largest distance of a point from it.
fn principal_capsule(points: impl Iterator<Item = Vector> + Clone) -> ([Vector; 2], f64) {
    let count = points.clone().count().max(1) as f64;
    let mean = points.clone().fold(Vector::ZERO, |sum, p| sum + p) / count;
    let mut covariance = nalgebra::Matrix3::<f64>::zeros();
    for p in points.clone() {
        let d = nalgebra::Vector3::new(p.x - mean.x, p.y - mean.y, p.z - mean.z);
        covariance += d * d.transpose();
    }
    let eigen = covariance.symmetric_eigen();
    let largest = eigen.eigenvalues.imax();
    let column = eigen.eigenvectors.column(largest);
    let direction = Vector::new(column[0], column[1], column[2]).normalize_or_zero();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in points.clone() {
        let t = (p - mean).dot(direction);
        lo = lo.min(t);
        hi = hi.max(t);
    }
    if !lo.is_finite() {
        return ([mean, mean], 0.0);
    }
    let ends = [mean + direction * lo, mean + direction * hi];
    let radius = points.map(|p| segment_point_distance(ends, p)).fold(0.0, f64::max);
    (ends, radius)
}

/// Distance from `p` to the segment `ends`.
fn segment_point_distance([a, b]: [Vector; 2], p: Vector) -> f64 {
    let ab = b - a;
    let length2 = ab.length_squared();
    let t = if length2 > 0.0 {
        ((p - a).dot(ab) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - p).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed box mesh of 12 triangles with half extents `h`.
    fn box_mesh(h: Vector) -> (Vec<Vector>, Vec<[u32; 3]>) {
        let vertices = (0..8)
            .map(|i| {
                Vector::new(
                    if i & 1 == 0 { -h.x } else { h.x },
                    if i & 2 == 0 { -h.y } else { h.y },
                    if i & 4 == 0 { -h.z } else { h.z },
                )
            })
            .collect();
        let faces = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        (vertices, faces)
    }

    #[test]
    fn every_triangle_is_in_exactly_one_leaf_inside_its_sphere() {
        let (vertices, faces) = box_mesh(Vector::new(0.3, 0.1, 0.05));
        let tree = SphereTree::new(&vertices, &faces);
        let mut covered = 0;
        for node in &tree.nodes {
            for t in tree.leaf(node) {
                for v in t.vertices() {
                    assert!((v - node.center).length() <= node.radius + 1e-15);
                }
            }
            if node.children.is_none() {
                covered += node.count;
            }
        }
        assert_eq!(covered as usize, faces.len());
    }
}
