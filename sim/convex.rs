//! Convex pieces of a triangle mesh, for the physics engines: rapier colliding two non-convex
//! trimeshes is slow (it dominated a UR5 run), and MuJoCo collides a mesh as its convex hull,
//! which fills a gripper's opening or a U-shaped part. Both engines get the same pieces instead:
//! a VHACD decomposition (parry), each piece the exact convex hull of the original surface inside
//! it (the mesh's own vertices and its triangles clipped to the piece's voxels), so the pieces hug
//! the real surface. Exact geometry (the collision world, the re-measuring of engine contacts)
//! keeps using the mesh itself.
//!
//! A decomposition is computed once per mesh and kept on disk ([`cache_dir`]), keyed by a SHA-256
//! of the mesh's vertex and triangle bytes, the parameters and [`FORMAT_VERSION`]; within a
//! process it is also kept in memory. A cache entry that cannot be read or does not check out is
//! recomputed; a cache that cannot be written is skipped. VHACD is deterministic (no hashing, no
//! threads), so the same mesh gives the same pieces bit for bit, cached or not.

use crate::model::TriMesh;
use parry3d_f64::math::Vector;
use parry3d_f64::transformation::vhacd::{VHACDParameters, VHACD};
use parry3d_f64::transformation::voxelization::FillMode;
use sha2::{Digest, Sha256};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

/// Version of the decomposition and of the cache file layout; a change makes new keys.
pub const FORMAT_VERSION: u32 = 1;

/// Voxel grid resolution along the mesh's longest side. 64 cells on a 0.2 m UR5 link are about
/// 3 mm; the exact hulls then follow the surface, not the voxels.
pub const RESOLUTION: u32 = 64;
/// Largest concavity VHACD leaves in a piece (fraction of the mesh's size).
pub const CONCAVITY: f64 = 0.01;
/// VHACD's `max_convex_hulls`, a target it can overshoot by a few (5 to 10 pieces per Panda and
/// UR5 link): each piece is one more convex shape per contact test.
pub const MAX_PIECES: u32 = 16;
/// The decomposing library, part of the key: another version may cut a mesh differently, and a
/// cached decomposition must be the one this build would compute.
const DECOMPOSER: &str = "parry3d-f64 0.31 VHACD, exact hulls";

const MAGIC: &[u8; 8] = b"PGCONVEX";
/// Larger cache files are not read (a real mesh's pieces are well below a megabyte).
const MAX_CACHE_FILE_BYTES: u64 = 64 << 20;

/// One convex piece: its hull's vertices (m, the mesh's frame) and outward triangles.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvexPiece {
    /// Hull vertices.
    pub vertices: Vec<[f64; 3]>,
    /// Hull triangles as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

/// Where a decomposition came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// This process had already computed or read it.
    Memory,
    /// Read from the disk cache.
    Disk,
    /// Computed now (no cache entry, or one that did not read back); written to the cache if
    /// there is one.
    Computed,
}

/// The VHACD parameters of [`decompose`].
pub fn parameters() -> VHACDParameters {
    VHACDParameters {
        resolution: RESOLUTION,
        concavity: CONCAVITY,
        max_convex_hulls: MAX_PIECES,
        fill_mode: FillMode::FloodFill { detect_cavities: false },
        ..VHACDParameters::default()
    }
}

/// The cache folder: `$XDG_CACHE_HOME/proving-ground/convex`, else
/// `$HOME/.cache/proving-ground/convex`, else one in the temporary folder. Never a folder of an
/// input: the key names no user file.
pub fn cache_dir() -> PathBuf {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty() && Path::new(v).is_absolute())
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME")
                .filter(|v| !v.is_empty() && Path::new(v).is_absolute())
                .map(|home| PathBuf::from(home).join(".cache"))
        })
        .unwrap_or_else(std::env::temp_dir);
    base.join("proving-ground").join("convex")
}

/// The cache key of a mesh: hex SHA-256 of the format version, the decomposer, the parameters
/// and the mesh.
pub fn key(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> String {
    let mut hash = Sha256::new();
    hash.update(MAGIC);
    hash.update(FORMAT_VERSION.to_le_bytes());
    hash.update(DECOMPOSER.as_bytes());
    let p = parameters();
    hash.update(format!("{p:?}").as_bytes());
    hash.update((vertices.len() as u64).to_le_bytes());
    for v in vertices.iter().flatten() {
        hash.update(v.to_le_bytes());
    }
    hash.update((triangles.len() as u64).to_le_bytes());
    for i in triangles.iter().flatten() {
        hash.update(i.to_le_bytes());
    }
    hash.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// Pieces of a decomposition; `None` when the mesh cannot be decomposed (no triangles, or flat:
/// VHACD finds no volume), and the engines then take the mesh as it is.
pub type Pieces = Option<Arc<Vec<ConvexPiece>>>;

/// Per memory key, the pieces once known: threads asking for the same mesh at once (the rapier
/// and MuJoCo runs of one validation) wait for one decomposition instead of repeating it.
type Memory = HashMap<String, Arc<OnceLock<Pieces>>>;

static MEMORY: Mutex<Option<Memory>> = Mutex::new(None);

/// The convex pieces of `mesh`, from memory, the disk cache ([`cache_dir`]) or computed.
pub fn pieces(mesh: &TriMesh) -> Pieces {
    pieces_with_cache(&mesh.vertices, &mesh.triangles, Some(&cache_dir())).0
}

/// Computes (or reads) the pieces of several meshes in parallel, so that later [`pieces`] calls
/// find them in memory.
pub fn prepare<'a>(meshes: impl IntoIterator<Item = &'a TriMesh>) {
    use rayon::prelude::*;
    let meshes: Vec<&TriMesh> = meshes.into_iter().collect();
    meshes.par_iter().for_each(|mesh| {
        pieces(mesh);
    });
}

/// The convex pieces of a mesh with the disk cache in `dir` (`None`: no disk cache), and where
/// they came from.
pub fn pieces_with_cache(vertices: &[[f64; 3]], triangles: &[[u32; 3]], dir: Option<&Path>) -> (Pieces, Source) {
    let key = key(vertices, triangles);
    let memory_key = match dir {
        Some(dir) => format!("{}/{key}", dir.display()),
        None => key.clone(),
    };
    let cell = lock_memory()
        .get_or_insert_with(HashMap::new)
        .entry(memory_key)
        .or_default()
        .clone();
    let mut source = Source::Memory;
    let pieces = cell.get_or_init(|| {
        let file = dir.map(|d| d.join(format!("{key}.bin")));
        if let Some(pieces) = file.as_deref().and_then(read_cache) {
            source = Source::Disk;
            return pieces;
        }
        source = Source::Computed;
        let pieces = decompose(vertices, triangles);
        if let (Some(dir), Some(file)) = (dir, &file) {
            // A cache that cannot be written (read-only or missing home) only costs time.
            let _ = std::fs::create_dir_all(dir)
                .and_then(|()| crate::files::write_atomic(file, &encode(pieces.as_deref()), true).map_err(std::io::Error::other));
        }
        pieces.map(Arc::new)
    });
    (pieces.clone(), source)
}

/// Forgets the pieces this process knows, so the next request reads the disk cache (tests).
pub fn forget_in_memory() {
    if let Some(memory) = lock_memory().as_mut() {
        memory.clear();
    }
}

fn lock_memory() -> std::sync::MutexGuard<'static, Option<Memory>> {
    // A panic while holding the lock leaves a map of complete entries: still usable.
    MEMORY.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Decomposes a mesh without any cache.
pub fn decompose(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Option<Vec<ConvexPiece>> {
    decompose_with(vertices, triangles, &parameters())
}

/// Decomposes a mesh with other VHACD parameters (to measure them; the engines use
/// [`decompose`]'s).
pub fn decompose_with(vertices: &[[f64; 3]], triangles: &[[u32; 3]], params: &VHACDParameters) -> Option<Vec<ConvexPiece>> {
    if triangles.is_empty() || triangles.iter().flatten().any(|&i| i as usize >= vertices.len()) {
        return None;
    }
    let points: Vec<Vector> = vertices.iter().map(|v| Vector::new(v[0], v[1], v[2])).collect();
    // parry asserts on some degenerate inputs; a mesh it cannot decompose is used whole.
    let hulls =
        std::panic::catch_unwind(|| VHACD::decompose(params, &points, triangles, true).compute_exact_convex_hulls(&points, triangles))
            .ok()?;
    let pieces: Vec<ConvexPiece> = hulls
        .into_iter()
        // A flat or empty part has no hull: its surface is covered by its neighbours' hulls.
        .filter(|(points, triangles)| points.len() >= 4 && !triangles.is_empty())
        .map(|(points, triangles)| ConvexPiece {
            vertices: points.iter().map(|p| [p.x, p.y, p.z]).collect(),
            triangles,
        })
        .collect();
    (!pieces.is_empty()).then_some(pieces)
}

/// Cache file: magic, version, then `0` (no decomposition) or `1`, the piece count and per
/// piece its vertex and triangle counts, vertices (f64) and triangles (u32), all little-endian;
/// last the SHA-256 of everything before it.
fn encode(pieces: Option<&[ConvexPiece]>) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    match pieces {
        None => out.push(0),
        Some(pieces) => {
            out.push(1);
            out.extend_from_slice(&(pieces.len() as u32).to_le_bytes());
            for piece in pieces {
                out.extend_from_slice(&(piece.vertices.len() as u32).to_le_bytes());
                out.extend_from_slice(&(piece.triangles.len() as u32).to_le_bytes());
                for v in piece.vertices.iter().flatten() {
                    out.extend_from_slice(&v.to_le_bytes());
                }
                for i in piece.triangles.iter().flatten() {
                    out.extend_from_slice(&i.to_le_bytes());
                }
            }
        }
    }
    let digest = Sha256::digest(&out);
    out.extend_from_slice(&digest);
    out
}

fn read_cache(file: &Path) -> Option<Pieces> {
    let meta = std::fs::metadata(file).ok()?;
    if !meta.is_file() || meta.len() > MAX_CACHE_FILE_BYTES {
        return None;
    }
    decode(&std::fs::read(file).ok()?)
}

/// The pieces of a cache file; `None` for anything that does not check out.
fn decode(bytes: &[u8]) -> Option<Pieces> {
    let (body, digest) = bytes.split_at_checked(bytes.len().checked_sub(32)?)?;
    if Sha256::digest(body).as_slice() != digest {
        return None;
    }
    let mut reader = Reader { bytes: body };
    if reader.take(8)? != MAGIC || reader.u32()? != FORMAT_VERSION {
        return None;
    }
    let pieces = match reader.take(1)?[0] {
        0 => None,
        1 => {
            let count = reader.u32()? as usize;
            let mut pieces = Vec::with_capacity(count.min(1024));
            for _ in 0..count {
                let (nv, nt) = (reader.u32()? as usize, reader.u32()? as usize);
                let vertices = (0..nv)
                    .map(|_| Some([reader.f64()?, reader.f64()?, reader.f64()?]))
                    .collect::<Option<Vec<_>>>()?;
                let triangles = (0..nt)
                    .map(|_| Some([reader.u32()?, reader.u32()?, reader.u32()?]))
                    .collect::<Option<Vec<_>>>()?;
                let finite = vertices.iter().flatten().all(|v| v.is_finite());
                if !finite || triangles.iter().flatten().any(|&i| i as usize >= nv) || nv < 4 || nt == 0 {
                    return None;
                }
                pieces.push(ConvexPiece { vertices, triangles });
            }
            if pieces.is_empty() {
                return None;
            }
            Some(Arc::new(pieces))
        }
        _ => return None,
    };
    reader.bytes.is_empty().then_some(pieces)
}

struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let (head, tail) = self.bytes.split_at_checked(n)?;
        self.bytes = tail;
        Some(head)
    }

    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }

    fn f64(&mut self) -> Option<f64> {
        Some(f64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encoding_round_trips_and_rejects_damage() {
        let piece = ConvexPiece {
            vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0 / 3.0]],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        };
        let bytes = encode(Some(std::slice::from_ref(&piece)));
        assert_eq!(decode(&bytes), Some(Some(Arc::new(vec![piece]))));
        assert_eq!(decode(&encode(None)), Some(None));
        for cut in [0, 1, 8, bytes.len() / 2, bytes.len() - 1] {
            assert_eq!(decode(&bytes[..cut]), None, "cut at {cut}");
        }
        let mut flipped = bytes.clone();
        flipped[20] ^= 1;
        assert_eq!(decode(&flipped), None);
    }
}
