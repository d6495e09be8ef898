//! Shipped designs: the set the issue asks for, their hardware cost, and closed-form tool poses.

mod common;

use common::{design_files, stem};
use proving_ground::design::{self, DesignMode};
use proving_ground::model::from_design;

#[test]
fn ships_the_required_designs() {
    let designs: Vec<_> = design_files()
        .iter()
        .map(|p| design::load(p).unwrap_or_else(|e| panic!("{e}")))
        .collect();
    let count = |mode: DesignMode, dof: Option<usize>| {
        designs
            .iter()
            .filter(|d| d.mode == mode && dof.is_none_or(|n| d.dof() == n))
            .count()
    };
    assert!(count(DesignMode::Economic, None) >= 3);
    assert!(count(DesignMode::Free, None) >= 3);
    assert_eq!(count(DesignMode::Preset, Some(6)), 4);
    assert!(count(DesignMode::Modular, Some(6)) >= 4);
    let paper = designs.iter().find(|d| d.name == "paper-real-world").expect("paper robot shipped");
    assert_eq!(paper.dof(), 5);
    let names: Vec<&str> = paper.modules.as_ref().expect("modular").iter().map(|m| m.name()).collect();
    assert_eq!(names, ["direct", "L-short", "direct", "direct", "I-long"]);
}

#[test]
fn design_names_match_file_names() {
    for path in design_files() {
        let design = design::load(&path).expect("loads");
        assert_eq!(design.name, stem(&path), "{}", path.display());
    }
}

#[test]
fn hardware_cost_is_the_sum_of_absolute_offsets() {
    let ur5e = design::load(&common::repo().join("designs/ur5e.json")).expect("loads");
    let expected = 0.1625 + 0.425 + 0.3922 + 0.1333 + 0.0997 + 0.0996;
    assert!((ur5e.hardware_cost() - expected).abs() < 1e-12);
    let paper = design::load(&common::repo().join("designs/paper-real-world.json")).expect("loads");
    // direct 0.1, L-short 0.1 + 0.2, direct 0.1, direct 0.1, I-long 0.4: 1.0 m.
    assert!((paper.hardware_cost() - 1.0).abs() < 1e-12);
}

#[test]
fn ur5e_tool_at_zero_matches_the_closed_form() {
    // Standard DH at q = 0: x = a2 + a3, y = -(d4 + d6), z = d1 - d5; tool z points along -y.
    let model = from_design(&design::load(&common::repo().join("designs/ur5e.json")).expect("loads"));
    let tool = model.tool_pose(&[0.0; 6]);
    let expected = nalgebra::Vector3::new(-0.425 - 0.3922, -(0.1333 + 0.0996), 0.1625 - 0.0997);
    assert!((tool.translation.vector - expected).norm() < 1e-12, "{}", tool.translation.vector);
    let tool_z = tool.rotation * nalgebra::Vector3::z();
    assert!((tool_z - nalgebra::Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-12, "{tool_z}");
}

#[test]
fn paper_robot_tool_at_zero_matches_the_closed_form() {
    // Slots direct, L-short, direct, direct, I-long at q = 0, frames composed by hand. Each
    // alpha = +90 deg turns the frame about x: after joint 1 z points along -y0, after joint 3
    // along -z0, after joint 4 along +y0. Origins: (0, 0, 0.1) -> (0.2, -0.1, 0.1) ->
    // (0.2, -0.2, 0.1) -> (0.2, -0.2, 0.0) -> (0.2, 0.2, 0.0).
    let model = from_design(&design::load(&common::repo().join("designs/paper-real-world.json")).expect("loads"));
    let tool = model.tool_pose(&[0.0; 5]);
    let expected = nalgebra::Vector3::new(0.2, 0.2, 0.0);
    assert!((tool.translation.vector - expected).norm() < 1e-12, "{}", tool.translation.vector);
}
