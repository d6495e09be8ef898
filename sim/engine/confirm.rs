//! Engine contacts measured again in exact geometry at the engine's own configuration, so a
//! contact only an engine sees (rapier's f32 narrow phase on cylinders is up to 1.25 cm off,
//! MuJoCo's cylinders are approximate) is told apart from a real one.

use super::ContactInterval;
use crate::collide::{self, CollisionWorld, Distances, QueryOptions};
use crate::model::Model;
use crate::plan::TimedPath;

/// Every pair within a kilometre measured exactly, not bounded.
const EVERY_PAIR_EXACTLY: QueryOptions = QueryOptions {
    margin: 1e3,
    hulls: false,
    exact_depth: true,
    mesh_hulls: false,
};

/// Fills [`ContactInterval::parry_distance_m`] of each contact: the exact signed distance of its
/// pair at its configuration (`model` placed as `world` was built). A contact whose pair or
/// configuration does not fit the world is left unmeasured.
pub fn confirm_contacts(model: &Model, world: &CollisionWorld, contacts: &mut [ContactInterval]) {
    let mut ws = model.workspace();
    let mut out = Distances::new();
    let query = EVERY_PAIR_EXACTLY;
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

/// Reference configurations sampled per contact interval (and at least one every 5 ms).
const REFERENCE_SAMPLES: usize = 16;

/// Fills [`ContactInterval::reference_distance_m`] of each dynamic-run contact: the smallest exact
/// distance of its pair at the reference configurations over its interval (sampled every 5 ms,
/// at least 16 times). A contact whose pair does not fit the world is left
/// unmeasured.
pub fn measure_reference(model: &Model, world: &CollisionWorld, timed: &TimedPath, contacts: &mut [ContactInterval]) {
    let mut ws = model.workspace();
    let mut out = Distances::new();
    let query = EVERY_PAIR_EXACTLY;
    let mut q = vec![0.0; model.dof()];
    let mut qd = vec![0.0; model.dof()];
    for contact in contacts {
        let Some(index) = world.pairs().iter().position(|p| p.a_name == contact.a && p.b_name == contact.b) else {
            continue;
        };
        let span = (contact.end_s - contact.start_s).max(0.0);
        let samples = REFERENCE_SAMPLES.max((span / 5e-3).ceil() as usize).min(100_000);
        let mut smallest = f64::INFINITY;
        for k in 0..=samples {
            let t = contact.start_s + span * k as f64 / samples as f64;
            timed.sample(t, &mut q, &mut qd);
            model.forward(&q, &mut ws);
            collide::distances(world, &ws.link_in_world, &query, &mut out);
            if let Some(e) = out.estimates.get(index) {
                smallest = smallest.min(e.distance);
            }
        }
        contact.reference_distance_m = smallest.is_finite().then_some(smallest);
    }
}
