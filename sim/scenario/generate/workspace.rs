//! The paper's workspace task ("Adapting to Task Requirements"): 1000 poses with positions
//! uniform in a 0.8 x 1.0 x 0.8 m box (x, y, z) and orientations uniform on SO(3), judged as full
//! poses, rotationally symmetric about the tool z axis, or positions only; the box is scaled by
//! 0.5 to 1.5 for the paper's size study.

use super::{provenance, uniform_rotation, FLOOR_HEIGHT_M};
use crate::scenario::{Floor, Goal, Scenario, ScenarioError, Tolerance};
use nalgebra::{Isometry3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Goals in the committed workspace scenarios (paper: 1000).
pub const WORKSPACE_GOALS: usize = 1000;
/// Seed of the committed workspace scenarios; the three tolerance modes share it, so they hold
/// the same poses. Arbitrary, fixed once.
pub const WORKSPACE_SEED: u64 = 1000;
/// Edge lengths of the workspace box along x, y, z at scale 1 (m; paper, Fig. "workspace").
pub const WORKSPACE_BOX_SIZE_M: [f64; 3] = [0.8, 1.0, 0.8];
/// Centre of the box at scale 1, in the base frame (m). The paper does not place its box; here it
/// spans x in [0.2, 1.0], y in [-0.5, 0.5], z in [0, 0.8]: in front of the base, clear of the
/// first joint modules (0.2 m ahead of the base axis), its bottom 0.1 m above the floor, and its
/// centre 0.72 m from the shoulder, inside the reach of a 1 m arm. Scaling multiplies both the
/// centre and the size, so the box grows away from the base.
pub const WORKSPACE_BOX_CENTRE_M: [f64; 3] = [0.6, 0.0, 0.4];
/// Allowed scale factors (paper: "uniformly scale workspace dimensions by a factor between
/// 0.5-1.5").
pub const WORKSPACE_SCALE_RANGE: [f64; 2] = [0.5, 1.5];

/// `count` poses in the workspace box scaled by `scale`, judged with `tolerance`, from `seed`.
///
/// Positions are uniform in the box of [`WORKSPACE_BOX_SIZE_M`] centred at
/// [`WORKSPACE_BOX_CENTRE_M`], both multiplied by `scale`; orientations are uniform on SO(3)
/// (Shoemake's method). No obstacles; floor at [`super::FLOOR_HEIGHT_M`].
///
/// # Errors
/// [`ScenarioError::Parameter`] when `count` is 0 or `scale` is outside
/// [`WORKSPACE_SCALE_RANGE`].
pub fn workspace(count: usize, scale: f64, tolerance: Tolerance, seed: u64) -> Result<Scenario, ScenarioError> {
    let [low, high] = WORKSPACE_SCALE_RANGE;
    if !(low..=high).contains(&scale) {
        return Err(ScenarioError::Parameter {
            generator: "workspace".into(),
            parameter: "scale".into(),
            message: format!("{scale}: expected a factor in [{low}, {high}]"),
        });
    }
    if count == 0 {
        return Err(ScenarioError::Parameter {
            generator: "workspace".into(),
            parameter: "count".into(),
            message: "0: a scenario needs at least one goal".into(),
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let bounds: [(f64, f64); 3] = std::array::from_fn(|axis| {
        let centre = WORKSPACE_BOX_CENTRE_M[axis] * scale;
        let half = WORKSPACE_BOX_SIZE_M[axis] * scale / 2.0;
        (centre - half, centre + half)
    });
    let goals = (0..count)
        .map(|index| {
            let [x, y, z] = bounds.map(|(lo, hi)| rng.random_range(lo..hi) + 0.0);
            let position = Vector3::new(x, y, z);
            Goal {
                name: format!("goal {index}"),
                position,
                rotation: uniform_rotation(&mut rng),
                tolerance,
                task: None,
            }
        })
        .collect();
    let tolerance_name = tolerance.name();
    Ok(Scenario {
        name: format!("workspace-{tolerance_name}"),
        world_from_base: Isometry3::identity(),
        floor: Some(Floor { height: FLOOR_HEIGHT_M }),
        obstacles: vec![],
        goals,
        home: None,
        provenance: Some(provenance(
            "workspace",
            seed,
            &[
                ("count", count.into()),
                ("scale", scale.into()),
                ("tolerance", tolerance_name.into()),
            ],
        )),
        notes: Vec::new(),
    })
}
