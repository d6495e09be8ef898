//! The library's one entry point, [`proving_ground::validate`], gives what `validate-design`
//! gives: the same report, byte for byte, with every option the CLI applies before validating.

mod common;

use assert_cmd::cargo::CommandCargoExt;
use common::{panda_urdf, repo};
use proving_ground::pipeline::Engines;
use proving_ground::run::{report_json, Outcome, Stop};
use proving_ground::scenario::Tolerance;
use std::process::Command;

fn panda_srdf() -> std::path::PathBuf {
    repo().join("designs/urdf/example-robot-data/robots/panda_description/srdf/panda.srdf")
}

/// The Panda with its SRDF, on a cluttered task, every goal judged `z_symmetric`, MuJoCo only,
/// small search and planner budgets.
fn options() -> proving_ground::Options {
    let mut opts = proving_ground::Options {
        srdf: Some(panda_srdf()),
        scenario: Some(repo().join("scenarios/cluttered/task-00.json")),
        tolerance: Some(Tolerance::ZSymmetric),
        kinematics_checks: 20,
        ..Default::default()
    };
    opts.validate.engines = "mujoco".parse::<Engines>().expect("an engine");
    opts.validate.ik.search_boxes = 2_000;
    // A tenth of the default planner budget: the goal without a path otherwise spends minutes
    // in the planner, and the comparison needs the option to take effect, not the search.
    opts.validate.planner.budget = 2_000;
    opts
}

#[test]
fn validate_gives_the_cli_json_report_byte_for_byte() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let json = dir.path().join("report.json");
    let child = Command::cargo_bin("validate-design")
        .expect("binary is built")
        .current_dir(repo())
        .arg(panda_urdf())
        .arg("--srdf")
        .arg(panda_srdf())
        .arg("--scenario")
        .arg(repo().join("scenarios/cluttered/task-00.json"))
        .args(["--tolerance", "z_symmetric", "--engines", "mujoco", "--mujoco-checks", "20"])
        .args(["--search-boxes", "2000", "--plan-budget", "2000", "--quiet", "--json"])
        .arg(&json)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("runs");
    // The library's run while the CLI's goes on: the two are the test's whole time.
    let run = proving_ground::validate(&panda_urdf(), &options(), &proving_ground::progress::Silent).expect("validates");
    let output = child.wait_with_output().expect("the CLI finishes");
    let cli = std::fs::read_to_string(&json).expect("the CLI wrote the report");
    let report = run.report.as_ref().expect("a whole run has a report");
    let library = report_json(report).expect("serialises");
    assert_eq!(library, cli, "the library's report differs from the CLI's");

    // The options took effect (the comparison alone would pass if both ignored them).
    let value: serde_json::Value = serde_json::from_str(&library).expect("JSON");
    let excluded = value["criteria"]["excluded_pairs"].as_array().expect("excluded pairs");
    assert!(
        excluded.iter().any(|p| p.to_string().contains("disabled in SRDF panda.srdf")),
        "the SRDF's pairs are left out: {excluded:?}"
    );
    assert!(run.scenario.goals.iter().all(|g| g.tolerance == Tolerance::ZSymmetric));
    assert_eq!(
        value["criteria"]["planner"]["budget"], 2000,
        "the planner's budget is the one asked for"
    );
    assert!(report.inputs.kinematics_check.as_ref().is_some_and(|c| c.agree));
    let code = match run.outcome() {
        Outcome::Pass => 0,
        Outcome::Fail => 1,
        Outcome::Undecided => 3,
    };
    assert_eq!(output.status.code(), Some(code), "{}", String::from_utf8_lossy(&output.stderr));
}

#[test]
fn validate_stops_where_asked_and_reports_errors_with_the_file() {
    let described = proving_ground::validate(
        &panda_urdf(),
        &proving_ground::Options {
            stop: Stop::Described,
            ..options()
        },
        &proving_ground::progress::Silent,
    )
    .expect("builds");
    assert!(described.kinematics_check.is_none() && described.report.is_none());
    assert_eq!(described.model.dof(), 7);
    assert_eq!(described.outcome(), Outcome::Pass);

    let srdf_on_a_design = proving_ground::validate(
        &repo().join("designs/ur5e.json"),
        &proving_ground::Options {
            stop: Stop::Described,
            ..options()
        },
        &proving_ground::progress::Silent,
    )
    .expect_err("an SRDF is for URDF input");
    let message = srdf_on_a_design.to_string();
    assert!(message.contains("panda.srdf") && message.contains("ur5e.json"), "{message}");
}

#[test]
fn the_exported_urdf_names_its_meshes_relative_to_itself_and_loads_elsewhere() {
    let dir = tempfile::tempdir().expect("temporary folder");
    let out = dir.path().join("nested/panda.urdf");
    std::fs::create_dir_all(out.parent().expect("a folder")).expect("folder");
    let opts = proving_ground::Options {
        stop: Stop::Described,
        exports: proving_ground::run::Exports {
            urdf: Some(out.clone()),
            ..Default::default()
        },
        load: proving_ground::pipeline::LoadOptions {
            tip_link: Some("panda_hand".into()),
            ..Default::default()
        },
        ..Default::default()
    };
    let run = proving_ground::validate(&panda_urdf(), &opts, &proving_ground::progress::Silent).expect("exports");
    let text = std::fs::read_to_string(&out).expect("written");
    let filenames: Vec<&str> = text
        .split("filename=\"")
        .skip(1)
        .filter_map(|rest| rest.split('"').next())
        .collect();
    assert!(!filenames.is_empty(), "the Panda has mesh colliders:\n{text}");
    for name in &filenames {
        assert!(name.starts_with("../"), "{name}: expected a path relative to the URDF's folder");
    }
    // Read back from its own folder, whatever the working folder: the same meshes.
    let back = proving_ground::pipeline::load_model(&out, &Default::default()).expect("the export loads");
    let meshes = |model: &proving_ground::model::Model| -> Vec<usize> {
        model
            .links
            .iter()
            .flat_map(|l| &l.colliders)
            .filter_map(|c| match &c.shape {
                proving_ground::model::Shape::Mesh(mesh) => Some(mesh.vertices.len()),
                _ => None,
            })
            .collect()
    };
    assert!(!meshes(&run.model).is_empty());
    assert_eq!(meshes(&back), meshes(&run.model));
}
