//! MuJoCo (the official library, through mujoco-rs) as a kinematic oracle: body poses, sites and
//! Jacobians for a joint configuration, addressed by name so the same code reads our MJCF export
//! and MuJoCo's own import of our URDF export.

use super::EngineError;
use mujoco_rs::prelude::*;
use nalgebra::{Isometry3, Matrix6xX, Quaternion, Translation3, UnitQuaternion};
use std::path::Path;

/// The MuJoCo version proving-ground is verified against; `mujoco/PIN` says the same.
pub use crate::mujoco::MUJOCO_VERSION;

/// A loaded MuJoCo model with the joints of our chain located in it.
pub struct MujocoKinematics {
    model: MjModel,
    source_name: String,
    qpos_address: Vec<usize>,
    dof_address: Vec<usize>,
}

/// What MuJoCo computed for one configuration.
#[derive(Debug, Clone)]
pub struct MujocoSample {
    /// World pose of each requested body, in request order.
    pub bodies: Vec<Isometry3<f64>>,
    /// World pose of the requested site.
    pub site: Option<Isometry3<f64>>,
    /// Site Jacobian (rows: linear, angular; columns: our joint order), from `mj_jacSite`.
    pub site_jacobian: Option<Matrix6xX<f64>>,
}

impl MujocoKinematics {
    /// Loads MJCF or URDF text (MuJoCo tells them apart by the root element).
    ///
    /// # Errors
    /// [`EngineError::MujocoLoad`] with MuJoCo's message, or a missing joint.
    pub fn from_xml_str(xml: &str, source_name: &str, joint_names: &[&str]) -> Result<Self, EngineError> {
        check_version()?;
        let model = MjModel::from_xml_string(xml).map_err(|e| EngineError::MujocoLoad {
            source_name: source_name.into(),
            message: e.to_string(),
        })?;
        Self::locate(model, source_name, joint_names)
    }

    /// Loads an MJCF or URDF file; relative asset paths resolve against its folder.
    ///
    /// # Errors
    /// As [`MujocoKinematics::from_xml_str`].
    pub fn from_file(path: &Path, joint_names: &[&str]) -> Result<Self, EngineError> {
        check_version()?;
        let name = path.display().to_string();
        let model = MjModel::from_xml(path).map_err(|e| EngineError::MujocoLoad {
            source_name: name.clone(),
            message: e.to_string(),
        })?;
        Self::locate(model, &name, joint_names)
    }

    fn locate(model: MjModel, source_name: &str, joint_names: &[&str]) -> Result<Self, EngineError> {
        let mut qpos_address = Vec::with_capacity(joint_names.len());
        let mut dof_address = Vec::with_capacity(joint_names.len());
        for name in joint_names {
            let id = model
                .name_to_id(MjtObjBase::mjOBJ_JOINT, name)
                .ok_or_else(|| EngineError::MissingElement {
                    source_name: source_name.into(),
                    kind: "joint",
                    name: name.to_string(),
                })?;
            qpos_address.push(model.jnt_qposadr()[id] as usize);
            dof_address.push(model.jnt_dofadr()[id] as usize);
        }
        Ok(Self {
            model,
            source_name: source_name.into(),
            qpos_address,
            dof_address,
        })
    }

    /// Number of bodies including the world body.
    pub fn body_count(&self) -> usize {
        self.model.ffi().nbody as usize
    }

    /// Number of geoms (every body's, the world's included).
    pub fn geom_count(&self) -> usize {
        self.model.ffi().ngeom as usize
    }

    /// Number of sites.
    pub fn site_count(&self) -> usize {
        self.model.ffi().nsite as usize
    }

    /// Runs `mj_kinematics` and `mj_comPos` at `q` (our joint order; other joints stay at their
    /// reference position) and reads the named bodies and site.
    ///
    /// # Errors
    /// [`EngineError::MissingElement`] for an unknown body or site name.
    pub fn sample(&self, q: &[f64], bodies: &[&str], site: Option<&str>) -> Result<MujocoSample, EngineError> {
        let find = |kind: MjtObjBase, label: &'static str, name: &str| {
            self.model.name_to_id(kind, name).ok_or_else(|| EngineError::MissingElement {
                source_name: self.source_name.clone(),
                kind: label,
                name: name.to_string(),
            })
        };
        let body_ids = bodies
            .iter()
            .map(|b| find(MjtObjBase::mjOBJ_BODY, "body", b))
            .collect::<Result<Vec<_>, _>>()?;
        let site_id = site.map(|s| find(MjtObjBase::mjOBJ_SITE, "site", s)).transpose()?;

        let mut data = self.model.make_data();
        let reference: Vec<f64> = self.model.qpos0().to_vec();
        data.qpos_mut().copy_from_slice(&reference);
        for (&address, &value) in self.qpos_address.iter().zip(q) {
            data.qpos_mut()[address] = value;
        }
        data.kinematics();
        data.com_pos();

        let pose = |position: &[f64; 3], quaternion: &[f64; 4]| {
            Isometry3::from_parts(
                Translation3::new(position[0], position[1], position[2]),
                UnitQuaternion::new_normalize(Quaternion::new(quaternion[0], quaternion[1], quaternion[2], quaternion[3])),
            )
        };
        let body_poses = body_ids.iter().map(|&id| pose(&data.xpos()[id], &data.xquat()[id])).collect();
        let (site_pose, site_jacobian) = match site_id {
            Some(id) => {
                let matrix = data.site_xmat()[id];
                let rotation = nalgebra::Rotation3::from_matrix_unchecked(nalgebra::Matrix3::from_row_slice(&matrix));
                let position = data.site_xpos()[id];
                let site_pose = Isometry3::from_parts(
                    Translation3::new(position[0], position[1], position[2]),
                    UnitQuaternion::from_rotation_matrix(&rotation),
                );
                let (jacp, jacr) = data.jac_site(true, true, id);
                let nv = self.model.ffi().nv as usize;
                let mut jacobian = Matrix6xX::zeros(self.dof_address.len());
                for (column, &dof) in self.dof_address.iter().enumerate() {
                    for row in 0..3 {
                        jacobian[(row, column)] = jacp[row * nv + dof];
                        jacobian[(row + 3, column)] = jacr[row * nv + dof];
                    }
                }
                (Some(site_pose), Some(jacobian))
            }
            None => (None, None),
        };
        Ok(MujocoSample {
            bodies: body_poses,
            site: site_pose,
            site_jacobian,
        })
    }
}

/// A MuJoCo model whose geoms are measured against each other with `mj_geomDistance`: the
/// oracle for exact collision distances (tests only; MuJoCo is exact for spheres, capsules and
/// boxes, approximates cylinders, and uses the convex hull of a mesh).
pub struct MujocoGeomDistance {
    model: MjModel,
    source_name: String,
}

/// What `mj_geomDistance` reports for two geoms, world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeomDistance {
    /// Signed distance (m), negative in penetration; `distance_max` when farther than that.
    pub distance: f64,
    /// Witness point on the first geom (m); zero when farther than `distance_max`.
    pub from: [f64; 3],
    /// Witness point on the second geom (m); zero when farther than `distance_max`.
    pub to: [f64; 3],
}

impl MujocoGeomDistance {
    /// Loads MJCF text.
    ///
    /// # Errors
    /// [`EngineError::MujocoLoad`] with MuJoCo's message, or [`EngineError::Mujoco`].
    pub fn from_xml_str(xml: &str, source_name: &str) -> Result<Self, EngineError> {
        check_version()?;
        let model = MjModel::from_xml_string(xml).map_err(|e| EngineError::MujocoLoad {
            source_name: source_name.into(),
            message: e.to_string(),
        })?;
        Ok(Self {
            model,
            source_name: source_name.into(),
        })
    }

    /// Runs `mj_kinematics` at the reference configuration and measures each named geom pair,
    /// looking no farther than `distance_max` (m).
    ///
    /// # Errors
    /// [`EngineError::MissingElement`] for an unknown geom name.
    pub fn distances(&self, pairs: &[(&str, &str)], distance_max: f64) -> Result<Vec<GeomDistance>, EngineError> {
        let find = |name: &str| {
            self.model
                .name_to_id(MjtObjBase::mjOBJ_GEOM, name)
                .ok_or_else(|| EngineError::MissingElement {
                    source_name: self.source_name.clone(),
                    kind: "geom",
                    name: name.to_string(),
                })
        };
        let ids = pairs
            .iter()
            .map(|(a, b)| Ok((find(a)?, find(b)?)))
            .collect::<Result<Vec<_>, EngineError>>()?;
        let mut data = self.model.make_data();
        data.kinematics();
        Ok(ids
            .into_iter()
            .map(|(a, b)| {
                let mut fromto = [0.0; 6];
                let distance = data.geom_distance(a, b, distance_max, Some(&mut fromto));
                GeomDistance {
                    distance,
                    from: [fromto[0], fromto[1], fromto[2]],
                    to: [fromto[3], fromto[4], fromto[5]],
                }
            })
            .collect())
    }
}

/// Loads MuJoCo (first call only) and fails when it is missing or not the pinned version; every
/// use of MuJoCo starts here.
///
/// # Errors
/// [`EngineError::Mujoco`].
pub fn check_version() -> Result<(), EngineError> {
    crate::mujoco::check_version().map_err(EngineError::from)
}
