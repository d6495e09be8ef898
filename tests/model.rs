//! The robot model: Jacobian against finite differences, the real-world URDF's structure,
//! physical mass properties of every shipped robot.

mod common;

use common::{panda_urdf, shipped_models};
use proving_ground::model::{from_urdf, Shape, UrdfOptions};
use rand::SeedableRng;

/// Central differences with h = 1e-6 have truncation error ~h^2 and rounding ~1e-16/h.
const FINITE_DIFFERENCE_AGREEMENT: f64 = 1e-8;

#[test]
fn jacobian_matches_central_finite_differences_of_fk() {
    let h = 1e-6;
    for (id, model) in shipped_models() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut ws = model.workspace();
        for _ in 0..100 {
            let q = model.random_configuration(&mut rng);
            model.jacobian(&q, &mut ws);
            for j in 0..model.dof() {
                let (mut plus, mut minus) = (q.clone(), q.clone());
                plus[j] += h;
                minus[j] -= h;
                let (tp, tm) = (model.tool_pose(&plus), model.tool_pose(&minus));
                let linear = (tp.translation.vector - tm.translation.vector) / (2.0 * h);
                // Angular velocity from the relative rotation tm^-1 * tp, expressed in the world.
                let delta = tm.rotation.rotation_to(&tp.rotation).scaled_axis() / (2.0 * h);
                let column = ws.jacobian.column(j);
                let error = (column.fixed_rows::<3>(0) - linear)
                    .norm()
                    .max((column.fixed_rows::<3>(3) - delta).norm());
                assert!(
                    error < FINITE_DIFFERENCE_AGREEMENT,
                    "{id}: column {j} differs by {error} at q = {q:?}"
                );
            }
        }
    }
}

#[test]
fn every_moving_link_has_physical_mass_properties() {
    for (id, model) in shipped_models() {
        assert!(
            model.links[0].inertial.is_none() || model.links[0].inertial.as_ref().is_some_and(|i| i.check().is_ok()),
            "{id}"
        );
        for link in &model.links[1..] {
            let inertial = link.inertial.as_ref().unwrap_or_else(|| panic!("{id}: {} has no mass", link.name));
            inertial.check().unwrap_or_else(|e| panic!("{id}: {}: {e}", link.name));
        }
    }
}

#[test]
fn panda_chain_folds_fixed_links_and_holds_fingers_at_zero() {
    let opts = UrdfOptions {
        tip_link: Some("panda_hand".into()),
        ..UrdfOptions::default()
    };
    let model = from_urdf(&panda_urdf(), &opts).expect("loads");
    assert_eq!(model.dof(), 7);
    assert!(model.diagnostics.is_empty(), "{:?}", model.diagnostics);
    let last = model.links.last().expect("links");
    assert_eq!(last.name, "panda_link7");
    for name in [
        "panda_link8",
        "panda_hand",
        "panda_hand_tcp",
        "panda_leftfinger",
        "panda_rightfinger",
    ] {
        assert!(
            last.merged.iter().any(|n| n == name),
            "{name} not merged into panda_link7: {:?}",
            last.merged
        );
    }
    // link7 mesh + hand mesh + 4 boxes per finger.
    let meshes = last.colliders.iter().filter(|c| matches!(c.shape, Shape::Mesh(_))).count();
    let boxes = last.colliders.iter().filter(|c| matches!(c.shape, Shape::Box { .. })).count();
    assert_eq!((meshes, boxes), (2, 8));
    // Published: flange 0.107 m beyond joint 7 along its z, hand turned -45 degrees about it.
    let zero = model.tool_pose(&[0.0; 7]);
    let expected = nalgebra::Vector3::new(0.088, 0.0, 0.333 + 0.316 + 0.384 - 0.107);
    assert!((zero.translation.vector - expected).norm() < 1e-12, "{}", zero.translation.vector);
    // A total mass check against the URDF's inertials (link1..link7 plus hand and fingers).
    let total: f64 = model.links[1..].iter().map(|l| l.inertial.as_ref().map_or(0.0, |i| i.mass)).sum();
    let expected_mass = 4.970684 + 0.646926 + 3.228604 + 3.587895 + 1.225946 + 1.666555 + 0.735522 + 0.73 + 2.0 * 0.015;
    assert!((total - expected_mass).abs() < 1e-9, "{total}");
}

#[test]
fn default_tip_of_a_design_export_is_the_last_moving_link() {
    let (_, model) = shipped_models().into_iter().find(|(id, _)| id == "ur5e").expect("ur5e shipped");
    let text = proving_ground::export::to_urdf(&model, &Default::default()).expect("exports");
    let back = proving_ground::model::from_urdf_str(&text, std::path::Path::new("ur5e.urdf"), &UrdfOptions::default()).expect("reads");
    assert_eq!(back.links.last().map(|l| l.name.as_str()), Some("link6"));
    assert!(back.links.last().is_some_and(|l| l.merged == ["tool"]));
}

/// Signed volume of a closed triangle mesh (divergence theorem).
fn volume(mesh: &proving_ground::model::TriMesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| nalgebra::Vector3::from(mesh.vertices[i as usize]));
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum()
}

#[test]
fn stl_obj_and_dae_meshes_load_to_the_same_solid_with_scale() {
    // Right tetrahedron with legs 0.1, 0.2, 0.3 m, stretched x2 along x: volume 2 * 0.006 / 6.
    let expected = 2.0 * 0.1 * 0.2 * 0.3 / 6.0;
    for format in ["stl", "obj", "dae"] {
        let file = common::fixture(&format!("meshes/tetrahedron.{format}"));
        let mesh = proving_ground::model::load_mesh(format, &file, [2.0, 1.0, 1.0]).unwrap_or_else(|e| panic!("{format}: {e}"));
        assert_eq!(mesh.triangles.len(), 4, "{format}");
        let v = volume(&mesh).abs();
        // STL stores f32 coordinates: 1e-9 relative is far below that rounding's effect here.
        assert!((v - expected).abs() < 1e-9, "{format}: volume {v}, expected {expected}");
        let max_x = mesh.vertices.iter().map(|p| p[0]).fold(f64::MIN, f64::max);
        assert!((max_x - 0.2).abs() < 1e-7, "{format}: scale not applied, max x {max_x}");
    }
}

#[test]
fn shipped_models_raise_no_warnings() {
    for (id, model) in shipped_models() {
        assert!(model.diagnostics.is_empty(), "{id}: {:?}", model.diagnostics);
    }
}
