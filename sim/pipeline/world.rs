//! The exact collision world a run checks: the placed model, the scenario, the exclusions.

use crate::collide;
use crate::error::Error;
use crate::model::Model;

/// The exact collision world of a placed model in a scenario, with the model's structurally
/// overlapping self pairs excluded (each with its reason, see [`collide::structural_overlaps`])
/// plus `extra` exclusions (e.g. from an SRDF).
///
/// # Errors
/// [`Error::Collide`] when the geometry cannot be built or an exclusion names an unknown link.
pub fn collision_world(
    placed: &Model,
    scenario: &crate::scenario::Scenario,
    extra: &[collide::ExcludedPair],
) -> Result<collide::CollisionWorld, Error> {
    let structural = collide::structural_overlaps(placed, &collide::StructuralOptions::default())?;
    let mut excluded_pairs = structural.pairs;
    excluded_pairs.extend_from_slice(extra);
    let opts = collide::CollideOptions {
        excluded_pairs,
        excluded_shapes: structural.shapes,
        structural_allowances: structural.allowances,
    };
    Ok(collide::world(placed, scenario, &opts)?)
}
