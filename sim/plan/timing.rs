//! Time parameterisation: synchronised trapezoidal velocity profiles between waypoints, and a
//! dwell at each goal.
//!
//! Each segment moves every joint along the straight joint-space line from one waypoint to the
//! next with one common path parameter `s` in [0, 1]; `s(t)` is a trapezoid (or triangle) whose
//! velocity and acceleration are the largest every joint's limits allow: `ds/dt <= v_j / |dq_j|`
//! and `d2s/dt2 <= a_j / |dq_j|` for every joint `j`. All joints start and stop together, and the
//! joint-space path is exactly the straight segment the continuous check certified.

use crate::model::{JointKind, Model};

/// Speed limit of a revolute joint without one (rad/s): the catalog modules' pi rad/s.
pub const DEFAULT_VELOCITY_RAD_S: f64 = std::f64::consts::PI;
/// Speed limit of a prismatic joint without one (m/s).
pub const DEFAULT_VELOCITY_M_S: f64 = 0.5;
/// Acceleration limit (rad/s^2 or m/s^2 per rad/s or m/s of speed limit): full speed in 0.5 s.
pub const DEFAULT_ACCELERATION_PER_VELOCITY: f64 = 2.0;
/// Time the reference rests at each goal (s), for the engines to settle and be judged.
pub const DEFAULT_DWELL_S: f64 = 0.5;

/// Per-joint limits used for timing.
#[derive(Debug, Clone, PartialEq)]
pub struct TimingLimits {
    /// Velocity limit per joint (rad/s or m/s).
    pub velocity: Vec<f64>,
    /// Acceleration limit per joint (rad/s^2 or m/s^2).
    pub acceleration: Vec<f64>,
    /// Rest at each goal (s).
    pub dwell_s: f64,
}

impl TimingLimits {
    /// The model's speed limits (URDF `velocity`, catalog pi rad/s), else the defaults above;
    /// accelerations [`DEFAULT_ACCELERATION_PER_VELOCITY`] times the speed limit.
    pub fn of(model: &Model) -> Self {
        let velocity: Vec<f64> = model
            .joints
            .iter()
            .map(|j| {
                j.max_velocity.filter(|v| v.is_finite() && *v > 0.0).unwrap_or(match j.kind {
                    JointKind::Prismatic => DEFAULT_VELOCITY_M_S,
                    _ => DEFAULT_VELOCITY_RAD_S,
                })
            })
            .collect();
        let acceleration = velocity.iter().map(|v| v * DEFAULT_ACCELERATION_PER_VELOCITY).collect();
        Self {
            velocity,
            acceleration,
            dwell_s: DEFAULT_DWELL_S,
        }
    }
}

/// One timed straight joint-space motion, followed by an optional dwell.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TimedSegment {
    /// Start configuration.
    pub from: Vec<f64>,
    /// End configuration.
    pub to: Vec<f64>,
    /// Goal index (scenario order) the segment ends at, if any.
    pub goal: Option<usize>,
    /// Start time (s).
    pub start_s: f64,
    /// Motion duration (s).
    pub motion_s: f64,
    /// Rest at `to` after the motion (s).
    pub dwell_s: f64,
    /// Peak and acceleration of the path parameter (1/s, 1/s^2).
    peak_rate: f64,
    rate_acceleration: f64,
}

impl TimedSegment {
    /// End of the motion, start of the dwell (s).
    pub fn arrival_s(&self) -> f64 {
        self.start_s + self.motion_s
    }

    /// End of the dwell (s).
    pub fn end_s(&self) -> f64 {
        self.start_s + self.motion_s + self.dwell_s
    }

    /// Path parameter and its rate at time `t` after the segment's start.
    fn parameter(&self, t: f64) -> (f64, f64) {
        if self.motion_s <= 0.0 || t >= self.motion_s {
            return (1.0, 0.0);
        }
        if t <= 0.0 {
            return (0.0, 0.0);
        }
        let (v, a, total) = (self.peak_rate, self.rate_acceleration, self.motion_s);
        let ramp = v / a;
        if t < ramp {
            (0.5 * a * t * t, a * t)
        } else if t > total - ramp {
            let left = total - t;
            (1.0 - 0.5 * a * left * left, a * left)
        } else {
            (0.5 * a * ramp * ramp + v * (t - ramp), v)
        }
    }
}

/// A timed joint trajectory: the reference both physics engines follow.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TimedPath {
    /// Segments in time order, contiguous.
    pub segments: Vec<TimedSegment>,
}

/// A window in which the reference rests at a goal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hold<'a> {
    /// Goal index in the scenario.
    pub goal: usize,
    /// Start and end of the rest (s).
    pub start_s: f64,
    /// End of the rest (s): where an engine is judged on holding the goal.
    pub end_s: f64,
    /// The configuration held.
    pub q: &'a [f64],
}

impl TimedPath {
    /// Times straight motions through `waypoints` (at least one: the start). `goals[i]` is the
    /// goal reached at `waypoints[i + 1]`, if any; each such waypoint gets the dwell.
    pub fn through(waypoints: &[Vec<f64>], goals: &[Option<usize>], limits: &TimingLimits) -> Self {
        let mut segments = Vec::with_capacity(waypoints.len().saturating_sub(1));
        let mut start_s = 0.0;
        for (i, pair) in waypoints.windows(2).enumerate() {
            let goal = goals.get(i).copied().flatten();
            let (peak_rate, rate_acceleration) = rates(&pair[0], &pair[1], limits);
            let motion_s = if peak_rate.is_finite() {
                let ramp = peak_rate / rate_acceleration;
                if peak_rate * ramp >= 1.0 {
                    // Triangle: never reaches the peak rate.
                    2.0 * (1.0 / rate_acceleration).sqrt()
                } else {
                    1.0 / peak_rate + ramp
                }
            } else {
                0.0
            };
            // A triangle profile peaks below the rate limit: store the rate it reaches.
            let peak_rate = if peak_rate.is_finite() {
                peak_rate.min((rate_acceleration).sqrt())
            } else {
                1.0
            };
            let dwell_s = if goal.is_some() { limits.dwell_s } else { 0.0 };
            segments.push(TimedSegment {
                from: pair[0].clone(),
                to: pair[1].clone(),
                goal,
                start_s,
                motion_s,
                dwell_s,
                peak_rate,
                rate_acceleration,
            });
            start_s += motion_s + dwell_s;
        }
        Self { segments }
    }

    /// Total duration (s).
    pub fn duration_s(&self) -> f64 {
        self.segments.last().map_or(0.0, TimedSegment::end_s)
    }

    /// Reference position and velocity at time `t` (clamped to the path), written into `q` and
    /// `qd` (length dof). An empty path leaves them untouched.
    pub fn sample(&self, t: f64, q: &mut [f64], qd: &mut [f64]) {
        let Some(last) = self.segments.last() else { return };
        let index = self.segments.partition_point(|s| s.end_s() <= t).min(self.segments.len() - 1);
        let segment = if t >= last.end_s() { last } else { &self.segments[index] };
        let (s, rate) = segment.parameter(t - segment.start_s);
        for j in 0..q.len() {
            let delta = segment.to[j] - segment.from[j];
            q[j] = segment.from[j] + s * delta;
            qd[j] = rate * delta;
        }
    }

    /// The rests at goals, in time order.
    pub fn holds(&self) -> Vec<Hold<'_>> {
        self.segments
            .iter()
            .filter_map(|s| {
                s.goal.map(|goal| Hold {
                    goal,
                    start_s: s.arrival_s(),
                    end_s: s.end_s(),
                    q: &s.to,
                })
            })
            .collect()
    }
}

/// Largest rate and acceleration of the path parameter every joint allows; infinite for a
/// segment that does not move.
fn rates(from: &[f64], to: &[f64], limits: &TimingLimits) -> (f64, f64) {
    let mut rate = f64::INFINITY;
    let mut acceleration = f64::INFINITY;
    for j in 0..from.len() {
        let delta = (to[j] - from[j]).abs();
        if delta > 0.0 {
            rate = rate.min(limits.velocity[j] / delta);
            acceleration = acceleration.min(limits.acceleration[j] / delta);
        }
    }
    (rate, acceleration)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(dof: usize) -> TimingLimits {
        TimingLimits {
            velocity: vec![1.0; dof],
            acceleration: vec![2.0; dof],
            dwell_s: 0.5,
        }
    }

    #[test]
    fn a_long_move_is_a_trapezoid_that_respects_the_slowest_joint() {
        // Joint 0 moves 2 rad at most 1 rad/s and 2 rad/s^2: 0.5 s ramps, 1.5 s at speed.
        let path = TimedPath::through(&[vec![0.0, 0.0], vec![2.0, -1.0]], &[Some(0)], &limits(2));
        let segment = &path.segments[0];
        assert!((segment.motion_s - 2.5).abs() < 1e-12, "{}", segment.motion_s);
        assert!((path.duration_s() - 3.0).abs() < 1e-12);
        let (mut q, mut qd) = (vec![0.0; 2], vec![0.0; 2]);
        let steps = 2500;
        let mut previous = vec![0.0; 2];
        let mut previous_qd = vec![0.0; 2];
        for i in 1..=steps {
            let t = 2.5 * i as f64 / steps as f64;
            path.sample(t, &mut q, &mut qd);
            for j in 0..2 {
                assert!(qd[j].abs() <= 1.0 + 1e-12, "speed {} at {t}", qd[j]);
                // Finite differences: velocity matches the position, acceleration within limit.
                let dt = 2.5 / steps as f64;
                assert!(((q[j] - previous[j]) / dt - 0.5 * (qd[j] + previous_qd[j])).abs() < 1e-6, "at {t}");
                assert!(((qd[j] - previous_qd[j]) / dt).abs() <= 2.0 + 1e-9, "at {t}");
            }
            // Synchronised: joint 1 is always half-way behind joint 0 in proportion.
            assert!((q[1] + 0.5 * q[0]).abs() < 1e-12);
            previous.clone_from(&q);
            previous_qd.clone_from(&qd);
        }
        assert_eq!(q, vec![2.0, -1.0]);
        let holds = path.holds();
        assert_eq!(holds.len(), 1);
        assert!((holds[0].start_s - 2.5).abs() < 1e-12 && (holds[0].end_s - 3.0).abs() < 1e-12);
    }

    #[test]
    fn a_short_move_is_a_triangle() {
        // 0.25 rad at 2 rad/s^2: 0.35 s up, 0.35 s down, peak 0.707 rad/s below the limit.
        let path = TimedPath::through(&[vec![0.0], vec![0.25]], &[None], &limits(1));
        let expected = 2.0 * (0.25f64 / 2.0).sqrt();
        assert!((path.duration_s() - expected).abs() < 1e-12);
        let (mut q, mut qd) = (vec![0.0], vec![0.0]);
        path.sample(expected / 2.0, &mut q, &mut qd);
        assert!(
            (q[0] - 0.125).abs() < 1e-12 && (qd[0] - (0.5f64).sqrt()).abs() < 1e-12,
            "{q:?} {qd:?}"
        );
        path.sample(10.0, &mut q, &mut qd);
        assert_eq!((q[0], qd[0]), (0.25, 0.0));
    }

    #[test]
    fn a_segment_that_does_not_move_takes_only_its_dwell() {
        let path = TimedPath::through(&[vec![1.0], vec![1.0]], &[Some(3)], &limits(1));
        assert_eq!(path.segments[0].motion_s, 0.0);
        assert_eq!(path.duration_s(), 0.5);
        let (mut q, mut qd) = (vec![0.0], vec![9.0]);
        path.sample(0.2, &mut q, &mut qd);
        assert_eq!((q[0], qd[0]), (1.0, 0.0));
    }
}
