//! Consumes a [`Model`](crate::model::Model), a [`Scenario`](crate::scenario::Scenario) and the link poses of a configuration.
//! Produces [`Distances`]: signed distances with witness points for the checked pairs, in the exact
//! geometry (parry3d-f64) or the paper's capsule model, and findings where the models disagree.
//! Fails with [`CollideError`] when the geometry cannot be built: a mesh parry rejects, an exclusion naming no link.
//!
//! # Files, each importing only those before it
//!
//! `primitives` (closed forms, shared constants, the measured-distance type) -> `mesh_tree`
//! (sphere trees over triangles) -> `geometry` (a parry shape per collider, its hull, tree and
//! bounds) -> `narrow` (one pair of shapes) -> `pairs` / `world` (what is checked) -> `exact` and
//! `approx` (every pair at a configuration), `structural`, `compare`, `motion` and `point` beside.
//!
//! # Pairs
//!
//! A [`CollisionWorld`] is built once per model and scenario by [`world`]. It lists every robot pair
//! it checks ([`CollisionWorld::pairs`]) and every pair it leaves out with the reason
//! ([`CollisionWorld::excluded`]); no pair is dropped silently, and none is dropped because it
//! touches at some configuration. The rule:
//!
//! - every link against every obstacle and the floor, the base (link 0) included: the base is
//!   fixed, so a base-obstacle contact does not depend on the configuration, but the robot is
//!   physically there and the contact is real;
//! - every link pair, except links joined by one joint (`i`, `i + 1`), the paper's rule; the base
//!   against non-adjacent links is checked;
//! - excluded: the base against the floor (the base is mounted; it sits on the floor by design),
//!   pairs with a link that has no geometry in either model, and the pairs given in
//!   [`CollideOptions::excluded_pairs`] (link names, e.g. from an SRDF disable list).
//!
//! Obstacles are not checked against each other or the floor.
//!
//! # Exact distances ([`distances`])
//!
//! Every collider is a parry shape in f64: `Ball`, `Cuboid`, `Capsule`, `Cylinder` (parry's axis is
//! y; ours is z, so the shape is turned by +90 degrees about x), and meshes as non-convex `TriMesh`
//! checked as they are, never as hulls. The floor is a `HalfSpace`. A distance is signed: negative
//! is a penetration depth. Witness points are in world coordinates, one on each body, and the unit
//! normal points from body `a` to body `b` (the direction `b` would move to separate).
//!
//! How each shape pair is measured (parry 0.31; the corrections are measured in `tests/collide.rs`):
//!
//! - balls and capsules against balls and capsules: closed form (closest points of the two axis
//!   segments, minus the radii), exact for depths too. A capsule against any other shape is its
//!   axis segment against it, minus the radius (exact: a convex set grown by `r` has its signed
//!   distance minus `r`), so GJK and EPA only see its polytope segment;
//! - a ball against any convex shape: parry's point projection, closed form for boxes, cylinders
//!   and hulls;
//! - other convex pairs (cylinders, boxes, segments, hulls): parry's GJK, started between the
//!   closest points of the shapes' axes, and EPA for an overlap. GJK stops early on curved shapes
//!   (up to 1.3e-5 m too far on cylinders), so a gap is polished by alternating projections onto
//!   the two shapes until the supporting planes across it certify the distance to 1e-10 m. EPA's
//!   depth of two overlapping cylinders is within 3e-10 m of the closed form, but it is slow
//!   (about 13 us per pair);
//! - a mesh against anything: the gap by a best-first descent of the mesh's sphere-and-capsule
//!   tree (both trees for two meshes, see `mesh_tree`), then the nearest triangle's contact
//!   measured as above; an overlap by parry's descent of its BVH, the deepest triangle's contact.
//!   The depth of an overlap is measured to the nearest triangle. A mesh is a surface, so a body
//!   wholly inside a closed mesh touches no triangle: when a mesh is closed (every edge shared by
//!   exactly two triangles), a point of the other body is also tested for containment (parry's
//!   pseudo-normals), and an enclosed body is reported as penetrating with `distance = -(gap to
//!   the surface)` and [`PairDistance::enclosed`] set; the true depth is larger. A body inside an
//!   open mesh is not detected;
//! - anything against the floor: the half-space's contact with the shape's lowest point (a mesh by
//!   its convex hull, which is exact there: the lowest point of a mesh is a vertex of its hull).
//!   parry 0.31 mishandles a half-space given as the second shape, so it is given first.
//!
//! If parry cannot give a depth for an overlap (EPA failing), the pair is reported touching
//! (distance 0, witnesses at the shape origins); no such case was seen in the tests.
//!
//! A query does not run every narrow phase. Each collider pair gets a lower bound on its signed
//! distance: the gap between the colliders' AABBs (or, when they overlap, minus their smallest
//! overlap along an axis: moving one body that far separates them), then, when that is not
//! enough, the signed distance of capsules that contain the colliders (a cylinder's axis and
//! radius, a box's longest axis). Collider pairs are visited by bound, smallest first, and
//! measured only when they can change an answer: a pair whose bound is within
//! [`QueryOptions::margin`] and below its body pair's best so far (so each reported distance is
//! the minimum over the colliders), or any pair whose bound is below the closest distance found
//! (branch and bound, so [`Distances::closest`] is the exact minimum over all pairs). Bounds are
//! lowered by 1e-9 m so rounding cannot skip the closest pair.
//!
//! # Hulls
//!
//! MuJoCo and most planners collide a mesh as its convex hull. For collider pairs with a mesh side
//! whose bound is within the margin (only those can be in contact), the distance with each mesh
//! replaced by its hull is also measured, and where the hull is in contact but the mesh is not
//! (an obstacle inside a gripper's opening), a [`CollisionFinding::HullDisagreement`] is
//! reported. [`QueryOptions::hulls`] turns this off.
//!
//! # The paper's approximate model ([`approximate_distances`])
//!
//! Each link is the union of capsules of radius [`PAPER_CAPSULE_RADIUS_M`](crate::model::PAPER_CAPSULE_RADIUS_M)
//! on its [`Link::segments`](crate::model::Link::segments) (a zero-length segment is a sphere);
//! obstacles keep their exact shapes. Capsule-capsule, capsule-sphere and capsule-capsule-obstacle
//! distances are closed-form (closest points of two segments, minus the radii), the floor is a
//! plane; box, cylinder and mesh obstacles are measured against a parry `Capsule` shape by the
//! exact model's narrow phase (its segment, then minus the radius). Every capsule pair is measured
//! (no broad phase: the closed forms cost less than bounds). The same pairs are checked as in the
//! exact model. [`compare`] names the pairs where the two models disagree about contact.

mod approx;
mod compare;
mod exact;
mod geometry;
mod mesh_tree;
mod motion;
mod narrow;
mod pairs;
mod point;
mod primitives;
mod structural;
mod world;

pub use approx::approximate_distances;
pub(crate) use approx::{capsule_floor, capsule_model, capsule_shape_distance, CapsuleModel, CapsuleOther};
pub use compare::compare;
pub use exact::{clear, clearance_by_kind, distances, distances_among};
pub use motion::MotionBounds;
pub use pairs::{CheckedPair, ExcludedPair, ExcludedShapePair, StructuralAllowance};
pub(crate) use primitives::{capsules, Closest};
pub use structural::{structural_overlaps, StructuralExclusions, StructuralOptions, TOUCHING_M};
pub use world::{world, CollisionWorld};

use nalgebra::Vector3;
use serde::Serialize;

/// Options for building a [`CollisionWorld`].
#[derive(Debug, Clone, Default)]
pub struct CollideOptions {
    /// Link pairs not to check, by link name (the model's link names, not names merged into a
    /// link), each with the reason it is safe to leave out; default none.
    pub excluded_pairs: Vec<ExcludedPair>,
    /// Collider pairs of otherwise checked link pairs not to measure, each with its reason;
    /// default none.
    pub excluded_shapes: Vec<ExcludedShapePair>,
    /// Link pairs whose measured shape pairs count only beyond a depth they overlap by
    /// construction (m); default none.
    pub structural_allowances: Vec<StructuralAllowance>,
}

/// Options for one distance query.
#[derive(Debug, Clone, Copy)]
pub struct QueryOptions {
    /// Report every pair whose signed distance is at most this (m); default 0: contacts only.
    /// NaN and negative values count as 0. The closest pair is reported whatever its distance.
    pub margin: f64,
    /// Measure mesh hulls and report [`CollisionFinding::HullDisagreement`]; default `true`.
    pub hulls: bool,
    /// Measure overlapping curved or boxy pairs (cylinders, boxes, capsules against them) exactly,
    /// by EPA, and polish separated ones to 1e-10 m; default `true`. When `false`, such an overlap
    /// reports the signed distance of the two shapes' bounding capsules instead (negative like the
    /// true depth, at least as deep, closed form, where EPA on two cylinders costs about 13 us), and
    /// a gap is GJK's own (up to 1.3e-5 m long on curved shapes). The sign is right either way
    /// (away from touching within rounding). For loops that only need the sign and a direction,
    /// such as collision-aware IK's loss gradient.
    pub exact_depth: bool,
    /// Measure a pair with a mesh side by the meshes' convex hulls, as convex shapes (with
    /// `exact_depth`'s meaning), instead of walking triangle pairs; default `false`. A hull holds
    /// its mesh, so a gap is at most the meshes' and an overlap may be the hulls' alone: neither
    /// the sign nor the size is the exact geometry's. For loops that need a direction and a rough
    /// size near the meshes, such as collision-aware IK's loss gradient, where one mesh pair walked
    /// to its exact closest triangles costs 0.2 to 0.7 ms and its hulls a few microseconds.
    pub mesh_hulls: bool,
}

impl Default for QueryOptions {
    fn default() -> Self {
        Self {
            margin: 0.0,
            hulls: true,
            exact_depth: true,
            mesh_hulls: false,
        }
    }
}

/// A body a pair is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(tag = "kind", content = "index", rename_all = "snake_case")]
pub enum Body {
    /// The model link at this index (`Model::links`; 0 is the base).
    Link(usize),
    /// The scenario obstacle at this index (`Scenario::obstacles`).
    Obstacle(usize),
    /// The scenario floor.
    Floor,
}

/// One piece of a body: a collider of a link, a capsule of the approximate model, an obstacle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Part {
    /// The body.
    pub body: Body,
    /// Index of the collider in `Link::colliders` (exact model) or of the segment in
    /// `Link::segments` (approximate model); 0 for obstacles and the floor.
    pub element: usize,
}

impl Part {
    /// The floor (it has one element).
    pub(crate) fn floor() -> Self {
        Self {
            body: Body::Floor,
            element: 0,
        }
    }
}

/// The signed distance of one checked pair, where it is measured.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PairDistance {
    /// Index of the pair in [`CollisionWorld::pairs`].
    pub pair: usize,
    /// The part of body `a` (always a link) the distance is measured from.
    pub a: Part,
    /// The part of body `b` the distance is measured to.
    pub b: Part,
    /// Signed distance (m): the gap between the bodies, or minus the penetration depth.
    pub distance: f64,
    /// Witness point on `a`, world frame (m).
    pub point_a: Vector3<f64>,
    /// Witness point on `b`, world frame (m).
    pub point_b: Vector3<f64>,
    /// Unit normal from `a` to `b`, world frame: moving `b` along it separates the bodies.
    pub normal: Vector3<f64>,
    /// The body is wholly inside a closed mesh; `distance` is minus its gap to the mesh surface,
    /// and the true depth is larger.
    pub enclosed: bool,
}

/// The smallest signed distance of each kind of checked pair at one configuration (m): the
/// robot against the obstacles, against itself, against the floor; `None` where the world checks
/// no pair of that kind (no obstacles, no floor). One number would hide the others: a modular
/// arm's mount 40 mm above the floor sets most goals' clearance, however close the obstacles are.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct ClearanceByKind {
    /// Against the scenario's obstacles.
    pub obstacles_m: Option<f64>,
    /// Between the robot's own links.
    pub self_m: Option<f64>,
    /// Against the floor.
    pub floor_m: Option<f64>,
}

impl ClearanceByKind {
    /// Each kind's smallest distance among `distances.within_margin`: a query with an infinite
    /// margin measures every checked pair exactly.
    pub fn of(distances: &Distances) -> Self {
        let mut out = Self::default();
        for pair in &distances.within_margin {
            out.lower(pair.b.body, pair.distance);
        }
        out
    }

    /// Takes `distance` (m) for the kind of a pair whose second body is `b` (the first is always
    /// a link) when it is smaller; an infinite distance (a pair without geometry) is none.
    pub fn lower(&mut self, b: Body, distance: f64) {
        if !distance.is_finite() {
            return;
        }
        let slot = self.slot(b);
        *slot = Some(slot.map_or(distance, |d: f64| d.min(distance)));
    }

    /// The value of the kind of a pair whose second body is `b`.
    pub fn for_body(mut self, b: Body) -> Option<f64> {
        *self.slot(b)
    }

    fn slot(&mut self, b: Body) -> &mut Option<f64> {
        match b {
            Body::Obstacle(_) => &mut self.obstacles_m,
            Body::Link(_) => &mut self.self_m,
            Body::Floor => &mut self.floor_m,
        }
    }

    /// Each kind's smaller value of the two.
    pub fn min(self, other: Self) -> Self {
        let min = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        Self {
            obstacles_m: min(self.obstacles_m, other.obstacles_m),
            self_m: min(self.self_m, other.self_m),
            floor_m: min(self.floor_m, other.floor_m),
        }
    }
}

/// What a query knows about one checked pair.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PairEstimate {
    /// Body `a` of the pair (always a link).
    pub a: Body,
    /// Body `b` of the pair.
    pub b: Body,
    /// The pair's signed distance (m) when `exact`, else a lower bound on it; infinite when a
    /// body has no geometry in this model (a link with segments but no colliders, or the reverse).
    pub distance: f64,
    /// Whether `distance` is the measured distance. Always true within the margin, for the
    /// closest pair, and in the approximate model.
    pub exact: bool,
}

/// A disagreement between the exact geometry and what other tools use.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "finding")]
pub enum CollisionFinding {
    /// A mesh's convex hull is in contact but the mesh itself is not (e.g. an obstacle inside a
    /// gripper's opening): MuJoCo and most planners, which use the hull, would call this a
    /// collision.
    HullDisagreement {
        /// Index of the pair in [`CollisionWorld::pairs`].
        pair: usize,
        /// Part of body `a`.
        a: Part,
        /// Part of body `b`.
        b: Part,
        /// Signed distance of the exact shapes (m), positive.
        exact_distance: f64,
        /// Signed distance with each mesh replaced by its convex hull (m), at most 0.
        hull_distance: f64,
    },
}

/// Where the paper's capsule model and the exact geometry disagree about contact.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "finding")]
pub enum ApproximationFinding {
    /// The capsule model says free, the exact geometry collides: a design judged on capsules
    /// would collide for real.
    UnsafeApproximation {
        /// Index of the pair in [`CollisionWorld::pairs`].
        pair: usize,
        /// Body `a` of the pair.
        a: Body,
        /// Body `b` of the pair.
        b: Body,
        /// Signed distance of the exact geometry (m).
        exact_distance: f64,
        /// Signed distance of the capsule model (m).
        approximate_distance: f64,
    },
    /// The capsule model says collision, the exact geometry is free: the design is rejected for
    /// a contact that does not exist.
    ConservativeApproximation {
        /// Index of the pair in [`CollisionWorld::pairs`].
        pair: usize,
        /// Body `a` of the pair.
        a: Body,
        /// Body `b` of the pair.
        b: Body,
        /// Signed distance of the exact geometry (m); a lower bound when `exact_lower_bound`.
        exact_distance: f64,
        /// The exact query did not measure this pair (it was beyond its margin); `exact_distance`
        /// is the broad-phase lower bound.
        exact_lower_bound: bool,
        /// Signed distance of the capsule model (m).
        approximate_distance: f64,
    },
}

/// The answer to one query; reuse it across queries (its buffers keep their capacity, so a query
/// in steady state does not allocate).
#[derive(Debug, Clone, Default, Serialize)]
pub struct Distances {
    /// The margin the query used (m).
    pub margin: f64,
    /// Every checked pair whose signed distance is at most `margin`, in [`CollisionWorld::pairs`] order.
    pub within_margin: Vec<PairDistance>,
    /// The pair with the smallest signed distance over all checked pairs; `None` only when no
    /// checked pair has geometry on both sides in this model.
    pub closest: Option<PairDistance>,
    /// One entry per checked pair, in [`CollisionWorld::pairs`] order.
    pub estimates: Vec<PairEstimate>,
    /// Hull disagreements found (exact queries only).
    pub findings: Vec<CollisionFinding>,
    /// Narrow-phase distance computations run (collider pairs measured).
    pub narrow_phase_calls: usize,
    /// Hull distance computations run.
    pub hull_calls: usize,
    #[serde(skip)]
    scratch: Scratch,
}

/// Per-query buffers, kept with the output so a query does not allocate.
#[derive(Debug, Clone, Default)]
struct Scratch {
    /// World pose of every link, as parry poses.
    link_poses: Vec<parry3d_f64::math::Pose>,
    /// World pose of every link collider.
    poses: Vec<parry3d_f64::math::Pose>,
    /// World AABB of every link collider.
    aabbs: Vec<parry3d_f64::bounding_volume::Aabb>,
    /// World segment ends of every collider's bounding capsule (exact) or every capsule
    /// (approximate).
    segments: Vec<[Vector3<f64>; 2]>,
    /// Lower bound on each candidate's signed distance; replaced by the distance once measured.
    bounds: Vec<f64>,
    /// How far each candidate has been looked at.
    stages: Vec<Stage>,
    /// Unmeasured candidates by bound, smallest first (keys from `exact::order_key`).
    queue: std::collections::BinaryHeap<std::cmp::Reverse<(u64, usize)>>,
    /// Per pair: the smallest measured distance and its witness data.
    best: Vec<Option<PairDistance>>,
    /// Per candidate with two mesh sides: its nearest triangle pair when last measured, which
    /// speeds up the next query near that configuration without changing its answer.
    hints: Vec<Option<[u32; 2]>>,
}

impl Distances {
    /// An empty answer, ready to be filled by [`distances`] or [`approximate_distances`].
    pub fn new() -> Self {
        Self::default()
    }

    /// True when some checked pair is in contact (signed distance <= 0).
    pub fn in_contact(&self) -> bool {
        self.closest.is_some_and(|closest| closest.distance <= 0.0)
    }

    /// Empties the answer for a world with `pair_count` pairs, keeping the buffers.
    fn reset(&mut self, margin: f64, pair_count: usize) {
        self.margin = margin;
        self.within_margin.clear();
        self.closest = None;
        self.estimates.clear();
        self.findings.clear();
        self.narrow_phase_calls = 0;
        self.hull_calls = 0;
        self.scratch.best.clear();
        self.scratch.best.resize(pair_count, None);
    }

    /// Fills `within_margin`, `closest` and the exact part of `estimates` from `scratch.best`.
    fn collect(&mut self) {
        for best in self.scratch.best.iter().flatten() {
            if best.distance <= self.margin {
                self.within_margin.push(*best);
            }
            if self.closest.is_none_or(|closest| best.distance < closest.distance) {
                self.closest = Some(*best);
            }
        }
    }
}

/// How far a query has looked at a collider pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stage {
    /// Its bound is the AABB bound.
    Boxed,
    /// Its bound also covers the bounding capsules.
    Capsuled,
    /// Its bound also covers the convex hulls (a pair with a mesh side).
    Hulled,
    /// Its bound is its measured distance.
    Measured,
}

/// The margin a query uses: `margin`, with NaN and negative values as 0.
fn effective_margin(margin: f64) -> f64 {
    if margin > 0.0 {
        margin
    } else {
        0.0
    }
}

/// Why a collision world could not be built.
#[derive(Debug, thiserror::Error)]
pub enum CollideError {
    /// A mesh parry cannot use.
    #[error("{owner}: mesh `{uri}`: {message}")]
    Mesh {
        /// The link collider or obstacle holding the mesh.
        owner: String,
        /// The mesh as named in the robot or scenario description.
        uri: String,
        /// What is wrong with it.
        message: String,
    },
    /// A shape dimension that is not a positive finite number, or a pose that is not finite.
    #[error("{owner}: {message}")]
    InvalidShape {
        /// The link collider or obstacle.
        owner: String,
        /// The value and what was expected.
        message: String,
    },
    /// An exclusion names a link the model does not have.
    #[error("excluded pair {index} (`{a}`, `{b}`): no link named `{link}` in model `{model}` (links: {known})")]
    UnknownLink {
        /// Position of the exclusion in [`CollideOptions::excluded_pairs`].
        index: usize,
        /// First name of the exclusion.
        a: String,
        /// Second name of the exclusion.
        b: String,
        /// The name not found.
        link: String,
        /// The model.
        model: String,
        /// Every link the model has.
        known: String,
    },
    /// An exclusion names a link that was merged into another one (a fixed joint, or a link off
    /// the chain): exclusions apply to whole model links, so it would exclude more than it says.
    #[error(
        "excluded pair {index} (`{a}`, `{b}`): link `{link}` is merged into model link `{merged_into}`; name model links (links: {known})"
    )]
    MergedLink {
        /// Position of the exclusion in [`CollideOptions::excluded_pairs`].
        index: usize,
        /// First name of the exclusion.
        a: String,
        /// Second name of the exclusion.
        b: String,
        /// The merged name.
        link: String,
        /// The model link holding it.
        merged_into: String,
        /// Every link the model has.
        known: String,
    },
    /// A shape exclusion names a link or a collider the model does not have.
    #[error("excluded shape pair {index}: link `{link}` has no collider {shape} (it has {count})")]
    UnknownShape {
        /// Index in the exclusion list.
        index: usize,
        /// The link named.
        link: String,
        /// The collider index given.
        shape: usize,
        /// Colliders the link has.
        count: usize,
    },
    /// An exclusion names the same link twice.
    #[error("excluded pair {index}: `{link}` with itself; a link is never checked against itself")]
    SameLink {
        /// Position of the exclusion in [`CollideOptions::excluded_pairs`].
        index: usize,
        /// The link.
        link: String,
    },
}
