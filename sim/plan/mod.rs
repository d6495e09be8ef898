//! Consumes a model, a scenario and its IK solutions. Produces the trajectory through the
//! course: one reached configuration per goal in course order, joined by straight joint-space
//! segments certified collision-free, and its time parameterisation for the engines.

mod certify;
mod replay;
mod timing;
mod trajectory;

pub use certify::{CertifyOptions, MotionBounds, SegmentCheck, SegmentChecker, SegmentPoint, MAX_STEPS, TOUCH_TOLERANCE_M};

pub use replay::{replay_samples, replay_segments, ReplaySegment, REPLAY_STEP};
pub use timing::{
    Hold, TimedPath, TimedSegment, TimingLimits, DEFAULT_ACCELERATION_PER_VELOCITY, DEFAULT_DWELL_S, DEFAULT_VELOCITY_M_S,
    DEFAULT_VELOCITY_RAD_S,
};
pub use trajectory::{
    default_home, home_configuration, home_for, nearest_equivalent, plan, Attempt, GoalStep, PlanError, Trajectory, TrajectoryOptions,
};
