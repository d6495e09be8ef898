//! The `validate-design` binary: exit codes and error messages on real and broken inputs.

mod common;

use assert_cmd::Command;
use common::{fixture, panda_urdf, repo};

fn validate_design() -> Command {
    let mut cmd = Command::cargo_bin("validate-design").expect("binary is built");
    cmd.current_dir(repo());
    cmd
}

/// Runs the binary on a broken fixture and returns stderr, asserting exit code 2.
fn error_for(name: &str, extra: &[&str]) -> String {
    let output = validate_design().arg(fixture(name)).args(extra).output().expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(2), "{name}: expected exit 2, stderr: {stderr}");
    assert!(stderr.contains(name), "{name}: the message must name the file: {stderr}");
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    stderr
}

#[test]
fn main_command_validates_the_paper_robot_on_the_course_and_passes() {
    let output = validate_design().arg("designs/paper-real-world.json").output().expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(stdout.contains("MuJoCo 3.17.0") && stdout.contains(": agree"), "{stdout}");
    assert!(
        stdout.contains("design paper-real-world (modular, 5 joints, hardware cost 1.00 m) on scenario course"),
        "{stdout}"
    );
    assert!(stdout.contains("trajectory: 36 of 36 goals on certified paths"), "{stdout}");
    assert!(
        stdout.contains("rapier: 36 goals held") && stdout.contains("mujoco: 36 goals held"),
        "{stdout}"
    );
    assert!(stdout.trim_end().ends_with("verdict: PASS"), "{stdout}");
}

#[test]
fn panda_loads_without_a_tip_and_with_one() {
    // No --tip: the fingers are gripper joints, the tip is the TCP frame, and both are said.
    let output = validate_design().arg(panda_urdf()).arg("--describe").output().expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        stdout.contains("panda (URDF, chain panda_link0 -> panda_hand_tcp, 7 joints)"),
        "{stdout}"
    );
    assert!(
        stdout
            .contains("joint `panda_finger_joint1` (line 334) is a gripper joint, not an arm joint: joint `panda_finger_joint2` mimics it"),
        "{stdout}"
    );
    assert!(
        stdout.contains("joint `panda_finger_joint2` (line 342) is a gripper joint, not an arm joint: it has <mimic"),
        "{stdout}"
    );
    assert!(
        stdout.contains("tip `panda_hand_tcp` (no --tip): the arm is the longest chain of movable joints from `panda_link0` that are not gripper joints (7 joints, to link `panda_link7`)"),
        "{stdout}"
    );

    // A full run says the same on stderr.
    let output = validate_design()
        .arg(panda_urdf())
        .args(["--reach-only", "--mujoco-checks", "0"])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("info: ") && stderr.contains("tip `panda_hand_tcp` (no --tip)"),
        "{stderr}"
    );

    let output = validate_design()
        .arg(panda_urdf())
        .args(["--tip", "panda_hand", "--mujoco-checks", "20", "--kinematics-only"])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        stdout.contains("panda (URDF, chain panda_link0 -> panda_hand, 7 joints)"),
        "{stdout}"
    );
    assert!(!stdout.contains("model choices"), "an explicit --tip chooses nothing: {stdout}");
}

/// The Panda's SRDF, as the tests give it.
const PANDA_SRDF: &str = "designs/urdf/example-robot-data/robots/panda_description/srdf/panda.srdf";

/// `--describe` of the Panda with its SRDF and `options`: it must succeed; its stdout.
fn describe_panda_with_srdf(options: &[&str]) -> String {
    let output = validate_design()
        .arg(panda_urdf())
        .args(options)
        .args(["--srdf", PANDA_SRDF, "--describe"])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    assert_eq!(
        output.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    stdout
}

#[test]
fn srdf_leaves_out_the_disabled_pairs_with_their_reasons() {
    let srdf = PANDA_SRDF;
    let stdout = describe_panda_with_srdf(&[]);
    assert!(
        stdout.contains(&format!("collision pairs disabled by {srdf} (18 model link pairs left out):")),
        "{stdout}"
    );
    assert!(
        stdout.contains("  panda_link0 - panda_link2: disabled in SRDF panda.srdf: panda_link0 - panda_link2 \"Never\" (line 48)"),
        "{stdout}"
    );
    // The hand and fingers are merged into panda_link7: their pairs become its pairs.
    assert!(
        stdout.contains("  panda_link3 - panda_link7: disabled in SRDF panda.srdf: panda_hand - panda_link3 \"Never\" (line 36)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("not applied: panda_hand - panda_link7 (line 40): both are part of model link `panda_link7`"),
        "{stdout}"
    );
    // The fingers against link5 are not disabled: link5 - link7 stays checked.
    assert!(
        stdout.contains("not applied: panda_link5 - panda_link7: the SRDF disables only some"),
        "{stdout}"
    );

    // In a run, the JSON report lists them with their reasons.
    let dir = tempfile::tempdir().expect("temp dir");
    let json = dir.path().join("report.json");
    let output = validate_design()
        .arg(panda_urdf())
        .args(["--srdf", srdf, "--reach-only", "--mujoco-checks", "0", "--json"])
        .arg(&json)
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.code().is_some_and(|c| c < 2), "{stderr}");
    assert!(stderr.contains("18 self-collision pairs left out"), "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).expect("report")).expect("JSON");
    let excluded = report["criteria"]["excluded_pairs"].as_array().expect("excluded pairs");
    assert!(
        excluded.iter().any(|p| p["a"] == "panda_link0"
            && p["b"] == "panda_link2"
            && p["reason"]
                .as_str()
                .is_some_and(|r| r.contains("disabled in SRDF panda.srdf") && r.contains("\"Never\""))),
        "{excluded:?}"
    );
    assert!(
        report["inputs"]["model_choices"].as_array().is_some_and(|c| c.len() == 3),
        "{}",
        report["inputs"]
    );
}

#[test]
fn srdf_of_the_whole_robot_applies_to_an_arm_cut_from_it() {
    // A whole robot's SRDF names links an arm chosen with --base leaves out: their pairs are
    // never checked, so they are noted, not refused.
    let stdout = describe_panda_with_srdf(&["--base", "panda_link2"]);
    assert!(
        stdout.contains(&format!("collision pairs disabled by {PANDA_SRDF} (11 model link pairs left out):")),
        "{stdout}"
    );
    assert!(
        stdout.contains(
            "  not applied: panda_link0 - panda_link1 (line 47): `panda_link0` is in the URDF but not in the arm checked, so the pair is never checked"
        ),
        "{stdout}"
    );
}

#[test]
fn srdf_errors_name_the_file_and_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let srdf = dir.path().join("typo.srdf");
    // Writes the SRDF, runs `--describe` with it, expects exit 2 and returns stderr.
    let refused = |robot: &std::path::Path, text: &str| {
        std::fs::write(&srdf, text).expect("write");
        let output = validate_design()
            .arg(robot)
            .arg("--srdf")
            .arg(&srdf)
            .arg("--describe")
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        stderr
    };
    let stderr = refused(
        &panda_urdf(),
        "<robot name=\"panda\">\n  <disable_collisions link1=\"panda_link0\" link2=\"panda_lnk1\" reason=\"Adjacent\"/>\n</robot>\n",
    );
    assert!(
        stderr.contains("typo.srdf: <disable_collisions link1=\"panda_link0\" link2=\"panda_lnk1\"> (line 2): no link named `panda_lnk1`")
            && stderr.contains("nor in its URDF"),
        "{stderr}"
    );
    let stderr = refused(&panda_urdf(), "<robot><disable_collisions link1=\"panda_link0\"/></robot>");
    assert!(stderr.contains("<disable_collisions> (line 1): has no link2 attribute"), "{stderr}");
    let stderr = refused(&panda_urdf(), "<robot><unclosed></robot>");
    assert!(stderr.contains("typo.srdf: the XML:"), "{stderr}");
    let stderr = refused(std::path::Path::new("designs/ur5e.json"), "<robot><unclosed></robot>");
    assert!(stderr.contains("--srdf: is for URDF input"), "{stderr}");
}

#[test]
fn rejects_unknown_mode() {
    let stderr = error_for("unknown_mode.json", &[]);
    assert!(stderr.contains("unknown mode `telescopic`") && stderr.contains("mode"), "{stderr}");
}

#[test]
fn rejects_nan_with_line() {
    let stderr = error_for("nan_parameter.json", &[]);
    assert!(stderr.contains("line 5"), "{stderr}");
}

#[test]
fn rejects_out_of_range_number_with_line() {
    let stderr = error_for("out_of_range_number.json", &[]);
    assert!(stderr.contains("line 4") && stderr.contains("out of range"), "{stderr}");
}

#[test]
fn rejects_economic_violation_naming_joint_parameter_and_allowed_set() {
    let stderr = error_for("economic_violation.json", &[]);
    assert!(
        stderr.contains("joint 2 (joints[1]): a = 0.45 is not economic; allowed {0} U [-0.4, -0.1] U [0.1, 0.4] m"),
        "{stderr}"
    );
}

#[test]
fn rejects_unknown_module_listing_the_catalog() {
    let stderr = error_for("unknown_module.json", &[]);
    assert!(
        stderr.contains("T-short") && stderr.contains("L-long") && stderr.contains("line 3"),
        "{stderr}"
    );
}

#[test]
fn rejects_missing_mesh_naming_link_uri_and_places() {
    let stderr = error_for("missing_mesh.urdf", &["--package-path", "/opt/robots"]);
    assert!(
        stderr.contains("link `arm`") && stderr.contains("package://nowhere_description/meshes/arm.stl"),
        "{stderr}"
    );
    assert!(stderr.contains("/opt/robots/nowhere_description/meshes/arm.stl"), "{stderr}");
}

#[test]
fn rejects_branching_tree_with_tied_chains() {
    let stderr = error_for("branching_tree.urdf", &[]);
    assert!(
        stderr.contains("tie at 2 joints, ending at left_lower, right_lower; choose one with --tip"),
        "{stderr}"
    );
}

#[test]
fn branching_tree_loads_with_a_tip() {
    let output = validate_design()
        .arg(fixture("branching_tree.urdf"))
        .args(["--tip", "left_lower", "--describe"])
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));
}

#[test]
fn rejects_unknown_link() {
    let stderr = error_for("unknown_parent_link.urdf", &[]);
    assert!(
        stderr.contains("joint `shoulder` (line 5) <parent>: no link named `bsae`"),
        "{stderr}"
    );
    let stderr = error_for("branching_tree.urdf", &["--tip", "left_hand"]);
    assert!(stderr.contains("--tip: no link named `left_hand`"), "{stderr}");
}

#[test]
fn rejects_revolute_joint_without_limit() {
    let stderr = error_for("revolute_without_limit.urdf", &[]);
    assert!(
        stderr.contains("joint `shoulder` (line 5)") && stderr.contains("has no <limit>"),
        "{stderr}"
    );
}

#[test]
fn rejects_moving_link_without_inertial() {
    let stderr = error_for("missing_inertial.urdf", &[]);
    assert!(
        stderr.contains("link `arm` is moved by joint `shoulder` but has no <inertial>; its mass would be 0"),
        "{stderr}"
    );
}

/// A kinematics-only URDF (no `<inertial>`, as ROS-Industrial's support packages ship) is
/// checked for reach with a warning naming the link; only the dynamics refuse it (above).
#[test]
fn reach_only_needs_no_inertial() {
    let output = validate_design()
        .arg(fixture("missing_inertial.urdf"))
        .arg("--reach-only")
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(matches!(output.status.code(), Some(0 | 1 | 3)), "{stderr}");
    assert!(
        stderr.contains("link `arm` (line") && stderr.contains("has no <inertial>: reach, IK and collisions are checked"),
        "{stderr}"
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("verdict: "), "{stdout}");
    // An MJCF export needs the mass: refused before any work, as every write is.
    let out = std::env::temp_dir().join(format!("pg-massless-{}.xml", std::process::id()));
    let stderr = error_for(
        "missing_inertial.urdf",
        &["--reach-only", "--export-mjcf", out.to_str().expect("utf-8 path")],
    );
    assert!(
        stderr.contains("link `arm` is moved by joint `shoulder` but has no inertial"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing written");
}

/// What ROS's parser reads in vendors' files is read here too: a placeholder box of size 0 0 0
/// (ignored, with a warning naming it) and two `<material>` in one `<visual>` (visuals unread).
#[test]
fn reads_vendor_quirks() {
    let output = validate_design()
        .arg(fixture("vendor_quirks.urdf"))
        .args(["--reach-only", "--describe"])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("link `base` (line 7) <collision> 0") && stderr.contains("every size is 0 (a placeholder): ignored"),
        "{stderr}"
    );
}

#[test]
fn rejects_inertia_breaking_triangle_inequality() {
    let stderr = error_for("bad_inertia.urdf", &[]);
    assert!(stderr.contains("link `arm`") && stderr.contains("triangle inequality"), "{stderr}");
    assert!(stderr.contains("short by 96.0 %"), "{stderr}");
    assert!(stderr.contains("the <inertial> of link `arm` (line 4)"), "{stderr}");
}

/// A vendor's inertia a few per cent short of the triangle inequality (pybullet_data's xArm 6
/// misses it by 0.7 and 13.5 %) is balanced with a warning, and `--strict` refuses it.
#[test]
fn balances_an_inertia_slightly_short_of_the_triangle_inequality_with_a_warning() {
    let output = validate_design()
        .arg(fixture("slightly_unbalanced_inertia.urdf"))
        .arg("--describe")
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("link `arm` <inertial>") && stderr.contains("short by 4.76 %") && stderr.contains("raised"),
        "{stderr}"
    );
    let strict = error_for("slightly_unbalanced_inertia.urdf", &["--describe", "--strict"]);
    assert!(strict.contains("short by 4.76 %"), "{strict}");
}

#[test]
fn rejects_link_with_two_parents() {
    let stderr = error_for("two_parents.urdf", &[]);
    assert!(stderr.contains("link `b` is the child of two joints, `j2` and `j3`"), "{stderr}");
}

#[test]
fn rejects_mimic_joint_on_the_chain() {
    // With no --tip a trailing mimic joint is a gripper joint; a tip below it puts it on the chain.
    let stderr = error_for("mimic_on_chain.urdf", &["--tip", "b"]);
    assert!(stderr.contains("joint `j2`") && stderr.contains("is a mimic joint"), "{stderr}");
    let output = validate_design()
        .arg(fixture("mimic_on_chain.urdf"))
        .arg("--describe")
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(stdout.contains("mimic (URDF, chain base -> a, 1 joints)"), "{stdout}");
    assert!(
        stdout.contains("joint `j2` (line 7) is a gripper joint, not an arm joint: it has <mimic joint=\"j1\">"),
        "{stdout}"
    );
}

#[test]
fn a_robot_file_has_no_paper_model_figures() {
    // The paper's capsules and hardware cost are defined for designs: for a URDF they would be a
    // phantom (capsules on joint frames colliding at every goal).
    let output = validate_design()
        .arg(panda_urdf())
        .args([
            "--reach-only",
            "--mujoco-checks",
            "0",
            "--scenario",
            "scenarios/cluttered/task-00.json",
        ])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("paper loss: not for a robot file"), "{stdout}");
    assert!(!stdout.contains("capsules collide"), "{stdout}");
    let rows: Vec<&str> = stdout.lines().filter(|l| l.starts_with(|c: char| c.is_ascii_digit())).collect();
    assert!(!rows.is_empty(), "{stdout}");
    // The capsule column (the fifth number) is `-` on every goal row.
    for row in rows {
        assert!(row.split_whitespace().any(|w| w == "-"), "{row}");
    }
}

#[test]
fn reads_a_urdf_saved_as_xml_as_the_urdf_it_is() {
    let dir = tempfile::tempdir().expect("temp dir");
    let copy = dir.path().join("arm.xml");
    std::fs::copy(repo().join("tests/fixtures/mimic_on_chain.urdf"), &copy).expect("copy");
    let output = validate_design().arg(&copy).arg("--describe").output().expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(stdout.contains("read as a URDF: its root element is <robot>"), "{stdout}");
}

#[test]
fn rejects_unknown_input_type_and_missing_file() {
    // Each names what the input is and what would be read instead.
    for (input, says) in [
        (
            "Cargo.toml",
            "Cargo.toml: unknown extension `.toml`; expected a design (.json), a Timor assembly (.json), a URDF (.urdf) or an MJCF (.xml, .mjcf) file",
        ),
        ("designs", "designs: is a directory; expected a design"),
        ("-", "-: a robot is not read from standard input: save it to a file"),
        (".ci/run", ".ci/run: no extension to tell the input type"),
    ] {
        let output = validate_design().arg(input).output().expect("runs");
        assert_eq!(output.status.code(), Some(2), "{input}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains(says), "{input}: {stderr}");
    }
    let output = validate_design().arg("designs/no-such-design.json").output().expect("runs");
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("cannot read design designs/no-such-design.json"));
}

#[test]
fn usage_errors_exit_2_and_help_lists_examples_and_exit_codes() {
    let output = validate_design().arg("--no-such-flag").output().expect("runs");
    assert_eq!(output.status.code(), Some(2));
    let output = validate_design().arg("--help").output().expect("runs");
    let help = String::from_utf8_lossy(&output.stdout);
    assert!(
        help.contains("Examples:") && help.contains("Exit codes:") && help.contains("--export-mjcf"),
        "{help}"
    );
}

#[test]
fn exports_are_written_and_never_over_an_input() {
    let dir = tempfile::tempdir().expect("temp dir");
    let urdf = dir.path().join("robot.urdf");
    let mjcf = dir.path().join("robot.xml");
    let output = validate_design()
        .arg("designs/ur5e.json")
        .args(["--describe", "--export-urdf"])
        .arg(&urdf)
        .arg("--export-mjcf")
        .arg(&mjcf)
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(std::fs::read_to_string(&urdf).expect("URDF written").contains("<robot"));
    assert!(std::fs::read_to_string(&mjcf).expect("MJCF written").contains("<mujoco"));

    let copy = dir.path().join("design.json");
    std::fs::copy(repo().join("designs/ur5e.json"), &copy).expect("copy");
    let before = std::fs::read(&copy).expect("read");
    let output = validate_design().arg(&copy).arg("--export-mjcf").arg(&copy).output().expect("runs");
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("refusing to write"));
    assert_eq!(std::fs::read(&copy).expect("read"), before, "the input must be untouched");
}

#[test]
fn strict_turns_warnings_into_errors() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("frozen.urdf");
    std::fs::write(
        &path,
        r#"<robot name="frozen"><link name="base"/><link name="arm"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
        <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><limit lower="0" upper="0" effort="1" velocity="1"/></joint></robot>"#,
    )
    .expect("write");
    let output = validate_design().arg(&path).arg("--describe").output().expect("runs");
    assert_eq!(output.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&output.stderr).contains("the joint cannot move"));
    let output = validate_design()
        .arg(&path)
        .args(["--describe", "--strict"])
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2));
    // The error lists the warning; it is not printed a second time as a warning.
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(stderr.matches("the joint cannot move").count(), 1, "{stderr}");
}

#[test]
fn package_uris_resolve_through_ros_package_path_and_relative_meshes_through_the_urdf_folder() {
    let packages = tempfile::tempdir().expect("temp dir");
    let meshes = packages.path().join("tetra_description/meshes");
    std::fs::create_dir_all(&meshes).expect("mkdir");
    std::fs::copy(fixture("meshes/tetrahedron.dae"), meshes.join("tetra.dae")).expect("copy");
    let elsewhere = tempfile::tempdir().expect("temp dir");
    std::fs::copy(fixture("meshes/tetrahedron.obj"), elsewhere.path().join("tip.obj")).expect("copy");
    let urdf = elsewhere.path().join("tetra.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="tetra"><link name="base"/>
        <link name="arm"><collision><geometry><mesh filename="package://tetra_description/meshes/tetra.dae" scale="2 2 2"/></geometry></collision>
          <collision><origin xyz="0 0 0.5"/><geometry><mesh filename="tip.obj"/></geometry></collision>
          <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
        <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#,
    )
    .expect("write");

    let output = validate_design()
        .arg(&urdf)
        .arg("--kinematics-only")
        .env("ROS_PACKAGE_PATH", packages.path())
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(
        stdout.contains("mesh package://tetra_description/meshes/tetra.dae (4 triangles)") && stdout.contains("mesh tip.obj"),
        "{stdout}"
    );

    let output = validate_design().arg(&urdf).env_remove("ROS_PACKAGE_PATH").output().expect("runs");
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("link `arm`: mesh `package://tetra_description/meshes/tetra.dae` not found"),
        "{stderr}"
    );

    let output = validate_design()
        .arg(&urdf)
        .arg("--package-path")
        .arg(packages.path())
        .arg("--kinematics-only")
        .env_remove("ROS_PACKAGE_PATH")
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));

    // A sweep takes the same roots, and names the missing package without them.
    let sweep = |extra: &[&std::ffi::OsStr]| {
        validate_design()
            .arg("sweep")
            .arg(&urdf)
            .args(["--scenarios", "scenarios/cluttered/task-00.json"])
            .args(extra)
            .env_remove("ROS_PACKAGE_PATH")
            .output()
            .expect("runs")
    };
    let output = sweep(&[]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("package `tetra_description`"), "{stderr}");
    let output = sweep(&["--package-path".as_ref(), packages.path().as_os_str()]);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));
}

#[test]
fn an_undecided_design_exits_3_with_the_reasons_and_the_json_report_says_why() {
    let dir = tempfile::tempdir().expect("temp dir");
    let json = dir.path().join("report.json");
    // The course's goals are z_symmetric: for a 6-joint arm a continuum of solutions; the ones
    // neither reached nor proven over the free turn are undecided, not failures.
    let output = validate_design()
        .args(["designs/modular-compact.json", "--engines", "none", "--json"])
        .arg(&json)
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(3),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let verdict = stdout.lines().last().unwrap_or_default();
    assert!(
        verdict.starts_with("verdict: UNDECIDED: ") && verdict.contains("undecided"),
        "{stdout}"
    );
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).expect("written")).expect("json");
    assert_eq!(report["schema_version"], 2);
    assert_eq!(report["verdict"]["passed"], false);
    assert_eq!(report["verdict"]["word"], "UNDECIDED");
    assert!(report["verdict"]["reasons"].as_array().is_some_and(|r| !r.is_empty()));
    assert!(report["goals"]
        .as_array()
        .is_some_and(|g| g.iter().any(|g| g["outcome"] == "undecided")));
    assert_eq!(report["criteria"]["position_m"], 0.001);
    // The course's home is the 5-joint paper robot's: the 6-joint arm starts from its own.
    assert!(
        report["findings"]
            .as_array()
            .is_some_and(|f| f.iter().any(|f| f["kind"] == "home_replaced")),
        "{report}"
    );
    assert!(report["engines"].as_array().is_some_and(Vec::is_empty));
}

#[test]
fn a_goal_proven_unreachable_fails_the_design_with_exit_1() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scenario = dir.path().join("far.json");
    std::fs::write(
        &scenario,
        r#"{"name": "far", "tolerance": "pose", "goals": [{"position": [3.0, 0.0, 0.5], "quaternion": [1.0, 0.0, 0.0, 0.0]}]}"#,
    )
    .expect("writes");
    let output = validate_design()
        .args(["designs/ur5e.json", "--engines", "none", "--scenario"])
        .arg(&scenario)
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(1),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let verdict = stdout.lines().last().unwrap_or_default();
    assert_eq!(verdict, "verdict: FAIL: 1 goal unreachable (proven)", "{stdout}");
}

#[test]
fn bad_options_exit_2_naming_what_is_wrong() {
    let output = validate_design()
        .args(["designs/ur5e.json", "--engines", "bullet"])
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("unknown engine `bullet`"));

    let dir = tempfile::tempdir().expect("temp dir");
    let copy = dir.path().join("course.json");
    std::fs::copy("scenarios/course.json", &copy).expect("copy");
    let output = validate_design()
        .args(["designs/paper-real-world.json", "--engines", "none", "--scenario"])
        .arg(&copy)
        .arg("--json")
        .arg(&copy)
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("this run read that file"));
}

#[test]
fn help_shows_every_option_in_an_example() {
    let output = validate_design().arg("--help").output().expect("runs");
    let help = String::from_utf8_lossy(&output.stdout);
    let (options, examples) = help.split_once("Examples:").expect("examples section");
    let names: Vec<&str> = options
        .split_whitespace()
        .filter(|word| word.starts_with("--") && word.len() > 2)
        .map(|word| word.trim_end_matches(|c: char| !c.is_ascii_alphanumeric()))
        .filter(|name| !["--help", "--version"].contains(name))
        .collect();
    assert!(names.len() >= 18, "{names:?}");
    for name in names {
        assert!(
            examples.contains(&format!("{name} ")) || examples.contains(&format!("{name}\n")),
            "no example uses {name}"
        );
    }
}

#[test]
fn option_values_out_of_range_exit_2_naming_the_option() {
    for (option, value) in [
        ("--margin", "NaN"),
        ("--margin", "-0.5"),
        ("--margin", "inf"),
        ("--contact-depth", "NaN"),
        ("--threads", "0"),
        ("--ik-seeds", "0"),
    ] {
        let output = validate_design()
            .args(["designs/ur5e.json", "--engines", "none", &format!("{option}={value}")])
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{option} {value}: {stderr}");
        assert!(stderr.contains(option), "{option} {value}: {stderr}");
    }
}

#[test]
fn describe_and_kinematics_only_conflict() {
    let output = validate_design()
        .args(["designs/ur5e.json", "--describe", "--kinematics-only"])
        .output()
        .expect("runs");
    assert_eq!(output.status.code(), Some(2));
}

#[test]
fn a_float32_design_passes_strict_and_says_what_was_snapped() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("generated.json");
    let alpha = f64::from(std::f32::consts::FRAC_PI_2);
    std::fs::write(
        &path,
        format!(r#"{{"mode": "economic", "joints": [{{"d": 0.15, "a": 0, "alpha": {alpha}}}, {{"d": 0, "a": 0.4, "alpha": 0}}]}}"#),
    )
    .expect("write");
    let sentence =
        "joints[0].alpha = 1.5707963705062866 snapped to pi/2 (1.5707963267948966) (within 1e-6; a float32 generator's rounding)";
    let output = validate_design()
        .arg(&path)
        .args(["--describe", "--strict"])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0), "a snap is not a warning: {stdout}");
    assert!(stdout.contains(&format!("model choices:\n  {sentence}")), "{stdout}");
    // A run prints it on stderr, naming the file.
    let output = validate_design()
        .arg(&path)
        .args(["--strict", "--reach-only", "--scenario", "scenarios/cluttered/task-03.json"])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_ne!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains(&format!("info: {}: {sentence}", path.display())), "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
}
