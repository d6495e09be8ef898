//! Round trips of every shipped robot through our URDF and MJCF exports, with MuJoCo as the
//! independent oracle for our kinematics.

mod common;

use common::shipped_models;
use proving_ground::engine::{compare_kinematics, MujocoKinematics, ToolElement};
use proving_ground::export::{to_mjcf, to_urdf, MjcfOptions, UrdfExportOptions};
use proving_ground::frames::pose_difference;
use proving_ground::model::{from_urdf_str, UrdfOptions};
use rand::SeedableRng;
use std::path::Path;

/// Our URDF writer then our reader: the numbers are written in shortest round-trip form, so the
/// only difference left is the order of floating-point operations. Worst measured: ~2e-16.
const URDF_ROUND_TRIP: f64 = 1e-12;
/// MuJoCo vs our FK and Jacobian, both f64 on the same numbers. Worst measured: ~1e-15.
const MUJOCO_AGREEMENT: f64 = 1e-9;
const CONFIGURATIONS: usize = 100;
const SEED: u64 = 7;

#[test]
fn urdf_export_read_back_gives_the_same_kinematics() {
    for (id, model) in shipped_models() {
        let text = to_urdf(&model, &UrdfExportOptions::default()).unwrap_or_else(|e| panic!("{id}: {e}"));
        let opts = UrdfOptions {
            tip_link: Some("tool".into()),
            ..UrdfOptions::default()
        };
        let back = from_urdf_str(&text, Path::new(&format!("{id}.urdf")), &opts).unwrap_or_else(|e| panic!("{id}: {e}\n{text}"));
        assert_eq!(back.dof(), model.dof(), "{id}");
        assert_eq!(
            back.links.iter().map(|l| l.colliders.len()).sum::<usize>(),
            model.links.iter().map(|l| l.colliders.len()).sum::<usize>(),
            "{id}: colliders"
        );
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(SEED);
        let (mut ws, mut back_ws) = (model.workspace(), back.workspace());
        for _ in 0..CONFIGURATIONS {
            let q = model.random_configuration(&mut rng);
            model.forward(&q, &mut ws);
            back.forward(&q, &mut back_ws);
            // links[0] of the read-back model is the URDF's `world`; compare the moving links.
            for i in 1..model.links.len() {
                let (dt, da) = pose_difference(&ws.link_in_world[i], &back_ws.link_in_world[i]);
                assert!(
                    dt <= URDF_ROUND_TRIP && da <= URDF_ROUND_TRIP,
                    "{id}: link {i} differs by {dt} m, {da} rad at q = {q:?}"
                );
            }
            let (dt, da) = pose_difference(&ws.tool_in_world, &back_ws.tool_in_world);
            assert!(
                dt <= URDF_ROUND_TRIP && da <= URDF_ROUND_TRIP,
                "{id}: tool differs by {dt} m, {da} rad at q = {q:?}"
            );
        }
        for (a, b) in model.links.iter().skip(1).zip(back.links.iter().skip(1)) {
            let (ma, mb) = (
                a.inertial.as_ref().expect("moving link has mass"),
                b.inertial.as_ref().expect("moving link has mass"),
            );
            assert!(
                (ma.mass - mb.mass).abs() < 1e-12 && (ma.com - mb.com).norm() < 1e-12 && (ma.inertia - mb.inertia).abs().max() < 1e-12,
                "{id}: {} inertia",
                a.name
            );
        }
    }
}

#[test]
fn mjcf_export_matches_mujoco_kinematics_and_jacobian() {
    for (id, model) in shipped_models() {
        let xml = to_mjcf(&model, &MjcfOptions::default()).unwrap_or_else(|e| panic!("{id}: {e}"));
        let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
        let mujoco = MujocoKinematics::from_xml_str(&xml, &id, &names).unwrap_or_else(|e| panic!("{id}: {e}"));
        let agreement =
            compare_kinematics(&model, &mujoco, ToolElement::Site("tool"), CONFIGURATIONS, SEED).unwrap_or_else(|e| panic!("{id}: {e}"));
        let jacobian = agreement.max_jacobian_error.expect("site Jacobian compared");
        assert!(
            agreement.max_position_error_m <= MUJOCO_AGREEMENT
                && agreement.max_angle_error_rad <= MUJOCO_AGREEMENT
                && jacobian <= MUJOCO_AGREEMENT,
            "{id}: MuJoCo disagrees: {agreement:?}"
        );
        // MuJoCo's world body, one body per link, nothing else.
        assert_eq!(mujoco.body_count(), model.links.len() + 1, "{id}");
    }
}

#[test]
fn urdf_export_matches_mujocos_own_urdf_importer() {
    let dir = tempfile::tempdir().expect("temp dir");
    for (id, model) in shipped_models() {
        let text = to_urdf(
            &model,
            &UrdfExportOptions {
                mujoco_block: true,
                ..Default::default()
            },
        )
        .unwrap_or_else(|e| panic!("{id}: {e}"));
        let path = dir.path().join(format!("{id}.urdf"));
        std::fs::write(&path, &text).expect("write URDF");
        let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
        let mujoco = MujocoKinematics::from_file(&path, &names).unwrap_or_else(|e| panic!("{id}: {e}\n{text}"));
        let agreement =
            compare_kinematics(&model, &mujoco, ToolElement::Body("tool"), CONFIGURATIONS, SEED).unwrap_or_else(|e| panic!("{id}: {e}"));
        assert!(
            agreement.max_position_error_m <= MUJOCO_AGREEMENT && agreement.max_angle_error_rad <= MUJOCO_AGREEMENT,
            "{id}: MuJoCo's URDF importer disagrees: {agreement:?}"
        );
    }
}

/// A mesh whose vertices hold float noise (the ROBOTIS Open Manipulator's STLs: 1.5e-40 m after
/// scaling, below f32's smallest normal number) exports to an MJCF that MuJoCo loads, and agrees
/// with our kinematics.
#[test]
fn mesh_noise_below_f32_exports_to_an_mjcf_mujoco_loads() {
    use proving_ground::model::{Collider, Shape, TriMesh};
    let (id, mut model) = shipped_models().into_iter().next().expect("a shipped model");
    let vertices = vec![[1.5e-40, 0.0, -2.0e-35], [0.05, 0.0, 0.0], [0.0, 0.05, 1e-39], [0.0, 0.0, 0.05]];
    let last = model.links.len() - 1;
    model.links[last].colliders.push(Collider {
        link_from_shape: nalgebra::Isometry3::identity(),
        shape: Shape::Mesh(TriMesh {
            uri: "noise.stl".into(),
            file: std::path::PathBuf::from("noise.stl"),
            scale: [1.0; 3],
            vertices,
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }),
        label: "noise".into(),
    });
    let xml = to_mjcf(&model, &MjcfOptions::default()).expect("exports");
    assert!(
        xml.contains("-2e-35") && !xml.contains("1.5e-40"),
        "tiny vertices: {}",
        &xml[..xml.len().min(400)]
    );
    let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
    let mujoco = MujocoKinematics::from_xml_str(&xml, &id, &names).unwrap_or_else(|e| panic!("{id}: {e}"));
    let agreement = compare_kinematics(&model, &mujoco, ToolElement::Site("tool"), 10, SEED).expect("compares");
    assert!(agreement.max_position_error_m <= MUJOCO_AGREEMENT, "{agreement:?}");
}
