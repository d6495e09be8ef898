//! MJCF joints -> model joints: the frame at the joint anchor, kind and limits, and the rated
//! effort from MuJoCo's actuator force ranges (or a motor's control range).

use super::{Layout, Reader};
use crate::model::{Joint, JointKind, ModelError};
use mujoco_rs::mujoco_c::{mjtBias, mjtGain, mjtJoint, mjtTrn};
use mujoco_rs::prelude::*;
use nalgebra::{Isometry3, Unit, Vector3};

impl Reader<'_> {
    /// The joint of moving body `body`, `k`-th on the chain.
    pub(super) fn joint(&self, body: usize, layout: &Layout, k: usize) -> Result<Joint, ModelError> {
        let mj = self.mj;
        let joint = mj.body_jntadr()[body] as usize;
        let element = self.joint_element(joint);
        let above = mj.body_parentid()[body] as usize;
        debug_assert_eq!(layout.owner[above], k, "the chain check puts the previous link above");
        let anchor = Vector3::from(mj.jnt_pos()[joint]);
        let parent_from_joint =
            layout.link_from_body[above] * self.parent_from_body(body) * Isometry3::translation(anchor.x, anchor.y, anchor.z);

        // MJCF places bodies at the joint's `ref` position; our q = 0 is where the body is
        // drawn, so a non-zero ref would shift every joint value.
        let reference = mj.qpos0()[mj.jnt_qposadr()[joint] as usize];
        if reference != 0.0 {
            return Err(self.unsupported(
                element,
                format!("has ref=\"{reference}\"; only ref=\"0\" is read (the body is drawn at q = ref, the model's q = 0)"),
            ));
        }
        let axis = Vector3::from(mj.jnt_axis()[joint]);
        if !axis.iter().all(|v| v.is_finite()) || axis.norm() < 1e-9 {
            return Err(self.unsupported(element, format!("axis {axis:?} is not a finite non-zero vector")));
        }
        let limited = mj.jnt_limited()[joint];
        let [lower, upper] = mj.jnt_range()[joint];
        let kind = match (mj.jnt_type()[joint], limited) {
            (mjtJoint::mjJNT_HINGE, true) => JointKind::Revolute,
            (mjtJoint::mjJNT_HINGE, false) => JointKind::Continuous,
            (_, true) => JointKind::Prismatic,
            (_, false) => {
                return Err(self.unsupported(
                    element,
                    "is a slide joint without range; a prismatic joint needs lower and upper limits".into(),
                ))
            }
        };
        let limits = if limited {
            if !(lower.is_finite() && upper.is_finite() && lower <= upper) {
                return Err(self.unsupported(element, format!("range [{lower}, {upper}]: expected finite lower <= upper")));
            }
            Some([lower, upper])
        } else {
            None
        };
        Ok(Joint {
            name: self.name(MjtObjBase::mjOBJ_JOINT, joint),
            kind,
            parent_from_joint,
            axis: Unit::new_normalize(axis),
            limits,
            // MJCF has no velocity limit.
            max_velocity: None,
            max_effort: self.effort(joint),
        })
    }

    /// Rated effort: the joint's `actuatorfrcrange`, else what the actuators driving it can
    /// exert, added: a force-limited actuator's `forcerange` times its gear, a motor's (`<motor>`:
    /// fixed gain, no bias) `ctrlrange` times its gain and gear (the smaller of the two when both
    /// bound it); the larger magnitude of each range. `None` when any actuator on the joint is neither (a servo's ctrlrange is a position,
    /// not a force), or none drives it.
    fn effort(&self, joint: usize) -> Option<f64> {
        let mj = self.mj;
        let magnitude = |[lower, upper]: [f64; 2]| lower.abs().max(upper.abs());
        if mj.jnt_actfrclimited()[joint] {
            return Some(magnitude(mj.jnt_actfrcrange()[joint])).filter(|v| v.is_finite() && *v > 0.0);
        }
        let mut total = 0.0;
        let mut any = false;
        for actuator in 0..mj.ffi().nu as usize {
            let drives = matches!(mj.actuator_trntype()[actuator], mjtTrn::mjTRN_JOINT | mjtTrn::mjTRN_JOINTINPARENT)
                && mj.actuator_trnid()[actuator][0] as usize == joint;
            if !drives {
                continue;
            }
            let gear = mj.actuator_gear()[actuator][0].abs();
            let motor =
                mj.actuator_gaintype()[actuator] == mjtGain::mjGAIN_FIXED && mj.actuator_biastype()[actuator] == mjtBias::mjBIAS_NONE;
            let by_control = (motor && mj.actuator_ctrllimited()[actuator])
                .then(|| mj.actuator_gainprm()[actuator][0].abs() * magnitude(mj.actuator_ctrlrange()[actuator]));
            // MuJoCo clamps a motor's force to its forcerange after the gain: the smaller bound.
            let force = match (mj.actuator_forcelimited()[actuator], by_control) {
                (true, Some(control)) => magnitude(mj.actuator_forcerange()[actuator]).min(control),
                (true, None) => magnitude(mj.actuator_forcerange()[actuator]),
                (false, Some(control)) => control,
                (false, None) => return None,
            };
            any = true;
            total += gear * force;
        }
        Some(total).filter(|v| any && v.is_finite() && *v > 0.0)
    }
}
