//! One self-contained HTML page: verdict, per-goal table, findings, an interactive 3D view
//! (three.js, vendored and inlined) with a timeline that plays the replayed segments, and the
//! clearance plot linked to the timeline. Geometry is the same triangles the SVG views draw,
//! embedded as base64 little-endian arrays; the page's forward kinematics is checked against
//! ours at a few clocks when it loads, and the page reports its state in `document.title`
//! (`ok <ms> ms` or `error: ...`) for a headless browser to read.

use super::scene::{surface, Surface};
use crate::frames::{wxyz, xyz};
use crate::model::{JointKind, Model};
use crate::report::{Report, Validation};
use crate::xml::escape_text as escape;
use nalgebra::Isometry3;
use serde_json::{json, Value};

const THREE: &str = include_str!("vendor/three.min.js");
const SCRIPT: &str = include_str!("page.js");
const STYLE: &str = include_str!("page.css");
/// Clocks per segment at which the page's forward kinematics is compared with ours.
const CHECKS: usize = 3;

/// The page as HTML text.
pub fn page(validation: &Validation, report: &Report) -> String {
    let data = data(validation, report);
    // `</` inside a script would end it; `<\/` is the same JSON string.
    let data = data.to_string().replace("</", "<\\/");
    let plot = validation
        .trajectory
        .as_ref()
        .map(|_| {
            let names: Vec<String> = validation.scenario.goals.iter().map(|g| g.name.clone()).collect();
            super::plot::clearance(
                &validation.replayed,
                &names,
                validation.settings.margin_m,
                "clearance along the trajectory",
            )
        })
        .unwrap_or_default();
    let title = format!("{} on {}", validation.model.name, validation.scenario.name);
    let mut out = String::with_capacity(THREE.len() + data.len() + 65_536);
    out.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    out.push_str(&format!(
        "<title>loading: {}</title>\n<style>\n{STYLE}</style>\n</head>\n<body>\n",
        escape(&title)
    ));
    out.push_str(&format!(
        "<header><h1>{}</h1><p class=\"{}\">{}</p>{}</header>\n",
        escape(&title),
        report.verdict.word.to_lowercase(),
        escape(&crate::report::verdict_line(&report.verdict)),
        reasons(report)
    ));
    out.push_str(
        "<section id=\"viewer\"><canvas id=\"three\"></canvas><div id=\"status\"></div></section>\n\
         <section id=\"timeline\"><button id=\"play\" type=\"button\">play</button>\
         <input id=\"clock\" type=\"range\" min=\"0\" max=\"1\" step=\"0.001\" value=\"0\"><span id=\"clock-label\"></span></section>\n",
    );
    out.push_str(&format!("<section id=\"plot\">{plot}</section>\n"));
    out.push_str(&goal_table(report));
    out.push_str(&format!(
        "<section id=\"summary\"><h2>Summary</h2><pre>{}</pre></section>\n",
        escape(&crate::report::summary(report))
    ));
    out.push_str(&findings(report));
    out.push_str("<footer>3D view: three.js r187 (MIT licence, vendored). Drag to orbit, scroll to zoom; click a goal row or the plot to go there.</footer>\n");
    out.push_str(&format!("<script id=\"data\" type=\"application/json\">{data}</script>\n"));
    out.push_str("<script>\n");
    out.push_str(THREE);
    out.push_str("\n</script>\n<script>\n");
    out.push_str(SCRIPT);
    out.push_str("</script>\n</body>\n</html>\n");
    out
}

fn reasons(report: &Report) -> String {
    if report.verdict.reasons.is_empty() {
        return String::new();
    }
    let items: String = report.verdict.reasons.iter().map(|r| format!("<li>{}</li>", escape(r))).collect();
    format!("<ul class=\"reasons\">{items}</ul>")
}

fn goal_table(report: &Report) -> String {
    let mut out = String::from(
        "<section id=\"goals\"><h2>Goals</h2><table><thead><tr><th>#</th><th>goal</th><th>tolerance</th><th>outcome</th>\
         <th>position error</th><th>orientation error</th><th>obstacles</th><th>self</th><th>floor</th><th>closest pair</th><th>held by</th></tr></thead><tbody>\n",
    );
    for goal in &report.goals {
        let number = |v: Option<f64>, scale: f64, digits: usize, unit: &str| {
            v.map(|v| format!("{:.digits$} {unit}", v * scale)).unwrap_or_else(|| "-".into())
        };
        out.push_str(&format!(
            "<tr data-goal=\"{}\" class=\"{}\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            goal.index,
            goal.outcome,
            goal.index,
            escape(&goal.name),
            goal.tolerance.name(),
            goal.outcome,
            number(goal.position_error_m, 1000.0, 3, "mm"),
            number(goal.orientation_error_deg, 1.0, 3, "deg"),
            number(goal.clearance_by_kind.and_then(|c| c.obstacles_m), 1000.0, 1, "mm"),
            number(goal.clearance_by_kind.and_then(|c| c.self_m), 1000.0, 1, "mm"),
            number(goal.clearance_by_kind.and_then(|c| c.floor_m), 1000.0, 1, "mm"),
            escape(goal.clearance_pair.as_deref().unwrap_or("-")),
            escape(&goal.held_by.join(", "))
        ));
    }
    out.push_str("</tbody></table></section>\n");
    out
}

fn findings(report: &Report) -> String {
    let mut out = String::from("<section id=\"findings\"><h2>Findings</h2><ul>\n");
    for finding in &report.findings {
        let kind = serde_json::to_value(finding.kind)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        let severity = serde_json::to_value(finding.severity)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        out.push_str(&format!(
            "<li class=\"{}\"{}><b>{}</b> {}: {}</li>\n",
            escape(&severity),
            finding.goal.map(|g| format!(" data-goal=\"{g}\"")).unwrap_or_default(),
            escape(&severity),
            escape(&kind),
            escape(&finding.message)
        ));
    }
    if report.findings.is_empty() {
        out.push_str("<li>none</li>\n");
    }
    out.push_str("</ul></section>\n");
    out
}

/// Position then quaternion `x y z w` (three.js's order).
fn pose(iso: &Isometry3<f64>) -> Value {
    let [w, x, y, z] = wxyz(&iso.rotation);
    let [px, py, pz] = xyz(&iso.translation.vector);
    json!([px, py, pz, x, y, z, w])
}

fn geometry(surface: &Surface) -> Value {
    let positions: Vec<u8> = surface.vertices.iter().flatten().flat_map(|&v| (v as f32).to_le_bytes()).collect();
    let indices: Vec<u8> = surface.triangles.iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
    json!({"positions": base64(&positions), "indices": base64(&indices)})
}

fn data(validation: &Validation, report: &Report) -> Value {
    let model = &validation.model;
    let links: Vec<Value> = model
        .links
        .iter()
        .map(|link| {
            let shapes: Vec<Value> = link
                .colliders
                .iter()
                .map(|c| json!({"pose": pose(&c.link_from_shape), "geometry": geometry(&surface(&c.shape))}))
                .collect();
            json!({"name": link.name, "shapes": shapes})
        })
        .collect();
    let joints: Vec<Value> = model
        .joints
        .iter()
        .map(|j| {
            json!({
                "name": j.name,
                "prismatic": j.kind == JointKind::Prismatic,
                "origin": pose(&j.parent_from_joint),
                "axis": xyz(&j.axis.into_inner()),
            })
        })
        .collect();
    let obstacles: Vec<Value> = validation
        .scenario
        .obstacles
        .iter()
        .map(|o| json!({"name": o.name, "pose": pose(&o.world_from_shape), "geometry": geometry(&surface(&o.shape))}))
        .collect();
    let goals: Vec<Value> = validation
        .scenario
        .goals
        .iter()
        .zip(&report.goals)
        .map(|(goal, r)| {
            let q = goal.rotation.quaternion();
            json!({"name": goal.name, "position": xyz(&goal.position), "rotation": [q.i, q.j, q.k, q.w], "outcome": r.outcome})
        })
        .collect();
    let point = |p: &crate::plan::SegmentPoint| json!({"s": p.s, "a": p.a, "b": p.b, "distance": p.distance_m});
    let segments: Vec<Value> = validation
        .replayed
        .iter()
        .map(|s| {
            json!({
                "goal": s.goal,
                "planned": s.planned,
                "from": s.from,
                "to": s.to,
                "bound": finite(s.certified.certified_clearance_m),
                "by_kind": s.certified.certified_by_kind,
                "closest": s.certified.closest.as_ref().map(point),
                "touch": s.certified.touch.as_ref().map(point),
            })
        })
        .collect();
    let contacts: Vec<Value> = validation
        .engines
        .iter()
        .flat_map(|runs| runs.replay.contacts.iter().map(move |c| (runs.replay.engine, c)))
        .map(|(engine, c)| json!({"engine": engine, "a": c.a, "b": c.b, "start": c.start_s, "end": c.end_s}))
        .collect();
    json!({
        "robot": {
            "name": model.name,
            "base": pose(&model.world_from_base),
            "tool": pose(&model.last_from_tool),
            "links": links,
            "joints": joints,
        },
        "home": super::home(validation),
        "floor": validation.scenario.floor.map(|f| f.height),
        "obstacles": obstacles,
        "goals": goals,
        "segments": segments,
        "contacts": contacts,
        "margin": validation.settings.margin_m,
        "checks": checks(model, &validation.replayed, &super::home(validation)),
    })
}

fn finite(value: f64) -> Value {
    if value.is_finite() {
        json!(value)
    } else {
        Value::Null
    }
}

/// Our tool position at a few replay clocks (at home when there is no segment), for the page to
/// compare with its own forward kinematics.
fn checks(model: &Model, segments: &[crate::plan::ReplaySegment], home: &[f64]) -> Vec<Value> {
    if segments.is_empty() {
        return vec![json!({"clock": 0.0, "tool": xyz(&model.tool_pose(home).translation.vector)})];
    }
    let count = segments.len();
    (0..CHECKS)
        .map(|n| {
            let clock = (count as f64 * (n as f64 + 0.5) / CHECKS as f64).min(count as f64 - 1e-9);
            let k = clock.floor() as usize;
            let s = clock - k as f64;
            let segment = &segments[k.min(count - 1)];
            let q: Vec<f64> = segment.from.iter().zip(&segment.to).map(|(a, b)| a + s * (b - a)).collect();
            json!({"clock": clock, "tool": xyz(&model.tool_pose(&q).translation.vector)})
        })
        .collect()
}

/// Standard base64 with padding.
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_the_rfc_4648_vectors() {
        for (plain, encoded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), encoded, "{plain}");
        }
    }
}
