//! Link pairs that overlap by construction: in contact at every configuration.
//!
//! With the paper's link geometry (tubes of 0.12 m diameter) two links that are separated by one
//! short link (a `direct` module, d = 0.1 m; a UR wrist, d = 0.1 m) always overlap around the joint
//! between them, whatever the joint angles: the pair is structurally in contact and checking it
//! says nothing about a motion. Such pairs are found by sampling and excluded with their reason,
//! the "always in collision" category of a MoveIt collision matrix. Pairs that merely touch at the
//! home configuration are not excluded: one free sample keeps a pair checked.

use super::{world, Body, CollideError, CollideOptions, ExcludedPair, ExcludedShapePair, StructuralAllowance};
use crate::model::Model;
use crate::scenario::Scenario;
use nalgebra::Vector3;
use rand::SeedableRng;

/// Signed distance up to which a pair counts as in contact while sampling (m).
pub const TOUCHING_M: f64 = 1e-9;

/// Added to the deepest overlap sampled to make a structural allowance (m): sampling finds the
/// deepest overlap of two slabs only approximately, and exactly that depth is construction too.
pub(super) const DEPTH_SLACK_M: f64 = 1e-3;

/// Gap (m) within which the cheap sampling query's GJK distance (at most 1.3e-5 m longer than
/// the true one on curved shapes) is re-measured exactly before a pair counts as not touching.
const ESTIMATE_SLACK_M: f64 = 1e-4;

/// How far a sample's depth bound may exceed the deepest measured and the sample still be
/// skipped (m): below EPA's own error on curved shapes (3e-10 m measured, `tests/collide.rs`)
/// and a millionth of the slack added to the deepest.
const DEPTH_RESOLUTION_M: f64 = 1e-9;

/// Normals of measured overlaps kept per shape pair to bound the depth at other samples.
const NORMALS_KEPT: usize = 16;

/// Mixed into the seed of the fold samples, so they are not the first samples again.
const FOLD_STREAM: u64 = 0x464f_4c44;

/// Sampling settings for [`structural_overlaps`].
#[derive(Debug, Clone)]
pub struct StructuralOptions {
    /// Random configurations tried (default 256): a pair in contact at all of them is excluded.
    pub samples: usize,
    /// Seed of the configurations (default 0).
    pub seed: u64,
    /// Random configurations tried (default 1024) for a fold of the shapes that do not overlap by
    /// construction deeper than those that do: without one, the link pair is excluded whole.
    pub fold_samples: usize,
}

impl Default for StructuralOptions {
    fn default() -> Self {
        Self {
            samples: 256,
            seed: 0,
            fold_samples: 1024,
        }
    }
}

/// What [`structural_overlaps`] leaves out.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StructuralExclusions {
    /// Link pairs left out whole: in contact at every sample, and still so without any of their
    /// shape pairs that are.
    pub pairs: Vec<ExcludedPair>,
    /// Shape pairs left out of otherwise checked link pairs: the pieces in contact at every
    /// sample (a joint housing inside the next link's tube), the rest of the two links checked.
    pub shapes: Vec<ExcludedShapePair>,
    /// For those link pairs, the depth their other shape pairs must exceed to count: the
    /// deepest overlap of the excluded shape pairs.
    pub allowances: Vec<StructuralAllowance>,
}

/// Self pairs of `model` in contact at every sampled configuration: for each, the shape pairs
/// that are (excluded alone when the link pair is otherwise free at some sample, so a real fold
/// of one link into the other is still caught), else the whole link pair; each with its reason.
///
/// Each link pair is decided on its own, in the frame of its first link, so the answer is a
/// function of the two links' shapes, the joints between them and the sampling alone: it is
/// remembered for the process and reused for every model that shares them (a catalog sweep
/// builds the same pairs thousands of times).
///
/// # Errors
/// When the model's geometry cannot be built (see [`world`]).
pub fn structural_overlaps(model: &Model, opts: &StructuralOptions) -> Result<StructuralExclusions, CollideError> {
    let empty = Scenario {
        name: "empty".into(),
        world_from_base: nalgebra::Isometry3::identity(),
        floor: None,
        obstacles: vec![],
        goals: vec![],
        home: None,
        provenance: None,
        notes: Vec::new(),
    };
    let world = world(model, &empty, &CollideOptions::default())?;
    let mut configurations: Option<Vec<Vec<f64>>> = None;
    let mut exclusions = StructuralExclusions::default();
    for pair in world.pairs() {
        let (Body::Link(i), Body::Link(j)) = (pair.a, pair.b) else {
            continue;
        };
        let (first, second) = (i.min(j), i.max(j));
        let key = pair_key(model, first, second, &pair.a_name, &pair.b_name, opts);
        let cached = key.as_ref().and_then(|key| {
            let cache = CACHE.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            cache.as_ref().and_then(|cache| cache.get(key).cloned())
        });
        let found = match cached {
            Some(found) => found,
            None => {
                let samples = configurations.get_or_insert_with(|| {
                    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed);
                    (0..opts.samples).map(|_| model.random_configuration(&mut rng)).collect()
                });
                let found = analyse_pair(model, &world, (i, j), (&pair.a_name, &pair.b_name), samples, opts);
                if let Some(key) = key {
                    let mut guard = CACHE.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
                    let cache = guard.get_or_insert_with(std::collections::HashMap::new);
                    if cache.len() >= CACHE_ENTRIES {
                        cache.clear();
                    }
                    cache.insert(key, found.clone());
                }
                found
            }
        };
        exclusions.pairs.extend(found.pairs);
        exclusions.shapes.extend(found.shapes);
        exclusions.allowances.extend(found.allowances);
    }
    Ok(exclusions)
}

/// Link pairs decided so far, by [`pair_key`].
static CACHE: std::sync::Mutex<Option<std::collections::HashMap<Vec<u8>, StructuralExclusions>>> = std::sync::Mutex::new(None);

/// Pairs remembered at most (a catalog robot has 15; the 15 625 of the modular catalog share a
/// few thousand); beyond, the memory starts over.
const CACHE_ENTRIES: usize = 1 << 16;

/// A key's bytes: numbers by their bits (so exactly), texts and lists prefixed by their length
/// (so no two different sequences of them read the same). Bytes, not text: formatting every
/// float of a model was a fiftieth of a sweep's time.
#[derive(Default)]
struct Key(Vec<u8>);

impl Key {
    fn number(&mut self, value: f64) {
        self.0.extend_from_slice(&value.to_bits().to_le_bytes());
    }
    fn count(&mut self, value: usize) {
        self.word(value as u64);
    }
    fn word(&mut self, value: u64) {
        self.0.extend_from_slice(&value.to_le_bytes());
    }
    fn numbers(&mut self, values: &[f64]) {
        self.count(values.len());
        values.iter().for_each(|&v| self.number(v));
    }
    fn text(&mut self, value: &str) {
        self.count(value.len());
        self.0.extend_from_slice(value.as_bytes());
    }
    fn joint(&mut self, kind: crate::model::JointKind) {
        self.0.push(kind as u8);
    }
}

/// Everything a link pair's answer depends on, exactly: the sampling, every joint's kind and
/// limits (they decide the random stream), the joints between the two links, their shapes,
/// labels and names. `None` for a pair with a mesh, which is decided every time (a mesh's key
/// would be the whole mesh).
fn pair_key(model: &Model, first: usize, second: usize, a_name: &str, b_name: &str, opts: &StructuralOptions) -> Option<Vec<u8>> {
    use crate::model::Shape;
    let mut key = Key::default();
    key.count(opts.samples);
    key.word(opts.seed);
    key.count(opts.fold_samples);
    key.count(first);
    key.count(second);
    key.text(a_name);
    key.text(b_name);
    key.count(model.joints.len());
    for joint in &model.joints {
        key.joint(joint.kind);
        key.numbers(joint.limits.as_ref().map_or(&[][..], |l| &l[..]));
    }
    for joint in &model.joints[first..second] {
        key.numbers(joint.parent_from_joint.translation.vector.as_slice());
        key.numbers(joint.parent_from_joint.rotation.quaternion().coords.as_slice());
        key.numbers(joint.axis.as_slice());
        key.joint(joint.kind);
    }
    for link in [first, second] {
        key.count(model.links[link].colliders.len());
        for collider in &model.links[link].colliders {
            key.numbers(collider.link_from_shape.translation.vector.as_slice());
            key.numbers(collider.link_from_shape.rotation.quaternion().coords.as_slice());
            match &collider.shape {
                Shape::Sphere { radius } => key.numbers(&[0.0, *radius]),
                Shape::Cylinder { radius, length } => key.numbers(&[1.0, *radius, *length]),
                Shape::Capsule { radius, length } => key.numbers(&[2.0, *radius, *length]),
                Shape::Box { half_extents } => key.numbers(&[3.0, half_extents[0], half_extents[1], half_extents[2]]),
                Shape::Mesh(_) => return None,
            }
            key.text(&collider.label);
        }
    }
    Some(key.0)
}

/// Where link `second` is in link `first`'s frame at configuration `q`, laid out as the world
/// queries want it (one pose per link; the others unused).
fn placed(model: &Model, (first, second): (usize, usize), q: &[f64], out: &mut [nalgebra::Isometry3<f64>]) {
    let mut first_from_second = nalgebra::Isometry3::identity();
    for (joint, &value) in q.iter().enumerate().take(second).skip(first) {
        first_from_second *= model.joint_transform(joint, value);
    }
    out[first] = nalgebra::Isometry3::identity();
    out[second] = first_from_second;
}

/// The answer for the link pair `(i, j)` of `world` (built for `model` without obstacles), at
/// the sampled `configurations`.
fn analyse_pair(
    model: &Model,
    world: &super::CollisionWorld,
    (i, j): (usize, usize),
    (a_name, b_name): (&str, &str),
    configurations: &[Vec<f64>],
    opts: &StructuralOptions,
) -> StructuralExclusions {
    let mut found = StructuralExclusions::default();
    if configurations.is_empty() {
        return found;
    }
    let link_pair = (i.min(j), i.max(j));
    let shape_pairs: Vec<(usize, usize)> = (0..model.links[i].colliders.len())
        .flat_map(|a| (0..model.links[j].colliders.len()).map(move |b| (a, b)))
        .collect();
    let mut placements = Vec::with_capacity(configurations.len());
    let mut pose = vec![nalgebra::Isometry3::identity(); model.links.len()];
    // Touching counts as contact: tubes that meet end to end are at +-1e-17 m, and which side of
    // zero rounding lands on says nothing about the design. The cheap measure first (no EPA: an
    // overlap as the bounding capsules', a gap as GJK's own, at most 1.3e-5 m long), the exact
    // one only for a gap it cannot tell from touching.
    let touching = |pose: &[nalgebra::Isometry3<f64>], (a, b): (usize, usize), exact: bool| {
        world.collider_distance_with(pose, (i, a), (j, b), exact).unwrap_or(f64::INFINITY)
    };
    let capsules = |pose: &[nalgebra::Isometry3<f64>], (a, b): (usize, usize)| {
        world.collider_capsule_distance(pose, (i, a), (j, b)).unwrap_or(f64::NEG_INFINITY)
    };
    // Each shape pair's cheap measure at each sample, kept for the tests below.
    let mut estimates: Vec<Vec<f64>> = Vec::with_capacity(configurations.len());
    for q in configurations {
        placed(model, link_pair, q, &mut pose);
        // Capsules apart by more than the slack answer every test below as the cheap measure
        // (never nearer than they are) would.
        let each: Vec<f64> = shape_pairs
            .iter()
            .map(|&p| match capsules(&pose, p) {
                apart if apart > ESTIMATE_SLACK_M => apart,
                _ => touching(&pose, p, false),
            })
            .collect();
        let estimate = each.iter().copied().fold(f64::INFINITY, f64::min);
        let in_contact = estimate <= TOUCHING_M
            || (estimate <= ESTIMATE_SLACK_M
                && shape_pairs.iter().map(|&p| touching(&pose, p, true)).fold(f64::INFINITY, f64::min) <= TOUCHING_M);
        if !in_contact {
            return found;
        }
        placements.push(pose.clone());
        estimates.push(each);
    }
    let sampled = format!("in contact at all {} sampled configurations (seed {})", opts.samples, opts.seed);
    // The exact measure (EPA for an overlap, most of this function's cost) only where the cheap
    // one cannot answer: it is a lower bound within the GJK slack (a capsule overlaps at least
    // as deep as its shape), and each shape pair at each sample is measured at most once.
    let mut measured: std::collections::HashMap<(usize, usize), (f64, Vector3<f64>)> = std::collections::HashMap::new();
    let mut contact = |sample: usize, p: usize| -> (f64, Vector3<f64>) {
        *measured.entry((sample, p)).or_insert_with(|| {
            let (a, b) = shape_pairs[p];
            world
                .collider_contact(&placements[sample], (i, a), (j, b))
                .unwrap_or((f64::INFINITY, Vector3::z()))
        })
    };
    let samples = 0..configurations.len();
    let overlapping: Vec<usize> = (0..shape_pairs.len())
        .filter(|&p| {
            samples.clone().all(|k| {
                let estimate = estimates[k][p];
                estimate <= TOUCHING_M || (estimate <= ESTIMATE_SLACK_M && contact(k, p).0 <= TOUCHING_M)
            })
        })
        .collect();
    // How deep the two links overlap by construction: the rest counts only beyond it, and beyond
    // the slack the samples may fall short of the deepest configuration by. A sample cannot be
    // deeper than the deepest so far where its capsules overlap no deeper, or where the shapes
    // overlap no deeper along the normal of an overlap measured before (any direction bounds
    // the depth; the frame is the first link's at every sample), to within what EPA resolves:
    // a depth the same at every sample bounds itself only to rounding.
    let mut deepest = 0.0_f64;
    for &p in &overlapping {
        let (a, b) = shape_pairs[p];
        let mut normals: Vec<Vector3<f64>> = Vec::new();
        for k in samples.clone() {
            let bounded = -estimates[k][p] <= deepest
                || normals.iter().any(|n| {
                    world
                        .collider_overlap_along(&placements[k], (i, a), (j, b), n)
                        .is_some_and(|bound| bound <= deepest + DEPTH_RESOLUTION_M)
                });
            if bounded {
                continue;
            }
            let (gap, normal) = contact(k, p);
            deepest = deepest.max(-gap);
            if normals.len() < NORMALS_KEPT {
                normals.push(normal);
            }
        }
    }
    let depth = DEPTH_SLACK_M + deepest;
    let rest: Vec<usize> = (0..shape_pairs.len()).filter(|p| !overlapping.contains(p)).collect();
    // Without the overlapping pieces, is the rest of the two links free at some sample?
    let rest_free_somewhere = samples.clone().any(|k| {
        rest.iter()
            .all(|&p| estimates[k][p] + depth > TOUCHING_M + ESTIMATE_SLACK_M || contact(k, p).0 + depth > TOUCHING_M)
    });
    if overlapping.is_empty() || rest.is_empty() || !rest_free_somewhere {
        found.pairs.push(ExcludedPair::new(
            a_name,
            b_name,
            format!("{sampled}: the links overlap by construction, so checking them tells nothing about a motion"),
        ));
        return found;
    }
    // Can the rest of the two links fold into each other deeper than the construction does?
    // Where no sample shows it (two `direct` slots: link i + 2 stays in a slab that shares only
    // the construction's depth with link i), checking them would only slow every query.
    let mut fold_rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed ^ FOLD_STREAM);
    let folds = (0..opts.fold_samples).any(|_| {
        placed(model, link_pair, &model.random_configuration(&mut fold_rng), &mut pose);
        // The capsule bound overlaps at least as deep as the shapes: where even it does not reach
        // the construction's depth, the exact distance cannot either.
        let deeper = |exact: bool, p: (usize, usize)| touching(&pose, p, exact) + depth <= 0.0;
        rest.iter().any(|&p| {
            let p = shape_pairs[p];
            capsules(&pose, p) + depth <= ESTIMATE_SLACK_M && deeper(false, p) && deeper(true, p)
        })
    });
    if !folds {
        let labels: Vec<String> = overlapping
            .iter()
            .map(|&p| shape_pairs[p])
            .map(|(a, b)| format!("{} / {}", model.links[i].colliders[a].label, model.links[j].colliders[b].label))
            .collect();
        found.pairs.push(ExcludedPair::new(
            a_name,
            b_name,
            format!(
                "{sampled}, their shapes {} overlap by up to {:.1} mm by construction, and the others never overlap deeper at any of {} more (seed {}): no fold to check",
                labels.join(", "),
                depth * 1e3,
                opts.fold_samples,
                opts.seed
            ),
        ));
        return found;
    }
    found.allowances.push(StructuralAllowance {
        a: a_name.to_string(),
        b: b_name.to_string(),
        depth_m: depth,
        reason: format!(
            "{sampled}, some of their shapes overlap by up to {:.1} mm by construction: the other shape pairs are checked and count as in contact only deeper than that",
            depth * 1e3
        ),
    });
    for (a, b) in overlapping.into_iter().map(|p| shape_pairs[p]) {
        found.shapes.push(ExcludedShapePair {
            a: a_name.to_string(),
            a_shape: a,
            a_label: model.links[i].colliders[a].label.clone(),
            b: b_name.to_string(),
            b_shape: b,
            b_label: model.links[j].colliders[b].label.clone(),
            reason: format!("{sampled}: these two pieces overlap by construction; the rest of the two links is checked"),
        });
    }
    found
}
