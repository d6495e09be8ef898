//! Mesh files: finding them (`package://`, `file://`, relative paths) and loading them (STL, OBJ,
//! DAE through mesh-loader).

use crate::limits;
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
    // `exists`, not `is_file`: a directory or FIFO of that name is reported as what it is.
    candidates.iter().find(|path| path.exists()).cloned().ok_or(candidates)
}

/// What to do about a mesh `uri` that is not where the URDF says: the end of a
/// [`super::ModelError::MissingMesh`] message.
pub(super) fn missing_mesh_hint(uri: &str) -> String {
    if let Some(rest) = uri.strip_prefix("package://") {
        let package = rest.split_once('/').map_or(rest, |(package, _)| package);
        format!(
            "give the folder that holds the package `{package}` (for a ROS workspace, its `src`) with --package-path DIR, or list it in ROS_PACKAGE_PATH"
        )
    } else if Path::new(uri.strip_prefix("file://").unwrap_or(uri)).is_absolute() {
        "the URDF names an absolute path that does not exist on this machine: edit its filename, or copy the mesh there".into()
    } else {
        "the path is relative to the URDF's folder: keep the meshes where they were beside the URDF, or edit its filename".into()
    }
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
/// The loader's message when the file is unreadable, not a regular file, over
/// [`limits::MAX_MESH_BYTES`], of an unknown format, inconsistent or has no triangles.
pub fn load_mesh(uri: &str, file: &Path, scale: [f64; 3]) -> Result<TriMesh, String> {
    let bytes = crate::files::read_bytes(file, limits::MAX_MESH_BYTES).map_err(|e| e.to_string())?;
    load_mesh_bytes(uri, &bytes, file, scale)
}

/// Reads a mesh from the bytes of `file` (the format is taken from its extension) and applies
/// `scale`. Files the mesh refers to (an OBJ's materials) are read through the same checks.
///
/// # Errors
/// As [`load_mesh`], and more than [`limits::MAX_MESH_TRIANGLES`] triangles, a binary STL whose
/// header disagrees with its size, a vertex beyond [`limits::MAX_LENGTH_M`].
pub fn load_mesh_bytes(uri: &str, bytes: &[u8], file: &Path, scale: [f64; 3]) -> Result<TriMesh, String> {
    let has_extension = |wanted: &str| {
        file.extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case(wanted))
    };
    if has_extension("stl") {
        check_binary_stl(bytes)?;
    }
    if has_extension("dae") {
        check_collada(bytes)?;
    }
    let load = || {
        mesh_loader::Loader::default()
            .merge_meshes(true)
            .load_from_slice_with_reader(bytes, file, |path| crate::files::read_bytes(path, limits::MAX_MESH_BYTES))
    };
    // mesh-loader 0.1 panics (`todo!`, map lookups) on some malformed COLLADA files; the checks
    // above refuse the known cases, this turns any other into an error too.
    let scene = std::panic::catch_unwind(load)
        .map_err(|_| {
            "the mesh loader (mesh-loader) could not read this file: it is malformed or uses a feature it does not support".to_string()
        })?
        .map_err(|e| e.to_string())?;
    let mesh = scene.meshes.into_iter().next().ok_or("the file holds no mesh")?;
    if mesh.faces.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    if mesh.faces.len() > limits::MAX_MESH_TRIANGLES {
        return Err(too_many_triangles(mesh.faces.len()));
    }
    let vertices: Vec<[f64; 3]> = mesh
        .vertices
        .iter()
        .map(|v| [f64::from(v[0]) * scale[0], f64::from(v[1]) * scale[1], f64::from(v[2]) * scale[2]])
        .collect();
    if vertices.iter().flatten().any(|c| !c.is_finite()) {
        return Err("a vertex coordinate is not finite".into());
    }
    if let Some(c) = vertices.iter().flatten().find(|c| c.abs() > limits::MAX_LENGTH_M) {
        return Err(format!(
            "a vertex coordinate is {c} m after scaling; expected at most {} m in absolute value",
            limits::MAX_LENGTH_M
        ));
    }
    let count = u32::try_from(vertices.len()).map_err(|_| "more vertices than fit in 32 bits".to_string())?;
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

fn too_many_triangles(count: usize) -> String {
    format!(
        "{count} triangles; the limit is {} per mesh (use a simplified collision mesh)",
        limits::MAX_MESH_TRIANGLES
    )
}

/// COLLADA references that mesh-loader follows without checking: every `#id` an `<input>` or
/// `<accessor>` names exists, and a primitive's VERTEX input names its mesh's `<vertices>`.
fn check_collada(bytes: &[u8]) -> Result<(), String> {
    let text = std::str::from_utf8(bytes).map_err(|e| format!("not UTF-8 text (byte {})", e.valid_up_to()))?;
    let doc = limits::parse_xml(text)?;
    let line = |node: roxmltree::Node| doc.text_pos_at(node.range().start).row;
    let mut ids: std::collections::HashMap<&str, roxmltree::Node> = std::collections::HashMap::new();
    for node in doc.descendants() {
        let Some(id) = node.attribute("id") else { continue };
        // Ids are unique in XML; with two, mesh-loader and this check could follow different ones.
        if let Some(first) = ids.insert(id, node) {
            return Err(format!("line {}: id `{id}` is also the id of line {}", line(node), line(first)));
        }
    }
    for node in doc.descendants().filter(|n| n.has_tag_name("input") || n.has_tag_name("accessor")) {
        let Some(source) = node.attribute("source") else { continue };
        let id = source.strip_prefix('#').unwrap_or(source);
        let Some(target) = ids.get(id) else {
            return Err(format!(
                "line {}: <{} source=\"{source}\"> names no element of this file",
                line(node),
                node.tag_name().name()
            ));
        };
        if id.is_empty() {
            return Err(format!(
                "line {}: <{} source=\"{source}\"> names no id",
                line(node),
                node.tag_name().name()
            ));
        }
        // Data inputs read a <source> through its accessor, which must read a float array.
        if target.has_tag_name("source") {
            let array = target
                .descendants()
                .find(|n| n.has_tag_name("accessor"))
                .and_then(|a| a.attribute("source"))
                .and_then(|s| ids.get(s.strip_prefix('#').unwrap_or(s)));
            if !array.is_some_and(|a| a.has_tag_name("float_array")) {
                return Err(format!(
                    "line {}: <source id=\"{id}\"> has no <accessor> of a <float_array> of this file",
                    line(*target)
                ));
            }
        }
        let in_primitive = node
            .parent()
            .is_some_and(|p| !p.has_tag_name("vertices") && !p.has_tag_name("sampler"));
        if node.attribute("semantic") == Some("VERTEX") && in_primitive && !target.has_tag_name("vertices") {
            return Err(format!(
                "line {}: the VERTEX input names <{}>; expected the mesh's <vertices>",
                line(node),
                target.tag_name().name()
            ));
        }
    }
    check_collada_indices(&doc, &ids)
}

/// Elements an accessor's or a `<p>`'s numbers are read from.
type Ids<'a, 'input> = std::collections::HashMap<&'a str, roxmltree::Node<'a, 'input>>;

/// How many items the `<source>` `id` holds (its accessor's `count`), after checking that its
/// array has the numbers the accessor reads.
fn source_count(ids: &Ids, id: &str, line: &dyn Fn(roxmltree::Node) -> u32) -> Result<usize, String> {
    let Some(source) = ids.get(id) else {
        return Err(format!("`#{id}` names no element of this file"));
    };
    if source.has_tag_name("vertices") {
        let position = source
            .children()
            .find(|n| n.attribute("semantic") == Some("POSITION"))
            .and_then(|n| n.attribute("source"))
            .ok_or_else(|| format!("line {}: <vertices> without a POSITION input", line(*source)))?;
        let id = position.strip_prefix('#').unwrap_or(position);
        let count = source_count(ids, id, line)?;
        // mesh-loader reads positions only through an accessor of float X, Y, Z (and otherwise
        // indexes an empty list).
        let accessor = ids.get(id).and_then(|s| s.descendants().find(|n| n.has_tag_name("accessor")));
        if let Some(accessor) = accessor {
            let params: Vec<_> = accessor.children().filter(|n| n.has_tag_name("param")).collect();
            let stride: usize = accessor.attribute("stride").unwrap_or("1").parse().unwrap_or(0);
            if stride < 3 || params.len() < 3 || params.iter().any(|p| p.attribute("type") != Some("float")) {
                return Err(format!(
                    "line {}: the positions' <accessor> needs stride 3 or more and three float <param>s (X, Y, Z)",
                    line(accessor)
                ));
            }
        }
        return Ok(count);
    }
    let accessor = source
        .descendants()
        .find(|n| n.has_tag_name("accessor"))
        .ok_or_else(|| format!("line {}: <{}> without an <accessor>", line(*source), source.tag_name().name()))?;
    let number = |name: &str| -> Result<usize, String> {
        accessor
            .attribute(name)
            .unwrap_or("1")
            .parse::<usize>()
            .map_err(|_| format!("line {}: <accessor {name}>: expected a whole number", line(accessor)))
    };
    let (count, stride) = (number("count")?, number("stride")?.max(1));
    let array = accessor
        .attribute("source")
        .and_then(|s| ids.get(s.strip_prefix('#').unwrap_or(s)))
        .ok_or_else(|| format!("line {}: <accessor> names no array of this file", line(accessor)))?;
    let held = array.text().unwrap_or("").split_whitespace().count();
    if count.checked_mul(stride).is_none_or(|needed| needed > held) {
        return Err(format!(
            "line {}: <accessor count=\"{count}\" stride=\"{stride}\"> reads more numbers than its array holds ({held})",
            line(accessor)
        ));
    }
    Ok(count)
}

/// Every index of a primitive's `<p>` points into the source its input reads.
fn check_collada_indices(doc: &roxmltree::Document, ids: &Ids) -> Result<(), String> {
    let line = |node: roxmltree::Node| doc.text_pos_at(node.range().start).row;
    const PRIMITIVES: [&str; 7] = ["triangles", "polylist", "polygons", "trifans", "tristrips", "lines", "linestrips"];
    for primitive in doc.descendants().filter(|n| PRIMITIVES.iter().any(|p| n.has_tag_name(*p))) {
        let mut inputs = Vec::new();
        for input in primitive.children().filter(|n| n.has_tag_name("input")) {
            let offset: usize = input
                .attribute("offset")
                .unwrap_or("0")
                .parse()
                .map_err(|_| format!("line {}: <input offset>: expected a whole number", line(input)))?;
            let source = input.attribute("source").unwrap_or("");
            let count = source_count(ids, source.strip_prefix('#').unwrap_or(source), &line)?;
            inputs.push((offset, count));
        }
        let stride = inputs.iter().map(|(offset, _)| offset + 1).max().unwrap_or(1);
        // mesh-loader reads `count` triangles (or the polygons of `<vcount>`) without checking
        // that `<p>` holds them.
        let held: usize = primitive
            .descendants()
            .filter(|n| n.has_tag_name("p"))
            .map(|p| p.text().unwrap_or("").split_whitespace().count())
            .sum();
        let whole = |text: &str, what: &str| -> Result<usize, String> {
            text.parse::<usize>()
                .map_err(|_| format!("line {}: {what}: `{text}` is not a whole number", line(primitive)))
        };
        let count = whole(primitive.attribute("count").unwrap_or("0"), "count")?;
        let corners = if primitive.has_tag_name("triangles") {
            Some(count.saturating_mul(3))
        } else if primitive.has_tag_name("polylist") {
            let mut sum = 0usize;
            for vc in primitive.children().filter(|n| n.has_tag_name("vcount")) {
                for word in vc.text().unwrap_or("").split_whitespace() {
                    let n = whole(word, "<vcount>")?;
                    if n == 0 {
                        return Err(format!("line {}: <vcount> has a polygon of 0 vertices", line(vc)));
                    }
                    sum = sum.saturating_add(n);
                }
            }
            Some(sum)
        } else {
            None
        };
        if let Some(corners) = corners {
            if corners.saturating_mul(stride) > held {
                return Err(format!(
                    "line {}: <{}> needs {} indices in <p>, it holds {held}",
                    line(primitive),
                    primitive.tag_name().name(),
                    corners.saturating_mul(stride)
                ));
            }
        }
        for p in primitive.descendants().filter(|n| n.has_tag_name("p")) {
            for (k, word) in p.text().unwrap_or("").split_whitespace().enumerate() {
                let index: usize = word
                    .parse()
                    .map_err(|_| format!("line {}: <p>: `{word}` is not an index", line(p)))?;
                if let Some((_, count)) = inputs.iter().find(|(offset, count)| *offset == k % stride && index >= *count) {
                    return Err(format!(
                        "line {}: <p>: index {index} is past the {count} items of its source",
                        line(p)
                    ));
                }
            }
        }
    }
    Ok(())
}

/// A binary STL's header states its triangle count; a count the file's size contradicts is a
/// truncated or corrupt file (0, written by some exporters, is accepted). ASCII STL is checked
/// by the parser.
fn check_binary_stl(bytes: &[u8]) -> Result<(), String> {
    const HEADER: usize = 84;
    const TRIANGLE: usize = 50;
    let trimmed = bytes.iter().position(|b| !b.is_ascii_whitespace()).map_or(&[][..], |i| &bytes[i..]);
    let held = bytes.len().saturating_sub(HEADER) / TRIANGLE;
    let stated = bytes
        .get(80..HEADER)
        .and_then(|b| <[u8; 4]>::try_from(b).ok())
        .map(|b| u32::from_le_bytes(b) as usize);
    let Some(stated) = stated else {
        // Shorter than a binary header: only ASCII STL can be that small.
        return if trimmed.starts_with(b"solid") {
            Ok(())
        } else {
            Err(format!("{} bytes: too short for an STL file", bytes.len()))
        };
    };
    let consistent = stated == held && (bytes.len() - HEADER).is_multiple_of(TRIANGLE);
    // "solid" opens ASCII STL, but some binary exporters write it into the header too.
    if trimmed.starts_with(b"solid") && !consistent {
        return Ok(());
    }
    if held > limits::MAX_MESH_TRIANGLES {
        return Err(too_many_triangles(held));
    }
    if stated != held && stated != 0 {
        return Err(format!(
            "binary STL header states {stated} triangles but the file holds {held} ({} bytes); the file is truncated or corrupt",
            bytes.len()
        ));
    }
    Ok(())
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

    fn binary_stl(stated: u32, held: usize) -> Vec<u8> {
        let mut bytes = vec![0u8; 80];
        bytes.extend_from_slice(&stated.to_le_bytes());
        for k in 0..held {
            let mut triangle = vec![0u8; 50];
            for (i, value) in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, k as f32].iter().enumerate() {
                triangle[12 + 4 * i..16 + 4 * i].copy_from_slice(&value.to_le_bytes());
            }
            bytes.extend(triangle);
        }
        bytes
    }

    #[test]
    fn stl_header_claiming_more_triangles_than_held_is_refused() {
        let file = Path::new("m.stl");
        assert!(load_mesh_bytes("m.stl", &binary_stl(2, 2), file, [1.0; 3]).is_ok());
        let error = load_mesh_bytes("m.stl", &binary_stl(3, 2), file, [1.0; 3]).expect_err("truncated");
        assert!(error.contains("states 3 triangles but the file holds 2"), "{error}");
        assert!(load_mesh_bytes("m.stl", &binary_stl(0, 2), file, [1.0; 3]).is_ok());
    }

    #[test]
    fn collada_with_a_dangling_source_is_an_error_not_a_panic() {
        let dae = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/meshes/tetrahedron.dae")).expect("fixture");
        let file = Path::new("m.dae");
        assert!(load_mesh_bytes("m.dae", dae.as_bytes(), file, [1.0; 3]).is_ok());
        let source = dae
            .split("source=\"#")
            .nth(1)
            .and_then(|rest| rest.split('"').next())
            .expect("a source reference");
        let broken = dae.replacen(&format!("source=\"#{source}\""), "source=\"#nowhere\"", 1);
        let error = load_mesh_bytes("m.dae", broken.as_bytes(), file, [1.0; 3]).expect_err("refused");
        assert!(error.contains("#nowhere"), "{error}");
    }

    #[test]
    fn a_mesh_over_the_triangle_limit_is_refused_before_parsing() {
        let held = limits::MAX_MESH_TRIANGLES + 1;
        let mut bytes = vec![0u8; 80];
        bytes.extend_from_slice(&(held as u32).to_le_bytes());
        bytes.resize(84 + 50 * held, 0);
        let error = load_mesh_bytes("big.stl", &bytes, Path::new("big.stl"), [1.0; 3]).expect_err("refused");
        assert!(error.contains("200001 triangles; the limit is 200000"), "{error}");
    }

    /// Inputs on which mesh-loader 0.1.13 panicked (found by `fuzz/run`, target mesh_dae).
    #[test]
    fn collada_inputs_that_made_mesh_loader_panic_are_errors() {
        let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/meshes/fuzz-dae"));
        let mut count = 0;
        for entry in std::fs::read_dir(dir).expect("fixtures") {
            let path = entry.expect("entry").path();
            let bytes = std::fs::read(&path).expect("read");
            let error = load_mesh_bytes("m.dae", &bytes, Path::new("m.dae"), [1.0; 3]).expect_err("refused");
            // Refused by the checks, not by the backstop around a panic.
            assert!(!error.contains("(mesh-loader) could not read"), "{}: {error}", path.display());
            count += 1;
        }
        assert!(count >= 10, "{count} fixtures");
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
