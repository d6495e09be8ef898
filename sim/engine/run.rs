//! What a dynamic or kinematic engine run records, the same for rapier and MuJoCo, so the two
//! can be compared with each other and with the certified parry3d check.

use serde::Serialize;

/// Position-control gains per joint, chain order: `tau = kp (q_ref - q) + kd (qd_ref - qd)`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Gains {
    /// Stiffness per joint (N m/rad or N/m).
    pub stiffness: Vec<f64>,
    /// Damping per joint (N m s/rad or N s/m).
    pub damping: Vec<f64>,
}

/// Settings of one engine run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunOptions {
    /// Integration step (s); default 0.001.
    pub timestep_s: f64,
    /// Gravity along -z (m/s^2); default 9.81.
    pub gravity_m_s2: f64,
    /// Contacts shallower than this are not recorded (m); default 0: every contact the engine
    /// reports with a non-negative depth.
    pub contact_depth_m: f64,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            timestep_s: 0.001,
            gravity_m_s2: 9.81,
            contact_depth_m: 0.0,
        }
    }
}

/// Contact between two bodies over a time interval, as an engine's narrow phase reported it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContactInterval {
    /// Model link name.
    pub a: String,
    /// Model link name, obstacle name, or `floor`.
    pub b: String,
    /// First step time with the contact (s).
    pub start_s: f64,
    /// Last step time with the contact (s).
    pub end_s: f64,
    /// Deepest penetration reported in the interval (m).
    pub max_depth_m: f64,
    /// The engine's joint configuration at the deepest step.
    pub q: Vec<f64>,
    /// The exact (parry3d-f64) signed distance of the same pair at `q`, when the pipeline
    /// checked it (m): positive means the engine reports a contact exact geometry does not have.
    pub parry_distance_m: Option<f64>,
    /// The exact signed distance of the same pair along the reference (the planned, certified
    /// motion) over the contact's interval, its smallest value (m), when the pipeline measured
    /// it: positive means the reference keeps the pair apart and the engine's own tracking error
    /// brought them together.
    pub reference_distance_m: Option<f64>,
}

/// How well an engine held one goal: measured at the end of the goal's dwell.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GoalHold {
    /// Goal index in the scenario.
    pub goal: usize,
    /// Time of the measurement (s).
    pub time_s: f64,
    /// Tool position error against the kinematic reference (our FK of the reference
    /// configuration) (m).
    pub position_error_m: f64,
    /// Tool rotation angle error against the kinematic reference (rad).
    pub orientation_error_rad: f64,
    /// Largest joint error (rad or m).
    pub joint_error: f64,
}

/// Everything recorded in one run of one engine.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EngineRun {
    /// `rapier` or `mujoco`.
    pub engine: &'static str,
    /// `dynamic` (motors follow the reference) or `kinematic` (positions set directly).
    pub mode: &'static str,
    /// Steps taken.
    pub steps: usize,
    /// Step (s).
    pub timestep_s: f64,
    /// Largest joint tracking error over the run, per joint (rad or m).
    pub max_joint_error: Vec<f64>,
    /// Largest tool position error against the kinematic reference over the run (m).
    pub max_tool_position_error_m: f64,
    /// Largest tool orientation error against the kinematic reference over the run (rad).
    pub max_tool_orientation_error_rad: f64,
    /// Per goal with a dwell, in time order.
    pub holds: Vec<GoalHold>,
    /// Every contact between robot and obstacles or floor, and between checked link pairs.
    pub contacts: Vec<ContactInterval>,
    /// Largest joint effort over the run, per joint (N m or N).
    pub peak_effort: Vec<f64>,
}

/// Accumulates per-step contacts into intervals: one open interval per pair, closed when a
/// step no longer reports the pair.
#[derive(Debug, Default)]
pub struct ContactRecorder {
    open: Vec<ContactInterval>,
    closed: Vec<ContactInterval>,
    seen: Vec<bool>,
}

impl ContactRecorder {
    /// An empty recorder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Starts a step at `time_s`: call [`ContactRecorder::contact`] for each contact, then
    /// [`ContactRecorder::end_step`].
    pub fn begin_step(&mut self) {
        self.seen.clear();
        self.seen.resize(self.open.len(), false);
    }

    /// One contact of the current step at joint configuration `q`; `a` and `b` are ordered by
    /// the caller (link first).
    pub fn contact(&mut self, a: &str, b: &str, time_s: f64, depth_m: f64, q: &[f64]) {
        if let Some(index) = self.open.iter().position(|c| c.a == a && c.b == b) {
            let interval = &mut self.open[index];
            interval.end_s = time_s;
            if depth_m > interval.max_depth_m {
                interval.max_depth_m = depth_m;
                interval.q.clear();
                interval.q.extend_from_slice(q);
            }
            if index < self.seen.len() {
                self.seen[index] = true;
            }
        } else {
            self.open.push(ContactInterval {
                a: a.to_string(),
                b: b.to_string(),
                start_s: time_s,
                end_s: time_s,
                max_depth_m: depth_m,
                q: q.to_vec(),
                parry_distance_m: None,
                reference_distance_m: None,
            });
            self.seen.push(true);
        }
    }

    /// Closes the intervals of pairs not reported in this step.
    pub fn end_step(&mut self) {
        let mut index = 0;
        while index < self.open.len() {
            if self.seen[index] {
                index += 1;
            } else {
                self.closed.push(self.open.remove(index));
                self.seen.remove(index);
            }
        }
    }

    /// All intervals, ordered by start time, then names.
    pub fn finish(mut self) -> Vec<ContactInterval> {
        self.closed.append(&mut self.open);
        self.closed.sort_by(|x, y| {
            x.start_s
                .total_cmp(&y.start_s)
                .then_with(|| x.a.cmp(&y.a))
                .then_with(|| x.b.cmp(&y.b))
        });
        self.closed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contacts_merge_into_intervals_per_pair() {
        let mut recorder = ContactRecorder::new();
        for (step, pairs) in [
            vec![("l1", "ball")],
            vec![("l1", "ball"), ("l2", "floor")],
            vec![("l2", "floor")],
            vec![],
            vec![("l1", "ball")],
        ]
        .iter()
        .enumerate()
        {
            recorder.begin_step();
            for (a, b) in pairs {
                recorder.contact(a, b, step as f64, 0.001 * step as f64, &[step as f64]);
            }
            recorder.end_step();
        }
        let intervals = recorder.finish();
        let summary: Vec<(&str, &str, f64, f64, f64)> = intervals
            .iter()
            .map(|c| (c.a.as_str(), c.b.as_str(), c.start_s, c.end_s, c.max_depth_m))
            .collect();
        assert_eq!(
            summary,
            [
                ("l1", "ball", 0.0, 1.0, 0.001),
                ("l2", "floor", 1.0, 2.0, 0.002),
                ("l1", "ball", 4.0, 4.0, 0.004)
            ]
        );
    }
}
