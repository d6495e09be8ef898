//! Regressions of the hostile-input campaign (issue 10): no file the run read is ever replaced,
//! a failed write leaves the old file intact, files that are not regular are refused without
//! blocking, and MuJoCo is needed only by what uses it. Malformed contents are in
//! `tests/bad_inputs.rs` (the corpus under tests/fixtures/bad/).

mod common;

use assert_cmd::Command;
use common::{fixture, repo};
use std::path::Path;
use std::time::Duration;

fn validate_design() -> Command {
    let mut command = Command::cargo_bin("validate-design").expect("binary built");
    command.timeout(Duration::from_secs(120));
    command
}

fn stderr(output: &std::process::Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// A copy of the Panda description (URDF and meshes) in `dir`, so a failing test cannot damage
/// the repository's files.
fn panda_copy(dir: &Path) -> std::path::PathBuf {
    let source = repo().join("designs/urdf/example-robot-data");
    let status = std::process::Command::new("cp")
        .arg("-r")
        .arg(&source)
        .arg(dir)
        .status()
        .expect("cp runs");
    assert!(status.success());
    dir.join("example-robot-data/robots/panda_description/urdf/panda.urdf")
}

/// A binary STL tetrahedron (MuJoCo reads binary STL only).
fn binary_stl_tetrahedron() -> Vec<u8> {
    let v = [[0.0f32, 0.0, 0.0], [0.05, 0.0, 0.0], [0.0, 0.05, 0.0], [0.0, 0.0, 0.05]];
    let faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let mut bytes = vec![0u8; 80];
    bytes.extend_from_slice(&4u32.to_le_bytes());
    for face in faces {
        bytes.extend_from_slice(&[0u8; 12]);
        for index in face {
            for coordinate in v[index] {
                bytes.extend_from_slice(&coordinate.to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0u8; 2]);
    }
    bytes
}

#[test]
fn report_through_a_hard_link_to_the_design_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let design = dir.path().join("d.json");
    std::fs::copy(repo().join("designs/paper-real-world.json"), &design).expect("copy");
    let link = dir.path().join("link.json");
    std::fs::hard_link(&design, &link).expect("hard link");
    let before = std::fs::read(&design).expect("read");
    let output = validate_design()
        .arg(&design)
        .args(["--engines", "none", "--mujoco-checks", "0", "--json"])
        .arg(&link)
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("this run read that file"), "{}", stderr(&output));
    assert_eq!(std::fs::read(&design).expect("read"), before);
}

#[test]
fn default_scenario_read_from_the_current_directory_is_not_overwritten() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::create_dir(dir.path().join("scenarios")).expect("mkdir");
    let course = dir.path().join("scenarios/course.json");
    std::fs::copy(repo().join("scenarios/course.json"), &course).expect("copy");
    let before = std::fs::read(&course).expect("read");
    let output = validate_design()
        .current_dir(dir.path())
        .arg(repo().join("designs/paper-real-world.json"))
        .args(["--engines", "none", "--mujoco-checks", "0", "--json", "scenarios/course.json"])
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert_eq!(std::fs::read(&course).expect("read"), before);
}

#[test]
fn robot_mesh_is_not_overwritten_by_an_export() {
    let dir = tempfile::tempdir().expect("temp dir");
    let urdf = panda_copy(dir.path());
    let mesh = dir
        .path()
        .join("example-robot-data/robots/panda_description/meshes/collision/link3.stl");
    let before = std::fs::read(&mesh).expect("the Panda has link3.stl");
    let output = validate_design()
        .arg(&urdf)
        .args(["--tip", "panda_hand", "--describe", "--export-mjcf"])
        .arg(&mesh)
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("this run read that file"), "{}", stderr(&output));
    assert_eq!(std::fs::read(&mesh).expect("read"), before);
}

#[test]
fn scenario_mesh_is_not_overwritten_by_the_report() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::copy(fixture("meshes/tetrahedron.stl"), dir.path().join("tetrahedron.stl")).expect("copy");
    let scenario = dir.path().join("s.json");
    std::fs::write(
        &scenario,
        r#"{"obstacles": [{"type": "mesh", "file": "tetrahedron.stl", "position": [2, 2, 0]}],
            "goals": [{"position": [0.3, 0.1, 0.4], "quaternion": [0, 1, 0, 0]}]}"#,
    )
    .expect("write");
    let mesh = dir.path().join("tetrahedron.stl");
    let before = std::fs::read(&mesh).expect("read");
    let output = validate_design()
        .arg(repo().join("designs/paper-real-world.json"))
        .args(["--engines", "none", "--mujoco-checks", "0", "--scenario"])
        .arg(&scenario)
        .arg("--json")
        .arg(&mesh)
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert_eq!(std::fs::read(&mesh).expect("read"), before);
}

/// An MJCF that includes a file which names a mesh.
fn mjcf_with_include(dir: &Path) -> std::path::PathBuf {
    std::fs::write(dir.join("part.stl"), binary_stl_tetrahedron()).expect("write");
    std::fs::write(
        dir.join("assets.xml"),
        r#"<mujoco><asset><mesh name="part" file="part.stl"/></asset></mujoco>"#,
    )
    .expect("write");
    let main = dir.join("robot.xml");
    std::fs::write(
        &main,
        r#"<mujoco model="r"><include file="assets.xml"/><worldbody><body name="l1"><joint name="j1" type="hinge" range="-1 1"/>
           <geom type="mesh" mesh="part" mass="1"/><geom type="capsule" fromto="0 0 0 0 0 0.3" size="0.03" mass="1"/></body></worldbody></mujoco>"#,
    )
    .expect("write");
    main
}

#[test]
fn mjcf_include_and_its_mesh_are_not_overwritten() {
    let dir = tempfile::tempdir().expect("temp dir");
    let main = mjcf_with_include(dir.path());
    for target in ["assets.xml", "part.stl"] {
        let path = dir.path().join(target);
        let before = std::fs::read(&path).expect("read");
        let output = validate_design()
            .arg(&main)
            .args(["--describe", "--export-urdf"])
            .arg(&path)
            .output()
            .expect("runs");
        assert_eq!(output.status.code(), Some(2), "{target}: {}", stderr(&output));
        assert!(stderr(&output).contains("this run read that file"), "{}", stderr(&output));
        assert_eq!(std::fs::read(&path).expect("read"), before, "{target}");
    }
}

#[test]
fn mjcf_mesh_that_is_a_fifo_is_refused_without_blocking() {
    let dir = tempfile::tempdir().expect("temp dir");
    let main = mjcf_with_include(dir.path());
    std::fs::remove_file(dir.path().join("part.stl")).expect("remove");
    let status = std::process::Command::new("mkfifo")
        .arg(dir.path().join("part.stl"))
        .status()
        .expect("mkfifo runs");
    assert!(status.success());
    let output = validate_design()
        .timeout(Duration::from_secs(20))
        .arg(&main)
        .arg("--describe")
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("a FIFO"), "{}", stderr(&output));
}

#[test]
fn a_mesh_over_the_size_limit_is_refused_before_reading() {
    let dir = tempfile::tempdir().expect("temp dir");
    let urdf = panda_copy(dir.path());
    // A sparse file: 200 MiB on paper, nothing on disk.
    let mesh = dir
        .path()
        .join("example-robot-data/robots/panda_description/meshes/collision/link3.stl");
    std::fs::OpenOptions::new()
        .write(true)
        .open(&mesh)
        .and_then(|f| f.set_len(200 << 20))
        .expect("grow");
    let output = validate_design()
        .arg(&urdf)
        .args(["--tip", "panda_hand", "--describe"])
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("larger than the limit of 128 MiB"), "{}", stderr(&output));
}

/// Runs `command` under a file-size limit of 1 KiB (`ulimit -f 1`): every write past 1 KiB fails.
fn under_write_limit(args: &[&str], dir: &Path) -> std::process::Output {
    under_size_limit(1, args, dir)
}

/// Runs `command` where no file may grow past `kib` KiB (`ulimit -f`).
fn under_size_limit(kib: u64, args: &[&str], dir: &Path) -> std::process::Output {
    let binary = assert_cmd::cargo::cargo_bin("validate-design");
    let mut script = format!("ulimit -f {kib}; exec '{}'", binary.display());
    for arg in args {
        script.push_str(&format!(" '{arg}'"));
    }
    std::process::Command::new("sh")
        .arg("-c")
        .arg(script)
        .current_dir(dir)
        .output()
        .expect("sh runs")
}

#[test]
fn failed_write_leaves_the_old_report_and_export_intact() {
    let dir = tempfile::tempdir().expect("temp dir");
    let design = repo().join("designs/paper-real-world.json");
    let design = design.to_string_lossy();
    for (flag, name) in [("--json", "report.json"), ("--export-mjcf", "robot.xml")] {
        let old = dir.path().join(name);
        std::fs::write(&old, "old contents\n").expect("write");
        let output = under_write_limit(
            &[&design, "--engines", "none", "--mujoco-checks", "0", "--quiet", flag, name],
            dir.path(),
        );
        assert_eq!(output.status.code(), Some(2), "{flag}: {}", stderr(&output));
        assert_eq!(std::fs::read_to_string(&old).expect("read"), "old contents\n", "{flag}");
    }
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .expect("list")
        .filter_map(Result::ok)
        .map(|e| e.file_name())
        .collect();
    assert_eq!(left.len(), 2, "temporary files left behind: {left:?}");
}

#[test]
fn a_run_writes_its_outputs_as_one_set_or_leaves_the_old_ones() {
    let dir = tempfile::tempdir().expect("temp dir");
    let design = repo().join("designs/ur5e.json");
    let scenario = repo().join("scenarios/cluttered/task-00.json");
    let (design, scenario) = (design.to_string_lossy(), scenario.to_string_lossy());
    for name in ["r.json", "r.html", "r.urdf"] {
        std::fs::write(dir.path().join(name), "old\n").expect("write");
    }
    // The JSON (about 13 KiB) fits under 200 KiB, the page (about 800 KiB) does not: nothing
    // of this run may replace anything of the last one.
    let args = [
        &design as &str,
        "--scenario",
        &scenario,
        "--reach-only",
        "--mujoco-checks",
        "0",
        "--quiet",
        "--json",
        "r.json",
        "--svg",
        "pictures",
        "--html",
        "r.html",
        "--export-urdf",
        "r.urdf",
    ];
    let output = under_size_limit(200, &args, dir.path());
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    for name in ["r.json", "r.html", "r.urdf"] {
        assert_eq!(std::fs::read_to_string(dir.path().join(name)).expect("read"), "old\n", "{name}");
    }
    let pictures: Vec<_> = std::fs::read_dir(dir.path().join("pictures")).expect("list").collect();
    assert!(pictures.is_empty(), "no picture of a failed set: {pictures:?}");
    let left = std::fs::read_dir(dir.path()).expect("list").count();
    assert_eq!(left, 4, "temporaries left behind");
    // Without the limit all of them are written.
    let output = under_size_limit(1 << 20, &args, dir.path());
    assert!(matches!(output.status.code(), Some(1)), "{}", stderr(&output));
    assert!(std::fs::read_to_string(dir.path().join("r.html")).expect("read").len() > 100_000);
    assert!(std::fs::read_to_string(dir.path().join("r.urdf")).expect("read").contains("<robot"));
}

#[test]
fn a_home_from_the_command_line_is_where_the_trajectory_starts() {
    let dir = tempfile::tempdir().expect("temp dir");
    let design = repo().join("designs/ur5e.json");
    let json = dir.path().join("r.json");
    let home = "0.1,-1.2,1.1,-1.4,-1.5,0.2";
    let output = Command::cargo_bin("validate-design")
        .expect("binary")
        .arg(&design)
        .args(["--engines", "none", "--mujoco-checks", "0", "--quiet", "--home", home, "--json"])
        .arg(&json)
        .output()
        .expect("runs");
    assert!(matches!(output.status.code(), Some(0 | 1 | 3)), "{}", stderr(&output));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).expect("read")).expect("json");
    let started: Vec<f64> = report["trajectory"]["home"]
        .as_array()
        .expect("a home")
        .iter()
        .filter_map(serde_json::Value::as_f64)
        .collect();
    let given: Vec<f64> = home.split(',').map(|v| v.parse().expect("number")).collect();
    assert_eq!(started, given);
    assert!(report["trajectory"]["home_replaced"].is_null(), "{}", report["trajectory"]);
    for (bad, message) in [("0,1", "2 values for a robot of 6 joints"), ("-9,0,0,0,0,0", "outside its limits")] {
        let output = Command::cargo_bin("validate-design")
            .expect("binary")
            .arg(&design)
            .arg(format!("--home={bad}"))
            .output()
            .expect("runs");
        assert_eq!(output.status.code(), Some(2), "{bad}");
        assert!(stderr(&output).contains(message), "{bad}: {}", stderr(&output));
    }
}

#[test]
fn failed_generate_force_leaves_the_old_scenario_intact() {
    let dir = tempfile::tempdir().expect("temp dir");
    let old = dir.path().join("w.json");
    std::fs::write(&old, "old contents\n").expect("write");
    let output = under_write_limit(&["generate", "workspace", "--out", "w.json", "--force"], dir.path());
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert_eq!(std::fs::read_to_string(&old).expect("read"), "old contents\n");
    assert_eq!(
        std::fs::read_dir(dir.path()).expect("list").count(),
        1,
        "a temporary file was left behind"
    );
}

#[test]
fn without_the_mujoco_library_help_generate_and_rapier_runs_still_work() {
    let dir = tempfile::tempdir().expect("temp dir");
    let missing = dir.path().join("libmujoco.so.missing");
    let run = |args: &[&str]| {
        validate_design()
            .current_dir(repo())
            .env("MUJOCO_LIBRARY", &missing)
            .args(args)
            .output()
            .expect("runs")
    };
    assert_eq!(run(&["--help"]).status.code(), Some(0));
    let out = dir.path().join("c.json");
    let output = run(&["generate", "course", "--out", &out.to_string_lossy()]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let output = run(&[
        "designs/paper-real-world.json",
        "--engines",
        "rapier",
        "--mujoco-checks",
        "0",
        "--quiet",
    ]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let output = run(&["designs/paper-real-world.json", "--quiet"]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("needs MuJoCo 3.17.0") && stderr(&output).contains("pip install mujoco==3.17.0"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn the_binary_does_not_need_libmujoco_to_start() {
    let binary = assert_cmd::cargo::cargo_bin("validate-design");
    let output = std::process::Command::new("readelf")
        .arg("-d")
        .arg(&binary)
        .output()
        .expect("readelf runs");
    assert!(output.status.success());
    let dynamic = String::from_utf8_lossy(&output.stdout);
    assert!(dynamic.contains("(NEEDED)"), "{dynamic}");
    assert!(!dynamic.contains("libmujoco"), "{dynamic}");
}

#[test]
fn negative_option_values_name_the_option() {
    for (flag, value) in [("--seed", "-1"), ("--ik-seeds", "-3"), ("--threads", "-1"), ("--plan-budget", "-5")] {
        let output = validate_design()
            .current_dir(repo())
            .args(["designs/ur5e.json", flag, value])
            .output()
            .expect("runs");
        assert_eq!(output.status.code(), Some(2), "{flag}");
        assert!(stderr(&output).contains(flag), "{flag}: {}", stderr(&output));
    }
    let output = validate_design()
        .args([
            "generate",
            "workspace",
            "--count",
            "18446744073709551615",
            "--out",
            "/tmp/never-written.json",
        ])
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr(&output).contains("--count"), "{}", stderr(&output));
}

#[test]
fn a_device_as_design_or_scenario_is_refused_without_reading_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let design = dir.path().join("zero.json");
    std::os::unix::fs::symlink("/dev/zero", &design).expect("symlink");
    let output = validate_design()
        .timeout(Duration::from_secs(20))
        .arg(&design)
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("a device: expected a regular file"), "{}", stderr(&output));
    let output = validate_design()
        .timeout(Duration::from_secs(20))
        .arg(repo().join("designs/paper-real-world.json"))
        .args(["--scenario", "/dev/zero"])
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("/dev/zero") && stderr(&output).contains("a device"),
        "{}",
        stderr(&output)
    );
}
