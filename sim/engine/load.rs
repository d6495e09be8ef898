//! The static load check: the gravity torque every joint must hold along a trajectory, from
//! MuJoCo and from our own statics ([`Model::gravity_torques`]), against each joint's rating.

use super::mujoco_run::Loaded;
use super::{EngineError, RunOptions};
use crate::model::Model;
use serde::Serialize;

/// Smallest torque scale the MuJoCo cross-check is relative to (N m).
const LOAD_FLOOR_N_M: f64 = 1.0;

/// The static gravity load of every joint along a trajectory, against its rating.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StaticLoad {
    /// Gravity used (m/s^2, along world -z).
    pub gravity_m_s2: f64,
    /// Per joint, chain order.
    pub joints: Vec<JointLoad>,
    /// Largest disagreement between MuJoCo's gravity torque (`qfrc_bias` at rest) and ours
    /// ([`Model::gravity_torques`]) over all samples and joints, relative to the largest
    /// torque magnitude of that sample (at least 1 N m); above 1e-9 it is a finding (a bug on
    /// one side). `None` when MuJoCo did not run ([`static_load_ours`]).
    pub max_relative_disagreement: Option<f64>,
    /// The engine whose gravity torques were compared with ours ([`super::Engine::label`]);
    /// `None` from [`static_load_ours`].
    #[serde(skip)]
    pub cross_checked_by: Option<&'static str>,
}

/// Torque magnitudes (N m or N) at or below this are no load: the engines' rounding where the
/// exact load is zero (2.7e-15 N m on `free-offset-6dof`'s joint 6).
const NO_LOAD: f64 = 1e-9;

/// The static gravity load of one joint.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointLoad {
    /// Joint name.
    pub joint: String,
    /// Largest gravity torque magnitude over the samples, MuJoCo's (N m or N).
    pub peak_torque: f64,
    /// Index of the sample where it occurs (the first, on a tie); 0 without samples.
    pub sample: usize,
    /// The joint's rating (`Joint::max_effort`: catalog 60 N m, URDF `effort`), if known.
    pub rated: Option<f64>,
    /// The peak exceeds the rating.
    pub over: bool,
}

/// Gravity torque of every joint at each of `samples` (rad or m) held at rest, from MuJoCo
/// (`qfrc_bias` with zero velocity, after `mj_forward`) and cross-checked against
/// [`Model::gravity_torques`]; gravity `gravity_m_s2` (m/s^2) along world -z. `model` should
/// be placed as in the run (the base orientation decides where gravity points).
///
/// # Errors
/// [`EngineError::Export`], [`EngineError::MujocoLoad`], [`EngineError::Mujoco`], and
/// [`EngineError::ConfigurationLength`] for a sample of the wrong length.
pub fn static_load<Q: AsRef<[f64]>>(
    model: &Model,
    samples: impl IntoIterator<Item = Q>,
    gravity_m_s2: f64,
) -> Result<StaticLoad, EngineError> {
    let opts = RunOptions {
        gravity_m_s2,
        ..RunOptions::default()
    };
    let loaded = Loaded::new(model, None, None, None, &opts)?;
    let mut data = loaded.model.make_data();
    let mut joints = unloaded(model);
    let mut max_relative_disagreement = 0.0_f64;
    for (index, q) in samples.into_iter().enumerate() {
        let q = q.as_ref();
        check_length(model, index, q)?;
        loaded.set_configuration(&mut data, q);
        data.qvel_mut().fill(0.0);
        data.forward();
        let mujoco: Vec<f64> = loaded.dof_address.iter().map(|&d| data.qfrc_bias()[d]).collect();
        let ours = model.gravity_torques(q, gravity_m_s2);
        // Relative to the sample's largest torque, but never to less than 1 N m: an arm standing
        // straight up carries 1e-14 N m of rounding, whose relative spread means nothing.
        let scale = mujoco.iter().fold(LOAD_FLOOR_N_M, |a, b| a.max(b.abs()));
        for (j, load) in joints.iter_mut().enumerate() {
            let difference = (mujoco[j] - ours[j]).abs();
            max_relative_disagreement = max_relative_disagreement.max(difference / scale);
            load.record(mujoco[j], index);
        }
    }
    Ok(judged(joints, gravity_m_s2, Some(max_relative_disagreement)))
}

/// As [`static_load`] from our own gravity torques alone ([`Model::gravity_torques`], which
/// agrees with MuJoCo's to 5e-12 on every shipped design), for runs without MuJoCo: the rating is
/// judged whichever engines run.
///
/// # Errors
/// [`EngineError::ConfigurationLength`] for a sample of the wrong length.
pub fn static_load_ours<Q: AsRef<[f64]>>(
    model: &Model,
    samples: impl IntoIterator<Item = Q>,
    gravity_m_s2: f64,
) -> Result<StaticLoad, EngineError> {
    let mut joints = unloaded(model);
    let mut ws = model.workspace();
    for (index, q) in samples.into_iter().enumerate() {
        let q = q.as_ref();
        check_length(model, index, q)?;
        for (load, torque) in joints.iter_mut().zip(model.gravity_torques_in(&mut ws, q, gravity_m_s2)) {
            load.record(torque, index);
        }
    }
    Ok(judged(joints, gravity_m_s2, None))
}

/// [`EngineError::ConfigurationLength`] for sample `index` of the wrong length.
fn check_length(model: &Model, index: usize, q: &[f64]) -> Result<(), EngineError> {
    if q.len() == model.dof() {
        return Ok(());
    }
    Err(EngineError::ConfigurationLength {
        robot: model.name.clone(),
        context: "sample",
        index,
        found: q.len(),
        expected: model.dof(),
    })
}

impl JointLoad {
    /// Keeps `torque` (N m or N) of sample `index` when its magnitude is the largest so far (the
    /// first sample on a tie) and above [`NO_LOAD`]: a joint gravity does not load (its axis
    /// vertical, or the links beyond it balanced on it) peaks at 0 in sample 0, not at whichever
    /// sample's rounding came out largest.
    fn record(&mut self, torque: f64, index: usize) {
        if torque.abs() > self.peak_torque.max(NO_LOAD) {
            self.peak_torque = torque.abs();
            self.sample = index;
        }
    }
}

/// The peaks judged against the ratings.
fn judged(mut joints: Vec<JointLoad>, gravity_m_s2: f64, max_relative_disagreement: Option<f64>) -> StaticLoad {
    for load in &mut joints {
        load.over = load.rated.is_some_and(|rated| load.peak_torque > rated);
    }
    StaticLoad {
        gravity_m_s2,
        joints,
        max_relative_disagreement,
        cross_checked_by: None,
    }
}

fn unloaded(model: &Model) -> Vec<JointLoad> {
    model
        .joints
        .iter()
        .map(|joint| JointLoad {
            joint: joint.name.clone(),
            peak_torque: 0.0,
            sample: 0,
            rated: joint.max_effort,
            over: false,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::JointLoad;

    fn load() -> JointLoad {
        JointLoad {
            joint: "joint6".into(),
            peak_torque: 0.0,
            sample: 0,
            rated: None,
            over: false,
        }
    }

    #[test]
    fn rounding_is_no_load_and_a_real_torque_is_the_peak() {
        let mut joint = load();
        // MuJoCo's rounding on a joint gravity does not load, as on free-offset-6dof's joint 6.
        for (index, torque) in [(3, 2.7e-15), (148, -2.66e-15), (7, 1e-12)] {
            joint.record(torque, index);
        }
        assert_eq!((joint.peak_torque, joint.sample), (0.0, 0));
        joint.record(-0.4, 9);
        joint.record(0.3, 10);
        joint.record(0.4, 11);
        assert_eq!((joint.peak_torque, joint.sample), (0.4, 9), "the largest, the first on a tie");
    }
}
