//! Certified continuous collision checking of a straight joint-space segment, by conservative
//! advancement.
//!
//! Along `q(s) = q0 + s (q1 - q0)`, `s` in [0, 1], a point `p` of link `k` moves at most
//! `sum_j |dq_j| R_jk` per unit of `s`, where `R_jk` bounds the distance from joint `j`'s axis to
//! any point of link `k` whatever the configuration (see [`MotionBounds`]). A link against an
//! obstacle or the floor moves by that bound; a link pair `a < b` by the joints between them only
//! (the joints before `a` move both rigidly). So a pair `p` measured at `s_p` with clearance
//! `d_p` (exact, or a broad-phase lower bound) keeps more than `threshold + (d_p - threshold) / 2`
//! until `s_p + (d_p - threshold) / (2 M_p)`: its certified stretch. Each pair is measured again
//! where its stretch runs out (or, two thirds used, at a point made for another pair), the
//! advancement points being the nearest ends of stretches; every stretch is certified, with a
//! lower bound on its pair's clearance. The advancement stops at the end of the segment, or where
//! a clearance falls within [`TOUCH_TOLERANCE_M`] of the threshold: a touch (or a collision),
//! reported with the pair and where.

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
    /// Per pair, its last measurement along the segment being checked.
    known: Vec<Stretch>,
    /// Per pair, whether the next advancement point measures it.
    due: Vec<bool>,
    /// Per pair, how far the next advancement point measures it.
    levels: Vec<Option<f64>>,
    /// Whether the caller is stopping the run: a planner using this checker gives up.
    stop: Option<&'a (dyn Fn() -> bool + 'a)>,
}

/// A pair's clearance (or its lower bound) where it was last measured, at path parameter `at`,
/// and the end of the stretch that certifies (see [`Stretch::new`]).
#[derive(Debug, Clone, Copy, Default)]
struct Stretch {
    distance: f64,
    at: f64,
    until: f64,
}

impl Stretch {
    /// A pair measured at `at` with clearance `distance`; its stretch ends where it has lost
    /// half its excess over `threshold` for relative motion bound `rate`: never for a pair that
    /// does not move (or has no geometry), at once for one whose motion has no finite bound.
    fn new(distance: f64, at: f64, threshold: f64, rate: f64) -> Self {
        let excess = distance - threshold;
        let until = if excess.is_nan() || rate.is_nan() {
            // Nothing is certified by a number that is none: measured again at the next point.
            at
        } else if rate > 0.0 && excess.is_finite() {
            if rate.is_finite() {
                at + excess / (2.0 * rate)
            } else {
                at
            }
        } else {
            f64::INFINITY
        };
        Self { distance, at, until }
    }

    /// Lower bound on the pair's clearance at `s >= at`, for relative motion bound `rate`.
    fn bound_at(&self, s: f64, rate: f64) -> f64 {
        if s == self.at || self.distance == f64::INFINITY {
            // Also for an infinite rate, where the product is not a number.
            self.distance
        } else {
            self.distance - rate * (s - self.at)
        }
    }
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
            known: Vec::new(),
            due: Vec::new(),
            levels: Vec::new(),
            stop: None,
        }
    }

    /// The same checker, with `stop` telling a planner that uses it to give up (the caller is
    /// stopping the run and discards what it finds).
    pub fn with_stop(mut self, stop: &'a (dyn Fn() -> bool + 'a)) -> Self {
        self.stop = Some(stop);
        self
    }

    /// Whether the caller is stopping the run (see [`with_stop`](Self::with_stop)).
    pub fn stopped(&self) -> bool {
        self.stop.is_some_and(|stop| stop())
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
        self.query_among(q, false);
    }

    /// A query at `q`: of every pair, or (`due_only`) of the pairs due, each as far as its level
    /// asks (see [`collide::distances_among`]).
    fn query_among(&mut self, q: &[f64], due_only: bool) {
        self.model.forward(q, &mut self.ws);
        let query = QueryOptions {
            margin: self.opts.threshold_m,
            hulls: false,
            exact_depth: true,
            mesh_hulls: false,
        };
        let levels = due_only.then_some(self.levels.as_slice());
        collide::distances_among(self.world, &self.ws.link_in_world, &query, levels, &mut self.out);
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
        // The whole advancement, not one that gives up at the first point without room: a free
        // segment that grazes is still a fallback, and a blocked one is reported where it stops.
        let mut ends = [f64::NAN; 2];
        let check = self.advance_until(from, to, room, &mut None, &mut ends, f64::NEG_INFINITY);
        let ok = keeps(&check, (self.opts.threshold_m + room).min(ends[0]).min(ends[1]));
        (ok, check)
    }

    /// [`roomy_free`](Self::roomy_free)'s answer and [`advance`](Self::advance)'s roomy point
    /// in one check that stops early as [`keeps_room`](Self::keeps_room) does: whether the
    /// segment is free with room, the check (whole only when it is), and how far it is certified
    /// with room up to where it stopped.
    pub fn roomy_advance(&mut self, from: &[f64], to: &[f64], room: f64) -> (bool, SegmentCheck, Option<f64>) {
        let mut roomy = None;
        let (ok, check) = self.keeps_room_from_end(from, to, room, &mut roomy);
        (ok, check, roomy)
    }

    /// `roomy_free(from, to, room).0`, the same answer for less: the advancement stops at the
    /// first point that keeps neither `room` nor its ends' clearance, since that point alone
    /// decides `false`. The end's clearance is measured first, at the configuration the
    /// advancement would end at.
    pub fn keeps_room(&mut self, from: &[f64], to: &[f64], room: f64) -> bool {
        self.keeps_room_from_end(from, to, room, &mut None).0
    }

    fn keeps_room_from_end(&mut self, from: &[f64], to: &[f64], room: f64, roomy: &mut Option<f64>) -> (bool, SegmentCheck) {
        for (q, (a, b)) in self.q.iter_mut().zip(from.iter().zip(to)) {
            *q = a + 1.0 * (b - a);
        }
        let end = std::mem::take(&mut self.q);
        self.query(&end);
        self.q = end;
        let end_clearance = self.out.closest.map_or(f64::INFINITY, |c| c.distance);
        let mut ends = [f64::NAN; 2];
        let give_up = (self.opts.threshold_m + room).min(end_clearance);
        let check = self.advance_until(from, to, room, roomy, &mut ends, give_up);
        (keeps(&check, give_up.min(ends[0]).min(ends[1])), check)
    }

    /// The advancement; it gives up (not free) at the first point whose clearance is below both
    /// `give_up` and the start's.
    ///
    /// Each pair keeps its own stretch: measured at `s_p` with clearance `d_p`, it is certified
    /// until `s_p + (d_p - threshold) / (2 M_p)`, and it is measured again where that runs out,
    /// at a point made anyway once two thirds of it are used, or, when `room` is finite, where
    /// its bound falls below `threshold + room` (so that whether a point keeps room is known).
    /// Each advancement point is the nearest end of a stretch; both ends of the segment measure
    /// every pair. A pair far away or slow is then measured a few times per segment, not at every
    /// step the closest one forces.
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
        let pairs = self.world.pairs();
        self.rates.clear();
        self.rates
            .extend(pairs.iter().map(|pair| self.bounds.relative_motion(pair.a, pair.b, &self.delta)));
        self.known.clear();
        self.known.resize(pairs.len(), Stretch::default());
        self.due.clear();
        self.due.resize(pairs.len(), true);

        let mut s = 0.0;
        let mut queries = 0;
        let mut closest: Option<SegmentPoint> = None;
        let mut certified = f64::INFINITY;
        let mut by_kind = ClearanceByKind::default();
        // Each kind's smallest clearance measured exactly so far along the segment.
        let mut measured = ClearanceByKind::default();
        loop {
            for (q, (a, d)) in self.q.iter_mut().zip(from.iter().zip(&self.delta)) {
                *q = a + s * d;
            }
            let q = std::mem::take(&mut self.q);
            let every_pair = s == 0.0 || s >= 1.0;
            if every_pair {
                self.query_among(&q, false);
            } else {
                self.set_levels(s, room, give_up, &measured);
                self.query_among(&q, true);
            }
            queries += 1;
            let here = self.closest_point(s, &q);
            self.q = q;
            for (((known, estimate), due), rate) in self.known.iter_mut().zip(&self.out.estimates).zip(&self.due).zip(&self.rates) {
                if every_pair || *due {
                    *known = Stretch::new(estimate.distance, s, threshold, *rate);
                    by_kind.lower(estimate.b, estimate.distance);
                    if estimate.exact {
                        measured.lower(estimate.b, estimate.distance);
                    }
                }
            }
            let smallest = here.as_ref().map_or(f64::INFINITY, |p| p.distance_m);
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
            // Roomy when every pair's bound here keeps room (a pair measured here: its clearance).
            let needed = threshold + room;
            if s > 0.0
                && self
                    .known
                    .iter()
                    .zip(&self.rates)
                    .all(|(known, rate)| known.bound_at(s, *rate) >= needed)
            {
                *roomy = Some(s);
            }
            if s == 0.0 {
                ends[0] = smallest;
            }
            if s >= 1.0 {
                ends[1] = smallest;
                certified = certified.min(smallest);
                break;
            }
            // The nearest end of a pair's stretch, where it has lost half its excess clearance.
            let next = self.known.iter().fold(1.0f64, |next, known| next.min(known.until)).max(s);
            for (((known, rate), pair), due) in self.known.iter().zip(&self.rates).zip(pairs).zip(self.due.iter_mut()) {
                let bound = known.bound_at(next, *rate);
                certified = certified.min(bound);
                by_kind.lower(pair.b, bound);
                // A stretch two thirds used is renewed with the others: a point of its own later
                // would cost more than measuring it now (on primitive shapes, where queries are
                // cheap, the points are what costs).
                let until = known.until;
                *due = until <= next || until - next < (next - known.at) / 2.0 || (room.is_finite() && bound < needed);
            }
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
            s = next;
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

    /// The level each due pair is measured to at path parameter `s`: exactly when it could be
    /// the closest pair here, or the closest of its kind so far (`measured`: each kind's smallest
    /// exact clearance along the segment, which its certified bound follows), or below the room
    /// or the clearance that decides what this point is; else its cheaper bound serves.
    fn set_levels(&mut self, s: f64, room: f64, give_up: f64, measured: &ClearanceByKind) {
        let threshold = self.opts.threshold_m;
        let rest = self
            .known
            .iter()
            .zip(&self.rates)
            .zip(&self.due)
            .filter(|(_, due)| !**due)
            .map(|((known, rate), _)| known.bound_at(s, *rate))
            .fold(f64::INFINITY, f64::min);
        let deciding = if room.is_finite() {
            threshold + room
        } else {
            threshold + TOUCH_TOLERANCE_M
        };
        let floor = rest.max(deciding).max(give_up);
        self.levels.clear();
        self.levels.extend(
            self.world
                .pairs()
                .iter()
                .zip(&self.due)
                .map(|(pair, due)| due.then(|| floor.max(measured.for_body(pair.b).unwrap_or(f64::INFINITY)))),
        );
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
