//! The collision world: parry shapes for every link collider, capsule segment, obstacle and the
//! floor, and the pairs to check, built once per (model, scenario).

use super::geometry::{geometry, Geometry, RoundedSegment};
use super::pairs::{pair_lists, CheckedPair, ExcludedPair, ExcludedShapePair, StructuralAllowance, FLOOR_NAME};
use super::{Body, CollideError, CollideOptions};
use crate::frames::{parry_pose, parry_vector, vector_from_parry};
use crate::model::{Model, PAPER_CAPSULE_RADIUS_M};
use crate::scenario::Scenario;
use nalgebra::{Isometry3, Vector3};
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Pose;
use parry3d_f64::shape::{Capsule, SharedShape};
use std::collections::{HashMap, HashSet};

/// Everything a query needs about one model in one scenario: parry shapes in f64 and the pair
/// lists. Build it with [`world`]; it holds parry handles and is not part of any output.
pub struct CollisionWorld {
    pub(super) link_names: Vec<String>,
    pub(super) obstacle_names: Vec<String>,
    /// Every link collider, link by link.
    pub(super) colliders: Vec<ColliderGeometry>,
    /// Every capsule of the approximate model, link by link.
    pub(super) capsules: Vec<CapsuleGeometry>,
    pub(super) obstacles: Vec<ObstacleGeometry>,
    /// Height of the floor surface (m), if there is a floor.
    pub(super) floor: Option<f64>,
    pub(super) pairs: Vec<CheckedPair>,
    pub(super) excluded: Vec<ExcludedPair>,
    /// Collider pairs of checked link pairs left out, with their reasons.
    pub(super) excluded_shapes: Vec<ExcludedShapePair>,
    /// Link pairs whose remaining shape pairs count only beyond their overlap by construction.
    pub(super) structural_allowances: Vec<StructuralAllowance>,
    /// The same, as `(link, collider)` pairs, lower link first.
    pub(super) skipped: HashSet<ShapePair>,
    /// The collider pairs of the exact model, pair by pair.
    pub(super) candidates: Vec<Candidate>,
    /// The capsule pairs of the approximate model, pair by pair.
    pub(super) capsule_candidates: Vec<Candidate>,
}

/// Two colliders as `(link, collider index)`, lower first.
type ShapePair = ((usize, usize), (usize, usize));

/// One collider of a link.
pub(super) struct ColliderGeometry {
    pub(super) link: usize,
    /// Index in `Link::colliders`.
    pub(super) element: usize,
    /// Pose of the parry shape in the link frame.
    pub(super) link_from_shape: Pose,
    pub(super) geometry: Geometry,
}

/// One capsule of the approximate model.
pub(super) struct CapsuleGeometry {
    pub(super) link: usize,
    /// Index in `Link::segments`.
    pub(super) element: usize,
    /// Segment ends in the link frame (m).
    pub(super) start: Vector3<f64>,
    pub(super) end: Vector3<f64>,
    /// The same capsule as a parry shape in the link frame, for obstacles without a closed form.
    pub(super) geometry: Geometry,
}

/// One obstacle.
pub(super) struct ObstacleGeometry {
    pub(super) world_from_shape: Pose,
    pub(super) geometry: Geometry,
    pub(super) aabb: Aabb,
    /// The bounding capsule's segment ends in the world (m).
    pub(super) bounding: [Vector3<f64>; 2],
    /// The obstacle as the approximate model's closed forms see it.
    pub(super) rounded: Option<RoundedSegment>,
}

/// What a collider or capsule is paired with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Other {
    /// A collider (exact) or capsule (approximate) of another link, by index.
    Link(usize),
    Obstacle(usize),
    Floor,
}

/// One collider (or capsule) pair to measure.
#[derive(Debug, Clone, Copy)]
pub(super) struct Candidate {
    /// Index in [`CollisionWorld::pairs`].
    pub(super) pair: usize,
    /// Added to the measured distance (m): the depth two links overlap by construction, for the
    /// shape pairs of such links still checked (0 otherwise).
    pub(super) allowance: f64,
    /// Collider (or capsule) index on body `a`.
    pub(super) a: usize,
    pub(super) b: Other,
}

/// Builds the collision world of a model in a scenario.
///
/// # Errors
/// [`CollideError::Mesh`] for a mesh parry cannot use (no triangles, a face naming a missing
/// vertex, a non-finite vertex, no convex hull),
/// [`CollideError::InvalidShape`] for a dimension that is not positive and finite, and the
/// exclusion errors of [`CollideOptions::excluded_pairs`] ([`CollideError::UnknownLink`],
/// [`CollideError::MergedLink`], [`CollideError::SameLink`]).
pub fn world(model: &Model, scenario: &Scenario, opts: &CollideOptions) -> Result<CollisionWorld, CollideError> {
    let lists = pair_lists(model, scenario, opts)?;
    let mut colliders = Vec::new();
    let mut capsules = Vec::new();
    for (link_index, link) in model.links.iter().enumerate() {
        for (element, collider) in link.colliders.iter().enumerate() {
            let owner = format!("link `{}` collider {element} ({})", link.name, collider.label);
            let (link_from_shape, geometry) = geometry(&owner, &collider.link_from_shape, &collider.shape)?;
            colliders.push(ColliderGeometry {
                link: link_index,
                element,
                link_from_shape,
                geometry,
            });
        }
        for (element, segment) in link.segments.iter().enumerate() {
            if !segment.start.iter().chain(segment.end.iter()).all(|v| v.is_finite()) {
                return Err(CollideError::InvalidShape {
                    owner: format!("link `{}` segment {element}", link.name),
                    message: format!("ends {:?} and {:?} must be finite", segment.start, segment.end),
                });
            }
            let capsule = Capsule::new(parry_vector(&segment.start), parry_vector(&segment.end), PAPER_CAPSULE_RADIUS_M);
            capsules.push(CapsuleGeometry {
                link: link_index,
                element,
                start: segment.start,
                end: segment.end,
                geometry: Geometry::convex(SharedShape::new(capsule)),
            });
        }
    }
    let mut obstacles = Vec::with_capacity(scenario.obstacles.len());
    for obstacle in &scenario.obstacles {
        let owner = format!("obstacle `{}`", obstacle.name);
        let (world_from_shape, geometry) = geometry(&owner, &obstacle.world_from_shape, &obstacle.shape)?;
        let ends = [geometry.bounding.start, geometry.bounding.end];
        obstacles.push(ObstacleGeometry {
            aabb: geometry.shape.compute_aabb(&world_from_shape),
            bounding: ends.map(|end| vector_from_parry(world_from_shape * end)),
            rounded: geometry.rounded(&world_from_shape),
            world_from_shape,
            geometry,
        });
    }
    let floor = scenario.floor.map(|floor| floor.height);
    if let Some(height) = floor.filter(|h| !h.is_finite()) {
        return Err(CollideError::InvalidShape {
            owner: FLOOR_NAME.into(),
            message: format!("height {height} m must be finite"),
        });
    }

    let skipped = skipped_shapes(model, &opts.excluded_shapes)?;
    // Every element pair of every checked pair, so a query only walks flat lists.
    let collider_links: Vec<usize> = colliders.iter().map(|c| c.link).collect();
    let collider_ids: Vec<(usize, usize)> = colliders.iter().map(|c| (c.link, c.element)).collect();
    let allowances = link_allowances(model, &opts.structural_allowances)?;
    let allowance = |i: usize, j: usize| allowances.get(&(i.min(j), i.max(j))).copied().unwrap_or(0.0);
    let kept = |a: usize, b: usize| {
        let (x, y) = (collider_ids[a], collider_ids[b]);
        !skipped.contains(&(x.min(y), x.max(y)))
    };
    let capsule_links: Vec<usize> = capsules.iter().map(|c| c.link).collect();
    let mut candidates = Vec::new();
    let mut capsule_candidates = Vec::new();
    for (pair, checked) in lists.checked.iter().enumerate() {
        let Body::Link(link) = checked.a else {
            unreachable!("body a of a checked pair is always a link")
        };
        for (exact, links, out) in [
            (true, &collider_links, &mut candidates),
            (false, &capsule_links, &mut capsule_candidates),
        ] {
            for a in elements(links, link) {
                match checked.b {
                    // The paper's capsules of two links that overlap by construction overlap
                    // everywhere: its model, like its authors', leaves such pairs out.
                    Body::Link(other) if !exact && allowance(link, other) > 0.0 => {}
                    Body::Link(other) => out.extend(elements(links, other).filter(|&b| !exact || kept(a, b)).map(|b| Candidate {
                        pair,
                        allowance: if exact { allowance(link, other) } else { 0.0 },
                        a,
                        b: Other::Link(b),
                    })),
                    Body::Obstacle(k) => out.push(Candidate {
                        pair,
                        allowance: 0.0,
                        a,
                        b: Other::Obstacle(k),
                    }),
                    Body::Floor => out.push(Candidate {
                        pair,
                        allowance: 0.0,
                        a,
                        b: Other::Floor,
                    }),
                }
            }
        }
    }

    Ok(CollisionWorld {
        link_names: model.links.iter().map(|l| l.name.clone()).collect(),
        obstacle_names: scenario.obstacles.iter().map(|o| o.name.clone()).collect(),
        colliders,
        capsules,
        obstacles,
        floor,
        pairs: lists.checked,
        excluded: lists.excluded,
        excluded_shapes: opts.excluded_shapes.clone(),
        structural_allowances: opts.structural_allowances.clone(),
        skipped,
        candidates,
        capsule_candidates,
    })
}

impl CollisionWorld {
    /// Every pair a query checks; [`PairDistance::pair`](super::PairDistance::pair) indexes this list.
    pub fn pairs(&self) -> &[CheckedPair] {
        &self.pairs
    }

    /// Every robot pair left out, with the reason.
    pub fn excluded(&self) -> &[ExcludedPair] {
        &self.excluded
    }

    /// Collider pairs of checked link pairs that are not measured, with their reasons.
    pub fn excluded_shapes(&self) -> &[ExcludedShapePair] {
        &self.excluded_shapes
    }

    /// Link pairs whose other shape pairs count only beyond the depth they overlap by
    /// construction.
    pub fn structural_allowances(&self) -> &[StructuralAllowance] {
        &self.structural_allowances
    }

    /// Whether the physics engines collide this checked pair: every checked pair but two links
    /// with a structural allowance. The engines cannot count contacts only beyond a depth, and
    /// within it they would push apart what overlaps by construction; a fold deeper than the
    /// allowance is the certified check's to find.
    pub fn engines_collide(&self, pair: &CheckedPair) -> bool {
        !self
            .structural_allowances
            .iter()
            .any(|s| (s.a == pair.a_name && s.b == pair.b_name) || (s.a == pair.b_name && s.b == pair.a_name))
    }

    /// The excluded shape pairs as `((link, collider), (link, collider))`, lower first.
    pub fn excluded_shape_indices(&self) -> impl Iterator<Item = ((usize, usize), (usize, usize))> + '_ {
        self.skipped.iter().copied()
    }

    /// Whether collider `a.1` of link `a.0` is measured against collider `b.1` of link `b.0`
    /// when their link pair is checked (false for an excluded shape pair).
    pub fn shape_pair_checked(&self, a: (usize, usize), b: (usize, usize)) -> bool {
        !self.skipped.contains(&(a.min(b), a.max(b)))
    }

    /// The exact signed distance (m) between collider `a.1` of link `a.0` and collider `b.1` of
    /// link `b.0`, links placed at `link_in_world`, whether or not the pair is checked; `None`
    /// for a collider the model does not have.
    pub fn collider_distance(&self, link_in_world: &[Isometry3<f64>], a: (usize, usize), b: (usize, usize)) -> Option<f64> {
        self.collider_distance_with(link_in_world, a, b, true)
    }

    /// [`Self::collider_distance`] with the contact normal (unit, world frame, from `a` to `b`).
    pub fn collider_contact(&self, link_in_world: &[Isometry3<f64>], a: (usize, usize), b: (usize, usize)) -> Option<(f64, Vector3<f64>)> {
        let [(ca, pose_a), (cb, pose_b)] = self.placed_pair(link_in_world, a, b)?;
        let measured = super::narrow::measure_shapes(&pose_a, &ca.geometry, &pose_b, &cb.geometry, true);
        Some((measured.distance, vector_from_parry(measured.normal)))
    }

    /// An upper bound on how deep collider `a` overlaps collider `b` (m): how far `b` must move
    /// along `normal` (unit, world frame) to clear `a`, the extent of the two shapes along it.
    /// The depth is that move along the best direction, so any direction bounds it. `None` for
    /// a mesh or a collider the model does not have.
    pub fn collider_overlap_along(
        &self,
        link_in_world: &[Isometry3<f64>],
        a: (usize, usize),
        b: (usize, usize),
        normal: &Vector3<f64>,
    ) -> Option<f64> {
        let [(ca, pose_a), (cb, pose_b)] = self.placed_pair(link_in_world, a, b)?;
        let (map_a, map_b) = (ca.geometry.shape.as_support_map()?, cb.geometry.shape.as_support_map()?);
        let n = parry_vector(normal);
        let farthest_a = map_a.support_point(&pose_a, n).dot(n);
        let nearest_b = map_b.support_point(&pose_b, -n).dot(n);
        Some(farthest_a - nearest_b)
    }

    /// The signed distance (m) of the bounding capsules of collider `a` and collider `b`: a
    /// lower bound of theirs, in closed form.
    pub fn collider_capsule_distance(&self, link_in_world: &[Isometry3<f64>], a: (usize, usize), b: (usize, usize)) -> Option<f64> {
        let [(ca, pose_a), (cb, pose_b)] = self.placed_pair(link_in_world, a, b)?;
        let (ba, bb) = (&ca.geometry.bounding, &cb.geometry.bounding);
        let end = |pose: &Pose, point| vector_from_parry(pose * point);
        Some(
            super::primitives::capsules(
                end(&pose_a, ba.start),
                end(&pose_a, ba.end),
                ba.radius,
                end(&pose_b, bb.start),
                end(&pose_b, bb.end),
                bb.radius,
            )
            .distance,
        )
    }

    fn collider(&self, (link, element): (usize, usize)) -> Option<&ColliderGeometry> {
        self.colliders.iter().find(|c| c.link == link && c.element == element)
    }

    /// Colliders `a` and `b` with their shapes' world poses, links placed at `link_in_world`.
    fn placed_pair(
        &self,
        link_in_world: &[Isometry3<f64>],
        a: (usize, usize),
        b: (usize, usize),
    ) -> Option<[(&ColliderGeometry, Pose); 2]> {
        let place = |index| {
            let collider = self.collider(index)?;
            Some((collider, parry_pose(link_in_world.get(collider.link)?) * collider.link_from_shape))
        };
        Some([place(a)?, place(b)?])
    }

    /// [`Self::collider_distance`], or with `exact_depth` false its cheap bound (see
    /// [`super::QueryOptions::exact_depth`]): an overlap as the bounding capsules' (at least as
    /// deep), a gap as GJK's own (at most 1.3e-5 m long).
    pub fn collider_distance_with(
        &self,
        link_in_world: &[Isometry3<f64>],
        a: (usize, usize),
        b: (usize, usize),
        exact_depth: bool,
    ) -> Option<f64> {
        let [(ca, pose_a), (cb, pose_b)] = self.placed_pair(link_in_world, a, b)?;
        Some(super::narrow::measure_shapes(&pose_a, &ca.geometry, &pose_b, &cb.geometry, exact_depth).distance)
    }

    /// Number of links the world was built for (`link_in_world` must have this length).
    pub fn link_count(&self) -> usize {
        self.link_names.len()
    }

    /// Number of collider pairs of the exact model: what a query without broad phase would measure.
    pub fn collider_pair_count(&self) -> usize {
        self.candidates.len()
    }

    /// Number of capsule pairs of the approximate model.
    pub fn capsule_pair_count(&self) -> usize {
        self.capsule_candidates.len()
    }

    /// Whether a side of a collider pair is a mesh (the floor is measured by hull, so never).
    pub(super) fn has_mesh(&self, candidate: &Candidate) -> bool {
        match candidate.b {
            Other::Link(b) => self.colliders[candidate.a].geometry.is_mesh() || self.colliders[b].geometry.is_mesh(),
            Other::Obstacle(k) => self.colliders[candidate.a].geometry.is_mesh() || self.obstacles[k].geometry.is_mesh(),
            Other::Floor => false,
        }
    }

    /// Name of a body: its link or obstacle name, or `floor`.
    ///
    /// # Panics
    /// When the index is not a link or obstacle of this world.
    pub fn body_name(&self, body: Body) -> &str {
        match body {
            Body::Link(i) => &self.link_names[i],
            Body::Obstacle(k) => &self.obstacle_names[k],
            Body::Floor => FLOOR_NAME,
        }
    }
}

/// The allowances by link index pair, lower first.
fn link_allowances(model: &Model, allowances: &[StructuralAllowance]) -> Result<HashMap<(usize, usize), f64>, CollideError> {
    let mut out = HashMap::new();
    for (index, a) in allowances.iter().enumerate() {
        let find = |name: &str| {
            model
                .links
                .iter()
                .position(|l| l.name == name)
                .ok_or_else(|| CollideError::InvalidShape {
                    owner: format!("structural allowance {index} (`{}`, `{}`)", a.a, a.b),
                    message: format!("model `{}` has no link named `{name}`", model.name),
                })
        };
        let (i, j) = (find(&a.a)?, find(&a.b)?);
        if !(a.depth_m.is_finite() && a.depth_m >= 0.0) {
            return Err(CollideError::InvalidShape {
                owner: format!("structural allowance of links `{}` and `{}`", a.a, a.b),
                message: format!("depth {} m must be finite and at least 0", a.depth_m),
            });
        }
        out.insert((i.min(j), i.max(j)), a.depth_m);
    }
    Ok(out)
}

/// The excluded shape pairs as `(link, collider)` index pairs, lower first.
fn skipped_shapes(model: &Model, exclusions: &[ExcludedShapePair]) -> Result<HashSet<ShapePair>, CollideError> {
    let mut out = HashSet::new();
    for (index, e) in exclusions.iter().enumerate() {
        let find = |name: &str, shape: usize| {
            let link = model.links.iter().position(|l| l.name == name);
            match link {
                Some(i) if shape < model.links[i].colliders.len() => Ok((i, shape)),
                _ => Err(CollideError::UnknownShape {
                    index,
                    link: name.into(),
                    shape,
                    count: link.map_or(0, |i| model.links[i].colliders.len()),
                }),
            }
        };
        let (x, y) = (find(&e.a, e.a_shape)?, find(&e.b, e.b_shape)?);
        out.insert((x.min(y), x.max(y)));
    }
    Ok(out)
}

/// Indices of the elements (colliders or capsules) of `link`, given each element's link.
fn elements(element_links: &[usize], link: usize) -> impl Iterator<Item = usize> + '_ {
    element_links.iter().enumerate().filter(move |(_, &l)| l == link).map(|(k, _)| k)
}
