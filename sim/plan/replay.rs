//! The segments the engines replay kinematically, beside the certified check: the planned
//! edges and, for each goal without a path, the segment that was tried (the motion the paper's
//! heuristic would have made), each with its certified verdict.
//!
//! The replay clock is by segment, not by time: segment `k` occupies `[k, k + 1)` and a sample at
//! `k + s` is the configuration at path parameter `s` of segment `k`, so an engine's contact
//! maps back to its segment and to where on it. Samples are spaced at most [`REPLAY_STEP`] apart
//! in every joint: the engines are sampled checkers, unlike the certified one.

use super::certify::SegmentCheck;
use super::trajectory::{GoalStep, Trajectory};
use serde::Serialize;

/// Largest joint change between replay samples (rad or m).
pub const REPLAY_STEP: f64 = 0.005;

/// One segment to replay.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReplaySegment {
    /// Goal the segment heads for.
    pub goal: usize,
    /// Part of the trajectory (certified free) or a blocked goal's attempt.
    pub planned: bool,
    /// Start configuration.
    pub from: Vec<f64>,
    /// End configuration.
    pub to: Vec<f64>,
    /// The certified check of the segment.
    pub certified: SegmentCheck,
}

/// The segments of `trajectory` to replay, in goal order: every edge of each reached goal's
/// path, and each unreached goal's attempt.
pub fn replay_segments(trajectory: &Trajectory) -> Vec<ReplaySegment> {
    let mut previous = trajectory.home.clone();
    let mut segments = Vec::new();
    for step in &trajectory.steps {
        match step {
            GoalStep::Reached {
                goal,
                waypoints,
                segments: checks,
                ..
            } => {
                for (to, check) in waypoints.iter().zip(checks) {
                    segments.push(ReplaySegment {
                        goal: *goal,
                        planned: true,
                        from: previous.clone(),
                        to: to.clone(),
                        certified: check.clone(),
                    });
                    previous.clone_from(to);
                }
            }
            _ => {
                if let Some(attempt) = step.attempt() {
                    segments.push(ReplaySegment {
                        goal: step.goal(),
                        planned: false,
                        from: attempt.from.clone(),
                        to: attempt.to.clone(),
                        certified: attempt.segment.clone(),
                    });
                }
            }
        }
    }
    segments
}

/// Samples `(replay clock, configuration)` of `segments`; both ends of every segment included
/// (the end at `k + 1 - 1e-9`, so it still maps to segment `k`).
pub fn replay_samples(segments: &[ReplaySegment]) -> Vec<(f64, Vec<f64>)> {
    // Sized once: tens of thousands of goals make millions of samples, and a doubling vector
    // would hold up to twice that.
    let mut samples = Vec::with_capacity(segments.iter().map(|segment| steps(segment) + 1).sum());
    samples.extend(replay_sample_iter(segments));
    samples
}

/// [`replay_samples`] one at a time, for a pass that need not hold them all (the static load
/// of a run without engines).
pub fn replay_sample_iter(segments: &[ReplaySegment]) -> impl Iterator<Item = (f64, Vec<f64>)> + '_ {
    segments.iter().enumerate().flat_map(|(k, segment)| {
        let count = steps(segment);
        (0..=count).map(move |i| {
            let s = i as f64 / count as f64;
            let q = segment.from.iter().zip(&segment.to).map(|(a, b)| a + s * (b - a)).collect();
            (k as f64 + s.min(1.0 - 1e-9), q)
        })
    })
}

/// Steps of [`REPLAY_STEP`] that sample a segment (at least one).
fn steps(segment: &ReplaySegment) -> usize {
    let largest = segment.from.iter().zip(&segment.to).map(|(a, b)| (b - a).abs()).fold(0.0, f64::max);
    ((largest / REPLAY_STEP).ceil() as usize).max(1)
}
