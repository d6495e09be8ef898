//! Timor module sets and assemblies, against Timor itself: tool poses and collision geometry
//! placements computed by timor-python 1.1.1 (pinocchio, hpp-fcl) with
//! `scripts/timor_reference.py`, stored in `tests/fixtures/timor/reference.json`; the exports
//! of an assembly loaded by MuJoCo (its VRML pieces written as STL for the URDF).

mod common;

use common::repo;
use nalgebra::{Isometry3, Matrix4};
use proving_ground::engine::{compare_kinematics, MujocoKinematics, ToolElement};
use proving_ground::export::{to_mjcf, to_urdf, written_meshes, MjcfOptions, UrdfExportOptions};
use proving_ground::frames::pose_difference;
use proving_ground::model::{from_timor, Model, Shape};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Our f64 chain against pinocchio's f64 chain: the same products in another order.
const TIMOR_AGREEMENT: f64 = 1e-9;

#[derive(Deserialize)]
struct Reference {
    cases: Vec<Case>,
    design_spaces: Vec<DesignSpace>,
}

#[derive(Deserialize)]
struct DesignSpace {
    module_set: String,
    most_modules: usize,
    orders: Vec<String>,
}

#[derive(Deserialize)]
struct Case {
    module_set: String,
    module_order: Vec<String>,
    joints: Vec<String>,
    configurations: Vec<Configuration>,
}

#[derive(Deserialize)]
struct Configuration {
    q: Vec<f64>,
    tool: [[f64; 4]; 4],
    geometries: Vec<Geometry>,
}

#[derive(Deserialize)]
struct Geometry {
    name: String,
    pose: [[f64; 4]; 4],
    #[serde(rename = "type")]
    kind: String,
    half_extents: Option<[f64; 3]>,
    radius: Option<f64>,
    length: Option<f64>,
}

fn isometry(rows: &[[f64; 4]; 4]) -> Isometry3<f64> {
    let m = Matrix4::from_fn(|r, c| rows[r][c]);
    let rotation = nalgebra::Rotation3::from_matrix(&m.fixed_view::<3, 3>(0, 0).into_owned());
    Isometry3::from_parts(
        nalgebra::Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]),
        nalgebra::UnitQuaternion::from_rotation_matrix(&rotation),
    )
}

fn reference() -> Reference {
    let text = std::fs::read_to_string(repo().join("tests/fixtures/timor/reference.json")).expect("reference");
    serde_json::from_str(&text).expect("reference parses")
}

/// Writes an assembly of the shipped set `set` in `dir` and reads it.
fn assembly(dir: &Path, set: &str, order: &[String]) -> (PathBuf, Model) {
    let path = dir.join(format!("{set}-{}.json", order.join("-")));
    let text = serde_json::json!({ "moduleSet": set, "moduleOrder": order }).to_string();
    std::fs::write(&path, text).expect("write assembly");
    let model = from_timor(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (path, model)
}

#[test]
fn tool_poses_and_collision_geometry_agree_with_timor() {
    let dir = tempfile::tempdir().expect("temp dir");
    let reference = reference();
    assert!(reference.cases.len() >= 5);
    for case in &reference.cases {
        let (path, model) = assembly(dir.path(), &case.module_set, &case.module_order);
        let id = path.display().to_string();
        let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names, case.joints, "{id}: joints");
        let mut ws = model.workspace();
        for configuration in &case.configurations {
            model.forward(&configuration.q, &mut ws);
            let (dt, da) = pose_difference(&ws.tool_in_world, &isometry(&configuration.tool));
            assert!(
                dt < TIMOR_AGREEMENT && da < TIMOR_AGREEMENT,
                "{id}: tool differs by {dt} m, {da} rad"
            );

            // Every geometry Timor places, ours at the same place with the same shape; a
            // mesh file of convex pieces is one geometry to Timor and one collider per piece here.
            let mut matched = 0;
            for geometry in &configuration.geometries {
                let ours: Vec<(Isometry3<f64>, &Shape)> = model
                    .links
                    .iter()
                    .enumerate()
                    .flat_map(|(i, link)| link.colliders.iter().map(move |c| (i, c)))
                    .filter(|(_, c)| c.label == geometry.name || c.label.starts_with(&format!("{}/", geometry.name)))
                    .map(|(i, c)| (ws.link_in_world[i] * c.link_from_shape, &c.shape))
                    .collect();
                assert!(!ours.is_empty(), "{id}: no collider for Timor's {}", geometry.name);
                matched += ours.len();
                for (pose, shape) in ours {
                    let (dt, da) = pose_difference(&pose, &isometry(&geometry.pose));
                    assert!(
                        dt < TIMOR_AGREEMENT && da < TIMOR_AGREEMENT,
                        "{id}: {} differs by {dt} m, {da} rad",
                        geometry.name
                    );
                    let same = match (shape, geometry.kind.as_str()) {
                        (Shape::Box { half_extents }, "box") => {
                            let theirs = geometry.half_extents.expect("box size");
                            (0..3).all(|k| (half_extents[k] - theirs[k]).abs() < 1e-12)
                        }
                        (Shape::Cylinder { radius, length }, "cylinder") => {
                            (radius - geometry.radius.expect("radius")).abs() < 1e-12
                                && (length - geometry.length.expect("length")).abs() < 1e-12
                        }
                        (Shape::Sphere { radius }, "sphere") => (radius - geometry.radius.expect("radius")).abs() < 1e-12,
                        (Shape::Mesh(_), "mesh") => true,
                        _ => false,
                    };
                    assert!(
                        same,
                        "{id}: {} is a {} here, a {} to Timor",
                        geometry.name,
                        shape.kind(),
                        geometry.kind
                    );
                }
            }
            let total: usize = model.links.iter().map(|l| l.colliders.len()).sum();
            assert_eq!(matched, total, "{id}: colliders Timor does not have");
        }
    }
}

#[test]
fn exports_of_an_assembly_load_in_mujoco_with_the_same_kinematics() {
    let dir = tempfile::tempdir().expect("temp dir");
    for case in &reference().cases {
        let (path, model) = assembly(dir.path(), &case.module_set, &case.module_order);
        let id = path.display().to_string();
        let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
        let xml = to_mjcf(&model, &MjcfOptions::default()).unwrap_or_else(|e| panic!("{id}: {e}"));
        let mujoco = MujocoKinematics::from_xml_str(&xml, &id, &names).unwrap_or_else(|e| panic!("{id}: {e}"));
        let agreement = compare_kinematics(&model, &mujoco, ToolElement::Site("tool"), 50, 3).unwrap_or_else(|e| panic!("{id}: {e}"));
        assert!(
            agreement.max_position_error_m < TIMOR_AGREEMENT && agreement.max_angle_error_rad < TIMOR_AGREEMENT,
            "{id}: MJCF in MuJoCo: {agreement:?}"
        );
        // VRML pieces (IMPROV) are written as STL beside the URDF, which names them.
        let stem = case.module_order.join("-");
        let urdf = dir.path().join(format!("{stem}.urdf"));
        let opts = UrdfExportOptions {
            mujoco_block: true,
            mesh_base: Some(dir.path().to_path_buf()),
            mesh_folder: Some(dir.path().join(format!("{stem}-meshes"))),
        };
        let text = to_urdf(&model, &opts).unwrap_or_else(|e| panic!("{id}: {e}"));
        std::fs::write(&urdf, text).expect("write URDF");
        let meshes = written_meshes(&model, &opts);
        let pieces = model
            .links
            .iter()
            .flat_map(|l| &l.colliders)
            .filter(|c| matches!(c.shape, Shape::Mesh(_)))
            .count();
        assert_eq!(meshes.len(), pieces, "{id}: every VRML piece written");
        for (path, bytes) in meshes {
            std::fs::create_dir_all(path.parent().expect("folder")).expect("mesh folder");
            std::fs::write(path, bytes).expect("write mesh");
        }
        // Without a folder to write them in, VRML pieces are refused with the reason.
        if pieces > 0 {
            let refused = to_urdf(&model, &UrdfExportOptions::default()).expect_err("VRML without a mesh folder");
            assert!(refused.to_string().contains("VRML"), "{refused}");
        }
        let mujoco = MujocoKinematics::from_file(&urdf, &names).unwrap_or_else(|e| panic!("{id}: {e}"));
        let agreement = compare_kinematics(&model, &mujoco, ToolElement::Body("tool"), 50, 3).unwrap_or_else(|e| panic!("{id}: {e}"));
        assert!(
            agreement.max_position_error_m < TIMOR_AGREEMENT && agreement.max_angle_error_rad < TIMOR_AGREEMENT,
            "{id}: URDF in MuJoCo: {agreement:?}"
        );
    }
}

/// Runs `validate-design ARGS`, expecting exit 2; its standard error.
fn refused(args: &[&str]) -> String {
    let output = assert_cmd::Command::cargo_bin("validate-design")
        .expect("binary is built")
        .current_dir(repo())
        .args(args)
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

#[test]
fn a_module_set_given_as_the_robot_says_what_it_is_and_what_to_give() {
    // The file a new user tried: Timor's `Infinity` limits read, the modules listed.
    let stderr = refused(&["designs/timor/geometric_primitive_modules/modules.json", "--kinematics-only"]);
    assert!(stderr.contains("a Timor module set (10 modules: J1, J2, base"), "{stderr}");
    assert!(stderr.contains("moduleOrder"), "{stderr}");
}

#[test]
fn broken_assemblies_name_the_key_and_the_connectors() {
    let dir = tempfile::tempdir().expect("temp dir");
    let set = repo().join("designs/timor/geometric_primitive_modules");
    let cases: [(&str, serde_json::Value, &str); 7] = [
        ("unknown", serde_json::json!({"moduleSet": set, "moduleOrder": ["base", "J9"]}), "moduleOrder[1]: no module `J9`"),
        (
            "no-mate",
            serde_json::json!({"moduleSet": set, "moduleOrder": ["base", "J2", "J2", "eef", "J2"]}),
            "moduleOrder[4]: module `J2-2` mates with no free connector",
        ),
        ("no-base", serde_json::json!({"moduleSet": set, "moduleOrder": ["J2", "eef"]}), "needs exactly one (a base module)"),
        ("no-joint", serde_json::json!({"moduleSet": set, "moduleOrder": ["base", "i_15", "eef"]}), "has no moving joint"),
        (
            "bad-connection",
            serde_json::json!({"moduleSet": set, "moduleOrder": ["base", "J2", "eef"], "moduleConnection": [[0, "base2robot", 1, "J2_distal"]]}),
            "moduleConnection[0]: the connectors do not mate: `base2robot` (m, type `default`, size [0.08]) and `J2_distal` (m, type `default`, size [0.08]): their genders do not mate",
        ),
        ("missing-set", serde_json::json!({"moduleSet": "nowhere", "moduleOrder": ["base"]}), "moduleSet: `nowhere` is no module set file"),
        ("not-a-list", serde_json::json!({"moduleSet": set, "moduleOrder": "base"}), "line 1"),
    ];
    for (name, assembly, expected) in cases {
        let path = dir.path().join(format!("{name}.json"));
        std::fs::write(&path, assembly.to_string()).expect("write");
        let stderr = refused(&[path.to_str().expect("utf-8"), "--kinematics-only"]);
        assert!(stderr.contains(expected), "{name}: {stderr}");
        assert!(stderr.contains(&format!("{name}.json")), "{name}: the file is named: {stderr}");
    }
}

#[test]
fn a_broken_module_set_names_the_module_and_the_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let original = std::fs::read_to_string(repo().join("designs/timor/geometric_primitive_modules/modules.json")).expect("set");
    let cases = [
        ("\"gender\": \"m\"", "\"gender\": \"x\"", "gender: `x`; expected f, m or h"),
        (
            "\"type\": \"revolute\"",
            "\"type\": \"spherical\"",
            "joint `Revolute` type: `spherical`",
        ),
        (
            "\"positionUpper\": 0.06",
            "\"positionUpper\": Infinity",
            "a prismatic joint needs both limits",
        ),
        ("\"mass\": 0.3377840421139745", "\"mass\": -1", "mass -1"),
        ("\"r\": 0.032", "\"r\": -0.032", "expected a positive length"),
        ("\"poseParent\"", "\"poseParnet\"", "line "),
    ];
    for (k, (from, to, expected)) in cases.into_iter().enumerate() {
        assert!(original.contains(from), "{from}");
        let set = dir.path().join(format!("set{k}"));
        std::fs::create_dir(&set).expect("dir");
        std::fs::write(set.join("modules.json"), original.replacen(from, to, 1)).expect("write set");
        let assembly = dir.path().join(format!("assembly{k}.json"));
        let text = serde_json::json!({"moduleSet": format!("set{k}"), "moduleOrder": ["base", "J1", "J2", "eef"]}).to_string();
        std::fs::write(&assembly, text).expect("write assembly");
        let stderr = refused(&[assembly.to_str().expect("utf-8"), "--kinematics-only"]);
        assert!(stderr.contains(expected), "{to}: {stderr}");
        assert!(stderr.contains("modules.json"), "{to}: the set is named: {stderr}");
    }
}

#[test]
fn the_shipped_assemblies_validate_kinematically() {
    for name in ["geometric-6r", "improv-6r"] {
        let output = assert_cmd::Command::cargo_bin("validate-design")
            .expect("binary is built")
            .current_dir(repo())
            .args([&format!("designs/timor/{name}.json"), "--kinematics-only"])
            .output()
            .expect("runs");
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert!(output.status.success(), "{name}: {}", String::from_utf8_lossy(&output.stderr));
        assert!(stdout.contains("Timor assembly"), "{stdout}");
    }
    // `--export-urdf` writes IMPROV's VRML pieces as STL beside the URDF; it reads back whole.
    let dir = tempfile::tempdir().expect("temp dir");
    let urdf = dir.path().join("improv.urdf");
    let output = assert_cmd::Command::cargo_bin("validate-design")
        .expect("binary is built")
        .current_dir(repo())
        .args(["designs/timor/improv-6r.json", "--kinematics-only", "--export-urdf"])
        .arg(&urdf)
        .output()
        .expect("runs");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let original = from_timor(&repo().join("designs/timor/improv-6r.json")).expect("assembly");
    let back = proving_ground::model::from_urdf(&urdf, &Default::default()).expect("the exported URDF reads");
    let colliders = |m: &Model| m.links.iter().map(|l| l.colliders.len()).sum::<usize>();
    assert_eq!(colliders(&back), colliders(&original));
    // L1, L2 and L3: 2 + 3 + 4 convex pieces.
    assert_eq!(dir.path().join("improv-meshes").read_dir().expect("mesh folder").count(), 9);
    let q = [0.3, -0.4, 0.5, 0.2, -0.1, 0.6];
    let (dt, da) = pose_difference(&back.tool_pose(&q), &original.tool_pose(&q));
    assert!(dt < 1e-12 && da < 1e-12, "{dt} m, {da} rad");
}

#[test]
fn a_module_set_as_a_design_space_lists_what_timor_assembles() {
    for space in reference().design_spaces {
        let set = proving_ground::model::TimorSet::load(&space.module_set).expect("shipped set");
        let (orders, reached) = set.assemblies(space.most_modules, false).expect("within the cap");
        assert_eq!(reached, space.most_modules);
        let mut ours: Vec<String> = orders.iter().map(|o| o.join(",")).collect();
        ours.sort();
        assert_eq!(ours.len(), space.orders.len(), "{}", space.module_set);
        assert_eq!(ours, space.orders, "{}", space.module_set);
    }
    // Without @N, as many modules as keep the list within the cap; with too many, the error
    // says how many fit.
    let set = proving_ground::model::TimorSet::load("geometric_primitive_modules").expect("shipped set");
    let (orders, reached) = set.assemblies(8, true).expect("fits");
    assert!(
        reached < 8 && orders.len() <= proving_ground::model::MAX_ASSEMBLIES && orders.len() > 3000,
        "{reached}: {}",
        orders.len()
    );
    let error = set.assemblies(8, false).expect_err("over the cap");
    assert!(error.contains(&format!("timor:geometric_primitive_modules@{reached}")), "{error}");
}

#[test]
fn a_sweep_over_a_module_set_writes_its_best_assemblies_as_files_that_validate() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (out, best) = (dir.path().join("sweep"), dir.path().join("best"));
    let output = assert_cmd::Command::cargo_bin("validate-design")
        .expect("binary is built")
        .current_dir(repo())
        .args([
            "sweep",
            "timor:geometric_primitive_modules@4",
            "--scenarios",
            "scenarios/cluttered/task-00.json",
            "--quiet",
            "--top",
            "3",
        ])
        .arg("--out")
        .arg(&out)
        .arg("--best-designs")
        .arg(&best)
        .output()
        .expect("runs");
    assert!(
        output.status.code().is_some_and(|c| c <= 1),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let mut files: Vec<PathBuf> = std::fs::read_dir(&best)
        .expect("best designs")
        .map(|e| e.expect("entry").path())
        .collect();
    files.sort();
    assert_eq!(files.len(), 3);
    for file in files {
        let model = from_timor(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        assert!(model.dof() >= 1);
    }
    // One assembly by its id, wherever a robot is taken.
    let output = assert_cmd::Command::cargo_bin("validate-design")
        .expect("binary is built")
        .current_dir(repo())
        .args(["timor:IMPROV/1,21,4,22,5,23,12", "--kinematics-only"])
        .output()
        .expect("runs");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stderr = refused(&["timor:IMPROV/1,21,99", "--kinematics-only"]);
    assert!(stderr.contains("moduleOrder[2]: no module `99`"), "{stderr}");
}
