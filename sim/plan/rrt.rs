//! Bidirectional RRT-Connect in joint space with certified edges, and certified shortcutting.
//!
//! Why RRT-Connect: consecutive goals of a course are usually joined by a straight segment or a
//! short detour; RRT-Connect finds short detours in few samples, needs no precomputed roadmap
//! (each pair of goals has its own start and goal set), and with one tree rooted at the start and
//! one rooted at every goal configuration it searches towards the whole goal set at once.
//!
//! Every edge added to a tree is checked by the conservative advancement of [`SegmentChecker`]:
//! an extension towards a random sample (at most [`STEP`] long in joint space) that is blocked
//! keeps the part of it certified free up to the last advancement point with [`ROOM_M`] of
//! clearance, so the trees only hold certified edges and no node is born grazing. The other tree
//! then tries to reach the new node by one certified straight edge (the "connect" step done in
//! one exact check). Joining edges and shortcuts must also keep [`ROOM_M`] (or the clearance of
//! their closer end, for an edge into a goal configuration that has less): a path that grazes
//! obstacles is free, but an engine following it with a few millimetres of tracking error, or
//! with f32 geometry, would be tested at the edge of its approximations rather than on the
//! design. The path found is shortcut (greedy from each vertex to the furthest one it
//! sees, then random shortcuts between points on two edges), and every edge of the final path is
//! checked again as it stands: what is returned is proven free edge by edge.
//!
//! Random choices come from one ChaCha8 stream per call, seeded by the caller: the same inputs
//! give the same path on any machine and any number of threads. The budget counts samples.

use super::certify::SegmentChecker;
use super::planner::{distance, polyline_length, Failure, Path, Planner};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Longest extension towards a random sample (joint-space norm, rad and m as numbers).
pub const STEP: f64 = 1.0;
/// Clearance beyond the threshold a new tree node must keep (m): a node that grazes an obstacle
/// makes every edge from it crawl.
pub const ROOM_M: f64 = 2e-3;
/// Extensions shorter than this add no node (joint-space norm).
const MIN_PROGRESS: f64 = 1e-3;
/// Random shortcut attempts after the greedy pass.
const RANDOM_SHORTCUTS: usize = 32;

/// RRT-Connect for one model: the joints' limits (sampling bounds) and the sample budget.
#[derive(Debug, Clone)]
pub struct RrtConnect {
    /// Limits per joint; `None` for a joint without (sampled within a turn of the start and goals).
    pub limits: Vec<Option<[f64; 2]>>,
    /// Random samples before giving up.
    pub budget: usize,
    /// Goal configurations (the first of the goal set) tried by one straight segment before the
    /// trees grow.
    pub straight_attempts: usize,
}

/// One tree: configurations stored flat, each node's parent, and the goal a goal-tree node
/// descends from.
struct Tree {
    dof: usize,
    q: Vec<f64>,
    parent: Vec<Option<usize>>,
    root: Vec<usize>,
}

impl Tree {
    fn new(dof: usize) -> Self {
        Self {
            dof,
            q: Vec::new(),
            parent: Vec::new(),
            root: Vec::new(),
        }
    }

    fn len(&self) -> usize {
        self.parent.len()
    }

    fn config(&self, node: usize) -> &[f64] {
        &self.q[node * self.dof..(node + 1) * self.dof]
    }

    fn add(&mut self, q: &[f64], parent: Option<usize>, root: usize) -> usize {
        self.q.extend_from_slice(q);
        self.parent.push(parent);
        self.root.push(root);
        self.parent.len() - 1
    }

    /// The node nearest `q` (the first of equals, so ties break by insertion order).
    fn nearest(&self, q: &[f64]) -> usize {
        let mut best = (0, f64::INFINITY);
        for node in 0..self.len() {
            let d: f64 = self.config(node).iter().zip(q).map(|(a, b)| (a - b) * (a - b)).sum();
            if d < best.1 {
                best = (node, d);
            }
        }
        best.0
    }

    /// Configurations from `node` up to its root, `node` first.
    fn to_root(&self, node: usize) -> Vec<Vec<f64>> {
        let mut out = vec![self.config(node).to_vec()];
        let mut at = node;
        while let Some(parent) = self.parent[at] {
            out.push(self.config(parent).to_vec());
            at = parent;
        }
        out
    }
}

fn lerp(a: &[f64], b: &[f64], s: f64) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x + s * (y - x)).collect()
}

/// Grows `tree` from its node nearest `towards` by one certified edge of at most [`STEP`];
/// returns the new node.
fn extend(checker: &mut SegmentChecker<'_>, tree: &mut Tree, towards: &[f64]) -> Option<usize> {
    let near = tree.nearest(towards);
    let from = tree.config(near).to_vec();
    let length = distance(&from, towards);
    if length < MIN_PROGRESS {
        return None;
    }
    let target = if length > STEP {
        lerp(&from, towards, STEP / length)
    } else {
        towards.to_vec()
    };
    reach(checker, tree, near, &from, &target)
}

/// Adds to `tree` the part of the edge `from` (node `near`) to `target` certified with room:
/// all of it when free, else up to the last roomy advancement point.
fn reach(checker: &mut SegmentChecker<'_>, tree: &mut Tree, near: usize, from: &[f64], target: &[f64]) -> Option<usize> {
    let (check, roomy) = checker.advance(from, target, ROOM_M);
    grow_to(tree, near, from, target, &check, roomy, checker.threshold())
}

/// Adds to `tree` what `check` (of the edge `from`, node `near`, to `target`) certified with
/// room: the whole edge, or up to the last roomy advancement point `roomy`.
fn grow_to(
    tree: &mut Tree,
    near: usize,
    from: &[f64],
    target: &[f64],
    check: &super::certify::SegmentCheck,
    roomy: Option<f64>,
    threshold: f64,
) -> Option<usize> {
    let root = tree.root[near];
    if check.free && check.closest.as_ref().is_none_or(|c| c.distance_m >= threshold + ROOM_M) {
        return Some(tree.add(target, Some(near), root));
    }
    let s = roomy?;
    let q = lerp(from, target, s);
    (distance(from, &q) >= MIN_PROGRESS).then(|| tree.add(&q, Some(near), root))
}

impl RrtConnect {
    /// Sampling bounds per joint: a turn either side of the start and the first goal
    /// configurations (the nearest equivalents of the goal's solutions), within the limits. A
    /// joint that turns several times over would otherwise spread the samples over copies of
    /// the same configurations: every configuration has an equivalent in this window.
    fn bounds(&self, start: &[f64], goals: &[Vec<f64>]) -> Vec<[f64; 2]> {
        let firsts = &goals[..self.straight_attempts.clamp(1, goals.len().max(1)).min(goals.len())];
        self.limits
            .iter()
            .enumerate()
            .map(|(j, limits)| {
                let values = firsts.iter().map(|g| g[j]).chain([start[j]]);
                let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
                let window = [lo - std::f64::consts::PI, hi + std::f64::consts::PI];
                match limits {
                    // Moved inside the limits rather than cut by them, so it keeps a whole turn
                    // (or the whole range, when that is shorter).
                    Some([lower, upper]) if upper >= lower => {
                        let width = (window[1] - window[0]).min(upper - lower);
                        // Not `clamp`: `upper - (upper - lower)` can round below `lower`.
                        let from = window[0].min(upper - width).max(*lower);
                        [from, from + width]
                    }
                    _ => window,
                }
            })
            .collect()
    }
}

impl Planner for RrtConnect {
    fn connect(&mut self, checker: &mut SegmentChecker<'_>, start: &[f64], goals: &[Vec<f64>], stream: u64) -> Result<Path, Failure> {
        self.connect_after(checker, start, goals, stream, None)
    }
}

/// What the straight segments to the first goals of a goal set gave: how many were tried, the
/// first grazing one among them and the first goal's stop.
pub(super) type TriedStraight = (usize, (Option<Path>, Failure));

impl RrtConnect {
    /// [`Planner::connect`], with the straight segments to the first goals already tried when
    /// `tried` says so (none of them kept room): they are not checked again.
    pub(super) fn connect_after(
        &mut self,
        checker: &mut SegmentChecker<'_>,
        start: &[f64],
        goals: &[Vec<f64>],
        stream: u64,
        tried: Option<TriedStraight>,
    ) -> Result<Path, Failure> {
        let firsts = &goals[..self.straight_attempts.min(goals.len())];
        // A straight segment that keeps room first; one that grazes only when no detour with
        // room is found, since an engine's tracking error would turn its graze into a contact.
        let (tight, first_failure) = match straight_with_room_after(checker, start, firsts, tried) {
            Ok(path) => return Ok(path),
            Err(not_roomy) => not_roomy,
        };
        let fallback = |failure: Failure| match &tight {
            Some(path) => Ok(path.clone()),
            None => Err(failure),
        };
        if self.budget == 0 || goals.is_empty() {
            return fallback(first_failure);
        }
        let dof = start.len();
        let bounds = self.bounds(start, goals);
        let mut rng = ChaCha8Rng::seed_from_u64(stream);
        let mut from_start = Tree::new(dof);
        from_start.add(start, None, 0);
        let mut from_goals = Tree::new(dof);
        for (index, goal) in goals.iter().enumerate() {
            from_goals.add(goal, None, index);
        }
        let mut sample = vec![0.0; dof];
        let mut grow_start = true;
        for samples in 1..=self.budget {
            if checker.stopped() {
                return Err(Failure { samples, ..first_failure });
            }
            for (x, [lo, hi]) in sample.iter_mut().zip(&bounds) {
                *x = if hi > lo { rng.random_range(*lo..=*hi) } else { *lo };
            }
            let (grow, other) = if grow_start {
                (&mut from_start, &mut from_goals)
            } else {
                (&mut from_goals, &mut from_start)
            };
            grow_start = !grow_start;
            let Some(new) = extend(checker, grow, &sample) else { continue };
            let target = grow.config(new).to_vec();
            let near = other.nearest(&target);
            let from = other.config(near).to_vec();
            let (joined, check, roomy) = checker.roomy_advance(&from, &target, ROOM_M);
            if !joined {
                // Grow the other tree as far as the same check certified it towards the new node.
                grow_to(other, near, &from, &target, &check, roomy, checker.threshold());
                continue;
            }
            // The two trees meet: start ... meeting edge ... a goal configuration.
            let (start_node, goal_node) = if grow_start {
                // `grow` was the goal tree (the flag has already flipped).
                (near, new)
            } else {
                (new, near)
            };
            let mut points = from_start.to_root(start_node);
            points.reverse();
            points.extend(from_goals.to_root(goal_node));
            let target = from_goals.root[goal_node];
            let length_before_shortcut = polyline_length(start, &points[1..]);
            let points = shortcut(checker, &points, &mut rng);
            return certify_polyline(checker, &points)
                .map(|segments| Path {
                    waypoints: points[1..].to_vec(),
                    segments,
                    target,
                    length_before_shortcut,
                    samples,
                })
                .or_else(fallback);
        }
        fallback(closest_attempt(checker, &from_start, goals, self.budget).unwrap_or(Failure {
            samples: self.budget,
            ..first_failure
        }))
    }
}

/// Straight segments to `goals` in order: the first that keeps [`ROOM_M`] (or its ends'
/// clearance); else the first free one, which grazes, if any, and where the first one stops.
pub(super) fn straight_with_room(
    checker: &mut SegmentChecker<'_>,
    start: &[f64],
    goals: &[Vec<f64>],
) -> Result<Path, (Option<Path>, Failure)> {
    straight_with_room_after(checker, start, goals, None)
}

/// [`straight_with_room`], going on from what the straight segments to the first goals gave.
fn straight_with_room_after(
    checker: &mut SegmentChecker<'_>,
    start: &[f64],
    goals: &[Vec<f64>],
    tried: Option<TriedStraight>,
) -> Result<Path, (Option<Path>, Failure)> {
    let (done, (mut tight, mut failure)) = tried.unwrap_or_else(|| {
        let failure = Failure {
            samples: 0,
            stop: None,
            gap: goals.first().map(|g| distance(start, g)),
        };
        (0, (None, failure))
    });
    for (target, goal) in goals.iter().enumerate().skip(done) {
        let (roomy, segment) = checker.roomy_free(start, goal, ROOM_M);
        if target == 0 && !segment.free {
            failure.stop = segment.touch.clone().or_else(|| segment.closest.clone());
        }
        let path = |segment| Path {
            waypoints: vec![goal.clone()],
            segments: vec![segment],
            target,
            length_before_shortcut: distance(start, goal),
            samples: 0,
        };
        if roomy {
            return Ok(path(segment));
        }
        if segment.free && tight.is_none() {
            tight = Some(path(segment));
        }
    }
    Err((tight, failure))
}

/// After a failed search: the start-tree node nearest the goal set, and where its straight edge
/// to the nearest goal configuration stops.
fn closest_attempt(checker: &mut SegmentChecker<'_>, tree: &Tree, goals: &[Vec<f64>], samples: usize) -> Option<Failure> {
    let mut best: Option<(usize, usize, f64)> = None;
    for (index, goal) in goals.iter().enumerate() {
        let node = tree.nearest(goal);
        let gap = distance(tree.config(node), goal);
        if best.is_none_or(|(_, _, d)| gap < d) {
            best = Some((node, index, gap));
        }
    }
    let (node, index, gap) = best?;
    let check = checker.check(tree.config(node), &goals[index]);
    Some(Failure {
        samples,
        stop: check.touch.or(check.closest),
        gap: Some(gap),
    })
}

/// Checks every edge of `points` as it stands.
fn certify_polyline(checker: &mut SegmentChecker<'_>, points: &[Vec<f64>]) -> Result<Vec<super::certify::SegmentCheck>, Failure> {
    let mut segments = Vec::with_capacity(points.len().saturating_sub(1));
    for pair in points.windows(2) {
        let check = checker.check(&pair[0], &pair[1]);
        if !check.free {
            // Sub-edges of certified edges are free; this only guards the bookkeeping.
            return Err(Failure {
                samples: 0,
                stop: check.touch.or(check.closest),
                gap: Some(distance(&pair[0], &pair[1])),
            });
        }
        segments.push(check);
    }
    Ok(segments)
}

/// Shortens a certified polyline by certified shortcuts: greedily from each vertex to the
/// furthest later vertex it reaches by a free edge, random shortcuts between points on two
/// edges, and the greedy pass again. Every kept edge is a checked free edge or part of one.
fn shortcut(checker: &mut SegmentChecker<'_>, points: &[Vec<f64>], rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let points = greedy(checker, points);
    let points = random_shortcuts(checker, points, rng);
    greedy(checker, &points)
}

/// From each vertex, the furthest later vertex a free edge reaches.
fn greedy(checker: &mut SegmentChecker<'_>, points: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut out = vec![points[0].clone()];
    let mut i = 0;
    while i + 1 < points.len() {
        let mut next = i + 1;
        for j in (i + 2..points.len()).rev() {
            if checker.keeps_room(&points[i], &points[j], ROOM_M) {
                next = j;
                break;
            }
        }
        out.push(points[next].clone());
        i = next;
    }
    out
}

fn random_shortcuts(checker: &mut SegmentChecker<'_>, mut points: Vec<Vec<f64>>, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    for _ in 0..RANDOM_SHORTCUTS {
        let edges = points.len() - 1;
        if edges < 2 {
            break;
        }
        let first = rng.random_range(0..edges - 1);
        let second = rng.random_range(first + 1..edges);
        let (s, t) = (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
        let a = lerp(&points[first], &points[first + 1], s);
        let b = lerp(&points[second], &points[second + 1], t);
        let saved = distance(&points[first + 1], &a)
            + polyline_length(&points[first + 1], &points[first + 2..=second])
            + distance(&points[second], &b)
            - distance(&a, &b);
        if saved <= 1e-9 {
            continue;
        }
        if !checker.keeps_room(&a, &b, ROOM_M) {
            continue;
        }
        let mut shorter = points[..=first].to_vec();
        shorter.push(a);
        shorter.push(b);
        shorter.extend_from_slice(&points[second + 1..]);
        points = shorter;
    }
    points
}
