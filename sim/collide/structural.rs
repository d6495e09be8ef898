//! Link pairs that overlap by construction: in contact at every configuration.
//!
//! With the paper's link geometry (tubes of 0.12 m diameter) two links that are separated by one
//! short link (a `direct` module, d = 0.1 m; a UR wrist, d = 0.1 m) always overlap around the joint
//! between them, whatever the joint angles: the pair is structurally in contact and checking it
//! says nothing about a motion. Such pairs are found by sampling and excluded with their reason,
//! the "always in collision" category of a MoveIt collision matrix. Pairs that merely touch at the
//! home configuration are not excluded: one free sample keeps a pair checked.

use super::{distances, world, CollideError, CollideOptions, Distances, ExcludedPair, QueryOptions};
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

/// Self pairs of `model` in contact at every sampled configuration, as exclusions with the reason.
///
/// # Errors
/// When the model's geometry cannot be built (see [`world`]).
pub fn structural_overlaps(model: &Model, opts: &StructuralOptions) -> Result<Vec<ExcludedPair>, CollideError> {
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
    for _ in 0..opts.samples {
        model.forward(&model.random_configuration(&mut rng), &mut ws);
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
    Ok(pairs
        .iter()
        .zip(&always)
        .filter(|(_, always)| **always)
        .map(|(pair, _)| {
            ExcludedPair::new(
                pair.a_name.clone(),
                pair.b_name.clone(),
                format!(
                    "in contact at all {} sampled configurations (seed {}): the links overlap by construction, so checking them tells nothing about a motion",
                    opts.samples, opts.seed
                ),
            )
        })
        .collect())
}
