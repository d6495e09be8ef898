//! The readable summary of a report, as `validate-design` prints it.

use super::{FindingKind, Report, Severity};
use std::fmt::Write;

/// Context findings of one kind printed before the rest are only counted.
const INFO_PER_KIND: usize = 3;

fn mm(value: Option<f64>) -> String {
    value.map_or_else(|| "-".into(), |v| format!("{:.1}", v * 1e3))
}

/// The lines above the goal table: the kinematics check, input warnings, the design and the
/// scenario, the planner, the criteria.
fn head(report: &Report) -> String {
    let mut out = String::new();
    if let Some(check) = &report.inputs.kinematics_check {
        let _ = writeln!(out, "{}", check.line());
    }
    for warning in &report.inputs.warnings {
        let _ = writeln!(out, "input {warning}");
    }
    let design = &report.design;
    let _ = writeln!(
        out,
        "design {} ({}, {} joints{}) on scenario {} ({} goals, {} obstacles{})",
        design.name,
        design.mode,
        design.dof,
        design
            .hardware_cost_m
            .map(|c| format!(", hardware cost {c:.2} m"))
            .unwrap_or_default(),
        report.scenario.name,
        report.scenario.goals,
        report.scenario.obstacles,
        if report.scenario.floor { ", floor" } else { "" }
    );
    let c = &report.criteria;
    if c.mode == "reach_only" {
        let _ = writeln!(
            out,
            "reach-only: the paper's static metric (a collision-free IK solution per goal from {} starts, seed {}); no trajectory, no engines",
            c.ik_seeds, c.seed
        );
    } else if let Some(planner) = &c.planner {
        let budget = if planner.kind.samples() {
            format!(", budget {} samples per goal", planner.budget)
        } else {
            String::new()
        };
        let _ = writeln!(out, "planner: {}{budget}, seed {}", planner.kind.name(), planner.seed);
    }
    let _ = writeln!(
        out,
        "criteria: reached < {} mm and < {} deg, collision-free with margin {} mm in exact geometry ({} pairs excluded{}), held within {} mm / {} deg, engines: {}",
        c.position_m * 1e3,
        c.orientation_deg,
        c.collision_margin_m * 1e3,
        c.excluded_pairs.len(),
        match c.excluded_shapes.len() {
            0 => String::new(),
            n => format!(", and {n} shape {} overlapping by construction", if n == 1 { "pair" } else { "pairs" }),
        },
        c.hold_position_m * 1e3,
        c.hold_orientation_deg,
        if c.engines.is_empty() { "none".to_string() } else { c.engines.join(", ") }
    );

    out
}

/// The lines between the goal table and the findings: the trajectory, the engines, the replay's
/// agreement, the static load and the paper loss.
fn lower_block(report: &Report) -> String {
    let mut out = String::new();
    if let Some(t) = &report.trajectory {
        trajectory_lines(&mut out, t);
    }

    for engine in &report.engines {
        // An engine whose effort is its control law's estimate (rapier: ten times MuJoCo's on the
        // same joint) has no number here; the JSON report keeps it, marked as an estimate.
        let effort = if crate::engine::find(engine.engine).is_some_and(|e| e.effort().estimate) {
            ", effort not measured (a control-law estimate, in the JSON report only)".to_string()
        } else {
            let peaks = engine
                .peak_effort
                .iter()
                .zip(&engine.rated_effort)
                .map(|(p, r)| r.map_or_else(|| format!("{p:.0}"), |r| format!("{p:.0}/{r:.0}")))
                .collect::<Vec<_>>()
                .join(" ");
            format!(", peak effort {peaks}")
        };
        let _ = writeln!(
            out,
            "{}: {} goals held (worst {:.3} mm, {:.3} deg), {} contacts, {} in the kinematic replay{effort}",
            engine.engine,
            engine.goals_held,
            engine.worst_hold_position_m * 1e3,
            engine.worst_hold_orientation_deg,
            engine.contacts.len(),
            engine.replay_contacts.len(),
        );
    }
    if !report.engines.is_empty() {
        let segments = report.trajectory.as_ref().map_or(0, |t| t.replayed_segments);
        let agreement: Vec<String> = report
            .engines
            .iter()
            .map(|engine| {
                let disagreements = report
                    .findings
                    .iter()
                    .filter(|f| f.engine == Some(engine.engine))
                    .filter(|f| matches!(f.kind, FindingKind::ReplayContactNotPredicted | FindingKind::ReplayContactMissed))
                    .count();
                format!("{} {} of {segments}", engine.engine, segments - disagreements.min(segments))
            })
            .collect();
        let _ = writeln!(out, "replay agrees with the certified check on segments: {}", agreement.join(", "));
    }
    if let Some(load) = &report.static_load {
        let _ = writeln!(
            out,
            "static load (N m, peak gravity torque / rating): {}",
            load.joints
                .iter()
                .map(|j| j.rated.map_or_else(
                    || format!("{:.1}", j.peak_torque),
                    |r| format!("{:.1}/{r:.0}{}", j.peak_torque, if j.over { "!" } else { "" })
                ))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    match &report.paper_loss {
        Some(loss) => {
            if let Some(total) = loss.total {
                let chosen = loss
                    .at_chosen
                    .map_or_else(String::new, |c| format!(" ({c:.4} at the chosen configurations)"));
                let _ = writeln!(out, "paper loss {total:.4}{chosen}");
            }
        }
        None => {
            let _ = writeln!(
                out,
                "paper loss: not for a robot file (the paper's capsule model and hardware cost are defined for designs)"
            );
        }
    }

    out
}

/// The report's summary as text without the goal table and the findings (the HTML page shows
/// those as tables of its own): what the text report says above and below the goal table.
pub fn summary(report: &Report) -> String {
    format!("{}{}", head(report), lower_block(report))
}

/// The report as text: one line per goal, the trajectory, the engines, the static load, the
/// findings that matter and the verdict line.
pub fn render(report: &Report) -> String {
    let mut out = head(report);
    let _ = writeln!(
        out,
        "\ngoal                      outcome      pos mm  ori deg  obst mm  self mm  floor mm  capsule mm  held by         closest pair"
    );
    for goal in &report.goals {
        let status = goal.outcome;
        let _ = writeln!(
            out,
            "{:<3} {:<21} {:<11} {:>6}  {:>7}  {:>7}  {:>7}  {:>8}  {:>10}  {:<14}  {}",
            goal.index,
            truncate(&goal.name, 21),
            status,
            goal.position_error_m.map_or_else(|| "-".into(), |v| format!("{:.2}", v * 1e3)),
            goal.orientation_error_deg.map_or_else(|| "-".into(), |v| format!("{v:.2}")),
            mm(goal.clearance_by_kind.and_then(|c| c.obstacles_m)),
            mm(goal.clearance_by_kind.and_then(|c| c.self_m)),
            mm(goal.clearance_by_kind.and_then(|c| c.floor_m)),
            mm(goal.approximate_clearance_m),
            if goal.held_by.is_empty() {
                "-".to_string()
            } else {
                goal.held_by.join(", ")
            },
            goal.clearance_pair.as_deref().unwrap_or("-")
        );
    }

    out.push_str(&lower_block(report));
    if !report.findings.is_empty() {
        let _ = writeln!(out, "\nfindings:");
        // Every failure and warning; context (info) up to three of a kind, the rest counted.
        let mut shown: std::collections::BTreeMap<FindingKind, usize> = std::collections::BTreeMap::new();
        for f in &report.findings {
            let tag = match f.severity {
                Severity::Fail => "FAIL",
                Severity::Undecided => "UNDECIDED",
                Severity::Warn => "warn",
                Severity::Info => "info",
            };
            let count = shown.entry(f.kind).or_default();
            *count += 1;
            if f.severity > Severity::Info || *count <= INFO_PER_KIND {
                let _ = writeln!(out, "  {tag} {}", f.message);
            }
        }
        for (kind, count) in shown {
            let info = report
                .findings
                .iter()
                .filter(|f| f.kind == kind && f.severity == Severity::Info)
                .count();
            if info > INFO_PER_KIND && count == info {
                let name = serde_json::to_value(kind)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_string))
                    .unwrap_or_default();
                let _ = writeln!(
                    out,
                    "  info ... and {} more `{name}` findings (all in the JSON report)",
                    info - INFO_PER_KIND
                );
            }
        }
    }
    let _ = writeln!(out, "\n{}", verdict_line(&report.verdict));
    out
}

/// The trajectory's certified clearance in mm, by kind of pair where known.
fn certified_clearance(t: &super::TrajectoryReport) -> String {
    if t.certified_clearance_m.is_some_and(f64::is_infinite) {
        // No pair was measured: a robot without collision geometry.
        return "none measured (nothing to collide)".into();
    }
    let kinds = t.certified_by_kind.map_or(String::new(), |k| {
        let kinds = [("obstacles", k.obstacles_m), ("self", k.self_m), ("floor", k.floor_m)];
        let listed: Vec<String> = kinds
            .iter()
            .filter(|(_, m)| m.is_some())
            .map(|(kind, m)| format!("{kind} {}", mm(*m)))
            .collect();
        format!(" ({})", listed.join(", "))
    });
    format!("{} mm{kinds}", mm(t.certified_clearance_m))
}

fn trajectory_lines(out: &mut String, t: &super::TrajectoryReport) {
    let goals = t.reached + t.unreachable + t.undecided + t.no_path;
    let detours = t.segments.iter().filter(|s| s.edges > 1).count();
    let _ = writeln!(
        out,
        "\ntrajectory: {} of {goals} goals on certified paths ({} edges, {detours} detours), {} unreachable, {} undecided, {} without a path; certified clearance {}; {:.2} rad in joint space ({:.2} before shortcutting), tool path {:.2} m, {:.1} s",
        t.reached,
        t.edges,
        t.unreachable,
        t.undecided,
        t.no_path,
        certified_clearance(t),
        t.joint_length,
        t.joint_length_before_shortcut,
        t.tool_path_m,
        t.duration_s
    );
    if let Some(closest) = t
        .segments
        .iter()
        .filter(|s| s.planned)
        .filter_map(|s| s.closest.as_ref().map(|c| (s.goal, c)))
        .min_by(|a, b| a.1.distance_m.total_cmp(&b.1.distance_m))
    {
        let _ = writeln!(
            out,
            "  closest approach {:.1} mm ({} and {}) on the path to goal {}",
            closest.1.distance_m * 1e3,
            closest.1.a,
            closest.1.b,
            closest.0
        );
    }
    for segment in t.segments.iter().filter(|s| s.outcome == "no_path") {
        if let Some(stop) = &segment.stop {
            let _ = writeln!(
                out,
                "  goal {} without a path: the closest attempt stops where {} and {} touch ({:.1} mm)",
                segment.goal,
                stop.a,
                stop.b,
                stop.distance_m * 1e3
            );
        }
    }
}

fn truncate(text: &str, width: usize) -> String {
    if text.chars().count() <= width {
        text.to_string()
    } else {
        text.chars().take(width - 1).chain(std::iter::once('~')).collect()
    }
}

/// The verdict as one line: `verdict: PASS`, or `verdict: FAIL: ` (`UNDECIDED: `) and the
/// reasons.
pub fn verdict_line(verdict: &super::Verdict) -> String {
    if verdict.passed {
        "verdict: PASS".to_string()
    } else {
        format!("verdict: {}: {}", verdict.word, verdict.reasons.join("; "))
    }
}
