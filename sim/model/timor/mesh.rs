//! A Timor mesh geometry: a file relative to the module set's folder, scaled. STL, OBJ and DAE go
//! through the model's mesh loader; `.wrl` (VRML 2.0) files are Timor's convex decompositions
//! (made with bounding-mesh, one `IndexedFaceSet` per convex piece), read here, each piece a
//! collider of its own.

use super::set::Problem;
use crate::limits;
use crate::model::{load_mesh, Collider, Shape, TriMesh};
use nalgebra::Isometry3;
use std::collections::BTreeMap;
use std::path::Path;

/// The colliders of a mesh geometry with these parameters (`file`, optional `scale`); `dir` is
/// the folder the file is relative to, `anchor` says which for messages.
pub(crate) fn colliders(
    parameters: &BTreeMap<String, serde_json::Value>,
    element: &str,
    dir: &Path,
    label: &str,
    body_from_shape: Isometry3<f64>,
    anchor: &str,
) -> Result<Vec<Collider>, Problem> {
    let uri = parameters.get("file").and_then(serde_json::Value::as_str).ok_or_else(|| {
        (
            format!("{element} parameters"),
            format!("a mesh needs `file` (a path relative to {anchor})"),
        )
    })?;
    let scale = match parameters.get("scale") {
        None => [1.0; 3],
        Some(serde_json::Value::Number(n)) => [n.as_f64().unwrap_or(f64::NAN); 3],
        Some(serde_json::Value::Array(v)) if v.len() == 3 => std::array::from_fn(|k| v[k].as_f64().unwrap_or(f64::NAN)),
        Some(other) => {
            return Err((
                format!("{element} parameters scale"),
                format!("{other}; expected a number or three numbers"),
            ))
        }
    };
    if scale.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return Err((
            format!("{element} parameters scale"),
            format!("{scale:?}; expected positive numbers"),
        ));
    }
    let relative = uri.strip_prefix("package://").unwrap_or(uri);
    let file = dir.join(relative);
    if !file.is_file() {
        return Err((
            format!("{element} parameters file"),
            format!("mesh `{uri}` not found at {} (mesh files are relative to {anchor})", file.display()),
        ));
    }
    let is_wrl = file
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("wrl"));
    let meshes = if is_wrl {
        let text = crate::files::read_text(&file, limits::MAX_MESH_BYTES)
            .map_err(|e| (format!("{element} parameters file"), format!("cannot read {}: {e}", file.display())))?;
        read_wrl(&text, uri, &file, scale)
            .map_err(|problem| (format!("{element} parameters file"), format!("{}: {problem}", file.display())))?
    } else {
        vec![load_mesh(uri, &file, scale)
            .map_err(|problem| (format!("{element} parameters file"), format!("{}: {problem}", file.display())))?]
    };
    let count = meshes.len();
    Ok(meshes
        .into_iter()
        .enumerate()
        .map(|(p, mesh)| Collider {
            link_from_shape: body_from_shape,
            shape: Shape::Mesh(mesh),
            label: if count > 1 { format!("{label}/{p}") } else { label.to_string() },
        })
        .collect())
}

/// One convex piece: vertices and triangles.
type Piece = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// The pieces of a VRML 2.0 file: every `IndexedFaceSet`'s `point` list and `coordIndex`
/// polygons (fanned into triangles), scaled.
fn read_wrl(text: &str, uri: &str, file: &Path, scale: [f64; 3]) -> Result<Vec<TriMesh>, String> {
    if !text.starts_with("#VRML V2.0") {
        return Err("not a VRML 2.0 file (it does not start with `#VRML V2.0`)".into());
    }
    let mut tokens = Vec::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("");
        let spaced = line.replace('[', " [ ").replace(']', " ] ").replace('{', " { ").replace('}', " } ");
        tokens.extend(
            spaced
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|t| !t.is_empty())
                .map(str::to_string),
        );
    }
    let mut pieces: Vec<Piece> = Vec::new();
    let mut i = 0;
    let list = |i: &mut usize| -> Result<Vec<&str>, String> {
        if tokens.get(*i + 1).map(String::as_str) != Some("[") {
            return Err(format!("`{}` is not followed by `[`", tokens[*i]));
        }
        let start = *i + 2;
        let end = tokens[start..].iter().position(|t| t == "]").ok_or("a list is not closed by `]`")? + start;
        *i = end;
        Ok(tokens[start..end].iter().map(String::as_str).collect())
    };
    let mut triangle_count = 0usize;
    while i < tokens.len() {
        match tokens[i].as_str() {
            "point" => {
                let numbers = list(&mut i)?
                    .iter()
                    .map(|t| t.parse::<f64>().map_err(|_| format!("`{t}` in a point list is not a number")))
                    .collect::<Result<Vec<f64>, String>>()?;
                if numbers.len() % 3 != 0 {
                    return Err(format!("a point list holds {} numbers, not a multiple of 3", numbers.len()));
                }
                let vertices: Vec<[f64; 3]> = numbers
                    .chunks(3)
                    .map(|c| [c[0] * scale[0], c[1] * scale[1], c[2] * scale[2]])
                    .collect();
                if let Some(c) = vertices.iter().flatten().find(|c| !c.is_finite() || c.abs() > limits::MAX_LENGTH_M) {
                    return Err(format!(
                        "a vertex coordinate is {c} m; expected finite, at most {} m",
                        limits::MAX_LENGTH_M
                    ));
                }
                pieces.push((vertices, Vec::new()));
            }
            "coordIndex" => {
                let (vertices, triangles) = pieces.last_mut().ok_or("`coordIndex` comes before any `point` list")?;
                let mut polygon: Vec<u32> = Vec::new();
                for t in list(&mut i)?.into_iter().chain(std::iter::once("-1")) {
                    let index: i64 = t.parse().map_err(|_| format!("`{t}` in coordIndex is not an integer"))?;
                    if index < 0 {
                        for k in 1..polygon.len().saturating_sub(1) {
                            triangles.push([polygon[0], polygon[k], polygon[k + 1]]);
                        }
                        polygon.clear();
                        continue;
                    }
                    let index = u32::try_from(index).ok().filter(|&v| (v as usize) < vertices.len());
                    polygon.push(index.ok_or_else(|| format!("coordIndex {t} names no vertex ({} in this piece)", vertices.len()))?);
                }
                triangle_count += triangles.len();
                if triangle_count > limits::MAX_MESH_TRIANGLES {
                    return Err(format!("more than {} triangles (the limit)", limits::MAX_MESH_TRIANGLES));
                }
            }
            _ => {}
        }
        i += 1;
    }
    let meshes: Vec<TriMesh> = pieces
        .into_iter()
        .filter(|(_, triangles)| !triangles.is_empty())
        .map(|(vertices, triangles)| TriMesh {
            uri: uri.to_string(),
            file: file.to_path_buf(),
            scale,
            vertices,
            triangles,
        })
        .collect();
    if meshes.is_empty() {
        return Err("holds no IndexedFaceSet with triangles".into());
    }
    Ok(meshes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_each_face_set_as_a_piece() {
        let text = "#VRML V2.0 utf8\n# a comment [\nShape { geometry IndexedFaceSet { coord Coordinate { point [\n 0 0 0, 1 0 0,\n 0 1 0, 0 0 1 ] }\n coordIndex [ 0, 1, 2, -1, 0, 1, 3, 2, -1 ] } }\nShape { geometry IndexedFaceSet { coord Coordinate { point [ 0 0 0, 2 0 0, 0 2 0 ] } coordIndex [ 0, 1, 2 ] } }\n";
        let pieces = read_wrl(text, "a.wrl", Path::new("a.wrl"), [1.0, 1.0, 2.0]).expect("valid");
        assert_eq!(pieces.len(), 2);
        assert_eq!(pieces[0].triangles, vec![[0, 1, 2], [0, 1, 3], [0, 3, 2]]);
        assert_eq!(pieces[0].vertices[3], [0.0, 0.0, 2.0]);
        assert_eq!(pieces[1].triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn refuses_what_it_cannot_read() {
        assert!(read_wrl("solid x", "a", Path::new("a"), [1.0; 3])
            .expect_err("not vrml")
            .contains("VRML"));
        let bad = "#VRML V2.0 utf8\npoint [ 0 0 0 ] coordIndex [ 0, 0, 5, -1 ]";
        assert!(read_wrl(bad, "a", Path::new("a"), [1.0; 3])
            .expect_err("index")
            .contains("names no vertex"));
        let odd = "#VRML V2.0 utf8\npoint [ 0 0 ]";
        assert!(read_wrl(odd, "a", Path::new("a"), [1.0; 3])
            .expect_err("count")
            .contains("multiple of 3"));
    }
}
