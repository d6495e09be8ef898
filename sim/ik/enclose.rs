//! Every configuration within a goal's tolerance in collision, proven through the colliding
//! pairs' own joints.
//!
//! Near a fold of the arm's solutions the configurations within 1 mm and 1 degree of a goal
//! spread along the fold, and no certificate around the pose's own solutions covers them; the
//! joint-space search with collisions must shrink its boxes in all joints at once until each is
//! certified in collision, and runs out of its budget (measured: `free-offset-6dof`'s goal 7 on
//! cluttered task 06 stayed open at 500 000 boxes). Yet a pair of links collides or not by the
//! joints between them alone: `link4` against `link6` by joints 5 and 6, whatever joints 1 to 4
//! do. So the proof splits in two, each part sound on its own:
//!
//! 1. **Enclosure.** The configurations within the tolerance that sampling found (see
//!    [`super::sampled`]) are grouped by their deepest pair and clustered; each cluster's values
//!    of its pair's joints, padded, make a box of those joints. The box is certified in collision
//!    throughout by a branch and bound over those joints alone (two to four numbers, not six): a
//!    cell goes when its centre's overlap is deeper than the pair can move within it (the same
//!    motion bound as the search's certificates); a free centre, or cells still open when the
//!    queries run out, fail the box.
//! 2. **Exclusion.** The joint space outside the boxes is cut into boxes, and the joint-space
//!    search proves of each, by the tool's motion bounds alone (no collision query), that none
//!    of its configurations comes within the tolerance.
//!
//! Together: every configuration within the limits and the tolerance lies in a box, where its
//! pair collides. A box too tight leaves a configuration within the tolerance outside it (the
//! exclusion fails), so the pads grow; one too wide takes in free configurations (the enclosure
//! fails), and then no wider pad can succeed.

use super::refine::Checker;
use super::search::{self, Radii, Search};
use super::{Goal, Ik};
use crate::collide::Body;
use std::f64::consts::TAU;

/// A configuration within a goal's tolerance that collides, and its deepest pair.
#[derive(Debug, Clone)]
pub(super) struct Member {
    pub(super) q: Vec<f64>,
    pub(super) pair: [Body; 2],
}

/// Members kept per goal: the sample's first ones (a thousand poses give up to a few thousand).
pub(super) const MOST_MEMBERS: usize = 4096;
/// Joint distance (rad, every joint of the pair) within which two members of one pair join one
/// cluster: branches of one pose lie a large part of a turn apart, the configurations within
/// a tolerance of one branch a few hundredths.
const LINK_RAD: f64 = 0.25;
/// Pads (rad) around each cluster's values, tried in turn.
const PADS: [f64; 3] = [0.02, 0.06, 0.18];
/// Joints a pair's box may span: beyond four the enclosure is as hard as the search it helps.
const MOST_JOINTS: usize = 4;
/// Pair queries for all the pads' enclosures, per collision query a goal's searches may make
/// (`Ik::collision_queries`: 20 000 among primitives, where a pair's exact depth
/// takes microseconds, 40 000 pair queries here; 200 with meshes, where one takes up to 5 ms).
const CELL_QUERIES_PER_QUERY: usize = 2;
/// The exclusion's boxes for all pads, per box of [`super::IkOptions::search_boxes`] (a
/// validation's 200 000: 800 000 boxes, about 1.5 s).
const EXCLUSION_BUDGET: usize = 4;
/// The share of the pair queries one trial of a wider box may take at most (4 000 of 40 000).
const TRIAL_SHARE: usize = 10;
/// The first step (rad) by which a box is widened on one side.
const FIRST_GROWTH_RAD: f64 = 0.05;
/// Boxes at most (clusters, each cut in two where it wraps across a whole turn's seam).
const MOST_BOXES: usize = 24;
/// A cell whose pair moves less than this (m) within it and is still not certified: the box
/// holds a configuration at contact, or as good as.
const SMALLEST_MOTION_M: f64 = 1e-6;

/// A box of one pair's joints, with the other joints over their whole ranges.
struct Enclosure {
    pair: [Body; 2],
    joints: Vec<usize>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    /// A member's configuration: the other joints' values for the pair's queries (they move
    /// neither body relative to the other).
    base: Vec<f64>,
}

/// The joints whose values place `pair`'s second body relative to its first (as
/// [`crate::collide::MotionBounds::relative_motion`] counts them), for `dof` joints.
fn pair_joints(pair: [Body; 2], dof: usize) -> Vec<usize> {
    match pair {
        [Body::Link(a), Body::Link(b)] => (a.min(b)..a.max(b).min(dof)).collect(),
        [Body::Link(link), _] | [_, Body::Link(link)] => (0..link.min(dof)).collect(),
        _ => Vec::new(),
    }
}

/// The pair a colliding configuration's box is made for, from the checker's last query: the
/// deepest of the colliding pairs that span at most [`MOST_JOINTS`] joints (a link against the
/// floor spans every joint before it, another link only those between), else the closest.
pub(super) fn member_pair(checker: &Checker, dof: usize) -> Option<[Body; 2]> {
    checker
        .colliding_pairs()
        .filter(|(pair, _)| (1..=MOST_JOINTS).contains(&pair_joints(*pair, dof).len()))
        .fold(None, |best: Option<([Body; 2], f64)>, (pair, distance)| match best {
            Some((_, deepest)) if deepest <= distance => best,
            _ => Some((pair, distance)),
        })
        .map(|(pair, _)| pair)
        .or_else(|| checker.closest_pair().map(|pair| pair.bodies))
}

/// Whether a joint's range is a whole turn (an angle and that angle plus a turn are one).
fn whole_turn(lower: f64, upper: f64) -> bool {
    upper - lower >= TAU - 1e-9
}

/// The intervals within `[lower, upper]` that `values`, padded by `pad`, cover: one, or two
/// where a whole turn's arc crosses the range's seam (a whole turn's values are first taken
/// into the range, a turn at a time). `None` for a value outside a narrower range, or not
/// finite: no box could then hold it.
fn intervals(values: &mut [f64], lower: f64, upper: f64, pad: f64) -> Option<Vec<[f64; 2]>> {
    let whole = whole_turn(lower, upper);
    for value in values.iter_mut() {
        if !value.is_finite() {
            return None;
        }
        if whole && !(lower..lower + TAU).contains(value) {
            *value = lower + (*value - lower).rem_euclid(TAU);
        } else if *value < lower || *value > upper {
            return None;
        }
    }
    values.sort_by(f64::total_cmp);
    let (&first, &last) = (values.first()?, values.last()?);
    let cut = if !whole {
        vec![[(first - pad).max(lower), (last + pad).min(upper)]]
    } else {
        // The arc is the circle less its largest gap between neighbouring values.
        let mut gap = first + TAU - last;
        let mut start = first;
        let mut end = last;
        for pair in values.windows(2) {
            if pair[1] - pair[0] > gap {
                gap = pair[1] - pair[0];
                start = pair[1];
                end = pair[0] + TAU;
            }
        }
        let (start, end) = (start - pad, end + pad);
        if end - start >= TAU {
            vec![[lower, upper]]
        } else {
            // `start` lies within a turn of the range: shift the arc so that it starts inside it.
            let shift = ((start - lower) / TAU).floor() * TAU;
            let (start, end) = (start - shift, end - shift);
            if end <= upper {
                vec![[start, end]]
            } else {
                vec![[start, upper], [lower, end - TAU]]
            }
        }
    };
    // Each interval within the range and not reversed, whatever the rounding did.
    cut.iter().all(|&[a, b]| lower <= a && a <= b && b <= upper).then_some(cut)
}

/// Single-linkage clusters of `members` (indices), by the largest joint difference over
/// `joints` (a whole turn's joints compared modulo a turn).
fn clusters(members: &[&Member], joints: &[usize], lower: &[f64], upper: &[f64]) -> Vec<Vec<usize>> {
    let n = members.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let near = |a: &Member, b: &Member| {
        joints.iter().all(|&j| {
            let d = a.q[j] - b.q[j];
            let d = if whole_turn(lower[j], upper[j]) { super::wrap_angle(d) } else { d };
            d.abs() <= LINK_RAD
        })
    };
    for i in 0..n {
        for k in i + 1..n {
            if near(members[i], members[k]) {
                let (a, b) = (root(&mut parent, i), root(&mut parent, k));
                // The smaller root stays: the clusters' order is the members'.
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut index_of = vec![usize::MAX; n];
    for i in 0..n {
        let r = root(&mut parent, i);
        if index_of[r] == usize::MAX {
            index_of[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[index_of[r]].push(i);
    }
    groups
}

/// The joint space from `lower` to `upper` less `boxes`, cut into boxes.
fn complement(lower: Vec<f64>, upper: Vec<f64>, boxes: &[(Vec<f64>, Vec<f64>)], out: &mut Vec<(Vec<f64>, Vec<f64>)>) {
    let n = lower.len();
    for (box_lower, box_upper) in boxes {
        if !(0..n).all(|j| box_lower[j] < upper[j] && box_upper[j] > lower[j]) {
            continue;
        }
        for j in 0..n {
            for cut in [box_lower[j], box_upper[j]] {
                if cut > lower[j] && cut < upper[j] {
                    let mut below = upper.clone();
                    below[j] = cut;
                    let mut above = lower.clone();
                    above[j] = cut;
                    complement(lower.clone(), below, boxes, out);
                    complement(above, upper, boxes, out);
                    return;
                }
            }
        }
        // The box holds the whole region.
        return;
    }
    out.push((lower, upper));
}

/// How the joints are named in a proof: "joint 5", "joints 5 and 6", "joints 3 to 5".
fn joints_words(joints: &[usize]) -> String {
    match joints {
        [j] => format!("joint {}", j + 1),
        [a, b] => format!("joints {} and {}", a + 1, b + 1),
        [a, .., b] => format!("joints {} to {}", a + 1, b + 1),
        [] => String::new(),
    }
}

impl Ik<'_> {
    /// The proof that every configuration within `goal`'s tolerance collides, from the members
    /// sampling found there (see the module's documentation); `None` where it does not hold at
    /// any pad, or the arm has no collision world.
    pub(super) fn enclose_tolerance(&mut self, goal: &Goal, members: &[Member]) -> Option<String> {
        let (lower, upper) = search::ranges(self.model)?;
        self.checker.as_ref()?;
        let dof = self.model.dof();
        // Group by pair, in the order the pairs first appear.
        let mut pairs: Vec<[Body; 2]> = Vec::new();
        for member in members {
            if !pairs.contains(&member.pair) {
                pairs.push(member.pair);
            }
        }
        let mut groups: Vec<([Body; 2], Vec<usize>, Vec<&Member>)> = Vec::new();
        for pair in pairs {
            let joints = pair_joints(pair, dof);
            if joints.is_empty() || joints.len() > MOST_JOINTS {
                return None;
            }
            let of_pair: Vec<&Member> = members.iter().filter(|m| m.pair == pair).collect();
            for cluster in clusters(&of_pair, &joints, &lower, &upper) {
                groups.push((pair, joints.clone(), cluster.iter().map(|&i| of_pair[i]).collect()));
            }
        }
        let margin = self.margin();
        // One budget for all pads: a wider pad is tried with what a tighter one left.
        let mut queries = CELL_QUERIES_PER_QUERY * self.collision_queries;
        let mut left = EXCLUSION_BUDGET * self.opts.search_boxes;
        for pad in PADS {
            let mut enclosures: Vec<Enclosure> = Vec::new();
            for (pair, joints, cluster) in &groups {
                // Each joint's intervals; their product is the cluster's boxes.
                let mut boxes: Vec<(Vec<f64>, Vec<f64>)> = vec![(lower.clone(), upper.clone())];
                for &j in joints {
                    let mut values: Vec<f64> = cluster.iter().map(|m| m.q[j]).collect();
                    let cut = intervals(&mut values, lower[j], upper[j], pad)?;
                    boxes = boxes
                        .into_iter()
                        .flat_map(|(l, u)| {
                            cut.iter().map(move |[a, b]| {
                                let (mut l, mut u) = (l.clone(), u.clone());
                                l[j] = *a;
                                u[j] = *b;
                                (l, u)
                            })
                        })
                        .collect();
                }
                for (l, u) in boxes {
                    enclosures.push(Enclosure {
                        pair: *pair,
                        joints: joints.clone(),
                        lower: l,
                        upper: u,
                        base: cluster[0].q.clone(),
                    });
                }
            }
            if enclosures.len() > MOST_BOXES {
                return None;
            }
            let mut firsts = Vec::with_capacity(enclosures.len());
            for enclosure in &enclosures {
                let first = self.certify_enclosure(enclosure, margin, &mut queries);
                firsts.push(first?);
            }
            // Each box widens on an equal share of the queries left.
            let share = queries / enclosures.len();
            let mut cells = 0;
            for (enclosure, first) in enclosures.iter_mut().zip(firsts) {
                let mut own = share;
                cells += self.grow(enclosure, margin, &lower, &upper, &mut own).unwrap_or(first);
                queries -= share - own;
            }
            let boxes: Vec<(Vec<f64>, Vec<f64>)> = enclosures.iter().map(|e| (e.lower.clone(), e.upper.clone())).collect();
            let mut pieces = Vec::new();
            complement(lower.clone(), upper.clone(), &boxes, &mut pieces);
            let mut searched = 0;
            let mut excluded = true;
            for (l, u) in &pieces {
                // Bounds alone: a local solve's end may lie outside the part.
                let mut solves = search::Solves(|_: &mut [f64]| false);
                match search::search_box(self.model, goal, Radii::REACHED, left, &mut solves, &[], l.clone(), u.clone()) {
                    Some(Search::Proven { boxes, .. }) => {
                        searched += boxes;
                        left -= boxes;
                    }
                    other => {
                        // The boxes an open or found part took are spent all the same.
                        left -= match other {
                            Some(Search::Open { boxes } | Search::Found { boxes, .. }) => boxes,
                            _ => 0,
                        };
                        excluded = false;
                        break;
                    }
                }
            }
            if !excluded {
                continue;
            }
            let mut named: Vec<String> = Vec::new();
            for enclosure in &enclosures {
                let name = format!(
                    "{} ({})",
                    self.checker.as_ref()?.pair_name(enclosure.pair),
                    joints_words(&enclosure.joints)
                );
                if !named.contains(&name) {
                    named.push(name);
                }
            }
            // With a margin, "collides" is "keeps less than the margin", as the verdict counts it.
            let (what, how) = if margin > 0.0 {
                (
                    format!("collides or keeps less than the {margin} m margin"),
                    format!("keep less than the {margin} m margin throughout ({cells} cells, each centre's distance short of the margin by more than the pair can move within it)"),
                )
            } else {
                (
                    "collides".to_string(),
                    format!("collide throughout ({cells} cells, each centre's overlap deeper than the pair can move within it)"),
                )
            };
            return Some(format!(
                "every configuration within the goal's tolerance {what}: no configuration within the joint limits outside {} boxes of the colliding pairs' joints comes within the tolerance (joint-space searches of {searched} boxes over {} parts, ruled out by how far the tool can move), and within those boxes {} {how}",
                enclosures.len(),
                pieces.len(),
                named.join(", ")
            ));
        }
        None
    }

    /// Widens `enclosure` joint by joint while it stays certified: to the joint's whole range,
    /// else side by side in doubling steps. The wider the boxes, the further the exclusion's
    /// parts keep from the tolerance, and the fewer boxes their searches take (`free-offset-6dof`'s
    /// goal 7 on cluttered task 06: about 860 000 boxes over 7 parts at the pad's boxes, 553 499
    /// over 5 once widened). The cells of the widest box certified, when it grew.
    fn grow(&mut self, enclosure: &mut Enclosure, margin: f64, lower: &[f64], upper: &[f64], queries: &mut usize) -> Option<usize> {
        let mut cells = None;
        let trial_queries = CELL_QUERIES_PER_QUERY * self.collision_queries / TRIAL_SHARE;
        let mut certified = |ik: &mut Self, enclosure: &Enclosure, queries: &mut usize| {
            let mut trial = (*queries).min(trial_queries);
            let before = trial;
            let took = ik.certify_enclosure(enclosure, margin, &mut trial);
            *queries -= before - trial;
            if took.is_some() {
                cells = took;
            }
            took.is_some()
        };
        for j in enclosure.joints.clone() {
            let kept = (enclosure.lower[j], enclosure.upper[j]);
            (enclosure.lower[j], enclosure.upper[j]) = (lower[j], upper[j]);
            if certified(self, enclosure, queries) {
                continue;
            }
            (enclosure.lower[j], enclosure.upper[j]) = kept;
            for downward in [true, false] {
                let mut step = FIRST_GROWTH_RAD;
                loop {
                    let before = (enclosure.lower[j], enclosure.upper[j]);
                    if downward {
                        enclosure.lower[j] = (enclosure.lower[j] - step).max(lower[j]);
                    } else {
                        enclosure.upper[j] = (enclosure.upper[j] + step).min(upper[j]);
                    }
                    if (enclosure.lower[j], enclosure.upper[j]) == before {
                        break;
                    }
                    if !certified(self, enclosure, queries) {
                        (enclosure.lower[j], enclosure.upper[j]) = before;
                        break;
                    }
                    step *= 2.0;
                }
            }
        }
        cells
    }

    /// Certifies that `enclosure`'s pair collides (keeps less than `margin`) throughout its
    /// box: the cells it took, or `None` at a free centre or when `queries` run out.
    fn certify_enclosure(&mut self, enclosure: &Enclosure, margin: f64, queries: &mut usize) -> Option<usize> {
        let checker = self.checker.as_mut()?;
        let levels = checker.pair_levels(enclosure.pair)?;
        let dof = self.model.dof();
        let mut q = enclosure.base.clone();
        let mut half = vec![0.0; dof];
        let mut stack: Vec<(Vec<f64>, Vec<f64>)> = vec![(enclosure.lower.clone(), enclosure.upper.clone())];
        let mut cells = 0;
        while let Some((lower, upper)) = stack.pop() {
            if *queries == 0 {
                return None;
            }
            *queries -= 1;
            cells += 1;
            for &j in &enclosure.joints {
                q[j] = 0.5 * (lower[j] + upper[j]);
                half[j] = 0.5 * (upper[j] - lower[j]);
            }
            let distance = checker.clearance_among(&q, &levels, true);
            if distance > margin {
                return None;
            }
            let motion = self.bounds.relative_motion(enclosure.pair[0], enclosure.pair[1], &half);
            if distance + motion <= margin {
                continue;
            }
            if motion < SMALLEST_MOTION_M {
                return None;
            }
            // Split the joint that moves the pair most within the cell.
            let mut single = vec![0.0; dof];
            let split = enclosure
                .joints
                .iter()
                .copied()
                .map(|j| {
                    single[j] = half[j];
                    let moves = self.bounds.relative_motion(enclosure.pair[0], enclosure.pair[1], &single);
                    single[j] = 0.0;
                    (j, moves)
                })
                .fold((enclosure.joints[0], f64::NEG_INFINITY), |best, (j, moves)| {
                    if moves > best.1 {
                        (j, moves)
                    } else {
                        best
                    }
                })
                .0;
            let middle = 0.5 * (lower[split] + upper[split]);
            let mut below = upper.clone();
            below[split] = middle;
            let mut above = lower.clone();
            above[split] = middle;
            stack.push((lower, below));
            stack.push((above, upper));
        }
        Some(cells)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ik::IkOptions;
    use rand::{Rng, SeedableRng};

    /// Boxes of joints 5 and 6 of `free-offset-6dof` (link4 against link6) at random: whenever
    /// one is certified, configurations sampled within it (the other joints at random too) all
    /// collide in the exact geometry; and the certificate holds for some boxes, so the check
    /// has something to check.
    #[test]
    fn a_certified_box_holds_no_free_configuration() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let model = crate::pipeline::load_model(&root.join("designs/free-offset-6dof.json"), &Default::default()).expect("design loads");
        let scenario = crate::pipeline::load_scenario(&root.join("scenarios/cluttered/task-06.json")).expect("scenario loads");
        let world = crate::pipeline::collision_world(&model, &scenario, &[]).expect("world builds");
        let mut ik = Ik::with_collisions(&model, &world, IkOptions::default());
        let pair = [Body::Link(4), Body::Link(6)];
        let levels = ik.checker.as_ref().and_then(|c| c.pair_levels(pair)).expect("the pair is checked");
        let (lower, upper) = search::ranges(&model).expect("bounded ranges");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut certified = 0;
        for _ in 0..300 {
            let mut enclosure = Enclosure {
                pair,
                joints: vec![4, 5],
                lower: lower.clone(),
                upper: upper.clone(),
                base: (0..6).map(|j| rng.random_range(lower[j]..upper[j])).collect(),
            };
            for j in [4, 5] {
                let width = rng.random_range(0.01..1.5);
                let start = rng.random_range(lower[j]..upper[j] - width);
                (enclosure.lower[j], enclosure.upper[j]) = (start, start + width);
            }
            let mut queries = 4_000;
            if ik.certify_enclosure(&enclosure, 0.0, &mut queries).is_none() {
                continue;
            }
            certified += 1;
            let checker = ik.checker.as_mut().expect("a collision world");
            for _ in 0..100 {
                let q: Vec<f64> = (0..6).map(|j| rng.random_range(enclosure.lower[j]..enclosure.upper[j])).collect();
                let distance = checker.clearance_among(&q, &levels, true);
                assert!(distance <= 0.0, "{q:?} in a certified box is free by {distance} m");
            }
        }
        assert!(certified >= 10, "only {certified} boxes certified");
    }

    #[test]
    fn an_arc_across_a_whole_turns_seam_is_cut_in_two() {
        let pi = std::f64::consts::PI;
        let mut values = vec![pi - 0.01, -pi + 0.02];
        let cut = intervals(&mut values, -pi, pi, 0.01).expect("values within a whole turn");
        assert_eq!(cut.len(), 2);
        assert!((cut[0][0] - (pi - 0.02)).abs() < 1e-12 && cut[0][1] == pi);
        assert!(cut[1][0] == -pi && (cut[1][1] - (-pi + 0.03)).abs() < 1e-12);
        let mut inside = vec![0.1, 0.3];
        assert_eq!(intervals(&mut inside, -pi, pi, 0.05).map(|c| c.len()), Some(1));
        let mut limited = vec![-2.0, 1.0];
        assert_eq!(intervals(&mut limited, -2.0, 1.0, 0.5), Some(vec![[-2.0, 1.0]]));
        // A whole turn's value given a turn off is the same angle: 3.5 is -2.78, next to -3.0.
        let mut turned = vec![-3.0, 3.5];
        let cut = intervals(&mut turned, -pi, pi, 0.01).expect("values within a whole turn");
        assert_eq!(cut.len(), 1);
        assert!(
            (cut[0][0] - (-3.01)).abs() < 1e-12 && (cut[0][1] - (3.5 - 2.0 * pi + 0.01)).abs() < 1e-12,
            "{cut:?}"
        );
        // Outside a narrower range, or not finite: no interval.
        assert_eq!(intervals(&mut [0.5, 1.5], -1.0, 1.0, 0.1), None);
        assert_eq!(intervals(&mut [f64::NAN], -pi, pi, 0.1), None);
    }

    #[test]
    fn the_complement_and_the_boxes_tile_the_region() {
        let boxes = vec![(vec![0.2, 0.2], vec![0.5, 0.6]), (vec![0.4, 0.0], vec![0.9, 0.3])];
        let mut pieces = Vec::new();
        complement(vec![0.0, 0.0], vec![1.0, 1.0], &boxes, &mut pieces);
        let area = |(l, u): &(Vec<f64>, Vec<f64>)| (u[0] - l[0]) * (u[1] - l[1]);
        let union = 0.3 * 0.4 + 0.5 * 0.3 - 0.1 * 0.1;
        let total: f64 = pieces.iter().map(area).sum();
        assert!((total + union - 1.0).abs() < 1e-12, "{total}");
        // No piece overlaps a box.
        for (l, u) in &pieces {
            for (bl, bu) in &boxes {
                assert!(!(0..2).all(|j| bl[j] < u[j] && bu[j] > l[j]));
            }
        }
    }
}
