//! Consumes a model, a scenario and its IK solutions. Produces the trajectory through the
//! course: one reached configuration per goal in course order, joined by paths of joint-space
//! edges each certified collision-free (a straight segment, or a detour found by RRT-Connect),
//! each goal's outcome (reached, unreachable, no path within the budget), and the time
//! parameterisation for the engines. Never fails on a design; only a scenario home that cannot
//! be used at all is an error.

mod certify;
mod planner;
mod replay;
mod rrt;
mod timing;
mod trajectory;

pub use certify::{CertifyOptions, MotionBounds, SegmentCheck, SegmentChecker, SegmentPoint, MAX_STEPS, TOUCH_TOLERANCE_M};

pub use planner::{distance, polyline_length, Failure, Path, Planner, PlannerKind, PlannerOptions, Straight, DEFAULT_PLAN_BUDGET};
pub use replay::{replay_sample_iter, replay_samples, replay_segments, ReplaySegment, REPLAY_STEP};
pub use rrt::{RrtConnect, ROOM_M, STEP};
pub use timing::{
    Hold, TimedPath, TimedSegment, TimingLimits, DEFAULT_ACCELERATION_PER_VELOCITY, DEFAULT_DWELL_S, DEFAULT_VELOCITY_M_S,
    DEFAULT_VELOCITY_RAD_S,
};
pub use trajectory::{
    default_home, home_configuration, home_for, nearest_equivalent, plan, plan_counted, whole_turn_equivalents, Attempt, GoalStep,
    PlanError, Trajectory, TrajectoryOptions,
};
