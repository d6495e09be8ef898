//! Mesh files: finding them (`package://`, `file://`, relative paths) and loading them (STL, OBJ,
//! DAE through mesh-loader).

use serde::Serialize;
use std::path::{Path, PathBuf};

/// A triangle mesh in its shape frame, scale already applied.
#[derive(Debug, Clone, Serialize)]
pub struct TriMesh {
    /// The mesh file as written in the robot description.
    pub uri: String,
    /// The file it resolved to.
    #[serde(skip)]
    pub file: PathBuf,
    /// Scale applied per axis.
    pub scale: [f64; 3],
    /// Vertex positions in metres.
    #[serde(skip)]
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as vertex indices.
    #[serde(skip)]
    pub triangles: Vec<[u32; 3]>,
}

/// Finds the file a mesh URI names.
///
/// - `package://NAME/REST`: `ROOT/NAME/REST` or, where `ROOT` itself is named `NAME`,
///   `ROOT/REST`, for every root in `package_paths` and then every folder that contains the
///   robot description (so a description shipped with its package needs no search path);
/// - `file://PATH` and plain paths: absolute as they are, relative to `description_dir`.
///
/// # Errors
/// Returns every place searched when none holds the file.
pub fn resolve_mesh_uri(uri: &str, description_dir: &Path, package_paths: &[PathBuf]) -> Result<PathBuf, Vec<PathBuf>> {
    let candidates: Vec<PathBuf> = if let Some(rest) = uri.strip_prefix("package://") {
        let (package, inner) = rest.split_once('/').unwrap_or((rest, ""));
        let roots = package_paths
            .iter()
            .cloned()
            .chain(description_dir.ancestors().map(Path::to_path_buf));
        roots
            .flat_map(|root| {
                let mut found = vec![root.join(package).join(inner)];
                if root.file_name().is_some_and(|name| name == package) {
                    found.push(root.join(inner));
                }
                found
            })
            .collect()
    } else {
        let plain = uri.strip_prefix("file://").unwrap_or(uri);
        vec![description_dir.join(plain)]
    };
    candidates.iter().find(|path| path.is_file()).cloned().ok_or(candidates)
}

/// Package search roots from a `ROS_PACKAGE_PATH`-style variable (`:`-separated).
pub fn package_paths_from_env(value: Option<&str>) -> Vec<PathBuf> {
    value
        .map(|v| v.split(':').filter(|s| !s.is_empty()).map(PathBuf::from).collect())
        .unwrap_or_default()
}

/// Loads a mesh file and applies `scale`.
///
/// # Errors
/// The loader's message when the file is unreadable, of an unknown format or has no triangles.
pub fn load_mesh(uri: &str, file: &Path, scale: [f64; 3]) -> Result<TriMesh, String> {
    let scene = mesh_loader::Loader::default()
        .merge_meshes(true)
        .load(file)
        .map_err(|e| e.to_string())?;
    let mesh = scene.meshes.into_iter().next().ok_or("the file holds no mesh")?;
    if mesh.faces.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    let vertices: Vec<[f64; 3]> = mesh
        .vertices
        .iter()
        .map(|v| [f64::from(v[0]) * scale[0], f64::from(v[1]) * scale[1], f64::from(v[2]) * scale[2]])
        .collect();
    if vertices.iter().flatten().any(|c| !c.is_finite()) {
        return Err("a vertex coordinate is not finite".into());
    }
    let count = vertices.len() as u32;
    if mesh.faces.iter().flatten().any(|&i| i >= count) {
        return Err("a face refers to a vertex that does not exist".into());
    }
    Ok(TriMesh {
        uri: uri.to_string(),
        file: file.to_path_buf(),
        scale,
        vertices,
        triangles: mesh.faces,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn package_uri_lists_every_place_searched() {
        let dir = Path::new("/nonexistent/robot/urdf");
        let searched = resolve_mesh_uri("package://arm/meshes/a.stl", dir, &[PathBuf::from("/opt/ros")]).unwrap_err();
        assert_eq!(searched[0], PathBuf::from("/opt/ros/arm/meshes/a.stl"));
        assert!(searched.contains(&PathBuf::from("/nonexistent/robot/urdf/arm/meshes/a.stl")));
        assert!(searched.contains(&PathBuf::from("/nonexistent/arm/meshes/a.stl")));
    }

    #[test]
    fn package_root_named_like_the_package_is_used_directly() {
        let searched = resolve_mesh_uri("package://arm/m.stl", Path::new("/x"), &[PathBuf::from("/ws/arm")]).unwrap_err();
        assert!(searched.contains(&PathBuf::from("/ws/arm/m.stl")));
    }

    #[test]
    fn env_path_splits_on_colons() {
        assert_eq!(
            package_paths_from_env(Some("/a::/b")),
            vec![PathBuf::from("/a"), PathBuf::from("/b")]
        );
        assert!(package_paths_from_env(None).is_empty());
    }
}
