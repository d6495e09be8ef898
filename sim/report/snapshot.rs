//! Reports as golden snapshots a reviewer reads in a minute: the verdict and the outcome counts
//! first, then the whole report with every number rounded to what is physically meaningful and
//! the internal counters left out (they move with every optimisation and say nothing about the
//! design). The same text backs `tests/golden.rs` and `validate-design snapshot`.

use super::Report;
use serde_json::Value;

/// Keys left out of snapshots: work counters of the exact checks, not properties of the design.
const REDACTED: [&str; 1] = ["queries"];

/// Numbers without a unit in their name smaller than this are rounding: none of a report's is
/// meaningful there (losses, ratios and counts).
const NOISE: f64 = 1e-9;

/// Joint configurations (radians), by key.
const CONFIGURATIONS: [&str; 5] = ["q", "chosen", "home", "from", "to"];

/// Rounds every number of a report value by the unit its field name ends in: lengths (`_m`) to
/// 0.1 mm, degrees to 0.01, radians and joint configurations to 1e-4 rad, times (`_s`) to 1 ms,
/// torques and efforts to 0.01 N m, cross-check disagreements to 1e-9; everything else to 4
/// significant digits, and to 0 below 1e-9 (`NOISE`). Negative zero becomes zero; redacted
/// keys are removed.
pub fn round_value(value: &mut Value, key: &str) {
    match value {
        Value::Number(number) if number.is_f64() => {
            let x = number.as_f64().unwrap_or(f64::NAN);
            let step = if key.ends_with("disagreement") {
                Some(1e-9)
            } else if key.ends_with("_m") {
                Some(1e-4)
            } else if key.ends_with("_deg") {
                Some(1e-2)
            } else if key.ends_with("_rad") || CONFIGURATIONS.contains(&key) {
                Some(1e-4)
            } else if key.ends_with("_s") {
                Some(1e-3)
            } else if key.contains("effort") || key.contains("torque") || key.ends_with("_nm") {
                Some(1e-2)
            } else {
                None
            };
            let r = match step {
                Some(step) => (x / step).round() * step,
                None if x == 0.0 || !x.is_finite() => x,
                // Rounding, not a quantity: the loss's distance term where every goal is reached
                // exactly. Its digits differ with the last bits of the solver.
                None if x.abs() < NOISE => 0.0,
                None => {
                    let scale = 10f64.powi(3 - x.abs().log10().floor() as i32);
                    (x * scale).round() / scale
                }
            };
            let r = if r == 0.0 { 0.0 } else { r };
            // The shortest decimal of the rounded value, read back so the text is that decimal.
            let text = match step {
                Some(step) => format!("{:.*}", (-step.log10()).round().max(0.0) as usize, r),
                None => format!("{r}"),
            };
            *value = serde_json::from_str(&text).unwrap_or(Value::Null);
        }
        Value::Array(items) => items.iter_mut().for_each(|item| round_value(item, key)),
        Value::Object(map) => {
            map.retain(|k, _| !REDACTED.contains(&k.as_str()));
            map.iter_mut().for_each(|(k, v)| round_value(v, k));
        }
        _ => {}
    }
}

/// One line describing the run a snapshot pins: design, scenario, and the settings.
pub fn description(report: &Report) -> String {
    let c = &report.criteria;
    let planner = c
        .planner
        .as_ref()
        .map(|p| {
            let kind = serde_json::to_value(p.kind).ok();
            let kind = kind.as_ref().and_then(Value::as_str).unwrap_or("?");
            format!(", planner {kind} (budget {}, seed {})", p.budget, p.seed)
        })
        .unwrap_or_default();
    format!(
        "design {} ({}, {} joints) on scenario {} ({} goals, {} obstacles); mode {}, IK seed {} x {} starts{planner}, engines: {}",
        report.design.name,
        report.design.mode,
        report.design.dof,
        report.scenario.name,
        report.scenario.goals,
        report.scenario.obstacles,
        c.mode,
        c.seed,
        c.ik_seeds,
        if c.engines.is_empty() {
            "none".to_string()
        } else {
            c.engines.join(", ")
        },
    )
}

/// The snapshot text of a report: a summary (verdict, goal outcomes, engines, findings by
/// severity), then the rounded report as YAML.
///
/// # Errors
/// serde_json's message when the report does not serialise (a bug).
pub fn snapshot_text(report: &Report) -> Result<String, String> {
    let mut value = serde_json::to_value(report).map_err(|e| e.to_string())?;
    round_value(&mut value, "");
    let mut outcomes = std::collections::BTreeMap::<String, usize>::new();
    for goal in value["goals"].as_array().into_iter().flatten() {
        let outcome = goal["outcome"].as_str().unwrap_or("unknown").to_string();
        *outcomes.entry(outcome).or_default() += 1;
    }
    let mut severities = std::collections::BTreeMap::<String, usize>::new();
    for finding in value["findings"].as_array().into_iter().flatten() {
        let severity = finding["severity"].as_str().unwrap_or("unknown").to_string();
        *severities.entry(severity).or_default() += 1;
    }
    let engines: Vec<String> = value["engines"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|e| {
            format!(
                "{}: {} goals held, {} contacts",
                e["engine"].as_str().unwrap_or("?"),
                e["goals_held"],
                e["contacts"].as_array().map_or(0, Vec::len)
            )
        })
        .collect();
    let counts =
        |map: &std::collections::BTreeMap<String, usize>| map.iter().map(|(k, n)| format!("{k} {n}")).collect::<Vec<_>>().join(", ");
    let mut out = String::new();
    out.push_str("summary:\n");
    out.push_str(&format!(
        "  verdict: {}\n",
        quoted(super::verdict_line(&report.verdict).trim_start_matches("verdict: "))
    ));
    out.push_str(&format!(
        "  goals: {}\n",
        quoted(&format!("{} ({})", report.goals.len(), counts(&outcomes)))
    ));
    out.push_str(&format!(
        "  engines: {}\n",
        quoted(&if engines.is_empty() { "none".into() } else { engines.join("; ") })
    ));
    out.push_str(&format!("  findings: {}\n", quoted(&counts(&severities))));
    out.push_str("report:\n");
    write_yaml(&value, 1, &mut out);
    Ok(out)
}

/// A string as a YAML double-quoted scalar (JSON's escaping is valid YAML).
fn quoted(text: &str) -> String {
    serde_json::to_string(text).unwrap_or_else(|_| "\"\"".into())
}

fn scalar(value: &Value) -> Option<String> {
    Some(match value {
        Value::Null => "~".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => quoted(s),
        Value::Array(a) if a.is_empty() => "[]".into(),
        Value::Object(o) if o.is_empty() => "{}".into(),
        _ => return None,
    })
}

/// Block-style YAML of a value whose containers are not empty, at `depth` (two spaces each).
fn write_yaml(value: &Value, depth: usize, out: &mut String) {
    let indent = "  ".repeat(depth);
    match value {
        Value::Object(map) => {
            for (key, item) in map {
                match scalar(item) {
                    Some(text) => out.push_str(&format!("{indent}{key}: {text}\n")),
                    None => {
                        out.push_str(&format!("{indent}{key}:\n"));
                        write_yaml(item, depth + 1, out);
                    }
                }
            }
        }
        Value::Array(items) => {
            for item in items {
                match scalar(item) {
                    Some(text) => out.push_str(&format!("{indent}- {text}\n")),
                    None => {
                        // The item's first line goes after the dash, the rest one level deeper.
                        let mut inner = String::new();
                        write_yaml(item, depth + 1, &mut inner);
                        let trimmed = inner.trim_start_matches(' ');
                        out.push_str(&format!("{indent}- {trimmed}"));
                    }
                }
            }
        }
        other => out.push_str(&format!("{indent}{}\n", scalar(other).unwrap_or_default())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_keeps_what_is_physically_meaningful() {
        let mut value = serde_json::json!({
            "distance_m": 0.123456789, "angle_deg": -0.0012, "orientation_rad": 0.000123456,
            "q": [1.23456789, -0.00001], "time_s": 1.23456, "loss": 32.98623, "count": 7,
            "peak_effort": [1e-15, 146.789], "queries": 12,
        });
        round_value(&mut value, "");
        assert_eq!(
            value,
            serde_json::json!({
                "distance_m": 0.1235, "angle_deg": 0.0, "orientation_rad": 0.0001,
                "q": [1.2346, 0.0], "time_s": 1.235, "loss": 32.99, "count": 7,
                "peak_effort": [0.0, 146.79],
            })
        );
    }

    #[test]
    fn yaml_nests_maps_in_lists() {
        let value = serde_json::json!({"a": [{"b": 1, "c": [2, 3]}, 4], "d": {}, "e": "x: y"});
        let mut out = String::new();
        write_yaml(&value, 0, &mut out);
        assert_eq!(out, "a:\n  - b: 1\n    c:\n      - 2\n      - 3\n  - 4\nd: {}\ne: \"x: y\"\n");
    }
}
