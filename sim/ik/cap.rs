//! Where a tool within the goal's tolerance can need a point that is fixed in the tool frame:
//! the tolerance turns the tool by at most `angle` and moves it by at most `slack`, so the point
//! (at `radius` from the tool's origin `centre`, towards `axis`) lies within `slack` of a
//! spherical cap: the sphere of that radius, within `angle` of `axis`. A ball of radius
//! `slack + radius * angle` about the point holds the cap too, but with a long lever most of the
//! ball is off the sphere: a wrist centre that passes the point sideways, or 10 mm too far from
//! the tool, is in the ball and still nowhere a tolerated tool needs it.
//!
//! [`Cap::lower_bound_above`] bounds a point's distance from the cap over every angle of a 3R
//! chain that carries it, by branch and bound: joints 2 and 3 over boxes (Lipschitz constants per
//! joint, as [`super::wrist`]'s ball bound), joint 1 exactly enough per box centre (a turn about
//! one line moves the point on a circle, bounded by its radius).

use super::lines::Line;
use nalgebra::Vector3;
use std::f64::consts::PI;

/// The most distance evaluations a bound may use (about 30 ns each).
const MAX_EVALUATIONS: usize = 100_000;

/// The evaluations a goal's bound gets for a joint-space search budget of `boxes`: half a box's
/// worth each, at most [`MAX_EVALUATIONS`] (validation's 200 000 boxes: 100 000), none below
/// 10 000 (a sweep's 200 boxes: too few to prove anything, so sweeps keep the ball alone and
/// their cost).
pub(crate) fn evaluations_for(boxes: usize) -> usize {
    let evaluations = (boxes / 2).min(MAX_EVALUATIONS);
    if evaluations < 5_000 {
        0
    } else {
        evaluations
    }
}
/// Boxes per angle of joints 2 and 3 to start with, and intervals of joint 1.
const START: usize = 32;
/// Joint 1's interval is not halved below this (rad): a box centre whose circle is that close to
/// the bound is split instead.
const SHORTEST: f64 = 1e-4;

/// The points within `angle` of `axis` on the sphere of `radius` about `centre`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cap {
    pub(crate) centre: Vector3<f64>,
    /// Unit vector.
    pub(crate) axis: Vector3<f64>,
    pub(crate) radius: f64,
    /// Below pi.
    pub(crate) angle: f64,
}

/// What one circle of joint 1 gives.
enum Circle {
    /// No point of it is within this much of the cap (above the floor asked for).
    Above(f64),
    /// A point of it is within `slack` of the cap: no bound can be proven.
    Within,
    /// Neither shown within the evaluations allowed.
    Open,
}

impl Cap {
    /// The distance of `x` from the cap: to the sphere where `x` is within the cone, else to the
    /// cap's rim in the plane of `x` and the axis.
    pub(crate) fn distance(&self, x: &Vector3<f64>) -> f64 {
        let v = x - self.centre;
        let s = v.norm();
        if s == 0.0 {
            return self.radius;
        }
        let off = (v.dot(&self.axis) / s).clamp(-1.0, 1.0).acos();
        if off <= self.angle {
            (s - self.radius).abs()
        } else {
            let turn = off - self.angle;
            (s * s + self.radius * self.radius - 2.0 * s * self.radius * turn.cos())
                .max(0.0)
                .sqrt()
        }
    }

    /// A lower bound, above `slack`, on the distance from the cap of `point` turned by joint 3
    /// about `lines[2]`, then joint 2 about `lines[1]`, then joint 1 about `lines[0]`, over every
    /// angle of the three; `None` when a turn puts it within `slack` or `budget` evaluations run
    /// out.
    pub(crate) fn lower_bound_above(&self, lines: [&Line; 3], point: &Vector3<f64>, slack: f64, budget: usize) -> Option<f64> {
        let [l1, l2, l3] = lines;
        let [lipschitz2, lipschitz3] = turn_rates(l2, l3, point);
        let mut boxes = torus_boxes(START);
        let mut bound = f64::INFINITY;
        let mut evaluations = 0;
        while let Some((t2, t3, h)) = boxes.pop() {
            let reach = (lipschitz2 + lipschitz3) * h;
            let carried = l2.turn(t2, &l3.turn(t3, point));
            match self.circle_above(l1, &carried, slack, slack + reach, &mut evaluations) {
                Circle::Above(low) => bound = bound.min(low - reach),
                Circle::Within => return None,
                Circle::Open => {
                    let quarter = h / 2.0;
                    for (d2, d3) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                        boxes.push((t2 + d2 * quarter, t3 + d3 * quarter, quarter));
                    }
                }
            }
            if evaluations > budget {
                return None;
            }
        }
        Some(bound)
    }

    /// Whether every turn of `x` about `line` stays further than `floor` from the cap (with a
    /// lower bound), comes within `slack`, or neither is shown.
    fn circle_above(&self, line: &Line, x: &Vector3<f64>, slack: f64, floor: f64, evaluations: &mut usize) -> Circle {
        // The point moves at its distance from the line per radian, on a circle: its squared
        // distance from the cap's centre and its height along the cap's axis are sinusoids of
        // the turn, whose ranges over an interval bound the distance from the cap from below
        // without sampling it (the sphere's distance; the cap's points are all at least
        // `radius cos(angle)` along the axis, and the height moves a point no faster than it).
        let along = line.axis * line.axis.dot(&(x - line.point));
        let centre = line.point + along;
        let spoke = x - centre;
        let lipschitz = spoke.norm();
        let across = line.axis.cross(&spoke);
        let offset = centre - self.centre;
        let squared = Sinusoid::new(
            offset.norm_squared() + spoke.norm_squared(),
            2.0 * offset.dot(&spoke),
            2.0 * offset.dot(&across),
        );
        let height = Sinusoid::new(offset.dot(&self.axis), spoke.dot(&self.axis), across.dot(&self.axis));
        let lowest_height = self.radius * self.angle.cos();
        let half = PI / START as f64;
        let mut intervals: Vec<(f64, f64)> = (0..START).map(|k| (-PI + (2 * k + 1) as f64 * half, half)).collect();
        let mut bound = f64::INFINITY;
        while let Some((t, h)) = intervals.pop() {
            let (near, far) = squared.range(t, h);
            let (_, highest) = height.range(t, h);
            let cheap = (near.max(0.0).sqrt() - self.radius)
                .max(self.radius - far.max(0.0).sqrt())
                .max(lowest_height - highest);
            if cheap > floor {
                bound = bound.min(cheap);
                continue;
            }
            *evaluations += 1;
            let value = self.distance(&line.turn(t, x));
            if value <= slack {
                return Circle::Within;
            }
            let low = (value - lipschitz * h).max(cheap);
            if low > floor {
                bound = bound.min(low);
            } else if h <= SHORTEST || value <= floor {
                // The box itself must shrink: its centre's circle comes too close.
                return Circle::Open;
            } else {
                intervals.push((t - h / 2.0, h / 2.0));
                intervals.push((t + h / 2.0, h / 2.0));
            }
        }
        Circle::Above(bound)
    }
}

/// How fast `point`, turned by joint 3 about `l3` and then by joint 2 about `l2`, moves per
/// radian of each, at most: a turn of joint 3 moves it at its distance from axis 3; of joint 2,
/// at most at axis 3's point's distance from axis 2 plus the point's from that point.
pub(super) fn turn_rates(l2: &Line, l3: &Line, point: &Vector3<f64>) -> [f64; 2] {
    let lipschitz3 = (point - l3.point).cross(&l3.axis).norm();
    let lipschitz2 = (l3.point - l2.point).cross(&l2.axis).norm() + (point - l3.point).norm();
    [lipschitz2, lipschitz3]
}

/// The torus of two angles as `start x start` boxes: centres and the half width.
pub(super) fn torus_boxes(start: usize) -> Vec<(f64, f64, f64)> {
    let half = PI / start as f64;
    let mut boxes = Vec::with_capacity(start * start);
    for i in 0..start {
        for j in 0..start {
            boxes.push((-PI + (2 * i + 1) as f64 * half, -PI + (2 * j + 1) as f64 * half, half));
        }
    }
    boxes
}

/// `mean + amplitude cos(t - phase)`.
struct Sinusoid {
    mean: f64,
    amplitude: f64,
    phase: f64,
}

impl Sinusoid {
    /// `mean + a cos t + b sin t`.
    fn new(mean: f64, a: f64, b: f64) -> Self {
        Self {
            mean,
            amplitude: a.hypot(b),
            phase: b.atan2(a),
        }
    }

    /// Its least and greatest values over `t +- h` (`h` below pi / 2).
    fn range(&self, t: f64, h: f64) -> (f64, f64) {
        let d = (t - self.phase + PI).rem_euclid(2.0 * PI) - PI;
        let ends = [(d - h).cos(), (d + h).cos()];
        let high = if d.abs() <= h { 1.0 } else { ends[0].max(ends[1]) };
        let low = if d.abs() >= PI - h { -1.0 } else { ends[0].min(ends[1]) };
        (self.mean + self.amplitude * low, self.mean + self.amplitude * high)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn cap() -> Cap {
        Cap {
            centre: Vector3::new(0.1, -0.2, 0.3),
            axis: Vector3::new(1.0, 2.0, -2.0) / 3.0,
            radius: 0.7,
            angle: 0.05,
        }
    }

    /// The closed-form distance against the nearest of many points of the cap.
    #[test]
    fn distance_is_the_nearest_point_of_the_cap() {
        let cap = cap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let other = cap.axis.cross(&Vector3::x()).normalize();
        let mut points = Vec::new();
        for i in 0..=60 {
            let tilt = cap.angle * i as f64 / 60.0;
            for k in 0..360 {
                let around = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(cap.axis), k as f64 * PI / 180.0);
                let tilted = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(other), tilt) * cap.axis;
                points.push(cap.centre + around * tilted * cap.radius);
            }
        }
        for _ in 0..200 {
            let x = cap.centre + Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)) * rng.random_range(0.1..1.2);
            let nearest = points.iter().map(|p| (p - x).norm()).fold(f64::INFINITY, f64::min);
            let d = cap.distance(&x);
            assert!(d <= nearest + 1e-12 && d >= nearest - 2e-3, "{d} against {nearest}");
        }
    }

    /// The bound against dense samples of the three angles: never above their smallest distance,
    /// and `None` where a sample is within the slack.
    #[test]
    fn bound_holds_against_dense_samples() {
        let line = |point: [f64; 3], axis: [f64; 3]| Line {
            point: Vector3::from(point),
            axis: Vector3::from(axis).normalize(),
        };
        let lines = [
            line([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            line([0.0, 0.1, 0.3], [0.0, 1.0, 0.0]),
            line([0.4, 0.1, 0.3], [0.0, 1.0, 0.2]),
        ];
        let point = Vector3::new(0.8, 0.1, 0.35);
        let carried = |t: [f64; 3]| lines[0].turn(t[0], &lines[1].turn(t[1], &lines[2].turn(t[2], &point)));
        let steps = 90;
        let mut proven = 0;
        for (k, radius) in [0.05, 0.3, 1.2, 1.9].into_iter().enumerate() {
            let cap = Cap {
                centre: Vector3::new(1.5, 0.0, 0.2),
                axis: Vector3::new(-1.0, 0.3 * k as f64, 0.1).normalize(),
                radius,
                angle: 0.02,
            };
            let mut smallest = f64::INFINITY;
            for i in 0..steps {
                for j in 0..steps {
                    for l in 0..steps {
                        let t = [i, j, l].map(|n| -PI + 2.0 * PI * n as f64 / steps as f64);
                        smallest = smallest.min(cap.distance(&carried(t)));
                    }
                }
            }
            match cap.lower_bound_above([&lines[0], &lines[1], &lines[2]], &point, 0.005, 1_000_000) {
                Some(bound) => {
                    proven += 1;
                    assert!(
                        bound > 0.005 && bound <= smallest + 1e-12,
                        "radius {radius}: {bound} above {smallest}"
                    );
                }
                None => assert!(smallest < 0.05, "radius {radius}: no bound though the samples stay {smallest} away"),
            }
        }
        assert!(proven >= 2, "{proven} caps bounded");
    }
}
