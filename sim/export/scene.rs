//! The whole scene as MJCF: the robot at the scenario's base pose and the scenario around it.

use super::{to_mjcf, ExportError, MjcfOptions};
use crate::model::{Collider, Model};
use crate::scenario::Scenario;

/// MJCF text of the whole scene: the model at the scenario's base pose, the obstacles as static
/// geoms named as in the scenario, the floor plane `floor`, a site `goal/K` at each goal's frame,
/// colours that tell them apart, and a keyframe per `(name, q)` of `keys` (the run's home and
/// each goal's chosen configuration), so MuJoCo's viewer shows what the run checks.
///
/// # Errors
/// [`ExportError`] (e.g. an obstacle named like a link geom, a key of another length).
pub fn scene_mjcf(model: &Model, scenario: &Scenario, keys: Vec<(String, Vec<f64>)>) -> Result<String, ExportError> {
    let placed = model.placed(&scenario.world_from_base);
    let world_colliders = scenario
        .obstacles
        .iter()
        .map(|o| Collider {
            link_from_shape: o.world_from_shape,
            shape: o.shape.clone(),
            label: o.name.clone(),
        })
        .collect();
    let world_sites = scenario
        .goals
        .iter()
        .enumerate()
        .map(|(k, goal)| {
            let pose = nalgebra::Isometry3::from_parts(goal.position.into(), goal.rotation);
            (format!("goal/{k}"), pose)
        })
        .collect();
    let opts = MjcfOptions {
        world_colliders,
        floor_height: scenario.floor.map(|f| f.height),
        world_sites,
        colours: true,
        keyframes: keys,
        ..Default::default()
    };
    to_mjcf(&placed, &opts)
}
