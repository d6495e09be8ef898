//! Shipped designs: the set the issue asks for, their hardware cost, and closed-form tool poses.

mod common;

use common::{design_files, stem};
use proving_ground::design::{self, DesignMode};
use proving_ground::ik::analytic::UrArm;
use proving_ground::model::from_design;
use std::f64::consts::FRAC_PI_2;

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

/// An economic elbow arm as a float32 generator writes it: pi/2 as float32's nearest value.
fn float32_economic_design(alpha: f64, d: f64) -> String {
    format!(
        r#"{{"mode": "economic", "joints": [
            {{"d": 0.15, "a": 0, "alpha": 1.5707963267948966}},
            {{"d": 0, "a": -0.4, "alpha": 0}},
            {{"d": {d}, "a": 0, "alpha": {alpha}}}
        ]}}"#
    )
}

#[test]
fn float32_pi_over_2_is_read_as_pi_over_2_and_said() {
    let written = -f64::from(std::f32::consts::FRAC_PI_2);
    assert_eq!(written.to_string(), "-1.5707963705062866");
    let path = std::path::Path::new("designs/generated.json");
    let design = design::parse(&float32_economic_design(written, 0.1), path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(design.joints[2].alpha.to_bits(), (-FRAC_PI_2).to_bits());
    let model = from_design(&design);
    assert!(model.diagnostics.is_empty(), "a snap is not a warning: {:?}", model.diagnostics);
    let rotation = model.last_from_tool.rotation;
    let exact = nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::x_axis(), -FRAC_PI_2);
    assert_eq!(rotation, exact, "the model is built from the snapped value");
    assert_eq!(
        model.source.choices(),
        ["joints[2].alpha = -1.5707963705062866 snapped to -pi/2 (-1.5707963267948966) (within 1e-6; a float32 generator's rounding)"]
    );
}

#[test]
fn two_millionths_off_is_still_not_economic() {
    let path = std::path::Path::new("designs/generated.json");
    let err = design::parse(&float32_economic_design(-FRAC_PI_2 - 2e-6, 0.1), path)
        .expect_err("2e-6 off is not a rounding")
        .to_string();
    assert_eq!(
        err,
        format!(
            "designs/generated.json: joint 3 (joints[2]): alpha = {} is not economic; allowed {{0, +pi/2, -pi/2}} rad",
            -FRAC_PI_2 - 2e-6
        )
    );
}

#[test]
fn a_length_next_to_an_interval_bound_is_read_as_the_bound() {
    let path = std::path::Path::new("generated.json");
    let design = design::parse(&float32_economic_design(-FRAC_PI_2, 0.1000000015), path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(design.joints[2].d, 0.1);
    let sentences: Vec<String> = design.snapped.iter().map(ToString::to_string).collect();
    assert_eq!(
        sentences,
        ["joints[2].d = 0.1000000015 snapped to 0.1 (within 1e-6; a float32 generator's rounding)"]
    );
    // Just outside the interval (float32's 0.4 is 0.4000000059604645) is read as its bound too.
    let design = design::parse(&float32_economic_design(0.0, f64::from(0.4_f32)), path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(design.joints[2].d, 0.4);
}

#[test]
fn the_hardware_cost_of_a_snapped_design_uses_the_values_used() {
    let path = std::path::Path::new("generated.json");
    let design = design::parse(&float32_economic_design(0.0, f64::from(0.4_f32)), path).unwrap_or_else(|e| panic!("{e}"));
    // 0.15 + 0.4 + 0.4 exactly, as the sum of the named values.
    assert_eq!(design.hardware_cost(), 0.15 + 0.4 + 0.4);
    assert_eq!(design.snapped.len(), 1);
}

#[test]
fn shipped_economic_designs_snap_nothing() {
    for path in design_files() {
        let design = design::load(&path).expect("loads");
        assert!(design.snapped.is_empty(), "{}: {:?}", path.display(), design.snapped);
    }
}

#[test]
fn ur15_preset_is_a_ur_arm_with_its_published_offsets() {
    let path = std::path::Path::new("ur15.json");
    let design = design::parse(r#"{"mode": "preset", "preset": "UR15"}"#, path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(design.preset, Some(design::catalog::Preset::Ur15));
    assert_eq!(design.dof(), 6);
    let expected = 0.2186 + 0.6475 + 0.5164 + 0.1746 + 0.1201 + 0.1153;
    assert!((design.hardware_cost() - expected).abs() < 1e-12, "{}", design.hardware_cost());
    let model = from_design(&design);
    assert!(UrArm::detect(&model).is_some(), "the closed-form IK takes the UR15");
}

#[test]
fn unknown_preset_lists_the_presets() {
    let err = design::parse(r#"{"mode": "preset", "preset": "UR16"}"#, std::path::Path::new("x.json"))
        .expect_err("no such preset")
        .to_string();
    assert!(err.contains("UR15") && err.contains("UR20"), "{err}");
}
