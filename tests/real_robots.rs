//! Real robots load right with no flags: the default tip follows fixed joints to the tool frame
//! the authors named, gripper joints are not arm joints, an SRDF's disabled pairs map onto the
//! merged links, and MJCF input takes `--tip` and reads `ctrlrange` x `gear` as ratings.

mod common;

use common::{panda_urdf, repo};
use proving_ground::model::{from_urdf, from_urdf_str, ModelSource, UrdfOptions};
use std::path::Path;

fn ur5_urdf() -> std::path::PathBuf {
    repo().join("tests/fixtures/urdf/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf")
}

fn tip_and_choices(source: &ModelSource) -> (String, Vec<String>) {
    match source {
        ModelSource::Urdf { tip_link, choices, .. } => (tip_link.clone(), choices.clone()),
        ModelSource::Mjcf { tip_body, choices, .. } => (tip_body.clone(), choices.clone()),
        ModelSource::Design { .. } | ModelSource::Timor { .. } => panic!("not a URDF or MJCF file"),
    }
}

#[test]
fn ur5_default_tip_is_tool0_not_ee_link() {
    let model = from_urdf(&ur5_urdf(), &UrdfOptions::default()).expect("the UR5 loads");
    assert_eq!(model.dof(), 6);
    let (tip, choices) = tip_and_choices(&model.source);
    assert_eq!(tip, "tool0");
    assert_eq!(model.links.last().map(|l| l.name.as_str()), Some("wrist_3_link"));
    assert!(model.links[6].merged.iter().any(|m| m == "ee_link"), "{:?}", model.links[6].merged);
    assert_eq!(choices.len(), 1, "{choices:?}");
    assert!(
        choices[0].starts_with("tip `tool0` (no --tip): the arm is the longest chain of movable joints from `world`")
            && choices[0].contains("6 joints, to link `wrist_3_link`"),
        "{choices:?}"
    );
    // The tool frame is tool0's: the same as asking for it.
    let asked = from_urdf(
        &ur5_urdf(),
        &UrdfOptions {
            tip_link: Some("tool0".into()),
            ..UrdfOptions::default()
        },
    )
    .expect("loads");
    assert!((asked.last_from_tool.to_homogeneous() - model.last_from_tool.to_homogeneous()).norm() < 1e-12);
    assert!(tip_and_choices(&asked.source).1.is_empty());
}

#[test]
fn panda_default_is_the_seven_joint_arm_to_the_tcp() {
    let model = from_urdf(&panda_urdf(), &UrdfOptions::default()).expect("the Panda loads with no --tip");
    assert_eq!(model.dof(), 7);
    assert!(model.joints.iter().all(|j| !j.name.contains("finger")));
    let (tip, choices) = tip_and_choices(&model.source);
    assert_eq!(tip, "panda_hand_tcp");
    let last = model.links.last().expect("links");
    for part in ["panda_hand", "panda_leftfinger", "panda_rightfinger"] {
        assert!(last.merged.iter().any(|m| m == part), "{part}: {:?}", last.merged);
    }
    assert_eq!(choices.len(), 3, "{choices:?}");
    assert!(choices[0].contains("`panda_finger_joint1`") && choices[0].contains("joint `panda_finger_joint2` mimics it"));
    assert!(choices[1].contains("`panda_finger_joint2`") && choices[1].contains("<mimic joint=\"panda_finger_joint1\">"));
    assert!(choices[2].starts_with("tip `panda_hand_tcp`"), "{choices:?}");

    // The TCP is 0.1034 m beyond the hand along its z axis.
    let hand = from_urdf(
        &panda_urdf(),
        &UrdfOptions {
            tip_link: Some("panda_hand".into()),
            ..UrdfOptions::default()
        },
    )
    .expect("loads");
    let q = vec![0.0; 7];
    let (tcp, hand) = (model.tool_pose(&q), hand.tool_pose(&q));
    let offset = hand.inverse() * tcp;
    assert!((offset.translation.vector - nalgebra::Vector3::new(0.0, 0.0, 0.1034)).norm() < 1e-9);
}

/// A 2-joint arm ending in `flange`, with whatever `extra` hangs from `link2`.
fn arm_with(extra: &str) -> String {
    let inertial = r#"<inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>"#;
    let limit = r#"<limit lower="-1" upper="1" effort="10" velocity="1"/>"#;
    format!(
        r#"<robot name="arm">
  <link name="base"/>
  <link name="link1">{inertial}</link>
  <link name="link2">{inertial}</link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/><axis xyz="0 0 1"/>{limit}</joint>
  <joint name="j2" type="revolute"><parent link="link1"/><child link="link2"/><origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>{limit}</joint>
  {extra}
</robot>"#
    )
}

fn load(text: &str) -> proving_ground::model::Model {
    from_urdf_str(text, Path::new("arm.urdf"), &UrdfOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn gripper_joints_by_name_by_branching_and_by_mimic() {
    let inertial = r#"<inertial><mass value="0.1"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>"#;
    let limit = r#"<limit lower="0" upper="0.04" effort="10" velocity="1"/>"#;
    // Z1-style: one gripper joint at the end, named so.
    let z1 = arm_with(&format!(
        r#"<link name="gripperMover">{inertial}</link>
  <joint name="jointGripper" type="revolute"><parent link="link2"/><child link="gripperMover"/><axis xyz="0 1 0"/>{limit}</joint>"#
    ));
    let model = load(&z1);
    assert_eq!(model.dof(), 2);
    let (tip, choices) = tip_and_choices(&model.source);
    assert_eq!(tip, "link2");
    assert!(
        choices[0].contains("joint `jointGripper` (line 8) is a gripper joint") && choices[0].contains("its name has `gripper`"),
        "{choices:?}"
    );
    assert!(
        choices[1].contains("no link fixed below it is named like a tool frame"),
        "{choices:?}"
    );

    // Two unnamed prismatic joints branching from the last moving body: fingers.
    let pair = arm_with(&format!(
        r#"<link name="a">{inertial}</link><link name="b">{inertial}</link>
  <joint name="left" type="prismatic"><parent link="link2"/><child link="a"/><axis xyz="0 1 0"/>{limit}</joint>
  <joint name="right" type="prismatic"><parent link="link2"/><child link="b"/><axis xyz="0 -1 0"/>{limit}</joint>"#
    ));
    let model = load(&pair);
    assert_eq!(model.dof(), 2);
    let (_, choices) = tip_and_choices(&model.source);
    assert!(
        choices[0].contains("it and joint `right` branch from the body joint `j2` moves"),
        "{choices:?}"
    );
    assert!(choices[1].contains("it and joint `left` branch"), "{choices:?}");

    // One unnamed, unmimicked joint at the end is an arm joint, as before.
    let third = arm_with(&format!(
        r#"<link name="a">{inertial}</link>
  <joint name="j3" type="prismatic"><parent link="link2"/><child link="a"/><axis xyz="0 1 0"/>{limit}</joint>"#
    ));
    assert_eq!(load(&third).dof(), 3);

    // A turning wrist whose link is called `gripper` (its joint's own name says nothing) stays
    // on the arm, and the choice says it was considered.
    let wrist = arm_with(&format!(
        r#"<link name="gripper">{inertial}</link>
  <joint name="wrist_3" type="revolute"><parent link="link2"/><child link="gripper"/><axis xyz="0 1 0"/>{limit}</joint>"#
    ));
    let model = load(&wrist);
    assert_eq!(model.dof(), 3);
    let (tip, choices) = tip_and_choices(&model.source);
    assert_eq!(tip, "gripper");
    assert!(
        choices.iter().any(|c| c.contains("joint `wrist_3` (line 8) (link `gripper`) is named like a gripper's (`gripper`) but kept as an arm joint")),
        "{choices:?}"
    );

    // A fixed tool frame below a gripper joint is not the arm's tool frame; a flange fixed
    // below the arm is.
    let flange = arm_with(&format!(
        r#"<link name="flange"/><link name="finger">{inertial}</link><link name="finger_tcp"/>
  <joint name="f" type="fixed"><parent link="link2"/><child link="flange"/><origin xyz="0 0 0.1"/></joint>
  <joint name="g" type="prismatic"><parent link="flange"/><child link="finger"/><axis xyz="0 1 0"/>{limit}</joint>
  <joint name="t" type="fixed"><parent link="finger"/><child link="finger_tcp"/></joint>"#
    ));
    let model = load(&flange);
    assert_eq!((model.dof(), tip_and_choices(&model.source).0.as_str()), (2, "flange"));
    assert!((model.last_from_tool.translation.vector.z - 0.1).abs() < 1e-12);

    // Two tool frames of the same rank: the arm's last link, and the tie said.
    let tied = arm_with(
        r#"<link name="left_tcp"/><link name="right_tcp"/>
  <joint name="l" type="fixed"><parent link="link2"/><child link="left_tcp"/></joint>
  <joint name="r" type="fixed"><parent link="link2"/><child link="right_tcp"/></joint>"#,
    );
    let (tip, choices) = tip_and_choices(&load(&tied).source);
    assert_eq!(tip, "link2");
    assert!(
        choices[0].contains("tie (left_tcp, right_tcp): choose one with --tip"),
        "{choices:?}"
    );
}

#[test]
fn srdf_pairs_map_onto_merged_links() {
    let model = from_urdf(&panda_urdf(), &UrdfOptions::default()).expect("loads");
    let srdf = repo().join("designs/urdf/example-robot-data/robots/panda_description/srdf/panda.srdf");
    let exclusions = proving_ground::srdf::exclusions(&srdf, &model).expect("the Panda SRDF reads");
    assert_eq!(exclusions.pairs.len(), 18);
    assert!(exclusions
        .pairs
        .iter()
        .all(|p| p.a != p.b && p.reason.starts_with("disabled in SRDF panda.srdf: ")));
    let link7 = exclusions
        .pairs
        .iter()
        .find(|p| p.a == "panda_link4" && p.b == "panda_link7")
        .expect("link4 - link7 covers the hand and fingers");
    assert!(
        link7.reason.contains("panda_hand - panda_link4 \"Never\" (line 37)"),
        "{}",
        link7.reason
    );
    // Notes: 6 pairs inside panda_link7, and link5 - link7 only partly disabled.
    assert_eq!(exclusions.notes.len(), 7, "{:?}", exclusions.notes);
    assert!(!exclusions.pairs.iter().any(|p| p.a == "panda_link5" && p.b == "panda_link7"));
}

fn arm_with_flange() -> std::path::PathBuf {
    repo().join("tests/fixtures/mjcf/arm_with_flange.xml")
}

#[test]
fn mjcf_default_tool_frame_is_the_tcp_site_and_fingers_are_not_arm_joints() {
    let model = proving_ground::model::from_mjcf(&arm_with_flange()).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["j1", "j2", "j3"]);
    let (tip, choices) = tip_and_choices(&model.source);
    assert_eq!(tip, "link3");
    for part in ["flange", "left_pad", "right_pad"] {
        assert!(
            model.links[3].merged.iter().any(|m| m == part),
            "{part}: {:?}",
            model.links[3].merged
        );
    }
    assert_eq!(choices.len(), 3, "{choices:?}");
    assert!(
        choices[0].starts_with("joint `left_slide` of body `left_pad` is a gripper joint, not an arm joint: an <equality joint> couples it to joint `right_slide`"),
        "{choices:?}"
    );
    assert!(choices[2].starts_with("tool frame: site `tcp` (no --tip)"), "{choices:?}");
    // The tcp site: 0.1 m to the flange, 0.12 m beyond it, z along the arm.
    let expected = nalgebra::Isometry3::from_parts(
        nalgebra::Translation3::new(0.22, 0.0, 0.0),
        nalgebra::UnitQuaternion::from_euler_angles(0.0, std::f64::consts::FRAC_PI_2, 0.0),
    );
    assert!(
        (model.last_from_tool.to_homogeneous() - expected.to_homogeneous()).norm() < 1e-9,
        "{}",
        model.last_from_tool
    );
}

#[test]
fn mjcf_ratings_come_from_ctrlrange_times_gear() {
    let model = proving_ground::model::from_mjcf(&arm_with_flange()).unwrap_or_else(|e| panic!("{e}"));
    let ratings: Vec<Option<f64>> = model.joints.iter().map(|j| j.max_effort).collect();
    // j1: 2 x 50; j2: 1.5 x 80; j3: the forcerange 0.5 bounds the control's 1 before the gear 10.
    assert_eq!(ratings, [Some(100.0), Some(120.0), Some(5.0)]);
}

#[test]
fn mjcf_tip_takes_a_body_or_a_site() {
    use proving_ground::model::from_mjcf_to;
    // A site halfway: the chain ends at its body, the rest of the arm is held still and said.
    let model = from_mjcf_to(&arm_with_flange(), Some("marker")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(model.dof(), 2);
    assert!((model.last_from_tool.translation.vector - nalgebra::Vector3::new(0.15, 0.0, 0.05)).norm() < 1e-12);
    let (tip, choices) = tip_and_choices(&model.source);
    assert_eq!(tip, "link2");
    assert!(choices[0].contains("joint `j3` of body `link3` is not on the chain"), "{choices:?}");
    // A body: its frame.
    let model = from_mjcf_to(&arm_with_flange(), Some("flange")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(model.dof(), 3);
    assert!((model.last_from_tool.translation.vector - nalgebra::Vector3::new(0.1, 0.0, 0.0)).norm() < 1e-12);
    // Unknown names are errors listing bodies and sites; a body nothing moves has no chain.
    let error = from_mjcf_to(&arm_with_flange(), Some("nope")).expect_err("unknown").to_string();
    assert!(
        error.contains("--tip: no body or site named `nope`") && error.contains("`flange`") && error.contains("`tcp`"),
        "{error}"
    );
    let error = from_mjcf_to(&arm_with_flange(), Some("base"))
        .expect_err("nothing moves")
        .to_string();
    assert!(error.contains("no joint moves body `base`"), "{error}");
}

#[test]
fn mjcf_tip_on_the_command_line() {
    let output = assert_cmd::Command::cargo_bin("validate-design")
        .expect("binary")
        .current_dir(repo())
        .args([
            "tests/fixtures/mjcf/arm_with_flange.xml",
            "--tip",
            "tcp",
            "--mujoco-checks",
            "10",
            "--kinematics-only",
        ])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(stdout.contains("arm_with_flange (MJCF, chain base -> link3, 3 joints)"), "{stdout}");
    assert!(stdout.contains("rated 120.0"), "{stdout}");
    assert!(
        stdout.contains("tool pose at q = 0: position [0.5200, 0.0000, 0.4000] m, rpy [0.0000, 1.5708, 0.0000]"),
        "{stdout}"
    );
}

#[test]
fn an_explicit_tip_keeps_the_old_chain_rules() {
    // A finger as the tip: its joint is on the chain like any other (8 joints), nothing chosen.
    let model = from_urdf(
        &panda_urdf(),
        &UrdfOptions {
            tip_link: Some("panda_leftfinger".into()),
            ..UrdfOptions::default()
        },
    )
    .expect("loads");
    assert_eq!(model.dof(), 8);
    assert!(tip_and_choices(&model.source).1.is_empty());
    // The mimic finger on the chain is refused, as before.
    let error = from_urdf(
        &panda_urdf(),
        &UrdfOptions {
            tip_link: Some("panda_rightfinger".into()),
            ..UrdfOptions::default()
        },
    )
    .expect_err("mimic on the chain");
    assert!(error.to_string().contains("joint `panda_finger_joint2`") && error.to_string().contains("is a mimic joint"));
    // MJCF chains that tie name both ends and ask for --tip.
    let error = proving_ground::model::from_mjcf(&repo().join("tests/fixtures/mjcf/branching_chain.xml"))
        .expect_err("tie")
        .to_string();
    assert!(
        error.contains("branch at body `base`")
            && error.contains("`left_arm`, `right_arm`")
            && error.contains("choose the chain's end with --tip"),
        "{error}"
    );
}

/// A URDF whose links carry only `<visual>` geometry (the iiwa 14 converted from MuJoCo
/// Menagerie, for one) is checked against nothing: the model says so, and stops saying so
/// once one moving link has a `<collision>`.
#[test]
fn an_arm_without_collision_geometry_is_named_in_a_warning() {
    let said = |model: &proving_ground::model::Model| {
        model
            .diagnostics
            .iter()
            .any(|d| d.message.contains("no link the joints move has <collision> geometry"))
    };
    let bare = load(&arm_with(""));
    assert!(said(&bare), "{:?}", bare.diagnostics);
    let shape = r#"<collision><geometry><cylinder radius="0.03" length="0.2"/></geometry></collision>"#;
    let text = arm_with("").replace(r#"<link name="link2">"#, &format!(r#"<link name="link2">{shape}"#));
    let with = load(&text);
    assert!(!said(&with), "{:?}", with.diagnostics);
}
