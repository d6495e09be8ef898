//! The paper's Table 1 (industrial manipulators on its 36 cluttered tasks) beside ours.

use super::record::Record;
use super::table::{self, percent};
use super::{SweepMode, SweepOptions};
use std::fmt::Write;
use std::path::PathBuf;

/// The scenarios of Table 1 when none are given: the paper's 36 cluttered tasks.
pub const TABLE_1_SCENARIOS: &str = "scenarios/cluttered";
/// The designs of Table 1: the paper's industrial presets.
pub const TABLE_1_DESIGNS: &str = "catalog:table1";

/// The sweep Table 1 is made of: reach-only, IK seeded by `seed`, written to `out` when given.
pub fn table_1_options(seed: u64, out: Option<PathBuf>, force: bool) -> SweepOptions {
    SweepOptions {
        mode: SweepMode::ReachOnly {
            ik: crate::ik::IkOptions {
                seed,
                ..Default::default()
            },
        },
        out,
        force,
        shard: None,
        reference: None,
        top: table::DEFAULT_TOP,
        ranking: table::Ranking::Loss,
        stop: None,
    }
}

/// One row of the paper's Table 1: solved tasks (%), solved goals (%), mean error (mm).
struct PaperRow {
    robot: &'static str,
    design: Option<&'static str>,
    tasks_percent: f64,
    goals_percent: f64,
    error_mm: f64,
}

/// "A Design Co-Pilot for Task-Tailored Manipulators", Table 1 (`tab:dh_comparison`).
const PAPER_TABLE_1: [PaperRow; 4] = [
    PaperRow {
        robot: "Ours",
        design: None,
        tasks_percent: 50.0,
        goals_percent: 86.56,
        error_mm: 5.20,
    },
    PaperRow {
        robot: "UR15",
        design: Some("preset/UR15"),
        tasks_percent: 36.0,
        goals_percent: 82.29,
        error_mm: 7.27,
    },
    PaperRow {
        robot: "UR20",
        design: Some("preset/UR20"),
        tasks_percent: 33.0,
        goals_percent: 77.43,
        error_mm: 7.62,
    },
    PaperRow {
        robot: "ABB2600",
        design: Some("preset/ABB-IRB-2600"),
        tasks_percent: 28.0,
        goals_percent: 75.70,
        error_mm: 20.50,
    },
];

/// The paper's layout, its numbers beside ours; `records` are a sweep of the table's presets.
pub fn table_1(records: &[Record], scenarios: usize) -> String {
    let overall = table::overall(records, &table::distributions(records, None));
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Table 1 of \"A Design Co-Pilot for Task-Tailored Manipulators\" (industrial robots, joint limits ignored), beside ours"
    );
    let _ = writeln!(
        out,
        "ours: {scenarios} tasks, this project's regeneration of the paper's cluttered tasks (its own draws are not published): compare trends, not digits"
    );
    let _ = writeln!(out, "ours: reach-only (a collision-free IK solution within 1 mm and 1 deg per goal), error = mean position error of IK's best configuration over every goal\n");
    let _ = writeln!(
        out,
        "{:<10} {:>21} {:>21} {:>23}",
        "", "solved tasks", "solved goals", "error (mean)"
    );
    let _ = writeln!(
        out,
        "{:<10} {:>10} {:>10} {:>10} {:>10} {:>11} {:>11}",
        "robot", "ours", "paper", "ours", "paper", "ours", "paper"
    );
    for row in &PAPER_TABLE_1 {
        let ours = row.design.and_then(|id| overall.iter().find(|o| o.design == id));
        let (tasks, goals, error) = match ours {
            Some(o) => (
                format!("{:.0} %", percent(o.tasks_solved, o.tasks)),
                format!("{:.2} %", percent(o.goals_solved, o.goals)),
                o.position_error_mm.map_or_else(|| "n/a".into(), |e| format!("{e:.2} mm")),
            ),
            None => ("-".into(), "-".into(), "-".into()),
        };
        let _ = writeln!(
            out,
            "{:<10} {:>10} {:>10} {:>10} {:>10} {:>11} {:>11}",
            row.robot,
            tasks,
            format!("{:.0} %", row.tasks_percent),
            goals,
            format!("{:.2} %", row.goals_percent),
            error,
            format!("{:.2} mm", row.error_mm),
        );
    }
    let _ = writeln!(out, "\n(\"Ours\" in the paper is its generated modular designs, best of eight per task; run `validate-design sweep catalog:modular6 ...` for our brute force.)");
    out
}
