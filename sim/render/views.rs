//! Four orthographic views (front, side, top, isometric) of the robot among its obstacles, floor
//! and goal frames, as one SVG: flat-shaded triangles drawn far to near (painter's order, ties by
//! index, so the bytes are the same on every run), goal frames drawn on top.

use super::scene::{Part, Triangle};
use super::svg::{self, px};
use crate::scenario::Scenario;
use crate::xml::Doc;
use nalgebra::{Point3, Vector3};

/// Picture size (px).
pub(super) const WIDTH: u32 = 1280;
/// Picture size (px).
pub(super) const HEIGHT: u32 = 960;
const TITLE_H: f64 = 56.0;
const LEGEND_H: f64 = 28.0;
const PAD: f64 = 22.0;
/// Characters of a 13 px caption line that fit the picture's width (about 7 px each).
const CAPTION_CHARS: usize = 170;
/// Height of a caption line (px).
const CAPTION_LINE: f64 = 16.0;

/// An orthographic camera: screen right, screen up, and the viewing direction (into the screen).
#[derive(Debug, Clone, Copy)]
pub(super) struct Camera {
    /// Panel label.
    pub(super) name: &'static str,
    right: Vector3<f64>,
    up: Vector3<f64>,
    forward: Vector3<f64>,
}

/// Front (from +x), side (from -y), top (from +z) and isometric (from +x, -y, +z).
pub(super) fn cameras() -> [Camera; 4] {
    let iso_forward = Vector3::new(-1.0, 1.0, -0.8).normalize();
    let iso_right = iso_forward.cross(&Vector3::z()).normalize();
    [
        Camera {
            name: "front (from +x)",
            right: Vector3::y(),
            up: Vector3::z(),
            forward: -Vector3::x(),
        },
        Camera {
            name: "side (from -y)",
            right: Vector3::x(),
            up: Vector3::z(),
            forward: Vector3::y(),
        },
        Camera {
            name: "top (from +z)",
            right: Vector3::x(),
            up: Vector3::y(),
            forward: -Vector3::z(),
        },
        Camera {
            name: "isometric",
            right: iso_right,
            up: iso_right.cross(&iso_forward),
            forward: iso_forward,
        },
    ]
}

/// Screen extent of a set of world points per camera, in metres along right and up.
#[derive(Debug, Clone, Copy)]
pub(super) struct Bounds {
    min: [[f64; 2]; 4],
    max: [[f64; 2]; 4],
}

impl Default for Bounds {
    fn default() -> Self {
        Self {
            min: [[f64::INFINITY; 2]; 4],
            max: [[f64::NEG_INFINITY; 2]; 4],
        }
    }
}

impl Bounds {
    /// Grows the bounds to hold `point` in every view.
    pub(super) fn add(&mut self, point: &Point3<f64>) {
        for (k, camera) in cameras().iter().enumerate() {
            let screen = [point.coords.dot(&camera.right), point.coords.dot(&camera.up)];
            for (axis, value) in screen.into_iter().enumerate() {
                self.min[k][axis] = self.min[k][axis].min(value);
                self.max[k][axis] = self.max[k][axis].max(value);
            }
        }
    }

    /// The scale (px per m) that fits view `k` into `width` by `height` px.
    pub(super) fn view_scale(&self, k: usize, width: f64, height: f64) -> f64 {
        let extent = |axis: usize| {
            let e = self.max[k][axis] - self.min[k][axis];
            if e.is_finite() && e > 0.0 {
                e
            } else {
                self.size()
            }
        };
        (width / extent(0)).min(height / extent(1))
    }

    /// The largest extent over views and axes (m); 1 when empty.
    pub(super) fn size(&self) -> f64 {
        let size = (0..4)
            .flat_map(|k| (0..2).map(move |axis| (k, axis)))
            .map(|(k, axis)| self.max[k][axis] - self.min[k][axis])
            .fold(0.0, f64::max);
        if size.is_finite() && size > 0.0 {
            size
        } else {
            1.0
        }
    }
}

/// What every picture of one run shares: obstacles, floor, goals and the framing.
#[derive(Debug, Clone)]
pub(super) struct Stage<'a> {
    /// The scenario.
    pub(super) scenario: &'a Scenario,
    /// Link names, [`crate::model::Model::links`] order.
    pub(super) link_names: Vec<String>,
    /// The obstacles' triangles.
    pub(super) obstacles: Vec<Triangle>,
    /// Per goal its outcome (`reached`, `unreachable`, `no_path`).
    pub(super) outcomes: Vec<&'static str>,
    /// The floor rectangle's corners (world), when the scenario has a floor.
    pub(super) floor: Option<[Point3<f64>; 4]>,
    /// Extent of everything any picture shows.
    pub(super) bounds: Bounds,
}

/// One picture: the robot at one configuration, what to mark, and what to say.
#[derive(Debug, Clone)]
pub(super) struct Shot {
    /// First line.
    pub(super) title: String,
    /// Second line.
    pub(super) subtitle: String,
    /// The robot's triangles.
    pub(super) robot: Vec<Triangle>,
    /// Bodies (link, obstacle or `floor`) drawn in the blocking colour.
    pub(super) blocked: Vec<String>,
    /// Bodies drawn in the closest-pair colour.
    pub(super) closest: Vec<String>,
    /// The goal the picture is about.
    pub(super) goal: Option<usize>,
}

// Neighbouring links alternate two greys: any hue would read as a goal's status (an orange link
// beside the legend's "no path" did).
const LINK_COLOURS: [[f64; 3]; 2] = [[0.72, 0.74, 0.77], [0.50, 0.53, 0.58]];
const OBSTACLE_COLOUR: [f64; 3] = [0.36, 0.56, 0.82];
const BLOCKED_COLOUR: [f64; 3] = [0.88, 0.12, 0.14];
const CLOSEST_COLOUR: [f64; 3] = [0.10, 0.80, 0.85];
/// Colour of a goal marker by outcome.
pub(super) fn outcome_colour(outcome: &str) -> &'static str {
    match outcome {
        "reached" => "#2ca02c",
        "no_path" => "#ff7f0e",
        "unreachable" => "#d62728",
        "undecided" => "#e377c2",
        _ => "#7f7f7f",
    }
}

/// The picture as SVG text.
pub(super) fn picture(stage: &Stage, shot: &Shot) -> String {
    let mut doc = svg::open(WIDTH, HEIGHT, Vec::new());
    let out = &mut doc;
    svg::text(out, PAD, 24.0, 18, "start", "#000000", &shot.title);
    // A long caption wraps rather than running off the right edge; the panels give way.
    let lines = wrap(&shot.subtitle, CAPTION_CHARS);
    for (k, line) in lines.iter().enumerate() {
        svg::text(out, PAD, 46.0 + CAPTION_LINE * k as f64, 13, "start", "#333333", line);
    }
    let title_h = TITLE_H + CAPTION_LINE * lines.len().saturating_sub(1) as f64;
    let panel_w = f64::from(WIDTH) / 2.0;
    let panel_h = (f64::from(HEIGHT) - title_h - LEGEND_H) / 2.0;
    for (k, camera) in cameras().iter().enumerate() {
        // Each view fills its panel (one scale for all left the scene a third of most panels);
        // each panel has its own scale bar.
        let scale = stage.bounds.view_scale(k, panel_w - 2.0 * PAD - 16.0, panel_h - 2.0 * PAD - 36.0);
        let left = panel_w * (k % 2) as f64;
        let top = title_h + panel_h * (k / 2) as f64;
        out.open("g", [("class", "view")]);
        let panel = [
            ("x", px(left + 4.0)),
            ("y", px(top + 4.0)),
            ("width", px(panel_w - 8.0)),
            ("height", px(panel_h - 8.0)),
            ("fill", "#f7f7f5".into()),
            ("stroke", "#c8c8c8".into()),
        ];
        out.empty("rect", panel);
        svg::text(out, left + 12.0, top + 20.0, 13, "start", "#444444", camera.name);
        let centre = [
            (stage.bounds.min[k][0] + stage.bounds.max[k][0]) / 2.0,
            (stage.bounds.min[k][1] + stage.bounds.max[k][1]) / 2.0,
        ];
        let (cx, cy) = (left + panel_w / 2.0, top + panel_h / 2.0 + 6.0);
        let project = |p: &Point3<f64>| {
            (
                cx + scale * (p.coords.dot(&camera.right) - centre[0]),
                cy - scale * (p.coords.dot(&camera.up) - centre[1]),
            )
        };
        view(out, stage, shot, camera, &project);
        scale_bar(out, left + panel_w - 16.0, top + panel_h - 14.0, scale);
        out.close("g");
    }
    legend(out);
    svg::finish(doc)
}

fn view(out: &mut Doc, stage: &Stage, shot: &Shot, camera: &Camera, project: &dyn Fn(&Point3<f64>) -> (f64, f64)) {
    if let Some(floor) = &stage.floor {
        let points: Vec<String> = floor.iter().map(project).map(|(x, y)| format!("{},{}", px(x), px(y))).collect();
        let points = points.join(" ");
        out.empty(
            "polygon",
            [("class", "floor"), ("points", &points), ("fill", "#e4e1da"), ("stroke", "#b9b4a8")],
        );
    }
    let light = (-camera.forward + 0.6 * camera.up - 0.3 * camera.right).normalize();
    let mut faces: Vec<(f64, usize, &Triangle)> = stage
        .obstacles
        .iter()
        .chain(&shot.robot)
        .enumerate()
        .map(|(index, t)| {
            let centroid = (t.corners[0].coords + t.corners[1].coords + t.corners[2].coords) / 3.0;
            (centroid.dot(&camera.forward), index, t)
        })
        .collect();
    // Far to near; equal depths keep their order, so the output does not depend on the sort.
    faces.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    out.open("g", [("class", "bodies"), ("stroke-width", "0.6"), ("stroke-linejoin", "round")]);
    for (_, _, triangle) in faces {
        let [a, b, c] = &triangle.corners;
        let normal = (b - a).cross(&(c - a));
        let Some(mut normal) = normal.try_normalize(1e-18) else { continue };
        let toward_viewer = -camera.forward;
        if normal.dot(&toward_viewer) < 0.0 {
            if triangle.outward {
                continue;
            }
            normal = -normal;
        }
        let (name, base, opacity) = match triangle.part {
            Part::Link(i) => (stage.link_names.get(i).map_or("", String::as_str), LINK_COLOURS[i % 2], None),
            Part::Obstacle(k) => (
                stage.scenario.obstacles.get(k).map_or("", |o| o.name.as_str()),
                OBSTACLE_COLOUR,
                Some(0.75),
            ),
        };
        let (base, opacity) = if shot.blocked.iter().any(|n| n == name) {
            (BLOCKED_COLOUR, None)
        } else if shot.closest.iter().any(|n| n == name) {
            (CLOSEST_COLOUR, None)
        } else {
            (base, opacity)
        };
        let shade = 0.45 + 0.55 * normal.dot(&light).max(0.0);
        let colour = hex(base, shade);
        let [(x0, y0), (x1, y1), (x2, y2)] = [project(a), project(b), project(c)];
        // Sub-pixel slivers add bytes and no picture.
        if ((x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)).abs() < 0.02 {
            continue;
        }
        let d = format!("M{} {}L{} {}L{} {}Z", px(x0), px(y0), px(x1), px(y1), px(x2), px(y2));
        let mut path = vec![("d", d), ("fill", colour.clone()), ("stroke", colour)];
        if let Some(o) = opacity {
            path.extend([("fill-opacity", o.to_string()), ("stroke-opacity", o.to_string())]);
        }
        out.empty("path", path);
    }
    out.close("g");
    goal_frames(out, stage, shot, project);
}

/// Above this many goals only the shot's goal gets a frame; the others are dots, one path per
/// outcome (a thousand frames in four views would be most of the picture's bytes).
const MANY_GOALS: usize = 60;

/// Each goal's frame (x red, y green, z blue) and a dot in its outcome's colour; the shot's
/// goal larger and named.
fn goal_frames(out: &mut Doc, stage: &Stage, shot: &Shot, project: &dyn Fn(&Point3<f64>) -> (f64, f64)) {
    let axis_length = 0.04 * stage.bounds.size();
    let many = stage.scenario.goals.len() > MANY_GOALS;
    out.open("g", [("class", "goals"), ("stroke-width", "1.2")]);
    let mut dots: [(&str, String); 4] = ["reached", "no_path", "unreachable", ""].map(|o| (o, String::new()));
    for (index, goal) in stage.scenario.goals.iter().enumerate() {
        let focus = shot.goal == Some(index);
        let origin = Point3::from(goal.position);
        let (ox, oy) = project(&origin);
        let outcome = stage.outcomes.get(index).copied().unwrap_or("");
        if many && !focus {
            let slot = dots.iter().position(|(o, _)| *o == outcome).unwrap_or(3);
            dots[slot].1.push_str(&format!("M{} {}h3v3h-3z", px(ox - 1.5), px(oy - 1.5)));
            continue;
        }
        let length = if focus { 2.0 * axis_length } else { axis_length };
        for (axis, colour) in [(Vector3::x(), "#d62728"), (Vector3::y(), "#2ca02c"), (Vector3::z(), "#1f77b4")] {
            let (ex, ey) = project(&(origin + goal.rotation * axis * length));
            let line = [
                ("x1", px(ox)),
                ("y1", px(oy)),
                ("x2", px(ex)),
                ("y2", px(ey)),
                ("stroke", colour.into()),
            ];
            out.empty("line", line);
        }
        let radius = if focus { 5.0 } else { 2.5 };
        let circle = [
            ("cx", px(ox)),
            ("cy", px(oy)),
            ("r", radius.to_string()),
            ("fill", outcome_colour(outcome).into()),
            ("stroke", "#000000".into()),
            ("stroke-width", if focus { "1.5" } else { "0.4" }.into()),
        ];
        out.empty("circle", circle);
        if focus {
            svg::text(out, ox + 8.0, oy - 8.0, 12, "start", "#000000", &goal.name);
        }
    }
    for (outcome, path) in dots.iter().filter(|(_, path)| !path.is_empty()) {
        out.empty(
            "path",
            [("d", path.as_str()), ("fill", outcome_colour(outcome)), ("stroke", "none")],
        );
    }
    out.close("g");
}

fn legend(out: &mut Doc) {
    let y = f64::from(HEIGHT) - 10.0;
    let items = [
        (hex(LINK_COLOURS[0], 1.0), "robot"),
        (hex(OBSTACLE_COLOUR, 1.0), "obstacle"),
        (hex(BLOCKED_COLOUR, 1.0), "blocking pair"),
        (hex(CLOSEST_COLOUR, 1.0), "closest pair"),
        (outcome_colour("reached").to_string(), "goal reached"),
        (outcome_colour("no_path").to_string(), "no path"),
        (outcome_colour("unreachable").to_string(), "unreachable"),
        (outcome_colour("undecided").to_string(), "undecided"),
    ];
    let mut x = PAD;
    for (colour, label) in items {
        let swatch = [
            ("x", px(x)),
            ("y", px(y - 11.0)),
            ("width", "12".into()),
            ("height", "12".into()),
            ("fill", colour),
        ];
        out.empty("rect", swatch);
        svg::text(out, x + 16.0, y, 12, "start", "#333333", label);
        x += 16.0 + 8.0 * label.len() as f64 + 18.0;
    }
}

/// A 0.1 m bar at `scale` (px per m) ending at (`right`, `y`).
fn scale_bar(out: &mut Doc, right: f64, y: f64, scale: f64) {
    let bar = 0.1 * scale;
    let line = [
        ("x1", px(right - bar)),
        ("y1", px(y - 4.0)),
        ("x2", px(right)),
        ("y2", px(y - 4.0)),
        ("stroke", "#000000".into()),
        ("stroke-width", "2".into()),
    ];
    out.empty("line", line);
    svg::text(out, right - bar - 6.0, y, 12, "end", "#333333", "0.1 m");
}

/// `text` in lines of at most `width` characters, broken at spaces (a longer word stands alone).
pub(super) fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > width {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    lines.push(line);
    lines
}

/// `#rrggbb` of `base` (0..1 per channel) times `shade`.
fn hex(base: [f64; 3], shade: f64) -> String {
    let channel = |c: f64| (c * shade * 255.0).round().clamp(0.0, 255.0) as u8;
    format!("#{:02x}{:02x}{:02x}", channel(base[0]), channel(base[1]), channel(base[2]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rgb(hex: &str) -> [f64; 3] {
        let channel = |k: usize| f64::from(u8::from_str_radix(&hex[1 + 2 * k..3 + 2 * k], 16).expect("hex colour")) / 255.0;
        [channel(0), channel(1), channel(2)]
    }

    fn apart(a: [f64; 3], b: [f64; 3]) -> f64 {
        a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt()
    }

    /// Status colours are for status: every goal outcome's colour is far from every other and
    /// from anything else the scene is drawn in (links at any shade, obstacles, the pairs).
    #[test]
    fn status_colours_are_reserved_for_status() {
        let outcomes = ["reached", "no_path", "unreachable", "undecided"];
        for (i, a) in outcomes.iter().enumerate() {
            for b in &outcomes[i + 1..] {
                assert!(apart(rgb(outcome_colour(a)), rgb(outcome_colour(b))) > 0.3, "{a} and {b}");
            }
            for shade in [0.55, 0.8, 1.0] {
                for base in LINK_COLOURS.iter().chain([&OBSTACLE_COLOUR, &CLOSEST_COLOUR]) {
                    let drawn = rgb(&hex(*base, shade));
                    assert!(apart(drawn, rgb(outcome_colour(a))) > 0.3, "{a} against {drawn:?}");
                }
            }
        }
    }

    /// Each view fills its panel: its extent at its scale touches the panel's width or height
    /// and fits both; a view with no extent falls back to the scene's size.
    #[test]
    fn each_view_is_scaled_to_its_panel() {
        let mut bounds = Bounds::default();
        for p in [Point3::new(-0.2, -0.5, 0.0), Point3::new(0.6, 0.3, 1.2)] {
            bounds.add(&p);
        }
        let (width, height) = (600.0, 400.0);
        for k in 0..4 {
            let scale = bounds.view_scale(k, width, height);
            let (w, h) = (bounds.max[k][0] - bounds.min[k][0], bounds.max[k][1] - bounds.min[k][1]);
            assert!(w * scale <= width + 1e-9 && h * scale <= height + 1e-9, "view {k}");
            assert!(
                (w * scale - width).abs() < 1e-9 || (h * scale - height).abs() < 1e-9,
                "view {k} does not fill"
            );
        }
        let mut point = Bounds::default();
        point.add(&Point3::new(0.1, 0.2, 0.3));
        assert_eq!(point.view_scale(0, width, height), height);
    }

    #[test]
    fn captions_wrap_at_spaces_and_keep_every_word() {
        let caption = "goal 3 (ball 1): unreachable: proven: all 8 solutions of the pose collide, throughout the goal's tolerance";
        let lines = wrap(caption, 40);
        assert!(lines.len() > 2 && lines.iter().all(|l| l.chars().count() <= 40), "{lines:?}");
        assert_eq!(lines.join(" "), caption);
        assert_eq!(wrap("short", 40), vec!["short".to_string()]);
        assert_eq!(wrap("", 40), vec![String::new()]);
    }

    #[test]
    fn cameras_are_right_handed_orthonormal_frames() {
        for camera in cameras() {
            let (r, u, f) = (camera.right, camera.up, camera.forward);
            for v in [r, u, f] {
                assert!((v.norm() - 1.0).abs() < 1e-12, "{}", camera.name);
            }
            assert!(
                r.dot(&u).abs() < 1e-12 && r.dot(&f).abs() < 1e-12 && u.dot(&f).abs() < 1e-12,
                "{}",
                camera.name
            );
            // right x up points at the viewer: the screen is not mirrored.
            assert!((r.cross(&u) + f).norm() < 1e-12, "{}", camera.name);
        }
    }
}
