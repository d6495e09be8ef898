//! The clearance-along-the-trajectory plot: per replayed segment (the planned edges and each
//! blocked goal's attempt, in order, segment `k` spanning `[k, k + 1)` of the replay clock) the
//! certified lower bound on its clearance (and that bound for each kind of pair: obstacles, the
//! robot itself, the floor), the closest approach measured on it, where it is blocked, and the
//! run's closest pair.

use super::svg::{self, px};
use crate::plan::ReplaySegment;
use crate::xml::Doc;

/// Picture size (px).
pub(super) const WIDTH: u32 = 1280;
/// Picture size (px).
pub(super) const HEIGHT: u32 = 440;
/// Plot area, px: left, right, top, bottom.
pub(super) const AREA: [f64; 4] = [90.0, 1250.0, 64.0, 380.0];

/// The plot as SVG. The root element carries `data-left`, `data-right` (px) and
/// `data-segments`, so a page can put a cursor at a replay clock.
pub(super) fn clearance(segments: &[ReplaySegment], goal_names: &[String], margin_m: f64, title: &str) -> String {
    let [left, right, top, bottom] = AREA;
    let count = segments.len().max(1) as f64;
    let mut values: Vec<f64> = vec![0.0, margin_m];
    for segment in segments {
        values.push(segment.certified.certified_clearance_m);
        values.extend(kinds(segment).into_iter().flatten());
        values.extend(segment.certified.closest.as_ref().map(|c| c.distance_m));
        values.extend(segment.certified.touch.as_ref().map(|c| c.distance_m));
    }
    values.retain(|v| v.is_finite());
    let low = values.iter().copied().fold(0.0, f64::min);
    let high = (values.iter().copied().fold(0.0, f64::max) * 1.05).max(low + 1e-3);
    let (low, high, step) = nice_range(low, high);
    let x = |clock: f64| left + (right - left) * clock / count;
    let y = |metres: f64| bottom - (bottom - top) * (metres.clamp(low, high) - low) / (high - low);

    let extra = vec![
        ("data-left", left.to_string()),
        ("data-right", right.to_string()),
        ("data-segments", segments.len().to_string()),
    ];
    let mut doc = svg::open(WIDTH, HEIGHT, extra);
    let out = &mut doc;
    svg::text(out, left, 24.0, 18, "start", "#000000", title);
    svg::text(
        out,
        left,
        46.0,
        12,
        "start",
        "#333333",
        "per segment: certified bound (blue; thin by kind: obstacles black, self purple dashed, floor brown dotted), closest (orange), blocked (red x); shaded: attempt",
    );
    // Attempts (not on the trajectory) behind everything.
    out.open("g", [("id", "attempts")]);
    for (k, _) in segments.iter().enumerate().filter(|(_, s)| !s.planned) {
        let rect = [
            ("x", px(x(k as f64))),
            ("y", top.to_string()),
            ("width", px(x(1.0) - x(0.0))),
            ("height", (bottom - top).to_string()),
            ("fill", "#fbe3e3".into()),
        ];
        out.empty("rect", rect);
    }
    out.close("g");
    out.open("g", [("id", "grid"), ("stroke", "#e2e2e2"), ("stroke-width", "1")]);
    let mut tick = low;
    let mut labels = Vec::new();
    while tick <= high + step * 1e-6 {
        line(out, left.to_string(), px(y(tick)), right.to_string(), px(y(tick)), &[]);
        labels.push(tick);
        tick += step;
    }
    out.close("g");
    for tick in labels {
        svg::text(
            out,
            left - 8.0,
            y(tick) + 4.0,
            11,
            "end",
            "#555555",
            &format!("{:.0} mm", tick * 1000.0),
        );
    }
    // Goal arrivals: where the next segment heads for another goal.
    out.open("g", [("id", "goals"), ("stroke", "#bbbbbb"), ("stroke-dasharray", "2 3")]);
    let label_every = (segments.len() / 40).max(1);
    let mut arrivals = Vec::new();
    for (k, segment) in segments.iter().enumerate() {
        if segments.get(k + 1).is_none_or(|next| next.goal != segment.goal) {
            arrivals.push((k + 1, segment.goal));
            let at = px(x((k + 1) as f64));
            line(out, at.clone(), top.to_string(), at, bottom.to_string(), &[]);
        }
    }
    out.close("g");
    for (n, (end, goal)) in arrivals.iter().enumerate() {
        if n % label_every == 0 {
            svg::text(out, x(*end as f64), bottom + 16.0, 10, "end", "#555555", &goal.to_string());
        }
    }
    svg::text(
        out,
        (left + right) / 2.0,
        bottom + 36.0,
        12,
        "middle",
        "#333333",
        "replayed segment (goal index at each arrival)",
    );
    // Zero and the margin.
    let zero = px(y(0.0));
    line(
        out,
        left.to_string(),
        zero.clone(),
        right.to_string(),
        zero,
        &[("stroke", "#000000"), ("stroke-width", "1")],
    );
    if margin_m > 0.0 {
        let at = px(y(margin_m));
        line(
            out,
            left.to_string(),
            at.clone(),
            right.to_string(),
            at,
            &[("stroke", "#d62728"), ("stroke-dasharray", "6 4")],
        );
        svg::text(
            out,
            right,
            y(margin_m) - 4.0,
            11,
            "end",
            "#d62728",
            &format!("margin {}", svg::mm(margin_m)),
        );
    }
    // Each kind's bound, thin and under the whole bound, which hides the kind that sets it.
    for (kind, (id, colour, dashes)) in KIND_STYLES.iter().enumerate() {
        out.open(
            "g",
            [
                ("id", *id),
                ("stroke", *colour),
                ("stroke-width", "1.2"),
                ("stroke-dasharray", *dashes),
            ],
        );
        for (k, segment) in segments.iter().enumerate() {
            let Some(bound) = kinds(segment)[kind] else { continue };
            let extent = segment.certified.touch.as_ref().map_or(1.0, |t| t.s);
            let end = px(x(k as f64 + extent).max(x(k as f64) + 1.0));
            line(out, px(x(k as f64)), px(y(bound)), end, px(y(bound)), &[]);
        }
        out.close("g");
    }
    out.open("g", [("id", "certified"), ("stroke", "#1f5fb4"), ("stroke-width", "2")]);
    for (k, segment) in segments.iter().enumerate() {
        let bound = segment.certified.certified_clearance_m;
        if !bound.is_finite() {
            continue;
        }
        let extent = segment.certified.touch.as_ref().map_or(1.0, |t| t.s);
        let end = px(x(k as f64 + extent).max(x(k as f64) + 1.0));
        line(out, px(x(k as f64)), px(y(bound)), end, px(y(bound)), &[]);
    }
    out.close("g");
    out.open("g", [("id", "measured"), ("fill", "#ff7f0e")]);
    for (k, segment) in segments.iter().enumerate() {
        if let Some(closest) = segment.certified.closest.as_ref().filter(|c| c.distance_m.is_finite()) {
            let circle = [
                ("cx", px(x(k as f64 + closest.s))),
                ("cy", px(y(closest.distance_m))),
                ("r", "2.5".into()),
            ];
            out.empty("circle", circle);
        }
    }
    out.close("g");
    out.open("g", [("id", "blocked"), ("stroke", "#d62728"), ("stroke-width", "2.5")]);
    for (k, segment) in segments.iter().enumerate() {
        if let Some(touch) = &segment.certified.touch {
            let (cx, cy) = (x(k as f64 + touch.s), y(touch.distance_m));
            let d = format!(
                "M{} {}L{} {}M{} {}L{} {}",
                px(cx - 5.0),
                px(cy - 5.0),
                px(cx + 5.0),
                px(cy + 5.0),
                px(cx - 5.0),
                px(cy + 5.0),
                px(cx + 5.0),
                px(cy - 5.0)
            );
            out.empty("path", [("d", d)]);
        }
    }
    out.close("g");
    // The closest pair of the trajectory itself (planned segments), ties to the first.
    let closest = segments
        .iter()
        .enumerate()
        .filter(|(_, s)| s.planned)
        .filter_map(|(k, s)| s.certified.closest.as_ref().map(|c| (k, c)))
        .filter(|(_, c)| c.distance_m.is_finite())
        .min_by(|a, b| a.1.distance_m.total_cmp(&b.1.distance_m).then(a.0.cmp(&b.0)));
    if let Some((k, point)) = closest {
        let (cx, cy) = (x(k as f64 + point.s), y(point.distance_m));
        let circle = [
            ("id", "closest-pair".to_string()),
            ("cx", px(cx)),
            ("cy", px(cy)),
            ("r", "7".into()),
            ("fill", "none".into()),
            ("stroke", "#000000".into()),
            ("stroke-width", "1.5".into()),
        ];
        out.empty("circle", circle);
        let goal = goal_names.get(segments[k].goal).map_or("", String::as_str);
        let label = format!(
            "closest: {} and {}, {} (segment {k}, to {goal})",
            point.a,
            point.b,
            svg::mm(point.distance_m)
        );
        // On the title's line, right-aligned: beside its point the label covered the data.
        svg::text(out, right, 24.0, 12, "end", "#000000", &format!("circled: {label}"));
    }
    if segments.is_empty() {
        svg::text(
            out,
            (left + right) / 2.0,
            (top + bottom) / 2.0,
            14,
            "middle",
            "#555555",
            "no segment: no goal has a path or an attempt",
        );
    }
    let frame = [
        ("x", left.to_string()),
        ("y", top.to_string()),
        ("width", (right - left).to_string()),
        ("height", (bottom - top).to_string()),
        ("fill", "none".into()),
        ("stroke", "#888888".into()),
    ];
    out.empty("rect", frame);
    svg::finish(doc)
}

/// Per kind of pair, as [`kinds`] orders them: group id, colour and dashes (none of the status
/// colours).
const KIND_STYLES: [(&str, &str, &str); 3] = [
    ("certified-obstacles", "#222222", "none"),
    ("certified-self", "#6a3d9a", "5 3"),
    ("certified-floor", "#8c564b", "1.5 2.5"),
];

/// A segment's certified bound per kind of pair: obstacles, self, floor (`None`: no such pair).
fn kinds(segment: &ReplaySegment) -> [Option<f64>; 3] {
    let by_kind = &segment.certified.certified_by_kind;
    [by_kind.obstacles_m, by_kind.self_m, by_kind.floor_m]
}

/// A `<line>` from `(x1, y1)` to `(x2, y2)` px, with `style` attributes.
fn line(doc: &mut Doc, x1: String, y1: String, x2: String, y2: String, style: &[(&'static str, &str)]) {
    let mut attributes = vec![("x1", x1), ("y1", y1), ("x2", x2), ("y2", y2)];
    attributes.extend(style.iter().map(|&(k, v)| (k, v.to_string())));
    doc.empty("line", attributes);
}

/// A range holding `[low, high]` whose ends are multiples of a 1, 2 or 5 step, about 6 steps.
fn nice_range(low: f64, high: f64) -> (f64, f64, f64) {
    let raw = (high - low) / 6.0;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * magnitude)
        .find(|&s| s >= raw)
        .unwrap_or(10.0 * magnitude);
    ((low / step).floor() * step, (high / step).ceil() * step, step)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_range_holds_the_values_on_round_steps() {
        let (low, high, step) = nice_range(-0.0012, 0.387);
        assert!(low <= -0.0012 && high >= 0.387, "{low} {high}");
        assert!((step - 0.1).abs() < 1e-12, "{step}");
        assert!(((high - low) / step).round() <= 7.0);
    }
}
