//! Findings: everything a user should know about a run, each with a kind, a severity, a message
//! and its numbers; and the verdict they make.
//!
//! The three checkers are compared on the replayed segments (see `plan::replay_segments`): the
//! certified parry3d check is the authority, so a contact an engine reports on a segment parry
//! certified free, or a blocked segment an engine replays without contact, is a disagreement to
//! review (severity `warn`), not a failure. Known sources: MuJoCo collides cylinders through its
//! general convex solver (a few micrometres off) and meshes as hulls; the engines are sampled
//! checkers (every 0.005 rad), so a contact thinner than a sample step can escape them.

use super::Report;
use super::{EngineRuns, Validation};
use crate::engine::ContactInterval;
use crate::plan::GoalStep;
use serde::Serialize;
use std::collections::BTreeMap;

/// How much a finding weighs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    /// Context, no action needed.
    Info,
    /// Worth a look; does not fail the design.
    Warn,
    /// What the harness could not decide within its limits (IK starts, the planner's budget):
    /// neither a pass nor a failure of the design.
    Undecided,
    /// Fails the design: proven.
    Fail,
}

/// What a finding is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FindingKind {
    /// No configuration reaches the goal collision-free within the thresholds, proven.
    GoalUnreachable,
    /// No collision-free configuration reaching the goal was found, and none is proven not to
    /// exist: the finding names what was tried.
    GoalUndecided,
    /// Collision-free configurations exist but the planner found no certified path to one within
    /// its budget.
    GoalNoPath,
    /// The home configuration is in collision.
    HomeInCollision,
    /// The scenario's home does not fit the robot, or the default home collides: the tour starts
    /// from the default home, or from the nearest collision-free configuration.
    HomeReplaced,
    /// An engine's dynamic run touched something while following the certified trajectory, and
    /// exact geometry confirms the contact at the engine's configuration.
    EngineContact,
    /// An engine's dynamic run reports a contact that exact geometry does not have at the
    /// engine's own configuration (an engine's geometric approximation).
    EngineContactNotConfirmed,
    /// An engine's dynamic run touched something that exact geometry confirms at the engine's
    /// configuration, while the certified reference keeps the pair apart at the same time: the
    /// controller's tracking error in that engine, not the design's motion.
    EngineContactFromTracking,
    /// An engine did not hold a goal within the hold tolerance after the dwell.
    GoalNotHeld,
    /// An engine did not hold a goal after contacts on the way that are the engine's (exact
    /// geometry refutes them, or the reference keeps the pair apart): the engine's
    /// approximation, not the design.
    GoalNotHeldAfterEngineArtefact,
    /// The two engines disagree on holding a goal.
    EnginesDisagree,
    /// An engine's replay reports a contact on a segment the certified check found free.
    ReplayContactNotPredicted,
    /// The certified check found a segment in contact that an engine's replay did not.
    ReplayContactMissed,
    /// The certified check and an engine's replay both found a blocked segment in contact.
    ReplayContactConfirmed,
    /// A joint's static gravity torque along the trajectory exceeds its rating.
    StaticOverload,
    /// Our gravity torques and MuJoCo's disagree (a model bug on one side).
    GravityModelMismatch,
    /// A joint's peak effort in a dynamic run exceeds its rating (the controller's stiffness
    /// during motion, not the static load).
    EffortOverRating,
    /// The paper's capsule model calls a configuration colliding that is free in exact geometry.
    ConservativeApproximation,
    /// The paper's capsule model calls a configuration free that collides in exact geometry.
    UnsafeApproximation,
}

/// One finding.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Finding {
    /// Kind.
    pub kind: FindingKind,
    /// Severity.
    pub severity: Severity,
    /// The goal concerned, if one.
    pub goal: Option<usize>,
    /// The engine concerned, if one.
    pub engine: Option<&'static str>,
    /// One line for a human.
    pub message: String,
    /// The numbers behind it, by name with their unit in the name.
    pub values: BTreeMap<&'static str, f64>,
}

fn finding(
    kind: FindingKind,
    severity: Severity,
    goal: Option<usize>,
    engine: Option<&'static str>,
    message: String,
    values: &[(&'static str, f64)],
) -> Finding {
    Finding {
        kind,
        severity,
        goal,
        engine,
        message,
        values: values.iter().copied().collect(),
    }
}

/// Every finding of a validation, in a fixed order.
pub(super) fn collect(validation: &Validation, engines: &[(&'static str, &EngineRuns)], hold: (f64, f64)) -> Vec<Finding> {
    let mut out = Vec::new();
    let Some(trajectory) = &validation.trajectory else {
        goal_findings(validation, &mut out);
        return out;
    };
    if let Some(home) = &trajectory.home_clearance {
        if home.distance_m <= validation.settings.margin_m + crate::plan::TOUCH_TOLERANCE_M {
            out.push(finding(
                FindingKind::HomeInCollision,
                Severity::Fail,
                None,
                None,
                format!("home configuration: {} and {} in contact", home.a, home.b),
                &[("distance_m", home.distance_m)],
            ));
        }
    }
    if let Some(reason) = &trajectory.home_replaced {
        out.push(finding(
            FindingKind::HomeReplaced,
            Severity::Info,
            None,
            None,
            format!(
                "{reason}: home {:?}",
                trajectory.home.iter().map(|q| (q * 1e4).round() / 1e4).collect::<Vec<_>>()
            ),
            &[],
        ));
    }
    goal_findings(validation, &mut out);
    for (name, runs) in engines {
        engine_findings(validation, name, runs, hold, &mut out);
    }
    // Each engine is compared with the first: a goal one holds and another misses.
    let (first_engine, others) = engines.split_first().map_or((None, &[][..]), |(f, o)| (Some(f), o));
    for ((a, first), (b, second)) in first_engine.into_iter().flat_map(|f| others.iter().map(move |o| (f, o))) {
        for hold_a in &first.dynamic.holds {
            let Some(hold_b) = second.dynamic.holds.iter().find(|h| h.goal == hold_a.goal) else {
                continue;
            };
            let held = |h: &crate::engine::GoalHold| h.position_error_m <= hold.0 && h.orientation_error_rad <= hold.1;
            if held(hold_a) != held(hold_b) {
                out.push(finding(
                    FindingKind::EnginesDisagree,
                    Severity::Warn,
                    Some(hold_a.goal),
                    None,
                    format!(
                        "goal {}: {a} {} it ({:.1} mm, {:.2} deg), {b} {} it ({:.1} mm, {:.2} deg)",
                        hold_a.goal,
                        if held(hold_a) { "holds" } else { "misses" },
                        hold_a.position_error_m * 1e3,
                        hold_a.orientation_error_rad.to_degrees(),
                        if held(hold_b) { "holds" } else { "misses" },
                        hold_b.position_error_m * 1e3,
                        hold_b.orientation_error_rad.to_degrees(),
                    ),
                    &[
                        ("first_position_m", hold_a.position_error_m),
                        ("second_position_m", hold_b.position_error_m),
                    ],
                ));
            }
        }
    }
    if let Some(load) = &validation.static_load {
        for (index, joint) in load.joints.iter().enumerate() {
            if joint.over {
                out.push(finding(
                    FindingKind::StaticOverload,
                    Severity::Fail,
                    None,
                    None,
                    format!(
                        "joint {} ({}): gravity alone needs {:.1} N m, rated {:.1} N m",
                        index + 1,
                        joint.joint,
                        joint.peak_torque,
                        joint.rated.unwrap_or(f64::NAN)
                    ),
                    &[("peak_torque", joint.peak_torque), ("rated", joint.rated.unwrap_or(f64::NAN))],
                ));
            }
        }
        if let Some(disagreement) = load.max_relative_disagreement.filter(|d| *d > 1e-9) {
            out.push(finding(
                FindingKind::GravityModelMismatch,
                Severity::Warn,
                None,
                None,
                format!(
                    "our gravity torques and {}'s differ by {disagreement:.2e} (relative)",
                    load.cross_checked_by.unwrap_or("the engine")
                ),
                &[("relative", disagreement)],
            ));
        }
    }
    out
}

fn goal_findings(validation: &Validation, out: &mut Vec<Finding>) {
    let settings = &validation.settings;
    for (index, goal) in validation.scenario.goals.iter().enumerate() {
        let solutions = validation.solutions.get(index).map(|g| g.solutions.as_slice()).unwrap_or_default();
        let best = solutions.first();
        // The paper's capsules are a model of designs; on a robot file's joint frames they would
        // be a phantom to compare with.
        if let Some(best) = best.filter(|_| validation.design.is_some()) {
            if let Some(c) = best.clearance {
                let margin = 0.0;
                if c.approximate_m <= margin && c.exact_m > margin {
                    out.push(finding(
                        FindingKind::ConservativeApproximation,
                        Severity::Info,
                        Some(index),
                        None,
                        format!(
                            "goal {index}: the paper's capsules collide ({:.1} mm), exact geometry is free ({:.1} mm)",
                            c.approximate_m * 1e3,
                            c.exact_m * 1e3
                        ),
                        &[("approximate_m", c.approximate_m), ("exact_m", c.exact_m)],
                    ));
                } else if c.approximate_m > margin && c.exact_m <= margin && best.pose_reached {
                    out.push(finding(
                        FindingKind::UnsafeApproximation,
                        Severity::Warn,
                        Some(index),
                        None,
                        format!(
                            "goal {index}: the paper's capsules are free ({:.1} mm), exact geometry collides ({:.1} mm)",
                            c.approximate_m * 1e3,
                            c.exact_m * 1e3
                        ),
                        &[("approximate_m", c.approximate_m), ("exact_m", c.exact_m)],
                    ));
                }
            }
        }
        let step = validation.trajectory.as_ref().and_then(|t| t.steps.get(index));
        let unreachable = match step {
            Some(step) => matches!(step, GoalStep::Unreachable { .. }),
            None => !best.is_some_and(|s| s.reached),
        };
        if unreachable {
            let (position, orientation, clearance) = best.map_or((f64::NAN, f64::NAN, f64::NAN), |s| {
                (
                    s.error.position_m,
                    s.error.orientation_rad,
                    s.clearance.map_or(f64::NAN, |c| c.exact_m),
                )
            });
            let proof = validation.proof(index);
            let open = validation.solutions.get(index).and_then(|g| g.undecided.as_ref());
            let why = match (&proof, open, best) {
                (Some(proof), _, _) => format!("unreachable: proven: {proof}"),
                (None, Some(open), Some(s)) if s.pose_reached => {
                    format!("undecided: {open} (best clearance {:.1} mm)", clearance * 1e3)
                }
                (None, Some(open), _) => format!("undecided: {open}"),
                (None, None, Some(s)) if s.pose_reached => format!(
                    "undecided: every solution found from {} IK starts (seed {}) collides (best clearance {:.1} mm); not proven unreachable",
                    settings.ik_seeds,
                    settings.seed,
                    clearance * 1e3
                ),
                _ => format!(
                    "undecided: no solution from {} IK starts (seed {}), closest miss {:.1} mm, {:.2} deg; not proven unreachable",
                    settings.ik_seeds,
                    settings.seed,
                    position * 1e3,
                    orientation.to_degrees()
                ),
            };
            let (kind, severity) = match proof {
                Some(_) => (FindingKind::GoalUnreachable, Severity::Fail),
                None => (FindingKind::GoalUndecided, Severity::Undecided),
            };
            out.push(finding(
                kind,
                severity,
                Some(index),
                None,
                format!("goal {index} ({}): {why}", goal.name),
                &[
                    ("position_m", position),
                    ("orientation_rad", orientation),
                    ("clearance_m", clearance),
                    ("proven", if proof.is_some() { 1.0 } else { 0.0 }),
                ],
            ));
        }
        if let Some(GoalStep::NoPath {
            tried,
            budget,
            samples,
            stop,
            gap,
            ..
        }) = step
        {
            let (pair, distance) = stop
                .as_ref()
                .map_or((String::from("?"), f64::NAN), |s| (format!("{} and {}", s.a, s.b), s.distance_m));
            let search = if *budget == 0 {
                "no straight segment to any of them is free (planner `straight`)".to_string()
            } else {
                format!(
                    "no certified path found in {samples} samples (budget {budget}); the search stayed {:.3} rad from the goal set",
                    gap.unwrap_or(f64::NAN)
                )
            };
            out.push(finding(
                FindingKind::GoalNoPath,
                Severity::Undecided,
                Some(index),
                None,
                format!(
                    "goal {index} ({}): {tried} collision-free configurations, {search}; the closest attempt stops where {pair} touch",
                    goal.name
                ),
                &[
                    ("distance_m", distance),
                    ("tried", *tried as f64),
                    ("budget", *budget as f64),
                    ("samples", *samples as f64),
                ],
            ));
        }
    }
}

/// The replay segment a contact interval's clock values fall in.
fn segments_of(contact: &ContactInterval) -> std::ops::RangeInclusive<usize> {
    (contact.start_s.max(0.0) as usize)..=(contact.end_s.max(0.0) as usize)
}

/// What an engine approximates, for findings that blame it.
fn approximation(engine: &str) -> &'static str {
    crate::engine::find(engine).map_or("the engine's geometric approximation", |e| e.approximation())
}

/// How exact geometry judges one engine contact of a dynamic run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ContactClass {
    /// Exact geometry has the contact at the engine's configuration, and the reference has it too
    /// (or was not measured): a real contact.
    Real,
    /// Exact geometry has it at the engine's configuration, the reference keeps the pair apart.
    Tracking,
    /// Exact geometry does not have it at the engine's configuration (or could not measure it).
    Refuted,
}

fn classify(contact: &ContactInterval) -> ContactClass {
    match (contact.parry_distance_m, contact.reference_distance_m) {
        (Some(exact), _) if exact.is_nan() || exact > 0.0 => ContactClass::Refuted,
        (None, _) => ContactClass::Refuted,
        (Some(_), Some(reference)) if reference > 0.0 => ContactClass::Tracking,
        _ => ContactClass::Real,
    }
}

fn engine_findings(validation: &Validation, name: &'static str, runs: &EngineRuns, hold: (f64, f64), out: &mut Vec<Finding>) {
    for contact in &runs.dynamic.contacts {
        let exact = contact.parry_distance_m.unwrap_or(f64::NAN);
        let reference = contact.reference_distance_m.unwrap_or(f64::NAN);
        let (kind, severity, verdict) = match classify(contact) {
            ContactClass::Refuted if exact.is_nan() => (
                FindingKind::EngineContactNotConfirmed,
                Severity::Warn,
                "not re-measured in exact geometry (the engine's configuration is unknown)".to_string(),
            ),
            ContactClass::Refuted => (
                FindingKind::EngineContactNotConfirmed,
                Severity::Warn,
                format!(
                    "but {:.1} mm apart in exact geometry at the engine's configuration ({})",
                    exact * 1e3,
                    approximation(name)
                ),
            ),
            ContactClass::Tracking => (
                FindingKind::EngineContactFromTracking,
                Severity::Warn,
                format!(
                    "exact geometry: {:.1} mm at the engine's configuration, but the certified reference keeps them {:.1} mm apart: {name}'s tracking error, not the planned motion",
                    exact * 1e3,
                    reference * 1e3
                ),
            ),
            ContactClass::Real => (
                FindingKind::EngineContact,
                Severity::Fail,
                format!("exact geometry: {:.1} mm", exact * 1e3),
            ),
        };
        out.push(finding(
            kind,
            severity,
            None,
            Some(name),
            format!(
                "{name}: {} and {} in contact from {:.3} s to {:.3} s, {:.1} mm deep, {verdict}",
                contact.a,
                contact.b,
                contact.start_s,
                contact.end_s,
                contact.max_depth_m * 1e3
            ),
            &[
                ("start_s", contact.start_s),
                ("end_s", contact.end_s),
                ("depth_m", contact.max_depth_m),
                ("exact_distance_m", exact),
                ("reference_distance_m", reference),
            ],
        ));
    }
    let mut holds: Vec<&crate::engine::GoalHold> = runs.dynamic.holds.iter().collect();
    holds.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    let mut since = f64::NEG_INFINITY;
    for h in holds {
        let window = since..=h.time_s;
        since = h.time_s;
        if h.position_error_m <= hold.0 && h.orientation_error_rad <= hold.1 {
            continue;
        }
        // Contacts between the previous goal's measurement and this one: if every one is the
        // engine's, so is the miss.
        let before: Vec<&ContactInterval> = runs
            .dynamic
            .contacts
            .iter()
            .filter(|c| c.start_s <= *window.end() && c.end_s >= *window.start())
            .collect();
        let artefact = !before.is_empty() && before.iter().all(|c| classify(c) != ContactClass::Real);
        let held = format!(
            "{name}: goal {} held {:.1} mm / {:.2} deg from the reference after the dwell",
            h.goal,
            h.position_error_m * 1e3,
            h.orientation_error_rad.to_degrees()
        );
        let (kind, severity, message) = if artefact {
            let pairs: Vec<String> = before.iter().map(|c| format!("{} and {}", c.a, c.b)).collect();
            (
                FindingKind::GoalNotHeldAfterEngineArtefact,
                Severity::Warn,
                format!(
                    "{held}, after contacts that are {name}'s, not the design's ({}): {}",
                    pairs.join(", "),
                    approximation(name)
                ),
            )
        } else {
            (FindingKind::GoalNotHeld, Severity::Fail, held)
        };
        out.push(finding(
            kind,
            severity,
            Some(h.goal),
            Some(name),
            message,
            &[("position_m", h.position_error_m), ("orientation_rad", h.orientation_error_rad)],
        ));
    }
    // An engine whose effort is its control law's estimate (rapier: ten times MuJoCo's on the
    // same joint) says nothing about a rating; its numbers stay in the JSON report, marked.
    let measured = crate::engine::find(name).is_none_or(|e| !e.effort().estimate);
    let efforts = runs.dynamic.peak_effort.iter().filter(|_| measured);
    for (joint, (peak, model_joint)) in efforts.zip(&validation.model.joints).enumerate() {
        if let Some(rated) = model_joint.max_effort {
            if *peak > rated {
                out.push(finding(
                    FindingKind::EffortOverRating,
                    Severity::Info,
                    None,
                    Some(name),
                    format!(
                        "{name}: joint {} ({}) peaks at {peak:.1} N m in motion, rated {rated:.1} N m{}",
                        joint + 1,
                        model_joint.name,
                        crate::engine::find(name).map_or_else(String::new, |e| format!(" ({})", e.effort().note))
                    ),
                    &[("peak", *peak), ("rated", rated)],
                ));
            }
        }
    }
    // Replay against the certified check, segment by segment.
    for (k, segment) in validation.replayed.iter().enumerate() {
        let contacts: Vec<&ContactInterval> = runs.replay.contacts.iter().filter(|c| segments_of(c).contains(&k)).collect();
        let parry_contact = !segment.certified.free;
        match (parry_contact, contacts.first()) {
            (false, Some(contact)) => out.push(finding(
                FindingKind::ReplayContactNotPredicted,
                Severity::Warn,
                Some(segment.goal),
                Some(name),
                format!(
                    "{name} replay: {} and {} in contact ({:.1} mm) on the segment to goal {} that parry3d certified free ({:.1} mm apart there)",
                    contact.a,
                    contact.b,
                    contact.max_depth_m * 1e3,
                    segment.goal,
                    contact.parry_distance_m.unwrap_or(f64::NAN) * 1e3
                ),
                &[
                    ("clock", contact.start_s),
                    ("depth_m", contact.max_depth_m),
                    ("exact_distance_m", contact.parry_distance_m.unwrap_or(f64::NAN)),
                ],
            )),
            (true, None) => out.push(finding(
                FindingKind::ReplayContactMissed,
                Severity::Warn,
                Some(segment.goal),
                Some(name),
                format!(
                    "{name} replay: no contact on the segment to goal {} where parry3d finds one",
                    segment.goal
                ),
                &[],
            )),
            (true, Some(contact)) => out.push(finding(
                FindingKind::ReplayContactConfirmed,
                Severity::Info,
                Some(segment.goal),
                Some(name),
                format!(
                    "{name} replay confirms the contact on the segment to goal {}: {} and {}, {:.1} mm deep",
                    segment.goal,
                    contact.a,
                    contact.b,
                    contact.max_depth_m * 1e3
                ),
                &[("clock", contact.start_s), ("depth_m", contact.max_depth_m)],
            )),
            (false, None) => {}
        }
    }
}

/// Passed when no finding fails or is undecided; failed when one fails (proven), else undecided;
/// the reasons count those findings by kind, failures first.
pub(super) fn verdict(findings: &[Finding], settings: &super::Settings, budget: Option<usize>) -> super::Verdict {
    let mut counts: BTreeMap<(FindingKind, bool), usize> = BTreeMap::new();
    let failed = findings.iter().any(|f| f.severity == Severity::Fail);
    let undecided = findings.iter().any(|f| f.severity == Severity::Undecided);
    let mut ordered: Vec<&Finding> = findings.iter().filter(|f| f.severity >= Severity::Undecided).collect();
    // Failures first: the reasons read from what is proven to what is open.
    ordered.sort_by_key(|f| std::cmp::Reverse(f.severity));
    let mut order: Vec<(FindingKind, bool)> = Vec::new();
    for f in ordered {
        let proven = f.values.get("proven").is_some_and(|p| *p > 0.0);
        let count = counts.entry((f.kind, proven)).or_default();
        if *count == 0 {
            order.push((f.kind, proven));
        }
        *count += 1;
    }
    let goals = |count: usize| if count == 1 { "goal" } else { "goals" };
    let reasons = order
        .iter()
        .map(|key| (key, counts[key]))
        .map(|((kind, _), count)| match kind {
            FindingKind::GoalUnreachable => format!("{count} {} unreachable (proven)", goals(count)),
            FindingKind::GoalUndecided => format!(
                "{count} {} undecided (not reached, not proven unreachable; IK {} starts, seed {})",
                goals(count),
                settings.ik_seeds,
                settings.seed
            ),
            FindingKind::GoalNoPath => match budget {
                Some(budget) if budget > 0 => format!("{count} {} without a path found in {budget} samples", goals(count)),
                _ => format!("{count} {} without a free straight segment", goals(count)),
            },
            other => {
                let what = match other {
                    FindingKind::HomeInCollision => "home configuration in collision",
                    FindingKind::EngineContact if count == 1 => "contact in the engines' dynamic runs",
                    FindingKind::EngineContact => "contacts in the engines' dynamic runs",
                    FindingKind::GoalNotHeld if count == 1 => "goal not held by an engine",
                    FindingKind::GoalNotHeld => "goals not held by an engine",
                    FindingKind::StaticOverload if count == 1 => "joint over its rated torque under gravity",
                    FindingKind::StaticOverload => "joints over their rated torque under gravity",
                    _ => "other failures",
                };
                format!("{count} {what}")
            }
        })
        .collect::<Vec<_>>();
    super::Verdict {
        passed: reasons.is_empty(),
        word: if failed {
            "FAIL"
        } else if undecided {
            "UNDECIDED"
        } else {
            "PASS"
        },
        reasons,
    }
}

impl Report {
    /// Findings of at least `severity`.
    pub fn findings_at_least(&self, severity: Severity) -> impl Iterator<Item = &Finding> {
        self.findings.iter().filter(move |f| f.severity >= severity)
    }
}
