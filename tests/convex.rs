//! Convex pieces of meshes (sim/convex.rs): coverage of the mesh, determinism, the disk cache.

mod common;

use proving_ground::convex::{self, ConvexPiece};
use proving_ground::model::{Model, Shape};
use proving_ground::pipeline::{load_model, LoadOptions};

fn ur5() -> Model {
    let path = common::fixture("urdf/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf");
    let opts = LoadOptions {
        tip_link: Some("tool0".into()),
        ..LoadOptions::default()
    };
    load_model(&path, &opts).expect("the UR5 fixture loads")
}

fn panda() -> Model {
    let opts = LoadOptions {
        tip_link: Some("panda_hand".into()),
        ..LoadOptions::default()
    };
    load_model(&common::panda_urdf(), &opts).expect("the Panda loads")
}

fn meshes(model: &Model) -> Vec<(String, &proving_ground::model::TriMesh)> {
    model
        .links
        .iter()
        .flat_map(|l| {
            l.colliders.iter().filter_map(move |c| match &c.shape {
                Shape::Mesh(m) => Some((format!("{} {}", l.name, c.label), m)),
                _ => None,
            })
        })
        .collect()
}

/// Largest distance (m) from a mesh vertex to the nearest piece (0 inside one).
fn uncovered(vertices: &[[f64; 3]], pieces: &[ConvexPiece]) -> f64 {
    use parry3d_f64::math::{Pose, Vector};
    use parry3d_f64::query::PointQuery;
    use parry3d_f64::shape::ConvexPolyhedron;
    let hulls: Vec<ConvexPolyhedron> = pieces
        .iter()
        .map(|p| {
            let points: Vec<Vector> = p.vertices.iter().map(|v| Vector::new(v[0], v[1], v[2])).collect();
            ConvexPolyhedron::from_convex_hull(&points).expect("a piece has a hull")
        })
        .collect();
    vertices
        .iter()
        .map(|v| {
            let point = Vector::new(v[0], v[1], v[2]);
            hulls
                .iter()
                .map(|h| h.distance_to_point(&Pose::identity(), point, true))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// Generalised winding number of a closed mesh at `p` (1 inside, 0 outside): the sum of the
/// triangles' signed solid angles (Van Oosterom and Strackee), independent of parry.
fn winding(vertices: &[[f64; 3]], triangles: &[[u32; 3]], p: nalgebra::Vector3<f64>) -> f64 {
    let v = |i: u32| nalgebra::Vector3::from(vertices[i as usize]) - p;
    let mut total = 0.0;
    for t in triangles {
        let (a, b, c) = (v(t[0]), v(t[1]), v(t[2]));
        let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
        let numerator = a.dot(&b.cross(&c));
        let denominator = la * lb * lc + a.dot(&b) * lc + b.dot(&c) * la + c.dot(&a) * lb;
        total += 2.0 * numerator.atan2(denominator);
    }
    total / (4.0 * std::f64::consts::PI)
}

/// Largest distance (m) from a point of a piece's surface (triangle centroids and edge
/// midpoints) outside the mesh to the mesh's surface: how far the pieces fill the mesh's
/// concavities (a piece's cut faces inside the mesh count 0).
fn overshoot(vertices: &[[f64; 3]], triangles: &[[u32; 3]], pieces: &[ConvexPiece]) -> f64 {
    use parry3d_f64::math::{Pose, Vector};
    use parry3d_f64::query::PointQuery;
    use parry3d_f64::shape::TriMesh;
    let points: Vec<Vector> = vertices.iter().map(|v| Vector::new(v[0], v[1], v[2])).collect();
    let mesh = TriMesh::new(points, triangles.to_vec()).expect("a mesh");
    let mut worst: f64 = 0.0;
    for piece in pieces {
        let v = |i: u32| nalgebra::Vector3::from(piece.vertices[i as usize]);
        for t in &piece.triangles {
            let (a, b, c) = (v(t[0]), v(t[1]), v(t[2]));
            for p in [(a + b + c) / 3.0, (a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0] {
                if winding(vertices, triangles, p) < 0.5 {
                    let d = mesh.distance_to_point(&Pose::identity(), Vector::new(p.x, p.y, p.z), false);
                    worst = worst.max(d);
                }
            }
        }
    }
    worst
}

fn bits(pieces: &[ConvexPiece]) -> Vec<(Vec<u64>, Vec<[u32; 3]>)> {
    pieces
        .iter()
        .map(|p| (p.vertices.iter().flatten().map(|v| v.to_bits()).collect(), p.triangles.clone()))
        .collect()
}

#[test]
fn pieces_contain_every_vertex_and_stay_near_the_surface() {
    for (robot, model) in [("ur5", ur5()), ("panda", panda())] {
        for (name, mesh) in meshes(&model) {
            let pieces = convex::decompose(&mesh.vertices, &mesh.triangles).expect("decomposes");
            // Each piece is the hull of the surface inside its voxels, so the pieces together
            // hold every vertex (to rounding).
            let uncovered = uncovered(&mesh.vertices, &pieces);
            assert!(uncovered < 1e-9, "{robot} {name}: a vertex {uncovered} m outside every piece");
            // How far the pieces fill the mesh's concavities (sampled on the pieces' faces):
            // measured 0.2 mm on the Panda, 12 mm on the UR5 (resolution 64).
            let bound = if robot == "panda" { 5e-4 } else { 15e-3 };
            let over = overshoot(&mesh.vertices, &mesh.triangles, &pieces);
            assert!(over < bound, "{robot} {name}: a piece reaches {over} m off the surface");
        }
    }
}

#[test]
fn decomposition_is_deterministic() {
    let model = panda();
    let (_, mesh) = meshes(&model).swap_remove(3);
    let a = convex::decompose(&mesh.vertices, &mesh.triangles).expect("decomposes");
    let b = convex::decompose(&mesh.vertices, &mesh.triangles).expect("decomposes");
    assert_eq!(bits(&a), bits(&b));
}

#[test]
fn the_disk_cache_gives_back_the_same_pieces_and_a_bad_entry_is_recomputed() {
    let model = panda();
    let (_, mesh) = meshes(&model).swap_remove(8);
    let dir = tempfile::tempdir().expect("temp dir");
    let cache = dir.path().join("convex");
    let (first, source) = convex::pieces_with_cache(&mesh.vertices, &mesh.triangles, Some(&cache));
    assert_eq!(source, convex::Source::Computed);
    let first = first.expect("decomposes");
    assert_eq!(
        bits(&first),
        bits(&convex::decompose(&mesh.vertices, &mesh.triangles).expect("decomposes"))
    );
    let file = cache.join(format!("{}.bin", convex::key(&mesh.vertices, &mesh.triangles)));
    assert!(file.is_file(), "{} written", file.display());

    let (again, source) = convex::pieces_with_cache(&mesh.vertices, &mesh.triangles, Some(&cache));
    assert_eq!(source, convex::Source::Memory);
    assert_eq!(bits(&again.expect("pieces")), bits(&first));

    convex::forget_in_memory();
    let (read, source) = convex::pieces_with_cache(&mesh.vertices, &mesh.triangles, Some(&cache));
    assert_eq!(source, convex::Source::Disk);
    assert_eq!(bits(&read.expect("pieces")), bits(&first));

    // Damaged in the middle, cut short, or not ours at all: recomputed, and the entry repaired.
    let good = std::fs::read(&file).expect("cache file");
    let mut flipped = good.clone();
    flipped[good.len() / 2] ^= 0x40;
    for bad in [flipped, good[..good.len() - 7].to_vec(), b"not a cache file".to_vec(), Vec::new()] {
        std::fs::write(&file, &bad).expect("damage the entry");
        convex::forget_in_memory();
        let (recomputed, source) = convex::pieces_with_cache(&mesh.vertices, &mesh.triangles, Some(&cache));
        assert_eq!(source, convex::Source::Computed);
        assert_eq!(bits(&recomputed.expect("pieces")), bits(&first));
        assert_eq!(std::fs::read(&file).expect("rewritten"), good);
    }
}

#[test]
fn a_cache_that_cannot_be_written_is_skipped() {
    let model = panda();
    let (_, mesh) = meshes(&model).swap_remove(7);
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("a-file");
    std::fs::write(&file, "in the way").expect("write");
    // A cache folder below a regular file can be neither created nor written.
    let cache = file.join("convex");
    let (pieces, source) = convex::pieces_with_cache(&mesh.vertices, &mesh.triangles, Some(&cache));
    assert_eq!(source, convex::Source::Computed);
    assert!(pieces.is_some());
    assert!(!cache.exists());
}

#[test]
fn a_flat_or_empty_mesh_has_no_pieces() {
    assert_eq!(convex::decompose(&[], &[]), None);
    let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    assert_eq!(convex::decompose(&flat, &[[0, 1, 2]]), None);
    assert_eq!(convex::decompose(&flat, &[[0, 1, 5]]), None, "an index out of range");
}
