//! A proof that holds for every goal at once: the arm's first joints collide wherever they are.
//!
//! A robot placed with an obstacle through its shoulder (a real arm's large first link on the
//! paper's cluttered tasks) collides at every configuration, so no goal is reachable free. Each
//! goal's own searches are bound to that goal's tolerance and give up near singularities; this
//! one asks only whether the links moved by joints 1 to `k` (`k` = 0, 1, 2, ...) collide with
//! an obstacle, the floor or one another throughout their joints' limits: a breadth-first cover
//! of those joints' box, each box certified in collision when its centre's deepest overlap is
//! deeper than its bodies can move within it (the certificate the joint-space search uses).

use super::refine::Checker;
use super::search::Clear;
use crate::collide::MotionBounds;
use crate::model::Model;
use std::collections::VecDeque;

/// Joints at most in the prefix: the cover's boxes grow as a power of it.
const MOST_JOINTS: usize = 3;

/// What the cover proved: the first `joints` joints collide at every configuration within
/// their limits.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Collides {
    pub(super) joints: usize,
    pub(super) boxes: usize,
    /// The pairs that certified boxes, in the order first met.
    pub(super) pairs: Vec<String>,
    /// The shallowest certified overlap at a box centre (m, negative), for the message.
    pub(super) shallowest_m: f64,
    /// The clearance a configuration must keep to count as free (m).
    pub(super) margin_m: f64,
}

impl Collides {
    /// The proof as a goal's report states it.
    pub(super) fn describe(&self) -> String {
        let pairs = super::summary(&self.pairs);
        let (collides, collide) = if self.margin_m > 0.0 {
            (
                format!("collides or keeps less than the {} m margin", self.margin_m),
                format!("collide or keep less than the {} m margin", self.margin_m),
            )
        } else {
            ("collides".to_string(), "collide".to_string())
        };
        if self.joints == 0 {
            return format!(
                "every configuration {collides}: the links no joint moves {collide} ({pairs}, clearance {:.1} mm)",
                self.shallowest_m * 1e3
            );
        }
        let (joints, move_) = if self.joints == 1 {
            ("joint 1 within its limits".to_string(), "it moves")
        } else {
            (format!("joints 1 to {} within their limits", self.joints), "they move")
        };
        format!(
            "every configuration {collides}, whatever the goal: at every position of {joints}, the links {move_} {collide} ({pairs}; {} {}, each throughout: its centre's clearance, {:.1} mm or less, is below the margin by more than its bodies can move within it)",
            self.boxes,
            if self.boxes == 1 { "box" } else { "boxes" },
            self.shallowest_m * 1e3
        )
    }
}

/// The first prefix of the arm (up to [`MOST_JOINTS`] joints) whose every configuration within
/// the joint limits collides, covered with at most `budget` boxes in all; `None` when each
/// prefix has a free configuration, runs out of boxes, or has unbounded joints.
pub(super) fn first_joints_collide(
    model: &Model,
    checker: &mut Checker,
    bounds: &MotionBounds,
    margin: f64,
    budget: usize,
) -> Option<Collides> {
    let (lower, upper) = super::search::ranges(model)?;
    let dof = model.dof();
    // Joints beyond the prefix move none of its links: they stay mid-range.
    let mut q: Vec<f64> = lower.iter().zip(&upper).map(|(lo, hi)| 0.5 * (lo + hi)).collect();
    // Every prefix's first box is centred on this configuration, and its pairs are among the
    // longest prefix's: where those keep the margin there, so do the shorter prefixes', and each
    // cover would stop at its first box. One query answers for all of them.
    let longest = checker.pairs_up_to(dof.min(MOST_JOINTS));
    if checker.clearance_among(&q, &longest, true) > margin {
        return None;
    }
    let mut half = vec![0.0; dof];
    let mut single = vec![0.0; dof];
    let mut left = budget;
    for joints in 0..=dof.min(MOST_JOINTS) {
        let levels = checker.pairs_up_to(joints);
        let mut proof = Collides {
            joints,
            boxes: 0,
            pairs: Vec::new(),
            shallowest_m: f64::NEG_INFINITY,
            margin_m: margin,
        };
        let mut queue: VecDeque<(Vec<f64>, Vec<f64>)> = VecDeque::from([(lower[..joints].to_vec(), upper[..joints].to_vec())]);
        let mut covered = true;
        while let Some((low, high)) = queue.pop_front() {
            if left == 0 {
                return None;
            }
            left -= 1;
            proof.boxes += 1;
            for j in 0..joints {
                q[j] = 0.5 * (low[j] + high[j]);
                half[j] = 0.5 * (high[j] - low[j]);
            }
            let clearance = checker.clearance_among(&q, &levels, true);
            // The joint-space search's certificate, on these pairs alone.
            let certified = super::judge_box(checker, bounds, model.links.len(), &half, clearance, margin);
            let pair = checker.closest_pair();
            let pair = match (certified, pair) {
                (Clear::Colliding, Some(pair)) => {
                    if !proof.pairs.contains(&pair.name) {
                        proof.pairs.push(pair.name);
                    }
                    proof.shallowest_m = proof.shallowest_m.max(clearance);
                    continue;
                }
                (Clear::Unknown, Some(pair)) if joints > 0 => pair,
                // A free centre, nothing to collide, or no joint to split: nothing proven.
                _ => {
                    covered = false;
                    break;
                }
            };
            // The joint that moves the pair furthest within the box is halved.
            let motions: Vec<f64> = (0..joints)
                .map(|j| {
                    single[j] = half[j];
                    let moves = bounds.relative_motion(pair.bodies[0], pair.bodies[1], &single);
                    single[j] = 0.0;
                    moves
                })
                .collect();
            let split = (0..joints).max_by(|&a, &b| motions[a].total_cmp(&motions[b])).unwrap_or(0);
            let middle = 0.5 * (low[split] + high[split]);
            let (mut first_high, mut second_low) = (high.clone(), low.clone());
            first_high[split] = middle;
            second_low[split] = middle;
            queue.push_back((low, first_high));
            queue.push_back((second_low, high));
        }
        half[..joints].fill(0.0);
        if covered {
            return Some(proof);
        }
    }
    None
}
