//! Link pairs that overlap by construction: in contact at every configuration.
//!
//! With the paper's link geometry (tubes of 0.12 m diameter) two links that are separated by one
//! short link (a `direct` module, d = 0.1 m; a UR wrist, d = 0.1 m) always overlap around the joint
//! between them, whatever the joint angles: the pair is structurally in contact and checking it
//! says nothing about a motion. Such pairs are found by sampling and excluded with their reason,
//! the "always in collision" category of a MoveIt collision matrix. Pairs that merely touch at the
//! home configuration are not excluded: one free sample keeps a pair checked.

use super::{distances, world, Body, CollideError, CollideOptions, Distances, ExcludedPair, ExcludedShapePair, QueryOptions};
use crate::model::Model;
use crate::scenario::Scenario;
use rand::SeedableRng;

/// Signed distance up to which a pair counts as in contact while sampling (m).
pub const TOUCHING_M: f64 = 1e-9;

/// Sampling settings for [`structural_overlaps`].
#[derive(Debug, Clone)]
pub struct StructuralOptions {
    /// Random configurations tried (default 256): a pair in contact at all of them is excluded.
    pub samples: usize,
    /// Seed of the configurations (default 0).
    pub seed: u64,
}

impl Default for StructuralOptions {
    fn default() -> Self {
        Self { samples: 256, seed: 0 }
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
}

/// Self pairs of `model` in contact at every sampled configuration: for each, the shape pairs
/// that are (excluded alone when the link pair is otherwise free at some sample, so a real fold
/// of one link into the other is still caught), else the whole link pair; each with its reason.
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
    };
    let world = world(model, &empty, &CollideOptions::default())?;
    let pairs = world.pairs();
    let mut always = vec![opts.samples > 0; pairs.len()];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed);
    let mut ws = model.workspace();
    let mut out = Distances::new();
    let query = QueryOptions {
        // Touching counts as contact: tubes that meet end to end are at +-1e-17 m, and which
        // side of zero rounding lands on says nothing about the design.
        margin: TOUCHING_M,
        hulls: false,
        exact_depth: true,
    };
    let mut placements = Vec::with_capacity(opts.samples);
    for _ in 0..opts.samples {
        model.forward(&model.random_configuration(&mut rng), &mut ws);
        placements.push(ws.link_in_world.clone());
        distances(&world, &ws.link_in_world, &query, &mut out);
        let mut touching = vec![false; pairs.len()];
        for pair in &out.within_margin {
            touching[pair.pair] = true;
        }
        for (always, touching) in always.iter_mut().zip(&touching) {
            *always &= *touching;
        }
        if !always.iter().any(|a| *a) {
            break;
        }
    }
    let sampled = format!("in contact at all {} sampled configurations (seed {})", opts.samples, opts.seed);
    let mut exclusions = StructuralExclusions::default();
    for (pair, _) in pairs.iter().zip(&always).filter(|(_, always)| **always) {
        let (Body::Link(i), Body::Link(j)) = (pair.a, pair.b) else {
            continue;
        };
        let shape_pairs: Vec<(usize, usize)> = (0..model.links[i].colliders.len())
            .flat_map(|a| (0..model.links[j].colliders.len()).map(move |b| (a, b)))
            .collect();
        let touching = |placement: &[nalgebra::Isometry3<f64>], (a, b): (usize, usize)| {
            world.collider_distance(placement, (i, a), (j, b)).is_some_and(|d| d <= TOUCHING_M)
        };
        let overlapping: Vec<(usize, usize)> = shape_pairs
            .iter()
            .copied()
            .filter(|&p| placements.iter().all(|placement| touching(placement, p)))
            .collect();
        // Without the overlapping pieces, is the rest of the two links free at some sample?
        let rest_free_somewhere = placements.iter().any(|placement| {
            shape_pairs
                .iter()
                .filter(|p| !overlapping.contains(p))
                .all(|&p| !touching(placement, p))
        });
        let some_rest = overlapping.len() < shape_pairs.len();
        if overlapping.is_empty() || !some_rest || !rest_free_somewhere {
            exclusions.pairs.push(ExcludedPair::new(
                pair.a_name.clone(),
                pair.b_name.clone(),
                format!("{sampled}: the links overlap by construction, so checking them tells nothing about a motion"),
            ));
            continue;
        }
        for (a, b) in overlapping {
            exclusions.shapes.push(ExcludedShapePair {
                a: pair.a_name.clone(),
                a_shape: a,
                a_label: model.links[i].colliders[a].label.clone(),
                b: pair.b_name.clone(),
                b_shape: b,
                b_label: model.links[j].colliders[b].label.clone(),
                reason: format!("{sampled}: these two pieces overlap by construction; the rest of the two links is checked"),
            });
        }
    }
    Ok(exclusions)
}
