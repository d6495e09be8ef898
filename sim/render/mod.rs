//! Consumes a [`Validation`] and its [`Report`].
//! Produces pictures (SVG, PNG: four views of the robot in exact geometry per goal, the scene, the
//! clearance plot) and one self-contained HTML page with an interactive 3D view.
//! Fails with [`RenderError`] only when the rasteriser refuses an SVG (a bug: it is plain SVG).
//!
//! Everything here is a pure function of its input: no clock, no hash order, fixed number
//! formats, so the same run gives the same bytes. Writing the files is the caller's.

mod html;
mod plot;
pub mod png;
mod scene;
mod svg;
mod views;

pub use html::page;
pub use scene::{surface, Surface, AROUND};

use crate::plan::{GoalStep, SegmentPoint};
use crate::report::{Report, Validation};
use nalgebra::Point3;
use views::{Bounds, Shot, Stage};

/// Why a picture could not be made.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// usvg or the PNG encoder refused a picture.
    #[error("picture {picture}: {message}")]
    Svg {
        /// The picture's file stem.
        picture: String,
        /// What the library said.
        message: String,
    },
}

/// One picture: its file stem (`scene`, `goal-007`, `clearance`) and its SVG text.
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    /// File name without extension.
    pub name: String,
    /// The SVG document.
    pub svg: String,
}

/// Every picture of a run: `scene` (the robot at home among the obstacles, every goal frame),
/// one `goal-NNN` per goal (the robot at the goal's chosen configuration, or where its attempt
/// is blocked, with the blocking or closest pair marked) and, when there is a trajectory,
/// `clearance` (the clearance plot).
pub fn pictures(validation: &Validation, report: &Report) -> Vec<Picture> {
    let model = &validation.model;
    let surfaces = scene::RobotSurfaces::of(model, &validation.scenario);
    let home = home(validation);
    let mut shots = vec![scene_shot(validation, report, &home)];
    for index in 0..validation.scenario.goals.len() {
        shots.push(goal_shot(validation, report, index));
    }
    // Framing: everything any picture shows, so flipping through them keeps the scene still.
    let obstacles = surfaces.obstacles();
    let mut bounds = Bounds::default();
    for triangle in &obstacles {
        triangle.corners.iter().for_each(|p| bounds.add(p));
    }
    for goal in &validation.scenario.goals {
        bounds.add(&Point3::from(goal.position));
    }
    for (q, ..) in &shots {
        for triangle in surfaces.robot(model, q) {
            triangle.corners.iter().for_each(|p| bounds.add(p));
        }
    }
    let floor = validation
        .scenario
        .floor
        .map(|floor| floor_rectangle(&surfaces, model, &home, floor.height, &validation.scenario));
    if let Some(corners) = &floor {
        corners.iter().for_each(|p| bounds.add(p));
    }
    let stage = Stage {
        scenario: &validation.scenario,
        link_names: model.links.iter().map(|l| l.name.clone()).collect(),
        obstacles,
        outcomes: report.goals.iter().map(|g| g.outcome).collect(),
        floor,
        bounds,
    };
    let width = validation.scenario.goals.len().saturating_sub(1).to_string().len().max(3);
    // Each picture on its own: the order and the bytes do not depend on the threads.
    use rayon::prelude::*;
    let mut pictures: Vec<Picture> = shots
        .into_par_iter()
        .enumerate()
        .map(|(n, (q, mut shot))| {
            shot.robot = surfaces.robot(model, &q);
            let name = match n {
                0 => "scene".to_string(),
                n => format!("goal-{:0width$}", n - 1),
            };
            Picture {
                name,
                svg: views::picture(&stage, &shot),
            }
        })
        .collect();
    if validation.trajectory.is_some() {
        let names: Vec<String> = validation.scenario.goals.iter().map(|g| g.name.clone()).collect();
        let title = format!("{} on {}: clearance along the trajectory", model.name, validation.scenario.name);
        pictures.push(Picture {
            name: "clearance".into(),
            svg: plot::clearance(&validation.replayed, &names, validation.settings.margin_m, &title),
        });
    }
    pictures
}

/// Where the robot starts: the trajectory's home, else the scenario's, else the default.
fn home(validation: &Validation) -> Vec<f64> {
    validation
        .trajectory
        .as_ref()
        .map(|t| t.home.clone())
        .or_else(|| validation.scenario.home.clone().filter(|h| h.len() == validation.model.dof()))
        .unwrap_or_else(|| crate::plan::default_home(&validation.model))
}

fn scene_shot(validation: &Validation, report: &Report, home: &[f64]) -> (Vec<f64>, Shot) {
    let reached = report.goals.iter().filter(|g| g.outcome == "reached").count();
    let title = format!(
        "{} on {}: {}",
        validation.model.name,
        validation.scenario.name,
        crate::report::verdict_line(&report.verdict)
    );
    let closest = validation.trajectory.as_ref().and_then(|t| t.home_clearance.clone());
    let subtitle = format!(
        "at home; {} obstacles, {} goals ({reached} reached){}",
        validation.scenario.obstacles.len(),
        validation.scenario.goals.len(),
        closest.as_ref().map(pair_text).unwrap_or_default()
    );
    let shot = Shot {
        title,
        subtitle,
        robot: Vec::new(),
        blocked: Vec::new(),
        closest: closest.map(|c| vec![c.a, c.b]).unwrap_or_default(),
        goal: None,
    };
    (home.to_vec(), shot)
}

fn pair_text(point: &SegmentPoint) -> String {
    format!("; closest pair {} and {}, {}", point.a, point.b, svg::mm(point.distance_m))
}

/// The configuration a goal's picture shows and what it marks.
fn goal_shot(validation: &Validation, report: &Report, index: usize) -> (Vec<f64>, Shot) {
    let goal = &validation.scenario.goals[index];
    let margin = validation.settings.margin_m;
    let ik_best = validation
        .solutions
        .get(index)
        .and_then(|s| s.solutions.first())
        .map(|s| s.q.clone());
    let clearance = validation.goal_clearances.get(index).cloned().flatten();
    let step = validation.trajectory.as_ref().and_then(|t| t.steps.get(index));
    let outcome = report.goals.get(index).map_or("", |g| g.outcome);
    let mut blocked = Vec::new();
    let mut closest = Vec::new();
    let (q, what) = match step {
        Some(GoalStep::Reached { q, clearance, .. }) => {
            closest.extend(clearance.iter().flat_map(|c| [c.a.clone(), c.b.clone()]));
            (
                Some(q.clone()),
                format!("reached{}", clearance.as_ref().map(pair_text).unwrap_or_default()),
            )
        }
        Some(step @ GoalStep::NoPath { stop, .. }) => {
            let attempt = step.attempt();
            let point = attempt.and_then(|a| a.segment.touch.clone()).or_else(|| stop.clone());
            match point {
                Some(point) => {
                    blocked.extend([point.a.clone(), point.b.clone()]);
                    let how = if attempt.is_some_and(|a| a.segment.touch.is_some()) {
                        "the straight attempt from the previous goal"
                    } else {
                        "the planner's closest attempt"
                    };
                    let text = format!(
                        "no path: {how} is blocked at s = {:.3} by {} and {} ({})",
                        point.s,
                        point.a,
                        point.b,
                        svg::mm(point.distance_m)
                    );
                    (Some(point.q), text)
                }
                None => (ik_best, "no path".to_string()),
            }
        }
        _ => {
            // Reach-only runs and unreachable goals: IK's best configuration.
            if let Some(point) = clearance.as_ref() {
                if point.distance_m <= margin {
                    blocked.extend([point.a.clone(), point.b.clone()]);
                } else {
                    closest.extend([point.a.clone(), point.b.clone()]);
                }
            }
            let proof = validation.proof(index).map(|p| format!(": {p}")).unwrap_or_default();
            let text = match (&ik_best, outcome) {
                (None, _) => format!("{outcome}: IK found no configuration{proof}; the robot at home"),
                (Some(_), "reached") => format!("reached (IK){}", clearance.as_ref().map(pair_text).unwrap_or_default()),
                (Some(_), _) => format!(
                    "{outcome}: IK's best configuration{}{proof}",
                    clearance.as_ref().map(pair_text).unwrap_or_default()
                ),
            };
            (ik_best, text)
        }
    };
    let q = q.unwrap_or_else(|| home(validation));
    let error = report
        .goals
        .get(index)
        .and_then(|g| g.position_error_m.map(|p| format!(", position error {}", svg::mm(p))))
        .unwrap_or_default();
    let shot = Shot {
        title: format!("goal {index} `{}` ({}){error}", goal.name, goal.tolerance.name()),
        subtitle: what,
        robot: Vec::new(),
        blocked,
        closest,
        goal: Some(index),
    };
    (q, shot)
}

/// The floor drawn as a rectangle under everything, 10 % wider than the scene on each side.
fn floor_rectangle(
    surfaces: &scene::RobotSurfaces,
    model: &crate::model::Model,
    home: &[f64],
    height: f64,
    scenario: &crate::scenario::Scenario,
) -> [Point3<f64>; 4] {
    let mut low = [f64::INFINITY; 2];
    let mut high = [f64::NEG_INFINITY; 2];
    let mut add = |p: &Point3<f64>| {
        for axis in 0..2 {
            low[axis] = low[axis].min(p[axis]);
            high[axis] = high[axis].max(p[axis]);
        }
    };
    surfaces
        .obstacles()
        .iter()
        .chain(&surfaces.robot(model, home))
        .for_each(|t| t.corners.iter().for_each(&mut add));
    scenario.goals.iter().for_each(|g| add(&Point3::from(g.position)));
    let margin = 0.1 * (high[0] - low[0]).max(high[1] - low[1]).max(0.2);
    let (x0, x1, y0, y1) = (low[0] - margin, high[0] + margin, low[1] - margin, high[1] + margin);
    [
        Point3::new(x0, y0, height),
        Point3::new(x1, y0, height),
        Point3::new(x1, y1, height),
        Point3::new(x0, y1, height),
    ]
}
