//! Link pairs that overlap by construction: in contact at every configuration.
//!
//! With the paper's link geometry (tubes of 0.12 m diameter) two links that are separated by one
//! short link (a `direct` module, d = 0.1 m; a UR wrist, d = 0.1 m) always overlap around the joint
//! between them, whatever the joint angles: the pair is structurally in contact and checking it
//! says nothing about a motion. Such pairs are found by sampling and excluded with their reason,
//! the "always in collision" category of a MoveIt collision matrix. Pairs that merely touch at the
//! home configuration are not excluded: one free sample keeps a pair checked.

use super::{
    distances, world, Body, CollideError, CollideOptions, Distances, ExcludedPair, ExcludedShapePair, QueryOptions, StructuralAllowance,
};
use crate::model::Model;
use crate::scenario::Scenario;
use rand::SeedableRng;

/// Signed distance up to which a pair counts as in contact while sampling (m).
pub const TOUCHING_M: f64 = 1e-9;

/// Added to the deepest overlap sampled to make a structural allowance (m): sampling finds the
/// deepest overlap of two slabs only approximately, and exactly that depth is construction too.
pub(super) const DEPTH_SLACK_M: f64 = 1e-3;

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
        let distance = |placement: &[nalgebra::Isometry3<f64>], (a, b): (usize, usize)| {
            world.collider_distance(placement, (i, a), (j, b)).unwrap_or(f64::INFINITY)
        };
        let overlapping: Vec<(usize, usize)> = shape_pairs
            .iter()
            .copied()
            .filter(|&p| placements.iter().all(|placement| distance(placement, p) <= TOUCHING_M))
            .collect();
        // How deep the two links overlap by construction: the rest counts only beyond it, and
        // beyond the slack 256 samples may fall short of the deepest configuration by.
        let depth = DEPTH_SLACK_M
            + overlapping
                .iter()
                .flat_map(|&p| placements.iter().map(move |placement| (p, placement)))
                .map(|(p, placement)| -distance(placement, p))
                .fold(0.0_f64, f64::max);
        let rest: Vec<(usize, usize)> = shape_pairs.iter().copied().filter(|p| !overlapping.contains(p)).collect();
        // Without the overlapping pieces, is the rest of the two links free at some sample?
        let rest_free_somewhere = placements
            .iter()
            .any(|placement| rest.iter().all(|&p| distance(placement, p) + depth > TOUCHING_M));
        if overlapping.is_empty() || rest.is_empty() || !rest_free_somewhere {
            exclusions.pairs.push(ExcludedPair::new(
                pair.a_name.clone(),
                pair.b_name.clone(),
                format!("{sampled}: the links overlap by construction, so checking them tells nothing about a motion"),
            ));
            continue;
        }
        // Can the rest of the two links fold into each other deeper than the construction does?
        // Where no sample shows it (two `direct` slots: link i + 2 stays in a slab that shares
        // only the construction's depth with link i), checking them would only slow every query.
        let mut fold_rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed ^ FOLD_STREAM);
        let folds = (0..opts.fold_samples).any(|_| {
            model.forward(&model.random_configuration(&mut fold_rng), &mut ws);
            rest.iter().any(|&p| distance(&ws.link_in_world, p) + depth <= 0.0)
        });
        if !folds {
            let labels: Vec<String> = overlapping
                .iter()
                .map(|&(a, b)| format!("{} / {}", model.links[i].colliders[a].label, model.links[j].colliders[b].label))
                .collect();
            exclusions.pairs.push(ExcludedPair::new(
                pair.a_name.clone(),
                pair.b_name.clone(),
                format!(
                    "{sampled}, their shapes {} overlap by up to {:.1} mm by construction, and the others never overlap deeper at any of {} more (seed {}): no fold to check",
                    labels.join(", "),
                    depth * 1e3,
                    opts.fold_samples,
                    opts.seed
                ),
            ));
            continue;
        }
        exclusions.allowances.push(StructuralAllowance {
            a: pair.a_name.clone(),
            b: pair.b_name.clone(),
            depth_m: depth,
            reason: format!(
                "{sampled}, some of their shapes overlap by up to {:.1} mm by construction: the other shape pairs are checked and count as in contact only deeper than that",
                depth * 1e3
            ),
        });
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
