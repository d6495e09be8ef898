//! Design (standard DH) -> Model, with the paper's link geometry and the catalog's masses.
//!
//! Joint `i` maps frame `i-1` to frame `i` by `Rot_z(q_i) Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i)`.
//! In the model, link `i` has the frame `F_{i-1} Rot_z(q_i)`: the fixed part of row `i` becomes
//! the origin of joint `i + 1`, and the fixed part of the last row goes into the tool offset.
//!
//! Geometry (robots.md): link `i` is a tube of length `|d_i|` along z from its origin, then a tube
//! of length `|a_i|` along x ending at frame `i`, both 0.12 m in diameter; when `a_i = d_i = 0` a
//! sphere of 0.12 m diameter sits at the joint. Modular designs also carry the joint module
//! housing, a 0.12 x 0.12 m cylinder centred on each joint along its axis.
//!
//! Mass (documented constants in `design::catalog`): tubes 3.0 kg/m as thin-walled tubes, and a
//! 1.8 kg joint module per joint as a solid 0.12 x 0.12 m cylinder on the joint axis, both on the
//! link the joint moves.

use super::{Collider, Inertial, Joint, JointKind, Link, Model, ModelSource, Segment, Shape};
use crate::design::catalog::{JOINT_MODULE_KG, JOINT_MODULE_LENGTH_M, LINK_DIAMETER_M, TUBE_KG_PER_M};
use crate::design::{Design, DesignMode};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::f64::consts::FRAC_PI_2;

/// Parameters below this length (m) add no tube: the paper's "a parameter equal to zero".
const ZERO_LENGTH_M: f64 = 1e-12;

/// Builds the model of a validated design.
pub fn from_design(design: &Design) -> Model {
    let radius = LINK_DIAMETER_M / 2.0;
    let fixed_part = |row: usize| {
        let j = &design.joints[row];
        Isometry3::from_parts(Translation3::new(0.0, 0.0, j.d), UnitQuaternion::identity())
            * Isometry3::from_parts(
                Translation3::new(j.a, 0.0, 0.0),
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), j.alpha),
            )
    };

    let mut joints = Vec::with_capacity(design.dof());
    let mut links = vec![Link {
        name: "base".into(),
        merged: vec![],
        colliders: vec![],
        inertial: None,
        segments: vec![],
    }];
    for (i, dh) in design.joints.iter().enumerate() {
        let number = i + 1;
        joints.push(Joint {
            name: format!("joint{number}"),
            kind: JointKind::Revolute,
            parent_from_joint: if i == 0 { Isometry3::identity() } else { fixed_part(i - 1) },
            axis: Vector3::z_axis(),
            limits: Some(dh.limits),
            max_velocity: Some(dh.max_velocity),
            max_effort: dh.rated_torque,
        });

        let mut colliders = Vec::new();
        let mut masses = vec![Inertial::solid_cylinder(JOINT_MODULE_KG, radius, JOINT_MODULE_LENGTH_M)];
        if design.mode == DesignMode::Modular {
            colliders.push(Collider {
                link_from_shape: Isometry3::identity(),
                shape: Shape::Cylinder {
                    radius,
                    length: JOINT_MODULE_LENGTH_M,
                },
                label: format!("joint module {number}"),
            });
        }
        if dh.d.abs() > ZERO_LENGTH_M {
            let pose = Isometry3::translation(0.0, 0.0, dh.d / 2.0);
            colliders.push(Collider {
                link_from_shape: pose,
                shape: Shape::Cylinder {
                    radius,
                    length: dh.d.abs(),
                },
                label: format!("d tube of joint {number}"),
            });
            masses.push(Inertial::thin_tube(TUBE_KG_PER_M * dh.d.abs(), radius, dh.d.abs()).transformed(&pose));
        }
        if dh.a.abs() > ZERO_LENGTH_M {
            // A cylinder's axis is its local z; turning it about y by +90 degrees lays it along x.
            let pose = Isometry3::from_parts(
                Translation3::new(dh.a / 2.0, 0.0, dh.d),
                UnitQuaternion::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2),
            );
            colliders.push(Collider {
                link_from_shape: pose,
                shape: Shape::Cylinder {
                    radius,
                    length: dh.a.abs(),
                },
                label: format!("a tube of joint {number}"),
            });
            masses.push(Inertial::thin_tube(TUBE_KG_PER_M * dh.a.abs(), radius, dh.a.abs()).transformed(&pose));
        }
        if dh.d.abs() <= ZERO_LENGTH_M && dh.a.abs() <= ZERO_LENGTH_M {
            colliders.push(Collider {
                link_from_shape: Isometry3::identity(),
                shape: Shape::Sphere { radius },
                label: format!("joint sphere {number}"),
            });
        }
        // The paper's capsules follow the same d and a segments; no segment at all is its sphere.
        let corner = Vector3::new(0.0, 0.0, dh.d);
        let mut segments = Vec::new();
        if dh.d.abs() > ZERO_LENGTH_M {
            segments.push(Segment {
                start: Vector3::zeros(),
                end: corner,
            });
        }
        if dh.a.abs() > ZERO_LENGTH_M {
            segments.push(Segment {
                start: corner,
                end: Vector3::new(dh.a, 0.0, dh.d),
            });
        }
        if segments.is_empty() {
            segments.push(Segment {
                start: Vector3::zeros(),
                end: Vector3::zeros(),
            });
        }
        links.push(Link {
            segments,
            name: format!("link{number}"),
            merged: vec![],
            colliders,
            inertial: Some(Inertial::combine(&masses).expect("a joint module always has positive mass")),
        });
    }

    Model {
        name: design.name.clone(),
        source: ModelSource::Design {
            mode: design.mode.name().into(),
            choices: design.snapped.iter().map(ToString::to_string).collect(),
        },
        world_from_base: design.base.isometry(),
        joints,
        links,
        last_from_tool: fixed_part(design.dof() - 1) * design.tool.isometry(),
        diagnostics: vec![],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design;
    use std::path::Path;

    /// Standard DH product, written independently of the model's link-frame bookkeeping.
    fn dh_tool(design: &Design, q: &[f64]) -> Isometry3<f64> {
        let mut pose = Isometry3::identity();
        for (j, &qi) in design.joints.iter().zip(q) {
            pose = pose
                * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), qi)
                * Translation3::new(0.0, 0.0, j.d)
                * Translation3::new(j.a, 0.0, 0.0)
                * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), j.alpha);
        }
        pose
    }

    #[test]
    fn tool_pose_equals_the_dh_product() {
        let text = r#"{"mode": "free", "joints": [
            {"d": 0.3, "a": 0.1, "alpha": 1.2}, {"d": -0.2, "a": 0.4, "alpha": -0.4},
            {"d": 0.0, "a": 0.0, "alpha": 0.7}, {"d": 0.15, "a": -0.3, "alpha": 0.0}]}"#;
        let design = design::parse(text, Path::new("t.json")).expect("valid");
        let model = from_design(&design);
        let q = [0.4, -1.3, 2.2, 0.9];
        let (dt, da) = crate::frames::pose_difference(&model.tool_pose(&q), &dh_tool(&design, &q));
        assert!(dt < 1e-14 && da < 1e-14, "{dt} {da}");
    }

    #[test]
    fn zero_offset_joint_becomes_a_sphere() {
        let text = r#"{"mode": "free", "joints": [{"d": 0, "a": 0, "alpha": 1.5}, {"d": 0.2, "a": 0, "alpha": 0}]}"#;
        let model = from_design(&design::parse(text, Path::new("t.json")).expect("valid"));
        assert!(matches!(
            model.links[1].colliders[..],
            [Collider {
                shape: Shape::Sphere { .. },
                ..
            }]
        ));
        assert!(model
            .links
            .iter()
            .skip(1)
            .all(|l| l.inertial.as_ref().is_some_and(|i| i.check().is_ok())));
    }

    #[test]
    fn a_tube_ends_at_the_next_frame() {
        let text = r#"{"mode": "free", "joints": [{"d": 0.2, "a": 0.3, "alpha": 0}]}"#;
        let model = from_design(&design::parse(text, Path::new("t.json")).expect("valid"));
        let a_tube = &model.links[1].colliders[1];
        let far_end = a_tube.link_from_shape * nalgebra::Point3::new(0.0, 0.0, 0.15);
        assert!((far_end.coords - Vector3::new(0.3, 0.0, 0.2)).norm() < 1e-15, "{far_end}");
    }
}
