//! Certified continuous collision checking of a straight joint-space segment, by conservative
//! advancement.
//!
//! Along `q(s) = q0 + s (q1 - q0)`, `s` in [0, 1], a point `p` of link `k` moves at most
//! `sum_j |dq_j| R_jk` per unit of `s`, where `R_jk` bounds the distance from joint `j`'s axis to
//! any point of link `k` whatever the configuration: the lengths of the joint offsets between
//! them (plus prismatic travel) and link `k`'s furthest collider point from its own origin. A link
//! against an obstacle or the floor moves by that bound; a link pair `a < b` by the joints between
//! them only (the joints before `a` move both rigidly). So from a configuration where pair `p` has
//! clearance `d_p` (exact, or the broad phase's lower bound), the step
//! `(d_p - threshold) / (2 M_p)` keeps it above `threshold + (d_p - threshold) / 2`: every step is
//! certified, with a lower bound on the clearance over it. The advancement stops at the end of
//! the segment, or where a clearance falls within [`TOUCH_TOLERANCE_M`] of the threshold: a touch
//! (or a collision), reported with the pair and where.

pub use crate::collide::MotionBounds;
use crate::collide::{self, ClearanceByKind, CollisionWorld, Distances, QueryOptions};
use crate::model::{KinematicsWorkspace, Model};
use serde::Serialize;

/// A clearance within this of the threshold ends the advancement as a touch (m): below it, the
/// steps would shrink without end near a grazing contact.
pub const TOUCH_TOLERANCE_M: f64 = 1e-6;
/// Most queries per segment before it is given up as not certified.
pub const MAX_STEPS: usize = 100_000;

/// Settings of the continuous check.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CertifyOptions {
    /// Clearance the segment must keep (m); default 0 (no contact). A positive value is a safety
    /// margin.
    pub threshold_m: f64,
}

impl Default for CertifyOptions {
    fn default() -> Self {
        Self { threshold_m: 0.0 }
    }
}

/// Where a segment comes closest or stops.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SegmentPoint {
    /// Path parameter in [0, 1].
    pub s: f64,
    /// The configuration there.
    pub q: Vec<f64>,
    /// Signed distance of the closest pair there (m).
    pub distance_m: f64,
    /// The closest pair's bodies by name.
    pub a: String,
    /// The closest pair's bodies by name.
    pub b: String,
}

/// The result of checking one segment.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SegmentCheck {
    /// No configuration of the segment comes within the threshold (certified).
    pub free: bool,
    /// The smallest clearance measured at the advancement points, and where.
    pub closest: Option<SegmentPoint>,
    /// A lower bound on the clearance over the whole segment (m), or over the part checked before
    /// a touch; certified by the motion bounds.
    pub certified_clearance_m: f64,
    /// The same bound for each kind of pair (obstacles, self, floor); the smallest of them is
    /// `certified_clearance_m`.
    pub certified_by_kind: ClearanceByKind,
    /// Where the advancement stopped at a touch or collision, when it did.
    pub touch: Option<SegmentPoint>,
    /// Collision queries made.
    pub queries: usize,
}

/// Checks segments of one model in one collision world; keeps its buffers between segments.
pub struct SegmentChecker<'a> {
    model: &'a Model,
    world: &'a CollisionWorld,
    bounds: MotionBounds,
    opts: CertifyOptions,
    ws: KinematicsWorkspace,
    out: Distances,
    q: Vec<f64>,
    delta: Vec<f64>,
    rates: Vec<f64>,
}

impl<'a> SegmentChecker<'a> {
    /// A checker for `model` (placed as the world was built) in `world`. A threshold that is not
    /// a finite number of at least 0 is taken as 0 (a NaN would certify everything).
    pub fn new(model: &'a Model, world: &'a CollisionWorld, opts: CertifyOptions) -> Self {
        let threshold_m = if opts.threshold_m.is_finite() {
            opts.threshold_m.max(0.0)
        } else {
            0.0
        };
        let opts = CertifyOptions { threshold_m };
        Self {
            model,
            world,
            bounds: MotionBounds::of(model),
            opts,
            ws: model.workspace(),
            out: Distances::new(),
            q: vec![0.0; model.dof()],
            delta: vec![0.0; model.dof()],
            rates: Vec::new(),
        }
    }

    /// The clearance every segment must keep (m).
    pub fn threshold(&self) -> f64 {
        self.opts.threshold_m
    }

    /// Clearance of one configuration and its closest pair.
    pub fn clearance(&mut self, q: &[f64]) -> Option<SegmentPoint> {
        self.query(q);
        self.closest_point(0.0, q)
    }

    fn query(&mut self, q: &[f64]) {
        self.model.forward(q, &mut self.ws);
        let query = QueryOptions {
            margin: self.opts.threshold_m,
            hulls: false,
            exact_depth: true,
            mesh_hulls: false,
        };
        collide::distances(self.world, &self.ws.link_in_world, &query, &mut self.out);
    }

    fn closest_point(&self, s: f64, q: &[f64]) -> Option<SegmentPoint> {
        self.out.closest.map(|c| SegmentPoint {
            s,
            q: q.to_vec(),
            distance_m: c.distance,
            a: self.world.body_name(c.a.body).to_string(),
            b: self.world.body_name(c.b.body).to_string(),
        })
    }

    /// Certifies the straight segment from `from` to `to`.
    pub fn check(&mut self, from: &[f64], to: &[f64]) -> SegmentCheck {
        self.advance(from, to, f64::INFINITY).0
    }

    /// [`check`](Self::check), also returning how far the segment is certified with room to
    /// spare: the largest path parameter `s` among the advancement points at which every pair
    /// keeps at least `room` (m) beyond the threshold (`[0, s]` is certified free, since the
    /// whole advancement up to any of its points is). `None` when no point past the start does.
    /// A planner grows its trees to such points, where a next motion is not born grazing.
    pub fn advance(&mut self, from: &[f64], to: &[f64], room: f64) -> (SegmentCheck, Option<f64>) {
        let mut roomy = None;
        let mut ends = [f64::NAN; 2];
        let check = self.advance_until(from, to, room, &mut roomy, &mut ends, f64::NEG_INFINITY);
        (check, roomy)
    }

    /// Whether the segment is certified free and, at every advancement point, keeps `room` (m)
    /// beyond the threshold or at least the clearance of its closer end: a free edge that does
    /// not come nearer its obstacles than it must. With the check.
    pub fn roomy_free(&mut self, from: &[f64], to: &[f64], room: f64) -> (bool, SegmentCheck) {
        let (ok, check, _) = self.roomy_advance(from, to, room);
        (ok, check)
    }

    /// [`roomy_free`](Self::roomy_free) and [`advance`](Self::advance) in one check: whether the
    /// segment is free with room, the check, and how far it is certified with room.
    pub fn roomy_advance(&mut self, from: &[f64], to: &[f64], room: f64) -> (bool, SegmentCheck, Option<f64>) {
        let mut roomy = None;
        let mut ends = [f64::NAN; 2];
        let check = self.advance_until(from, to, room, &mut roomy, &mut ends, f64::NEG_INFINITY);
        let ok = keeps(&check, (self.opts.threshold_m + room).min(ends[0]).min(ends[1]));
        (ok, check, roomy)
    }

    /// `roomy_free(from, to, room).0`, the same answer for less: the advancement stops at the
    /// first point that keeps neither `room` nor its ends' clearance, since that point alone
    /// decides `false`. The end's clearance is measured first, at the configuration the
    /// advancement would end at.
    pub fn keeps_room(&mut self, from: &[f64], to: &[f64], room: f64) -> bool {
        for (q, (a, b)) in self.q.iter_mut().zip(from.iter().zip(to)) {
            *q = a + 1.0 * (b - a);
        }
        let end = std::mem::take(&mut self.q);
        self.query(&end);
        self.q = end;
        let end_clearance = self.out.closest.map_or(f64::INFINITY, |c| c.distance);
        let mut roomy = None;
        let mut ends = [f64::NAN; 2];
        let give_up = (self.opts.threshold_m + room).min(end_clearance);
        let check = self.advance_until(from, to, room, &mut roomy, &mut ends, give_up);
        keeps(&check, give_up.min(ends[0]).min(ends[1]))
    }

    /// The advancement; it gives up (not free) at the first point whose clearance is below both
    /// `give_up` and the start's.
    fn advance_until(
        &mut self,
        from: &[f64],
        to: &[f64],
        room: f64,
        roomy: &mut Option<f64>,
        ends: &mut [f64; 2],
        give_up: f64,
    ) -> SegmentCheck {
        let threshold = self.opts.threshold_m;
        for (d, (a, b)) in self.delta.iter_mut().zip(from.iter().zip(to)) {
            *d = b - a;
        }
        self.rates.clear();
        self.rates.extend(
            self.world
                .pairs()
                .iter()
                .map(|pair| self.bounds.relative_motion(pair.a, pair.b, &self.delta)),
        );

        let mut s = 0.0;
        let mut queries = 0;
        let mut closest: Option<SegmentPoint> = None;
        let mut certified = f64::INFINITY;
        let mut by_kind = ClearanceByKind::default();
        loop {
            for (q, (a, d)) in self.q.iter_mut().zip(from.iter().zip(&self.delta)) {
                *q = a + s * d;
            }
            let q = std::mem::take(&mut self.q);
            self.query(&q);
            queries += 1;
            let here = self.closest_point(s, &q);
            self.q = q;
            let smallest = here.as_ref().map_or(f64::INFINITY, |p| p.distance_m);
            // Each pair's estimate here: the closest pair's kind takes `smallest`, as the whole
            // bound does where the advancement ends.
            for estimate in &self.out.estimates {
                by_kind.lower(estimate.b, estimate.distance);
            }
            if closest.as_ref().is_none_or(|c| smallest < c.distance_m) {
                closest.clone_from(&here);
            }
            if smallest <= threshold + TOUCH_TOLERANCE_M {
                certified = certified.min(smallest);
                return SegmentCheck {
                    free: false,
                    closest,
                    certified_clearance_m: certified,
                    certified_by_kind: by_kind,
                    touch: here,
                    queries,
                };
            }
            if s > 0.0 && smallest < give_up.min(ends[0]) {
                return SegmentCheck {
                    free: false,
                    closest,
                    certified_clearance_m: certified.min(smallest),
                    certified_by_kind: by_kind,
                    touch: None,
                    queries,
                };
            }
            if s > 0.0 && smallest >= threshold + room {
                *roomy = Some(s);
            }
            if s == 0.0 {
                ends[0] = smallest;
            }
            if s >= 1.0 {
                ends[1] = smallest;
            }
            if s >= 1.0 {
                certified = certified.min(smallest);
                break;
            }
            // The largest step every pair allows while losing at most half its excess clearance.
            let mut step = 1.0 - s;
            let mut lowest = f64::INFINITY;
            for (estimate, rate) in self.out.estimates.iter().zip(&self.rates) {
                let excess = estimate.distance - threshold;
                // An infinite distance is a pair with no geometry; an infinite rate is not
                // certifiable: no step then.
                if *rate > 0.0 && excess.is_finite() {
                    step = step.min(excess / (2.0 * rate));
                } else if !rate.is_finite() && excess.is_finite() {
                    step = 0.0;
                }
            }
            for (estimate, rate) in self.out.estimates.iter().zip(&self.rates) {
                let bound = estimate.distance - rate * step;
                lowest = lowest.min(bound);
                by_kind.lower(estimate.b, bound);
            }
            certified = certified.min(lowest);
            if queries >= MAX_STEPS {
                return SegmentCheck {
                    free: false,
                    closest,
                    certified_clearance_m: certified,
                    certified_by_kind: by_kind,
                    touch: None,
                    queries,
                };
            }
            s = (s + step).min(1.0);
        }
        SegmentCheck {
            free: true,
            closest,
            certified_clearance_m: certified,
            certified_by_kind: by_kind,
            touch: None,
            queries,
        }
    }

    /// The same segment checked only at `samples + 1` evenly spaced configurations (both ends
    /// included): what fixed-step checkers do. Returns the smallest clearance seen.
    pub fn sampled_clearance(&mut self, from: &[f64], to: &[f64], samples: usize) -> f64 {
        let mut smallest = f64::INFINITY;
        let mut q = vec![0.0; from.len()];
        for i in 0..=samples {
            let s = i as f64 / samples.max(1) as f64;
            for (x, (a, b)) in q.iter_mut().zip(from.iter().zip(to)) {
                *x = a + s * (b - a);
            }
            self.query(&q);
            smallest = smallest.min(self.out.closest.map_or(f64::INFINITY, |c| c.distance));
        }
        smallest
    }
}

/// Whether a checked segment is free and keeps `needed` (m) at every advancement point.
fn keeps(check: &SegmentCheck, needed: f64) -> bool {
    check.free && check.closest.as_ref().is_none_or(|c| c.distance_m >= needed)
}
