//! Scores against a task's reference distribution, the CSV and the ranked text tables.
//!
//! Normalised score (the paper's): `(L_worst - L) / (L_worst - L_best)` over the reference
//! designs' task losses of the same scenario, so 0 is the worst reference design and 1 the best
//! (a design better than every reference design scores above 1; where all reference losses are
//! equal, 1 when at least as good, else 0). Percentile: the share of
//! reference designs whose loss is worse, ties counted half (mid-rank), in percent; a reference
//! design with no loss (a goal without any configuration) counts as worse than any loss.

use super::record::Record;
use std::collections::BTreeMap;
use std::fmt::Write;

/// Rows of each ranked table in `table.txt` (the CSV has every record).
pub const DEFAULT_TOP: usize = 20;

/// One scenario's reference losses, sorted.
#[derive(Debug, Clone, Default)]
pub struct Distribution {
    losses: Vec<f64>,
    without_loss: usize,
}

impl Distribution {
    fn of<'a>(records: impl Iterator<Item = &'a Record>) -> Self {
        let mut distribution = Distribution::default();
        for record in records {
            match record.task_loss {
                Some(loss) => distribution.losses.push(loss),
                None => distribution.without_loss += 1,
            }
        }
        distribution.losses.sort_by(f64::total_cmp);
        distribution
    }

    /// Designs in the distribution.
    pub fn len(&self) -> usize {
        self.losses.len() + self.without_loss
    }

    /// Whether it has no design.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The normalised score of `loss`; `None` without a loss or a reference loss.
    pub fn score(&self, loss: Option<f64>) -> Option<f64> {
        let loss = loss?;
        let (best, worst) = (*self.losses.first()?, *self.losses.last()?);
        if worst > best {
            Some((worst - loss) / (worst - best))
        } else {
            Some(if loss <= best { 1.0 } else { 0.0 })
        }
    }

    /// The percentile of `loss` (0 to 100); `None` for an empty distribution.
    pub fn percentile(&self, loss: Option<f64>) -> Option<f64> {
        if self.is_empty() {
            return None;
        }
        let (worse, ties) = match loss {
            Some(loss) => {
                let below = self.losses.partition_point(|&l| l < loss);
                let not_above = self.losses.partition_point(|&l| l <= loss);
                (self.losses.len() - not_above + self.without_loss, not_above - below)
            }
            None => (0, self.without_loss),
        };
        Some(100.0 * (worse as f64 + 0.5 * ties as f64) / self.len() as f64)
    }
}

/// Per scenario id, the reference distribution: from `reference` records when given, else from
/// the sweep's own.
pub fn distributions(records: &[Record], reference: Option<&[Record]>) -> BTreeMap<String, Distribution> {
    let source = reference.unwrap_or(records);
    let mut by_scenario: BTreeMap<String, Vec<&Record>> = BTreeMap::new();
    for record in source {
        by_scenario.entry(record.scenario.clone()).or_default().push(record);
    }
    by_scenario
        .into_iter()
        .map(|(scenario, list)| (scenario, Distribution::of(list.into_iter())))
        .collect()
}

fn fixed(value: Option<f64>, decimals: usize) -> String {
    value.map_or_else(String::new, |v| format!("{v:.decimals$}"))
}

/// The CSV: one row per record, canonical order, with its score and percentile.
pub fn csv(records: &[Record], distributions: &BTreeMap<String, Distribution>) -> String {
    let mut out = String::from(
        "design,scenario,goals,goals_solved,goals_proven_unreachable,task_solved,position_error_mm,orientation_error_deg,hardware_cost_m,task_loss,score,percentile,verdict,goals_undecided\n",
    );
    for r in records {
        let distribution = distributions.get(&r.scenario);
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            quote(&r.design),
            quote(&r.scenario),
            r.goals,
            r.goals_solved,
            r.goals_proven_unreachable,
            r.task_solved,
            fixed(r.position_error_mm, 4),
            fixed(r.orientation_error_deg, 4),
            fixed(r.hardware_cost_m, 6),
            fixed(r.task_loss, 6),
            fixed(distribution.and_then(|d| d.score(r.task_loss)), 4),
            fixed(distribution.and_then(|d| d.percentile(r.task_loss)), 2),
            r.verdict.as_deref().unwrap_or(""),
            // Last, so readers of the earlier columns by position keep working.
            r.goals_undecided,
        );
    }
    out
}

fn quote(text: &str) -> String {
    if text.contains([',', '"', '\n']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// One design's numbers over every scenario of the sweep.
#[derive(Debug, Clone)]
pub struct Overall {
    /// The design's id.
    pub design: String,
    /// Scenarios solved, of `tasks`.
    pub tasks_solved: usize,
    /// Scenarios.
    pub tasks: usize,
    /// Goals solved, of `goals`.
    pub goals_solved: usize,
    /// Goals over every scenario.
    pub goals: usize,
    /// Goals proven unreachable.
    pub goals_proven: usize,
    /// Goals neither solved nor proven unreachable.
    pub goals_undecided: usize,
    /// Mean position error over every goal (mm).
    pub position_error_mm: Option<f64>,
    /// Mean orientation error over every goal (deg).
    pub orientation_error_deg: Option<f64>,
    /// Hardware cost (m).
    pub hardware_cost_m: Option<f64>,
    /// Mean normalised score over the scenarios.
    pub score: Option<f64>,
    /// Mean percentile over the scenarios.
    pub percentile: Option<f64>,
}

/// Per design, its numbers over the scenarios, in the designs' order of first appearance.
pub fn overall(records: &[Record], distributions: &BTreeMap<String, Distribution>) -> Vec<Overall> {
    let mut order: Vec<&str> = Vec::new();
    let mut by_design: BTreeMap<&str, Vec<&Record>> = BTreeMap::new();
    for record in records {
        let list = by_design.entry(&record.design).or_default();
        if list.is_empty() {
            order.push(&record.design);
        }
        list.push(record);
    }
    order
        .into_iter()
        .map(|design| {
            let list = &by_design[design];
            let goals: usize = list.iter().map(|r| r.goals).sum();
            let weighted = |value: fn(&Record) -> Option<f64>| -> Option<f64> {
                let sum: Option<f64> = list.iter().map(|r| value(r).map(|v| v * r.goals as f64)).sum();
                sum.filter(|_| goals > 0).map(|s| s / goals as f64)
            };
            let mean = |values: Vec<Option<f64>>| -> Option<f64> {
                let n = values.len();
                values.into_iter().sum::<Option<f64>>().filter(|_| n > 0).map(|s| s / n as f64)
            };
            let distribution = |r: &Record| distributions.get(&r.scenario);
            Overall {
                design: design.to_string(),
                tasks_solved: list.iter().filter(|r| r.task_solved).count(),
                tasks: list.len(),
                goals_solved: list.iter().map(|r| r.goals_solved).sum(),
                goals,
                goals_proven: list.iter().map(|r| r.goals_proven_unreachable).sum(),
                goals_undecided: list.iter().map(|r| r.goals_undecided).sum(),
                position_error_mm: weighted(|r| r.position_error_mm),
                orientation_error_deg: weighted(|r| r.orientation_error_deg),
                hardware_cost_m: list.first().and_then(|r| r.hardware_cost_m),
                score: mean(list.iter().map(|r| distribution(r).and_then(|d| d.score(r.task_loss))).collect()),
                percentile: mean(
                    list.iter()
                        .map(|r| distribution(r).and_then(|d| d.percentile(r.task_loss)))
                        .collect(),
                ),
            }
        })
        .collect()
}

/// [`overall`] in the overall table's order: tasks solved, then goals solved, then mean score
/// (then the id, for determinism).
pub fn ranked(records: &[Record], distributions: &BTreeMap<String, Distribution>) -> Vec<Overall> {
    let mut rows = overall(records, distributions);
    rows.sort_by(|a, b| {
        b.tasks_solved
            .cmp(&a.tasks_solved)
            .then(b.goals_solved.cmp(&a.goals_solved))
            .then(
                b.score
                    .unwrap_or(f64::NEG_INFINITY)
                    .total_cmp(&a.score.unwrap_or(f64::NEG_INFINITY)),
            )
            .then_with(|| a.design.cmp(&b.design))
    });
    rows
}

/// `part` of `whole` in percent (0 for nothing of nothing).
pub(super) fn percent(part: usize, whole: usize) -> f64 {
    if whole == 0 {
        0.0
    } else {
        100.0 * part as f64 / whole as f64
    }
}

/// How the per-task tables order designs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Ranking {
    /// The paper's: by task loss alone (a design that misses a goal can rank above one that
    /// solves the task when its other goals score better); robots without one (URDF, MJCF)
    /// after, by goals solved.
    #[default]
    Loss,
    /// Designs that solve the task first, then by goals solved, then by task loss.
    SolvedFirst,
}

impl Ranking {
    /// The name `--rank` takes.
    pub fn name(self) -> &'static str {
        match self {
            Ranking::Loss => "loss",
            Ranking::SolvedFirst => "solved-first",
        }
    }

    fn words(self) -> &'static str {
        match self {
            Ranking::Loss => "by task loss (robots without one after, by goals solved)",
            Ranking::SolvedFirst => "solving designs first, then by goals solved, then by task loss",
        }
    }
}

impl std::str::FromStr for Ranking {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        [Ranking::Loss, Ranking::SolvedFirst]
            .into_iter()
            .find(|r| r.name() == text)
            .ok_or_else(|| format!("`{text}` is not a ranking; expected `loss` or `solved-first`"))
    }
}

/// Width of the design column: the longest name shown, at least [`NAME_WIDTH`].
const NAME_WIDTH: usize = 32;

/// The ranked tables: per scenario (by `ranking`) and over all scenarios (`overall`, as
/// [`ranked`] orders it), `top` rows each. Full sweeps show each pair's verdict.
pub fn text(
    records: &[Record],
    distributions: &BTreeMap<String, Distribution>,
    overall: &[Overall],
    reference: &str,
    top: usize,
    ranking: Ranking,
) -> String {
    let mut out = String::new();
    let designs = records
        .iter()
        .map(|r| r.design.as_str())
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    let _ = writeln!(
        out,
        "{} records: {designs} designs; scores and percentiles against {reference}",
        records.len()
    );
    let mut scenarios: Vec<&str> = Vec::new();
    for record in records {
        if !scenarios.contains(&record.scenario.as_str()) {
            scenarios.push(&record.scenario);
        }
    }
    let width = |names: &mut dyn Iterator<Item = &str>| names.map(|n| n.chars().count()).max().unwrap_or(0).max(NAME_WIDTH);
    for scenario in &scenarios {
        let mut rows: Vec<&Record> = records.iter().filter(|r| r.scenario == *scenario).collect();
        let loss = |r: &Record| r.task_loss.unwrap_or(f64::INFINITY);
        rows.sort_by(|a, b| {
            let solved = b.task_solved.cmp(&a.task_solved).then(b.goals_solved.cmp(&a.goals_solved));
            let first = match ranking {
                Ranking::Loss => std::cmp::Ordering::Equal,
                Ranking::SolvedFirst => solved,
            };
            // Robots without a task loss (URDF and MJCF input) tie on it: goals solved order them.
            first
                .then(loss(a).total_cmp(&loss(b)))
                .then(solved)
                .then_with(|| a.design.cmp(&b.design))
        });
        rows.truncate(top);
        let distribution = distributions.get(*scenario);
        let all = records.iter().filter(|r| r.scenario == *scenario);
        let (count, solved) = all.fold((0, 0), |(n, s), r| (n + 1, s + usize::from(r.task_solved)));
        let verdicts = rows.iter().any(|r| r.verdict.is_some());
        let name = width(&mut rows.iter().map(|r| r.design.as_str()));
        let _ = writeln!(
            out,
            "\ntask {scenario}: {count} designs, {solved} solve it; best {} {}",
            rows.len(),
            ranking.words()
        );
        let verdict_head = if verdicts { format!(" {:<9}", "verdict") } else { String::new() };
        let _ = writeln!(
            out,
            "{:>5}  {:<name$} {:>6}{verdict_head} {:>8} {:>9} {:>9} {:>8} {:>11} {:>7} {:>6}",
            "rank", "design", "solved", "goals", "pos mm", "ori deg", "cost m", "task loss", "score", "pct"
        );
        for (rank, r) in rows.iter().enumerate() {
            let verdict = if verdicts {
                format!(" {:<9}", r.verdict.as_deref().unwrap_or("-"))
            } else {
                String::new()
            };
            let _ = writeln!(
                out,
                "{:>5}  {:<name$} {:>6}{verdict} {:>8} {:>9} {:>9} {:>8} {:>11} {:>7} {:>6}",
                rank + 1,
                r.design,
                if r.task_solved { "yes" } else { "no" },
                format!("{}/{}", r.goals_solved, r.goals),
                fixed(r.position_error_mm, 2),
                fixed(r.orientation_error_deg, 2),
                fixed(r.hardware_cost_m, 3),
                fixed(r.task_loss, 4),
                fixed(distribution.and_then(|d| d.score(r.task_loss)), 4),
                fixed(distribution.and_then(|d| d.percentile(r.task_loss)), 1),
            );
        }
    }
    let rows = &overall[..top.min(overall.len())];
    let name = width(&mut rows.iter().map(|o| o.design.as_str()));
    let _ = writeln!(
        out,
        "\noverall: {} tasks; best {} by tasks solved, then goals solved, then mean score",
        scenarios.len(),
        rows.len()
    );
    let _ = writeln!(
        out,
        "{:>5}  {:<name$} {:>13} {:>13} {:>8} {:>9} {:>9} {:>9} {:>8} {:>7} {:>6}",
        "rank", "design", "tasks solved", "goals solved", "proven", "undecided", "pos mm", "ori deg", "cost m", "score", "pct"
    );
    for (rank, o) in rows.iter().enumerate() {
        let _ = writeln!(
            out,
            "{:>5}  {:<name$} {:>13} {:>13} {:>8} {:>9} {:>9} {:>9} {:>8} {:>7} {:>6}",
            rank + 1,
            o.design,
            format!("{}/{} {:.0}%", o.tasks_solved, o.tasks, percent(o.tasks_solved, o.tasks)),
            format!("{:.2}%", percent(o.goals_solved, o.goals)),
            o.goals_proven,
            o.goals_undecided,
            fixed(o.position_error_mm, 2),
            fixed(o.orientation_error_deg, 2),
            fixed(o.hardware_cost_m, 3),
            fixed(o.score, 4),
            fixed(o.percentile, 1),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(design: &str, loss: Option<f64>) -> Record {
        Record {
            design: design.into(),
            scenario: "t".into(),
            goals: 8,
            goals_solved: 8,
            goals_proven_unreachable: 0,
            goals_undecided: 0,
            task_solved: true,
            position_error_mm: Some(0.0),
            orientation_error_deg: Some(0.0),
            hardware_cost_m: Some(1.0),
            task_loss: loss,
            verdict: None,
        }
    }

    #[test]
    fn robots_without_a_task_loss_rank_after_designs_by_goals_solved() {
        let solving = |design: &str, solved: usize| Record {
            goals_solved: solved,
            task_solved: solved == 8,
            ..record(design, None)
        };
        let records = [
            solving("a-robot", 4),
            record("dh-arm", Some(2.0)),
            solving("b-robot", 7),
            solving("c-robot", 8),
        ];
        let distributions = distributions(&records, None);
        let overall = ranked(&records, &distributions);
        let table = text(&records, &distributions, &overall, "the sweep", 10, Ranking::Loss);
        let order: Vec<usize> = ["dh-arm", "c-robot", "b-robot", "a-robot"]
            .iter()
            .map(|name| table.find(&format!(" {name} ")).unwrap_or(usize::MAX))
            .collect();
        assert!(order.windows(2).all(|pair| pair[0] < pair[1]), "{table}");
    }

    #[test]
    fn scores_are_zero_at_the_worst_and_one_at_the_best_reference_design() {
        let records = [
            record("a", Some(3.0)),
            record("b", Some(1.0)),
            record("c", Some(2.0)),
            record("d", None),
        ];
        let distributions = distributions(&records, None);
        let d = &distributions["t"];
        assert_eq!(d.score(Some(1.0)), Some(1.0));
        assert_eq!(d.score(Some(3.0)), Some(0.0));
        assert_eq!(d.score(Some(2.0)), Some(0.5));
        assert_eq!(d.score(None), None);
        // Of four, the best beats three (the design without a loss among them).
        assert_eq!(d.percentile(Some(1.0)), Some(100.0 * 3.5 / 4.0));
        assert_eq!(d.percentile(Some(3.0)), Some(100.0 * 1.5 / 4.0));
        assert_eq!(d.percentile(None), Some(100.0 * 0.5 / 4.0));
    }

    #[test]
    fn solved_first_puts_a_solving_design_above_a_better_loss_and_columns_fit_long_names() {
        let long = "designs/a-design-whose-file-name-is-far-longer-than-the-column.json";
        let mut missing = record(long, Some(1.0));
        (missing.task_solved, missing.goals_solved, missing.verdict) = (false, 7, Some("FAIL".into()));
        let mut solving = record("b", Some(2.0));
        solving.verdict = Some("PASS".into());
        let records = [missing, solving];
        let distributions = distributions(&records, None);
        let rank = |ranking| {
            let table = text(&records, &distributions, &ranked(&records, &distributions), "x", 5, ranking);
            let rows: Vec<String> = table
                .lines()
                .filter(|l| l.starts_with("    1 ") || l.starts_with("    2 "))
                .map(String::from)
                .collect();
            (table, rows)
        };
        let (table, rows) = rank(Ranking::Loss);
        assert!(rows[0].contains(long) && rows[1].contains(" b "), "{table}");
        assert!(table.contains("verdict"), "{table}");
        assert!(rows[0].contains(" FAIL ") && rows[1].contains(" PASS "), "{table}");
        // Every row of the per-task table has its columns at the same places.
        let ends: Vec<usize> = table.lines().skip(3).take(3).map(|l| l.len()).collect();
        assert!(ends.windows(2).all(|w| w[0] == w[1]), "{table}");
        let (table, rows) = rank(Ranking::SolvedFirst);
        assert!(rows[0].contains(" b ") && rows[1].contains(long), "{table}");
        assert!(table.contains("solving designs first"), "{table}");
        assert_eq!("solved-first".parse::<Ranking>(), Ok(Ranking::SolvedFirst));
        assert!("best".parse::<Ranking>().is_err());
    }
}
