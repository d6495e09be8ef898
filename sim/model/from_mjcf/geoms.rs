//! MJCF geoms -> colliders: MuJoCo's compiled geom types, sizes and frames become exact shapes in
//! the owner link's frame.

use super::{pose, Layout, Reader};
use crate::model::{Collider, Diagnostic, ModelError, Shape, TriMesh};
use mujoco_rs::mujoco_c::_mjtGeomBase as GeomType;
use mujoco_rs::prelude::*;
use nalgebra::{Isometry3, Point3};
use std::path::PathBuf;

impl Reader<'_> {
    /// The colliders of one body, in the frame of link `index` (its owner). Visual geoms
    /// (`contype` and `conaffinity` both 0) are skipped: they never collide in MuJoCo either.
    ///
    /// # Errors
    /// [`ModelError::UnsupportedMjcf`] for a plane, height field or SDF geom on a moving link
    /// (the base ignores planes and height fields: they are the floor), or a non-positive size.
    pub(in crate::model) fn colliders(
        &self,
        body: usize,
        index: usize,
        layout: &Layout,
        diagnostics: &mut Vec<Diagnostic>,
    ) -> Result<Vec<Collider>, ModelError> {
        let mj = self.mj;
        let first = mj.body_geomadr()[body];
        if first < 0 {
            return Ok(vec![]);
        }
        let first = first as usize;
        let mut colliders = Vec::new();
        for geom in first..first + mj.body_geomnum()[body] as usize {
            if mj.geom_contype()[geom] == 0 && mj.geom_conaffinity()[geom] == 0 {
                continue;
            }
            let name = self.name(MjtObjBase::mjOBJ_GEOM, geom);
            let element = format!("geom `{name}` of {}", self.body(body));
            let size = mj.geom_size()[geom];
            let positive = |values: &[f64], what: &str| -> Result<(), ModelError> {
                if values.iter().all(|v| v.is_finite() && *v > 0.0) {
                    Ok(())
                } else {
                    Err(self.unsupported(element.clone(), format!("{what} {values:?}: expected positive finite sizes")))
                }
            };
            let link_from_geom = layout.link_from_body[body] * pose(&mj.geom_pos()[geom], &mj.geom_quat()[geom]);
            let (geom_from_shape, shape) = match mj.geom_type()[geom] {
                GeomType::mjGEOM_PLANE | GeomType::mjGEOM_HFIELD if index == 0 => continue,
                kind @ (GeomType::mjGEOM_PLANE | GeomType::mjGEOM_HFIELD | GeomType::mjGEOM_SDF) => {
                    let what = match kind {
                        GeomType::mjGEOM_PLANE => "a plane",
                        GeomType::mjGEOM_HFIELD => "a height field",
                        _ => "an SDF",
                    };
                    return Err(self.unsupported(
                        element,
                        format!("is {what}; a robot link holds spheres, capsules, cylinders, boxes, ellipsoids and meshes only (planes and height fields are read on the base only, and ignored there)"),
                    ));
                }
                GeomType::mjGEOM_SPHERE => {
                    positive(&size[..1], "sphere radius")?;
                    (Isometry3::identity(), Shape::Sphere { radius: size[0] })
                }
                GeomType::mjGEOM_CAPSULE => {
                    positive(&size[..2], "capsule radius and half-length")?;
                    let shape = Shape::Capsule {
                        radius: size[0],
                        length: 2.0 * size[1],
                    };
                    (Isometry3::identity(), shape)
                }
                GeomType::mjGEOM_CYLINDER => {
                    positive(&size[..2], "cylinder radius and half-length")?;
                    let shape = Shape::Cylinder {
                        radius: size[0],
                        length: 2.0 * size[1],
                    };
                    (Isometry3::identity(), shape)
                }
                GeomType::mjGEOM_BOX => {
                    positive(&size, "box half-sizes")?;
                    (Isometry3::identity(), Shape::Box { half_extents: size })
                }
                GeomType::mjGEOM_ELLIPSOID => {
                    positive(&size, "ellipsoid semi-axes")?;
                    // The model has no ellipsoid; the enclosing sphere never misses a contact.
                    let radius = size.iter().copied().fold(0.0, f64::max);
                    diagnostics.push(Diagnostic {
                        path: self.path.to_path_buf(),
                        element: element.clone(),
                        message: format!("ellipsoid with semi-axes {size:?} m is checked as its enclosing sphere of radius {radius} m"),
                    });
                    (Isometry3::identity(), Shape::Sphere { radius })
                }
                GeomType::mjGEOM_MESH => self.mesh(geom, &element)?,
            };
            colliders.push(Collider {
                link_from_shape: link_from_geom * geom_from_shape,
                shape,
                label: format!("{}/{name}", self.name(MjtObjBase::mjOBJ_BODY, body)),
            });
        }
        Ok(colliders)
    }

    /// A mesh geom's triangles, in the mesh's own frame as written (MuJoCo moves a mesh to its
    /// centroid and principal axes and shifts the geom frame to match; `mesh_pos`/`mesh_quat`
    /// undo that), and that frame in the geom frame. Vertices are MuJoCo's single-precision,
    /// scaled copy.
    fn mesh(&self, geom: usize, element: &str) -> Result<(Isometry3<f64>, Shape), ModelError> {
        let mj = self.mj;
        let mesh = mj.geom_dataid()[geom];
        if mesh < 0 {
            return Err(self.unsupported(element.to_string(), "is a mesh geom without a mesh".into()));
        }
        let mesh = mesh as usize;
        let processed_from_original = pose(&mj.mesh_pos()[mesh], &mj.mesh_quat()[mesh]).inverse();
        let original_from_processed = processed_from_original.inverse();
        let (first_vertex, vertex_count) = (mj.mesh_vertadr()[mesh] as usize, mj.mesh_vertnum()[mesh] as usize);
        let vertices: Vec<[f64; 3]> = mj.mesh_vert()[first_vertex..first_vertex + vertex_count]
            .iter()
            .map(|v| {
                let p = original_from_processed * Point3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]));
                [p.x, p.y, p.z]
            })
            .collect();
        let (first_face, face_count) = (mj.mesh_faceadr()[mesh] as usize, mj.mesh_facenum()[mesh] as usize);
        let triangles: Vec<[u32; 3]> = mj.mesh_face()[first_face..first_face + face_count]
            .iter()
            .map(|f| f.map(|i| i as u32))
            .collect();
        if triangles.is_empty() || triangles.iter().flatten().any(|&i| i as usize >= vertex_count) {
            return Err(self.unsupported(
                element.to_string(),
                "mesh has no triangles, or a face names a missing vertex".into(),
            ));
        }
        let name = self.name(MjtObjBase::mjOBJ_MESH, mesh);
        let file = self.asset_path(mj.mesh_pathadr()[mesh]);
        Ok((
            processed_from_original,
            Shape::Mesh(TriMesh {
                uri: file
                    .as_ref()
                    .map(|f| f.display().to_string())
                    .unwrap_or_else(|| format!("mesh `{name}` (inline)")),
                file: file.unwrap_or_default(),
                scale: mj.mesh_scale()[mesh],
                vertices,
                triangles,
            }),
        ))
    }

    /// The asset path MuJoCo resolved, relative paths against the MJCF's folder.
    fn asset_path(&self, address: i32) -> Option<PathBuf> {
        let address = usize::try_from(address).ok()?;
        let paths = self.mj.paths();
        let bytes: Vec<u8> = paths.get(address..)?.iter().take_while(|&&c| c != 0).map(|&c| c as u8).collect();
        let text = String::from_utf8(bytes).ok().filter(|t| !t.is_empty())?;
        let path = PathBuf::from(text);
        Some(if path.is_absolute() {
            path
        } else {
            self.path.parent().map(|dir| dir.join(&path)).unwrap_or(path)
        })
    }
}
