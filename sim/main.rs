//! `validate-design`: reads a design or a URDF, describes the model, exports it, and checks the
//! export against MuJoCo's own kinematics.

use clap::Parser;
use proving_ground::engine::{compare_kinematics, MujocoKinematics, ToolElement, MUJOCO_VERSION};
use proving_ground::error::Error;
use proving_ground::export::{to_mjcf, to_urdf, MjcfOptions, UrdfExportOptions};
use proving_ground::model::{JointKind, Model, Shape};
use proving_ground::pipeline::{self, LoadOptions};
use std::path::PathBuf;
use std::process::ExitCode;

/// Position agreement demanded between our FK and MuJoCo's (m): both compute in f64 from the same
/// numbers, so anything above rounding is a bug. Worst measured on designs/: ~1e-15.
const MUJOCO_AGREEMENT_M: f64 = 1e-9;

const AFTER_HELP: &str = "\
Examples:
  validate-design designs/paper-real-world.json
  validate-design designs/urdf/panda.urdf --tip panda_hand
  validate-design designs/ur5e.json --export-urdf ur5e.urdf --export-mjcf ur5e.xml
  validate-design robot.urdf --package-path ~/ws/src --strict

Exit codes:
  0  the model was built and MuJoCo agrees with our kinematics
  1  MuJoCo disagrees with our kinematics by more than 1e-9 m / rad
  2  bad input or usage: the message names the file and the field or line

Environment:
  ROS_PACKAGE_PATH  extra ':'-separated roots for package:// mesh URIs";

/// Proves or disproves a robot manipulator design in simulation.
#[derive(Debug, Parser)]
#[command(name = "validate-design", version, about, after_help = AFTER_HELP)]
struct Cli {
    /// Design JSON (free, economic, modular, preset) or URDF file.
    design: PathBuf,
    /// URDF: first link of the chain [default: the root link].
    #[arg(long, value_name = "LINK")]
    base: Option<String>,
    /// URDF: last link of the chain [default: end of the longest chain of movable joints].
    #[arg(long, value_name = "LINK")]
    tip: Option<String>,
    /// URDF: a root for package://NAME/... mesh URIs (repeatable; searched before ROS_PACKAGE_PATH).
    #[arg(long = "package-path", value_name = "DIR")]
    package_paths: Vec<PathBuf>,
    /// Write the model as URDF to FILE (never over an input file).
    #[arg(long, value_name = "FILE")]
    export_urdf: Option<PathBuf>,
    /// Write the model as MJCF to FILE (never over an input file).
    #[arg(long, value_name = "FILE")]
    export_mjcf: Option<PathBuf>,
    /// Random configurations at which MuJoCo's kinematics are compared with ours (0 skips).
    #[arg(long, value_name = "N", default_value_t = 100)]
    mujoco_checks: usize,
    /// Seed of the random configurations.
    #[arg(long, value_name = "N", default_value_t = 1)]
    seed: u64,
    /// Print only the joints, links and tool pose; run nothing else.
    #[arg(long)]
    describe: bool,
    /// Treat warnings about the input as errors (exit 2).
    #[arg(long)]
    strict: bool,
    /// Print only the final line.
    #[arg(long)]
    quiet: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(&cli) {
        Ok(code) => code,
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: &Cli) -> Result<ExitCode, Error> {
    let opts = LoadOptions {
        base_link: cli.base.clone(),
        tip_link: cli.tip.clone(),
        package_paths: cli.package_paths.clone(),
    };
    let loaded = pipeline::load(&cli.design, &opts)?;
    let model = &loaded.model;
    for diagnostic in &model.diagnostics {
        eprintln!("{diagnostic}");
    }
    if cli.strict && !model.diagnostics.is_empty() {
        let list = model.diagnostics.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n");
        return Err(Error::Strict {
            count: model.diagnostics.len(),
            list,
        });
    }
    if !cli.quiet {
        print!("{}", describe(model, loaded.design.as_ref().map(|d| d.hardware_cost())));
    }

    let inputs = [cli.design.as_path()];
    let mjcf = to_mjcf(model, &MjcfOptions::default())?;
    if let Some(path) = &cli.export_urdf {
        pipeline::write_output(path, &to_urdf(model, &UrdfExportOptions::default())?, &inputs)?;
        if !cli.quiet {
            println!("wrote URDF {}", path.display());
        }
    }
    if let Some(path) = &cli.export_mjcf {
        pipeline::write_output(path, &mjcf, &inputs)?;
        if !cli.quiet {
            println!("wrote MJCF {}", path.display());
        }
    }
    if cli.describe || cli.mujoco_checks == 0 {
        if cli.quiet {
            println!("{}: {} joints, model built", model.name, model.dof());
        }
        return Ok(ExitCode::SUCCESS);
    }

    let joint_names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
    let mujoco = MujocoKinematics::from_xml_str(&mjcf, &format!("the MJCF export of {}", cli.design.display()), &joint_names)?;
    let agreement = compare_kinematics(model, &mujoco, ToolElement::Site("tool"), cli.mujoco_checks, cli.seed)?;
    let worst = agreement
        .max_position_error_m
        .max(agreement.max_angle_error_rad)
        .max(agreement.max_jacobian_error.unwrap_or(0.0));
    let passed = worst <= MUJOCO_AGREEMENT_M;
    println!(
        "MuJoCo {MUJOCO_VERSION} vs our kinematics on the MJCF export, {} configurations (seed {}): \
         max position error {:.1e} m, max angle error {:.1e} rad, max Jacobian error {:.1e}: {}",
        agreement.configurations,
        cli.seed,
        agreement.max_position_error_m,
        agreement.max_angle_error_rad,
        agreement.max_jacobian_error.unwrap_or(0.0),
        if passed { "agree" } else { "DISAGREE" }
    );
    if passed {
        Ok(ExitCode::SUCCESS)
    } else {
        println!("worst at `{}`, q = {:?}", agreement.worst_element, agreement.worst_configuration);
        Ok(ExitCode::from(1))
    }
}

fn describe(model: &Model, hardware_cost: Option<f64>) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let source = match &model.source {
        proving_ground::model::ModelSource::Design { mode } => format!("{mode} design"),
        proving_ground::model::ModelSource::Urdf { base_link, tip_link, .. } => format!("URDF, chain {base_link} -> {tip_link}"),
    };
    let _ = writeln!(out, "{} ({source}, {} joints)", model.name, model.dof());
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
            .unwrap_or_else(|| "fixed".into());
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
    let rpy = proving_ground::frames::rpy_of(&tool.rotation).map(clean);
    let p = tool.translation.vector.map(clean);
    let _ = writeln!(
        out,
        "\ntool pose at q = 0: position [{:.4}, {:.4}, {:.4}] m, rpy [{:.4}, {:.4}, {:.4}] rad\n",
        p.x, p.y, p.z, rpy[0], rpy[1], rpy[2]
    );
    out
}
