//! MJCF input: every shipped robot exported to MJCF and read back through MuJoCo must be the
//! same robot (kinematics, limits, mass properties, collision geometry); MuJoCo's own forward
//! kinematics is the oracle for MJCF features our exporter never writes (joint anchors off the
//! body origin, jointless bodies, sites); broken files exit 2 naming the file and the element.

mod common;

use assert_cmd::Command;
use common::{fixture, repo, shipped_models};
use proving_ground::engine::MujocoKinematics;
use proving_ground::export::{to_mjcf, MjcfOptions};
use proving_ground::frames::pose_difference;
use proving_ground::model::{from_mjcf, Collider, JointKind, Model, ModelError, ModelSource, Shape};
use rand::SeedableRng;
use std::path::Path;

/// Export then read back: MuJoCo compiles the same f64 numbers, re-normalising quaternions and
/// diagonalising inertias, so only rounding is left. Worst measured: see the final report.
const ROUND_TRIP: f64 = 1e-9;
/// Mesh vertices: MuJoCo keeps its own copy in f32 (relative 6e-8 of coordinates up to ~0.2 m).
const MESH_VERTEX_M: f64 = 1e-6;
const CONFIGURATIONS: usize = 100;
const SEED: u64 = 11;

/// Largest differences seen over the round trips, for the record.
#[derive(Debug, Default)]
struct Worst {
    pose_m: f64,
    pose_rad: f64,
    limit: f64,
    mass_relative: f64,
    inertia_relative: f64,
    com_m: f64,
    collider_pose: f64,
    collider_size: f64,
    mesh_vertex_m: f64,
}

fn read_back(id: &str, model: &Model, dir: &Path) -> Model {
    let text = to_mjcf(model, &MjcfOptions::default()).unwrap_or_else(|e| panic!("{id}: {e}"));
    let path = dir.join(format!("{id}.xml"));
    std::fs::write(&path, &text).expect("write MJCF");
    from_mjcf(&path).unwrap_or_else(|e| panic!("{id}: {e}"))
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

fn compare_collider(id: &str, link: &str, a: &Collider, b: &Collider, worst: &mut Worst) {
    let (dt, da) = pose_difference(&a.link_from_shape, &b.link_from_shape);
    worst.collider_pose = worst.collider_pose.max(dt).max(da);
    let size = |s: &Shape| -> Vec<f64> {
        match s {
            Shape::Sphere { radius } => vec![*radius],
            Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => vec![*radius, *length],
            Shape::Box { half_extents } => half_extents.to_vec(),
            Shape::Mesh(_) => vec![],
        }
    };
    assert_eq!(a.shape.kind(), b.shape.kind(), "{id}: link {link}: collider `{}`", a.label);
    for (x, y) in size(&a.shape).iter().zip(size(&b.shape)) {
        worst.collider_size = worst.collider_size.max((x - y).abs());
    }
    if let (Shape::Mesh(ma), Shape::Mesh(mb)) = (&a.shape, &b.shape) {
        // Vertices are compared in the link frame, so a wrong mesh frame shows here too.
        let in_link = |c: &Collider, v: &[f64; 3]| c.link_from_shape * nalgebra::Point3::from(*v);
        assert_eq!(ma.triangles.len(), mb.triangles.len(), "{id}: link {link}: `{}` triangles", a.label);
        if ma.vertices.len() == mb.vertices.len() {
            for (va, vb) in ma.vertices.iter().zip(&mb.vertices) {
                worst.mesh_vertex_m = worst.mesh_vertex_m.max((in_link(a, va) - in_link(b, vb)).norm());
            }
        } else {
            // MuJoCo merged duplicate vertices: every vertex must still have its twin.
            for vb in &mb.vertices {
                let nearest = ma
                    .vertices
                    .iter()
                    .map(|va| (in_link(a, va) - in_link(b, vb)).norm())
                    .fold(f64::INFINITY, f64::min);
                worst.mesh_vertex_m = worst.mesh_vertex_m.max(nearest);
            }
        }
    }
}

#[test]
fn shipped_robots_survive_an_mjcf_round_trip_through_mujoco() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut worst = Worst::default();
    for (id, model) in shipped_models() {
        let back = read_back(&id, &model, dir.path());
        assert_eq!(back.dof(), model.dof(), "{id}");
        assert_eq!(back.links.len(), model.links.len(), "{id}");
        assert!(back.diagnostics.is_empty(), "{id}: {:?}", back.diagnostics);
        assert_eq!(
            back.source,
            ModelSource::Mjcf {
                path: dir.path().join(format!("{id}.xml")),
                base_body: model.links[0].name.clone(),
                tip_body: model.links[model.dof()].name.clone(),
                choices: back.source.choices().to_vec(),
            },
            "{id}"
        );
        // The export marks its tool frame with the `tool` site, and the reader says it used it.
        assert!(
            matches!(back.source.choices(), [only] if only.starts_with("tool frame: site `tool` (no --tip")),
            "{id}: {:?}",
            back.source.choices()
        );

        // Kinematics: every link and the tool at seeded random configurations.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(SEED);
        let (mut ws, mut back_ws) = (model.workspace(), back.workspace());
        for _ in 0..CONFIGURATIONS {
            let q = model.random_configuration(&mut rng);
            model.forward(&q, &mut ws);
            back.forward(&q, &mut back_ws);
            let pairs = ws.link_in_world.iter().zip(&back_ws.link_in_world);
            for (i, (a, b)) in pairs.chain([(&ws.tool_in_world, &back_ws.tool_in_world)]).enumerate() {
                let (dt, da) = pose_difference(a, b);
                worst.pose_m = worst.pose_m.max(dt);
                worst.pose_rad = worst.pose_rad.max(da);
                assert!(
                    dt <= ROUND_TRIP && da <= ROUND_TRIP,
                    "{id}: frame {i} (links, then the tool) differs by {dt} m, {da} rad at q = {q:?} (seed {SEED})"
                );
            }
        }

        for (a, b) in model.joints.iter().zip(&back.joints) {
            assert_eq!(a.name, b.name, "{id}");
            assert_eq!(a.kind, b.kind, "{id}: joint {}", a.name);
            match (a.limits, b.limits) {
                (Some(x), Some(y)) => {
                    worst.limit = worst.limit.max((x[0] - y[0]).abs()).max((x[1] - y[1]).abs());
                }
                (x, y) => assert_eq!(x, y, "{id}: joint {} limits", a.name),
            }
        }

        for (a, b) in model.links.iter().zip(&back.links) {
            assert_eq!(a.name, b.name, "{id}");
            match (&a.inertial, &b.inertial) {
                (Some(ma), Some(mb)) => {
                    worst.mass_relative = worst.mass_relative.max(relative(ma.mass, mb.mass));
                    worst.com_m = worst.com_m.max((ma.com - mb.com).norm());
                    let scale = ma.inertia.abs().max();
                    worst.inertia_relative = worst.inertia_relative.max((ma.inertia - mb.inertia).abs().max() / scale);
                }
                // The base is static: the exporter may leave its mass out.
                (_, None) | (None, _) if a.name == model.links[0].name => {}
                (x, y) => panic!("{id}: link {}: inertial {x:?} became {y:?}", a.name),
            }
            assert_eq!(a.colliders.len(), b.colliders.len(), "{id}: link {} colliders", a.name);
            for (ca, cb) in a.colliders.iter().zip(&b.colliders) {
                compare_collider(&id, &a.name, ca, cb, &mut worst);
            }
        }
    }
    eprintln!("worst round-trip differences: {worst:?}");
    assert!(worst.limit <= ROUND_TRIP, "{worst:?}");
    assert!(
        worst.mass_relative <= ROUND_TRIP && worst.inertia_relative <= ROUND_TRIP,
        "{worst:?}"
    );
    assert!(worst.com_m <= ROUND_TRIP, "{worst:?}");
    assert!(worst.collider_pose <= ROUND_TRIP && worst.collider_size <= ROUND_TRIP, "{worst:?}");
    assert!(worst.mesh_vertex_m <= MESH_VERTEX_M, "{worst:?}");
}

/// An MJCF with what our exporter never writes: joint anchors off the body origin, a jointless
/// body between two moving ones, Euler angles in degrees, `fromto` capsules, a visual-only geom,
/// a floor plane, an ellipsoid, a mesh file and a `tool` site on a jointless end body.
fn hand_written_mjcf() -> String {
    let mesh = repo().join("tests/fixtures/meshes/tetrahedron.obj");
    format!(
        r#"<mujoco model="hand_written">
  <compiler angle="degree"/>
  <asset><mesh name="tetra" file="{}" scale="0.5 0.5 0.5"/></asset>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="pedestal" pos="0.2 -0.1 0.05" euler="0 0 30">
      <geom type="cylinder" size="0.08 0.05" mass="3"/>
      <body name="upper_arm" pos="0 0 0.1" euler="10 0 0">
        <joint name="shoulder" type="hinge" axis="0 1 1" pos="0.02 0.03 -0.01" range="-90 90"/>
        <geom type="capsule" fromto="0 0 0 0.1 0 0.3" size="0.03" mass="1.2"/>
        <geom type="sphere" size="0.2" contype="0" conaffinity="0" mass="0"/>
        <body name="bracket" pos="0.1 0 0.3" euler="0 20 0">
          <geom type="box" size="0.02 0.03 0.04" pos="0.01 0 0" mass="0.3"/>
          <body name="forearm" pos="0 0.05 0.02">
            <joint name="elbow" type="slide" axis="1 0 0" pos="0.1 0 0" range="-0.05 0.1"/>
            <geom type="mesh" mesh="tetra" pos="0.05 0 0" euler="0 0 45" mass="0.4"/>
            <geom type="ellipsoid" size="0.03 0.02 0.01" mass="0.1"/>
            <body name="hand" pos="0.2 0 0">
              <joint name="wrist" type="hinge" axis="1 0 0"/>
              <inertial pos="0.01 0 0" mass="0.5" diaginertia="0.001 0.002 0.0025"/>
              <body name="flange" pos="0.05 0 0" quat="0.9 0.1 0.3 0.2">
                <geom type="cylinder" size="0.02 0.01" mass="0.05"/>
                <site name="tool" pos="0 0 0.03" euler="0 90 0"/>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>"#,
        mesh.display()
    )
}

#[test]
fn hand_written_mjcf_agrees_with_mujocos_own_kinematics() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("hand_written.xml");
    std::fs::write(&path, hand_written_mjcf()).expect("write MJCF");
    let model = from_mjcf(&path).unwrap_or_else(|e| panic!("{e}"));

    assert_eq!(model.name, "hand_written");
    let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["shoulder", "elbow", "wrist"]);
    let kinds: Vec<JointKind> = model.joints.iter().map(|j| j.kind).collect();
    assert_eq!(kinds, [JointKind::Revolute, JointKind::Prismatic, JointKind::Continuous]);
    let shoulder = model.joints[0].limits.expect("limited");
    assert!(
        (shoulder[0] + std::f64::consts::FRAC_PI_2).abs() < 1e-15,
        "degrees become radians: {shoulder:?}"
    );
    let link_names: Vec<&str> = model.links.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(link_names, ["pedestal", "upper_arm", "forearm", "hand"]);
    assert_eq!(model.links[1].merged, ["bracket"]);
    assert_eq!(model.links[3].merged, ["flange"]);
    // The floor is ignored, the visual sphere skipped, the ellipsoid becomes a sphere.
    let kinds = |i: usize| model.links[i].colliders.iter().map(|c| c.shape.kind()).collect::<Vec<_>>();
    assert_eq!(kinds(0), ["cylinder"]);
    assert_eq!(kinds(1), ["capsule", "box"]);
    assert_eq!(kinds(2), ["mesh", "sphere"]);
    assert_eq!(kinds(3), ["cylinder"]);
    assert_eq!(model.diagnostics.len(), 1, "{:?}", model.diagnostics);
    assert!(model.diagnostics[0].message.contains("ellipsoid"), "{:?}", model.diagnostics);
    // Masses: every body's, merged bodies included, and MuJoCo's own total.
    let total: f64 = model.links.iter().filter_map(|l| l.inertial.as_ref()).map(|m| m.mass).sum();
    assert!((total - (3.0 + 1.2 + 0.3 + 0.4 + 0.1 + 0.5 + 0.05)).abs() < 1e-12, "{total}");

    // MuJoCo's body frames are our link frames moved back to the body origin, and its site is
    // our tool frame, at any configuration.
    let bodies = ["pedestal", "upper_arm", "forearm", "hand"];
    let anchors = [[0.0; 3], [0.02, 0.03, -0.01], [0.1, 0.0, 0.0], [0.0; 3]];
    let mujoco = MujocoKinematics::from_file(&path, &names).expect("MuJoCo loads it");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(SEED);
    let mut ws = model.workspace();
    let mut worst: f64 = 0.0;
    for _ in 0..CONFIGURATIONS {
        let q = model.random_configuration(&mut rng);
        model.forward(&q, &mut ws);
        let sample = mujoco.sample(&q, &bodies, Some("tool")).expect("sample");
        for (i, (theirs, anchor)) in sample.bodies.iter().zip(anchors).enumerate() {
            let ours = ws.link_in_world[i] * nalgebra::Translation3::new(-anchor[0], -anchor[1], -anchor[2]);
            let (dt, da) = pose_difference(&ours, theirs);
            worst = worst.max(dt).max(da);
            assert!(
                dt <= ROUND_TRIP && da <= ROUND_TRIP,
                "body {} at q = {q:?}: {dt} m, {da} rad",
                bodies[i]
            );
        }
        let (dt, da) = pose_difference(&ws.tool_in_world, &sample.site.expect("tool site"));
        worst = worst.max(dt).max(da);
        assert!(dt <= ROUND_TRIP && da <= ROUND_TRIP, "tool at q = {q:?}: {dt} m, {da} rad");
    }
    eprintln!("hand-written MJCF vs MuJoCo: worst {worst:e}");
}

#[test]
fn tool_defaults_to_the_last_moving_body_frame() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("no_site.xml");
    // Without the `tool` site the body named `flange` is the tool frame (named like one) ...
    let text = hand_written_mjcf().replace(r#"<site name="tool" pos="0 0 0.03" euler="0 90 0"/>"#, "");
    std::fs::write(&path, &text).expect("write MJCF");
    let model = from_mjcf(&path).unwrap_or_else(|e| panic!("{e}"));
    let flange = nalgebra::Isometry3::from_parts(
        nalgebra::Translation3::new(0.05, 0.0, 0.0),
        nalgebra::UnitQuaternion::new_normalize(nalgebra::Quaternion::new(0.9, 0.1, 0.3, 0.2)),
    );
    assert!((model.last_from_tool.to_homogeneous() - flange.to_homogeneous()).norm() < 1e-12);
    // ... and with no body or site named like a tool frame, the last moving body's frame.
    std::fs::write(&path, text.replace(r#"<body name="flange""#, r#"<body name="cap""#)).expect("write MJCF");
    let model = from_mjcf(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(model.last_from_tool, nalgebra::Isometry3::identity());
    // The elbow's anchor is off its body origin: the default tool is the body frame, not the link's.
    let mut shortened = hand_written_mjcf().replace(r#"<site name="tool" pos="0 0 0.03" euler="0 90 0"/>"#, "");
    let start = shortened.find(r#"<body name="hand""#).expect("hand body");
    let end = shortened.rfind("</body>\n          </body>").expect("forearm closes") + "</body>".len();
    shortened.replace_range(start..end, "");
    std::fs::write(&path, shortened).expect("write MJCF");
    let model = from_mjcf(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(model.dof(), 2);
    assert!((model.last_from_tool.translation.vector - nalgebra::Vector3::new(-0.1, 0.0, 0.0)).norm() < 1e-15);
}

#[test]
fn broken_files_are_errors_naming_the_element() {
    let cases: [(&str, &[&str]); 9] = [
        ("branching_chain.xml", &["right_arm", "left_arm", "branch at body `base`"]),
        ("ball_joint.xml", &["wrist_ball", "forearm", "ball joint"]),
        ("free_joint.xml", &["float", "floating_base", "free joint"]),
        ("two_joints_in_one_body.xml", &["gimbal", "yaw", "pitch"]),
        ("missing_mesh.xml", &["no_such_forearm.stl"]),
        ("unlimited_slide.xml", &["rail", "carriage", "range"]),
        ("tool_site_off_chain.xml", &["site `tool`", "upper_arm", "forearm"]),
        ("plane_on_link.xml", &["paddle"]),
        ("unknown_element.xml", &["gizmo"]),
    ];
    for (name, words) in cases {
        let path = fixture(&format!("mjcf/{name}"));
        let error = from_mjcf(&path).expect_err(name);
        let message = error.to_string();
        assert!(message.contains(&path.display().to_string()), "{name}: {message}");
        for word in words {
            assert!(message.contains(word), "{name}: `{word}` not in: {message}");
        }
        assert!(
            matches!(error, ModelError::MjcfLoad { .. } | ModelError::UnsupportedMjcf { .. }),
            "{name}: {error:?}"
        );
    }
}

fn validate_design() -> Command {
    let mut cmd = Command::cargo_bin("validate-design").expect("binary is built");
    cmd.current_dir(repo());
    cmd
}

#[test]
fn binary_reads_an_mjcf_robot() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("robot.xml");
    std::fs::write(&path, hand_written_mjcf()).expect("write MJCF");
    let output = validate_design()
        .arg(&path)
        .args(["--kinematics-only", "--mujoco-checks", "20"])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stdout}\n{stderr}");
    assert!(stdout.contains("hand_written (MJCF, chain pedestal -> hand, 3 joints)"), "{stdout}");
    assert!(stdout.contains("shoulder") && stdout.contains("prismatic"), "{stdout}");
    assert!(stderr.contains("ellipsoid"), "the warning is shown: {stderr}");
}

#[test]
fn binary_exits_2_on_broken_mjcf_naming_file_and_element() {
    for (name, element) in [
        ("branching_chain.xml", "right_arm"),
        ("ball_joint.xml", "wrist_ball"),
        ("missing_mesh.xml", "no_such_forearm.stl"),
        ("two_joints_in_one_body.xml", "gimbal"),
    ] {
        let output = validate_design()
            .arg(fixture(&format!("mjcf/{name}")))
            .arg("--kinematics-only")
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{name}: {stderr}");
        assert!(stderr.contains(name) && stderr.contains(element), "{name}: {stderr}");
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    }
    // --tip chooses one of the tied chains; the other arm is held still, and that is said.
    let output = validate_design()
        .arg(fixture("mjcf/branching_chain.xml"))
        .args(["--tip", "left_arm", "--describe"])
        .output()
        .expect("runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(
        stdout.contains("branching_chain (MJCF, chain base -> left_arm, 1 joints)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("joint `right_shoulder` of body `right_arm` is not on the chain; it is held at its reference position"),
        "{stdout}"
    );
    let output = validate_design()
        .arg(fixture("mjcf/branching_chain.xml"))
        .args(["--base", "base"])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--base") && stderr.contains("URDF"), "{stderr}");
}
