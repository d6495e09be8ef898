//! The model and scenario as text, for `--describe` and `--kinematics-only`: joints, links,
//! masses, geometry, the tool pose at zero, and the scenario in one line.

use crate::model::{JointKind, Model, Shape};
use crate::scenario::{Scenario, Tolerance};
use std::fmt::Write;

/// The model: joints with limits, speeds and ratings, links with masses and shapes, the tool
/// pose at q = 0, and the hardware cost when the model is a design.
pub fn describe(model: &Model, hardware_cost: Option<f64>) -> String {
    let mut out = String::new();
    let source = match &model.source {
        crate::model::ModelSource::Design { mode, .. } => format!("{mode} design"),
        crate::model::ModelSource::Urdf { base_link, tip_link, .. } => format!("URDF, chain {base_link} -> {tip_link}"),
        crate::model::ModelSource::Mjcf { base_body, tip_body, .. } => format!("MJCF, chain {base_body} -> {tip_body}"),
        crate::model::ModelSource::Timor { modules, tool, .. } => format!("Timor assembly {}, tool {tool}", modules.join(" ")),
    };
    let _ = writeln!(out, "{} ({source}, {} joints)", model.name, model.dof());
    let choices = model.source.choices();
    if !choices.is_empty() {
        let _ = writeln!(out, "\nmodel choices:");
        for choice in choices {
            let _ = writeln!(out, "  {choice}");
        }
    }
    if let Some(cost) = hardware_cost {
        let _ = writeln!(out, "hardware cost c_h = sum|a| + sum|d| = {cost:.4} m");
    }
    let _ = writeln!(out, "\njoints:");
    for (i, joint) in model.joints.iter().enumerate() {
        let kind = match joint.kind {
            JointKind::Revolute => "revolute",
            JointKind::Continuous => "continuous",
            JointKind::Prismatic => "prismatic",
        };
        let limits = joint
            .limits
            .map(|[lo, hi]| format!("[{lo:.4}, {hi:.4}]"))
            .unwrap_or_else(|| "none".into());
        let speed = joint.max_velocity.map(|v| format!("{v:.3}")).unwrap_or_else(|| "-".into());
        let effort = joint.max_effort.map(|v| format!("{v:.1}")).unwrap_or_else(|| "-".into());
        let _ = writeln!(
            out,
            "  {:>2} {:<16} {kind:<10} limits {limits:<20} max speed {speed:<6} rated {effort}",
            i + 1,
            joint.name
        );
    }
    let _ = writeln!(out, "\nlinks:");
    for (i, link) in model.links.iter().enumerate() {
        let mass = link
            .inertial
            .as_ref()
            .map(|m| format!("{:.3} kg", m.mass))
            .unwrap_or_else(|| if i == 0 { "fixed" } else { "no mass" }.into());
        let shapes: Vec<String> = link
            .colliders
            .iter()
            .map(|c| match &c.shape {
                Shape::Sphere { radius } => format!("sphere r={radius:.3}"),
                Shape::Cylinder { radius, length } => format!("cylinder r={radius:.3} l={length:.3}"),
                Shape::Capsule { radius, length } => format!("capsule r={radius:.3} l={length:.3}"),
                Shape::Box { half_extents: [x, y, z] } => format!("box {:.3}x{:.3}x{:.3}", 2.0 * x, 2.0 * y, 2.0 * z),
                Shape::Mesh(mesh) => format!("mesh {} ({} triangles)", mesh.uri, mesh.triangles.len()),
            })
            .collect();
        let shapes = if shapes.is_empty() {
            "no collision geometry".to_string()
        } else {
            shapes.join(", ")
        };
        let _ = writeln!(out, "  {i:>2} {:<16} {mass:<10} {shapes}", link.name);
    }
    let tool = model.tool_pose(&vec![0.0; model.dof()]);
    // Rounding noise below the printed precision would show as "-0.0000".
    let clean = |v: f64| if v.abs() < 5e-5 { 0.0 } else { v };
    let rpy = crate::frames::rpy_of(&tool.rotation).map(clean);
    let p = tool.translation.vector.map(clean);
    let _ = writeln!(
        out,
        "\ntool pose at q = 0: position [{:.4}, {:.4}, {:.4}] m, rpy [{:.4}, {:.4}, {:.4}] rad\n",
        p.x, p.y, p.z, rpy[0], rpy[1], rpy[2]
    );
    out
}

/// `scenario NAME: N obstacles, M goals, tolerance MODE` (modes with counts when they differ).
pub fn scenario_summary(scenario: &Scenario) -> String {
    let modes: Vec<(Tolerance, usize)> = [Tolerance::Pose, Tolerance::ZSymmetric, Tolerance::Position]
        .into_iter()
        .map(|t| (t, scenario.goals.iter().filter(|g| g.tolerance == t).count()))
        .filter(|(_, count)| *count > 0)
        .collect();
    let tolerance = match modes.as_slice() {
        [(only, _)] => only.name().to_string(),
        several => several
            .iter()
            .map(|(t, count)| format!("{} ({count})", t.name()))
            .collect::<Vec<_>>()
            .join(", "),
    };
    format!(
        "scenario {}: {} obstacles, {} goals, tolerance {tolerance}",
        scenario.name,
        scenario.obstacles.len(),
        scenario.goals.len()
    )
}
