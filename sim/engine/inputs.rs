//! The input checks both engines share: one seam, so rapier and MuJoCo refuse the same inputs
//! with the same messages before either builds a world.

use super::{EngineError, Gains, RunOptions};
use crate::model::Model;
use crate::plan::TimedPath;

/// A dynamic run's inputs: the step, the chain, the gains and every path configuration fit.
///
/// # Errors
/// [`EngineError::InvalidTimestep`], [`EngineError::Chain`], [`EngineError::GainsLength`],
/// [`EngineError::EmptyPath`] or [`EngineError::ConfigurationLength`].
pub(super) fn check_run(model: &Model, path: &TimedPath, gains: &Gains, opts: &RunOptions) -> Result<(), EngineError> {
    check_common(model, opts)?;
    let dof = model.dof();
    if gains.stiffness.len() != dof || gains.damping.len() != dof {
        return Err(EngineError::GainsLength {
            robot: model.name.clone(),
            stiffness: gains.stiffness.len(),
            damping: gains.damping.len(),
            expected: dof,
        });
    }
    if path.segments.is_empty() {
        return Err(EngineError::EmptyPath { robot: model.name.clone() });
    }
    let lengths = path
        .segments
        .iter()
        .map(|s| if s.from.len() != dof { s.from.len() } else { s.to.len() });
    check_lengths(model, "path segment", lengths)
}

/// A replay's inputs: the step, the chain and every sample's configuration fit.
///
/// # Errors
/// [`EngineError::InvalidTimestep`], [`EngineError::Chain`] or [`EngineError::ConfigurationLength`].
pub(super) fn check_replay(model: &Model, samples: &[(f64, Vec<f64>)], opts: &RunOptions) -> Result<(), EngineError> {
    check_common(model, opts)?;
    check_lengths(model, "sample", samples.iter().map(|(_, q)| q.len()))
}

fn check_common(model: &Model, opts: &RunOptions) -> Result<(), EngineError> {
    if !(opts.timestep_s.is_finite() && opts.timestep_s > 0.0) {
        return Err(EngineError::InvalidTimestep {
            timestep_s: opts.timestep_s,
        });
    }
    if model.links.len() != model.dof() + 1 {
        return Err(EngineError::Chain {
            robot: model.name.clone(),
            links: model.links.len(),
            joints: model.dof(),
        });
    }
    Ok(())
}

/// Each configuration has one value per joint.
///
/// # Errors
/// [`EngineError::ConfigurationLength`] naming the first that does not.
pub(super) fn check_lengths(model: &Model, context: &'static str, lengths: impl Iterator<Item = usize>) -> Result<(), EngineError> {
    for (index, found) in lengths.enumerate() {
        if found != model.dof() {
            return Err(EngineError::ConfigurationLength {
                robot: model.name.clone(),
                context,
                index,
                found,
                expected: model.dof(),
            });
        }
    }
    Ok(())
}
