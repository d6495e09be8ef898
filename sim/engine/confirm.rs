//! Engine contacts measured again in exact geometry at the engine's own configuration, so a
//! contact only an engine sees (rapier's f32 narrow phase on cylinders is up to 1.25 cm off,
//! MuJoCo's cylinders are approximate) is told apart from a real one.

use super::ContactInterval;
use crate::collide::{self, CollisionWorld, Distances, QueryOptions};
use crate::model::Model;

/// Fills [`ContactInterval::parry_distance_m`] of each contact: the exact signed distance of its
/// pair at its configuration (`model` placed as `world` was built). A contact whose pair or
/// configuration does not fit the world is left unmeasured.
pub fn confirm_contacts(model: &Model, world: &CollisionWorld, contacts: &mut [ContactInterval]) {
    let mut ws = model.workspace();
    let mut out = Distances::new();
    // Every pair within a kilometre is measured exactly, not bounded.
    let query = QueryOptions {
        margin: 1e3,
        hulls: false,
        exact_depth: true,
    };
    for contact in contacts {
        if contact.q.len() != model.dof() {
            continue;
        }
        let Some(index) = world.pairs().iter().position(|p| p.a_name == contact.a && p.b_name == contact.b) else {
            continue;
        };
        model.forward(&contact.q, &mut ws);
        collide::distances(world, &ws.link_in_world, &query, &mut out);
        contact.parry_distance_m = out.estimates.get(index).map(|e| e.distance);
    }
}
