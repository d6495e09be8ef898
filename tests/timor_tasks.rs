//! Timor / CoBRA tasks as scenarios: timor-python's own sample tasks read, round trips through
//! both formats, and a task run end to end, its goals judged against their own tolerance.

mod common;

use common::repo;
use proving_ground::scenario::{self, parse_timor_task, to_json, to_timor_task, Scenario};
use std::path::Path;

fn sample(name: &str) -> std::path::PathBuf {
    repo().join("tests/fixtures/timor/tasks").join(name)
}

fn assert_same(a: &Scenario, b: &Scenario) {
    assert_eq!(a.goals.len(), b.goals.len());
    for (x, y) in a.goals.iter().zip(&b.goals) {
        assert_eq!(x.name, y.name);
        assert!((x.position - y.position).norm() < 1e-12, "{} moved", x.name);
        assert!(x.rotation.angle_to(&y.rotation) < 1e-12, "{} turned", x.name);
        assert_eq!(x.tolerance, y.tolerance, "{}", x.name);
    }
    assert_eq!(a.obstacles.len(), b.obstacles.len());
    for (x, y) in a.obstacles.iter().zip(&b.obstacles) {
        let (dt, da) = proving_ground::frames::pose_difference(&x.world_from_shape, &y.world_from_shape);
        assert!(dt < 1e-12 && da < 1e-12, "{} moved", x.name);
        assert_eq!(format!("{:?}", x.shape), format!("{:?}", y.shape));
    }
    let (dt, da) = proving_ground::frames::pose_difference(&a.world_from_base, &b.world_from_base);
    assert!(dt < 1e-12 && da < 1e-12, "base moved");
}

#[test]
fn timors_sample_task_reads_with_its_base_goals_and_tolerances() {
    let s = &scenario::load_timor_task(&sample("PTP_1.json")).expect("PTP_1 reads");
    assert_eq!(s.name, "PTP_1");
    assert_eq!(s.world_from_base.translation.vector, nalgebra::Vector3::new(1.0, 2.0, 3.0));
    assert_eq!(s.goals.len(), 2);
    assert_eq!(s.goals[1].position, nalgebra::Vector3::new(2.0, 2.0, 3.0));
    let task = s.goals[0].task.as_ref().expect("the goal's own tolerance");
    assert_eq!([task.inner_m, task.outer_m, task.inner_rad, task.outer_rad], [0.01, 0.01, 0.1, 0.1]);
    assert!(s.notes.iter().any(|w| w.contains("base placement free")), "{:?}", s.notes);
    // The same through `scenario::load`, which tells the formats apart by their keys.
    assert_same(s, &scenario::load(&sample("PTP_1.json")).expect("loads"));
}

#[test]
fn what_a_scenario_cannot_hold_is_named() {
    let error = scenario::load(&sample("PTP_mixed_frames.json"))
        .expect_err("its one goal excludes its nominal")
        .to_string();
    assert!(
        error.contains("goals[0] (`1`): not checked: its tolerance z [-0.05, -0.01] excludes the nominal pose itself"),
        "{error}"
    );
    let error = scenario::load(&sample("PTP_2_cycle.json"))
        .expect_err("its meshes are not here")
        .to_string();
    assert!(
        error.contains("obstacles[0].collision[0]") && error.contains("assets/DMU_125P_compress.stl"),
        "{error}"
    );
    let text = std::fs::read_to_string(sample("PTP_1.json")).expect("sample");
    let more = text.replacen(
        r#""goals": ["#,
        r#""goals": [{"ID": "p", "type": "pause", "duration": 0.4}, {"ID": "f", "type": "follow", "trajectory": {"pose": []}}, "#,
        1,
    );
    let import = parse_timor_task(&more, Path::new("more.json")).expect("reads");
    assert_eq!(import.goals.len(), 2);
    for what in ["`pause` goal is not checked", "`follow` goal is not checked"] {
        assert!(import.notes.iter().any(|w| w.contains(what)), "{what}: {:?}", import.notes);
    }
    let broken = text.replacen("\"obstacles\": [],", "\"obstacles\": [], \"extra\": 1,", 1);
    let error = parse_timor_task(&broken, Path::new("broken.json"))
        .expect_err("unknown key")
        .to_string();
    assert!(
        error.contains("broken.json") && error.contains("extra") && error.contains("line"),
        "{error}"
    );
}

#[test]
fn tasks_and_scenarios_round_trip_through_both_formats() {
    let dir = tempfile::tempdir().expect("temp dir");
    // A task through the scenario format and back.
    let task = scenario::load(&sample("PTP_1.json")).expect("task");
    let as_scenario = dir.path().join("ptp1.json");
    std::fs::write(&as_scenario, to_json(&task)).expect("write");
    let back = scenario::load(&as_scenario).expect("scenario");
    assert_same(&task, &back);
    assert_eq!(task.goals[0].task, back.goals[0].task);
    let as_task = parse_timor_task(&to_timor_task(&back, None), Path::new("again.json")).expect("task again");
    assert_same(&task, &as_task);
    assert_eq!(task.goals[1].task, as_task.goals[1].task);
    // A scenario of ours (spheres, goals in course order) through the task format and back.
    let cluttered = scenario::load(&repo().join("scenarios/cluttered/task-00.json")).expect("cluttered");
    let written = dir.path().join("task-00.timor.json");
    scenario::save_timor_task(&cluttered, &written, false).expect("write task");
    let mut read = scenario::load(&written).expect("reads back");
    // Timor has no floor: it goes as a slab whose top is the floor's surface.
    let height = cluttered.floor.expect("the cluttered tasks have a floor").height;
    let slab = read.obstacles.pop().expect("the floor's slab");
    assert_eq!(slab.name, "floor");
    let proving_ground::model::Shape::Box { half_extents } = slab.shape else {
        panic!("a slab")
    };
    assert!((slab.world_from_shape.translation.vector.z + half_extents[2] - height).abs() < 1e-12);
    assert_same(&cluttered, &read);
    // The harness's own tolerance, said the task's way, and judged the same.
    let task = read.goals[0].task.as_ref().expect("written with its tolerance");
    assert_eq!(task.to_string(), "r_sph [0, 0.001], Theta_R [0, 0.017453292519943295]");
    assert!(proving_ground::ik::task_tolerance_gap(&read.goals[0]).is_none());
    assert!(
        scenario::save_timor_task(&cluttered, &written, false).is_err(),
        "an existing file is kept"
    );
}

/// The goals' outcomes in a `--json` report of `validate-design DESIGN --scenario SCENARIO`.
fn outcomes(design: &str, scenario: &Path, json: &Path) -> Vec<(String, String)> {
    let output = assert_cmd::Command::cargo_bin("validate-design")
        .expect("binary")
        .current_dir(repo())
        .args([
            design,
            "--scenario",
            scenario.to_str().expect("utf-8"),
            "--engines",
            "none",
            "--json",
            json.to_str().expect("utf-8"),
        ])
        .output()
        .expect("runs");
    assert!(
        output.status.code().is_some_and(|c| c <= 3),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(json).expect("report")).expect("JSON");
    report["goals"]
        .as_array()
        .expect("goals")
        .iter()
        .map(|g| {
            (
                g["outcome"].as_str().unwrap_or_default().to_string(),
                g["proven"].as_str().unwrap_or_default().to_string(),
            )
        })
        .collect()
}

#[test]
fn a_task_runs_end_to_end_and_a_wider_tolerance_is_never_proven_by_a_narrower_proof() {
    let dir = tempfile::tempdir().expect("temp dir");
    // The cluttered task as Timor would write it, once with the harness's tolerance and once
    // with CoBRA's usual 10 mm and 0.1 rad.
    let cluttered = scenario::load(&repo().join("scenarios/cluttered/task-00.json")).expect("cluttered");
    let exact = dir.path().join("exact.json");
    std::fs::write(&exact, to_timor_task(&cluttered, None)).expect("write");
    let wide = dir.path().join("wide.json");
    let text = to_timor_task(&cluttered, None)
        .replace("[0.0, 0.001]", "[0.0, 0.01]")
        .replace("[0.0, 0.017453292519943295]", "[0.0, 0.1]");
    std::fs::write(&wide, text).expect("write");
    let design = "designs/economic-elbow.json";
    let ours = outcomes(
        design,
        &repo().join("scenarios/cluttered/task-00.json"),
        &dir.path().join("ours.json"),
    );
    let same = outcomes(design, &exact, &dir.path().join("exact-report.json"));
    assert_eq!(ours, same, "the task with the harness's tolerance is the scenario");
    let judged = outcomes(design, &wide, &dir.path().join("wide-report.json"));
    assert!(
        ours.iter().any(|(o, _)| o == "unreachable"),
        "the oracle run proves something: {ours:?}"
    );
    for ((outcome, _), (wide_outcome, proof)) in ours.iter().zip(&judged) {
        match outcome.as_str() {
            // A configuration within 1 mm and 1 deg is within 10 mm and 0.1 rad.
            "reached" => assert_eq!(wide_outcome, "reached"),
            // Proven within 1 mm: a proof for the wider goal only by its own reach argument.
            "unreachable" => assert!(
                wide_outcome == "undecided" || (wide_outcome == "unreachable" && proof.contains("beyond what the task's tolerance")),
                "{wide_outcome}: {proof}"
            ),
            _ => {}
        }
    }
}
