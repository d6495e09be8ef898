//! Our kinematics against MuJoCo's on the same model: every link body, the tool frame and the
//! tool Jacobian at seeded random configurations.

use super::{EngineError, MujocoKinematics};
use crate::frames::pose_difference;
use crate::model::Model;
use nalgebra::Isometry3;
use rand::SeedableRng;
use serde::Serialize;

/// Which element of the MuJoCo model holds the tool frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ToolElement<'a> {
    /// A site (our MJCF export writes `tool`).
    Site(&'a str),
    /// A body (MuJoCo's import of our URDF export has a `tool` link).
    Body(&'a str),
}

/// Largest disagreements found, and where.
#[derive(Debug, Clone, Serialize)]
pub struct KinematicsAgreement {
    /// Configurations compared.
    pub configurations: usize,
    /// Bodies compared per configuration (links plus the tool).
    pub bodies: usize,
    /// Largest link-or-tool position difference (m).
    pub max_position_error_m: f64,
    /// Largest link-or-tool orientation difference (rad).
    pub max_angle_error_rad: f64,
    /// Largest absolute difference of one Jacobian entry, when the tool is a site.
    pub max_jacobian_error: Option<f64>,
    /// The body or `tool` where the largest position difference occurred.
    pub worst_element: String,
    /// The configuration of the largest position difference (rad or m).
    pub worst_configuration: Vec<f64>,
}

/// Compares our FK and Jacobian with MuJoCo's at `configurations` random configurations.
///
/// # Errors
/// When MuJoCo lacks a link body, joint, or the tool element.
pub fn compare_kinematics(
    model: &Model,
    mujoco: &MujocoKinematics,
    tool: ToolElement,
    configurations: usize,
    seed: u64,
) -> Result<KinematicsAgreement, EngineError> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut bodies: Vec<&str> = model.links.iter().map(|l| l.name.as_str()).collect();
    if let ToolElement::Body(name) = tool {
        bodies.push(name);
    }
    let site = match tool {
        ToolElement::Site(name) => Some(name),
        ToolElement::Body(_) => None,
    };
    let mut ws = model.workspace();
    let mut agreement = KinematicsAgreement {
        configurations,
        bodies: model.links.len() + 1,
        max_position_error_m: 0.0,
        max_angle_error_rad: 0.0,
        max_jacobian_error: site.map(|_| 0.0),
        worst_element: String::new(),
        worst_configuration: vec![],
    };
    for _ in 0..configurations {
        let q = model.random_configuration(&mut rng);
        model.jacobian(&q, &mut ws);
        let sample = mujoco.sample(&q, &bodies, site)?;
        let mut ours: Vec<(&str, Isometry3<f64>)> = model
            .links
            .iter()
            .map(|l| l.name.as_str())
            .zip(ws.link_in_world.iter().copied())
            .collect();
        if let ToolElement::Body(name) = tool {
            ours.push((name, ws.tool_in_world));
        }
        let mut theirs: Vec<Isometry3<f64>> = sample.bodies.clone();
        if let (Some(site_pose), Some(name)) = (sample.site, site) {
            ours.push((name, ws.tool_in_world));
            theirs.push(site_pose);
        }
        for ((name, our_pose), their_pose) in ours.iter().zip(&theirs) {
            let (dt, da) = pose_difference(our_pose, their_pose);
            if dt > agreement.max_position_error_m || agreement.worst_configuration.is_empty() {
                agreement.max_position_error_m = dt.max(agreement.max_position_error_m);
                agreement.worst_element = name.to_string();
                agreement.worst_configuration = q.clone();
            }
            agreement.max_angle_error_rad = agreement.max_angle_error_rad.max(da);
        }
        if let (Some(jacobian), Some(max)) = (&sample.site_jacobian, agreement.max_jacobian_error.as_mut()) {
            *max = max.max((jacobian - &ws.jacobian).abs().max());
        }
    }
    Ok(agreement)
}

/// Largest position (m), angle (rad) or Jacobian-entry difference between our kinematics and
/// MuJoCo's on the MJCF export that still agrees: both compute in f64 from the same numbers, so
/// anything above rounding is a bug in proving-ground, never a tolerance to loosen. Worst measured
/// on the shipped designs: about 1e-15.
pub const KINEMATICS_AGREEMENT: f64 = 1e-9;

/// The acceptance check of our kinematics against MuJoCo's on the MJCF export.
#[derive(Debug, Clone, Serialize)]
pub struct KinematicsCheck {
    /// The MuJoCo version that ran.
    pub mujoco_version: &'static str,
    /// Seed of the random configurations.
    pub seed: u64,
    /// What was compared and the largest differences.
    #[serde(flatten)]
    pub agreement: KinematicsAgreement,
    /// [`KINEMATICS_AGREEMENT`].
    pub tolerance: f64,
    /// Every difference within the tolerance.
    pub agree: bool,
}

impl KinematicsCheck {
    /// One line for a human: what was compared, the largest differences, agree or DISAGREE.
    pub fn line(&self) -> String {
        let a = &self.agreement;
        format!(
            "MuJoCo {} vs our kinematics on the MJCF export, {} configurations (seed {}): \
             max position error {:.1e} m, max angle error {:.1e} rad, max Jacobian error {:.1e}: {}",
            self.mujoco_version,
            a.configurations,
            self.seed,
            a.max_position_error_m,
            a.max_angle_error_rad,
            a.max_jacobian_error.unwrap_or(0.0),
            if self.agree { "agree" } else { "DISAGREE" }
        )
    }
}

/// Loads `mjcf` (the export of `model`, its tool a site `tool`) in MuJoCo and compares its
/// kinematics with ours at `configurations` seeded random configurations.
///
/// # Errors
/// [`EngineError`] when MuJoCo refuses the text or lacks a link, joint or the tool site.
pub fn check_kinematics(
    model: &Model,
    mjcf: &str,
    source_name: &str,
    configurations: usize,
    seed: u64,
) -> Result<KinematicsCheck, EngineError> {
    let joint_names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
    let mujoco = MujocoKinematics::from_xml_str(mjcf, source_name, &joint_names)?;
    let agreement = compare_kinematics(model, &mujoco, ToolElement::Site("tool"), configurations, seed)?;
    let worst = agreement
        .max_position_error_m
        .max(agreement.max_angle_error_rad)
        .max(agreement.max_jacobian_error.unwrap_or(0.0));
    Ok(KinematicsCheck {
        mujoco_version: super::MUJOCO_VERSION,
        seed,
        agree: worst <= KINEMATICS_AGREEMENT,
        agreement,
        tolerance: KINEMATICS_AGREEMENT,
    })
}
