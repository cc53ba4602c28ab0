//! Simplified visual meshes for small camera images, derived from an installed package's meshes
//! (never committed): every `.obj` and `.stl` in a folder is welded by position, simplified with
//! meshoptimizer's edge-collapse simplifier under a geometric error bound, and written as a
//! position-only OBJ into a folder named by the source meshes' content and the settings.
//!
//! - **Normals**: the packages' normals are per face corner (flat); a simplified mesh has other
//!   faces, so none are written and MuJoCo computes them at compile time, averaging face normals
//!   but keeping creases (its default `smoothnormal="false"`), as it already does for STL files.
//! - **Outlines**: open borders are locked (`LockBorder`), and the error bound is relative to each
//!   mesh's extent, so thin features and silhouettes survive where collapsing them would move the
//!   surface by more than the bound.
//!
//! What this does not do: physics never sees these meshes (the runtime simulates the full model
//! and renders a second model compiled from the simplified files), and nothing here knows which
//! camera size wants which level of detail (the runtime decides).

use crate::assets::AssetError;
use meshopt::{SimplifyOptions, VertexDataAdapter};
use sha2::{Digest, Sha256};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Largest surface deviation allowed, as a fraction of a mesh's extent.
pub const RELATIVE_ERROR: f32 = 0.008;
/// The face count a mesh is reduced towards (the error bound usually stops it first).
pub const TARGET_RATIO: f32 = 0.02;
/// Meshes with fewer faces than this are copied as they are.
const MIN_FACES: usize = 64;

/// A triangle mesh welded by position.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> AssetError + '_ {
    move |source| AssetError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn bad(path: &Path, what: &str) -> AssetError {
    AssetError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, what.to_string()),
    }
}

/// Collects positions into a welded mesh (equal coordinates, one vertex).
#[derive(Default)]
struct Welder {
    mesh: Mesh,
    index: HashMap<[u32; 3], u32>,
}

impl Welder {
    fn vertex(&mut self, p: [f32; 3]) -> u32 {
        let key = p.map(|c| if c == 0.0 { 0 } else { c.to_bits() });
        *self.index.entry(key).or_insert_with(|| {
            self.mesh.positions.push(p);
            (self.mesh.positions.len() - 1) as u32
        })
    }

    fn triangle(&mut self, t: [[f32; 3]; 3]) {
        let t = t.map(|p| self.vertex(p));
        if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
            self.mesh.triangles.push(t);
        }
    }
}

/// Reads a Wavefront OBJ's positions and faces (polygons as fans); normals, texture coordinates
/// and materials are ignored.
pub fn read_obj(path: &Path) -> Result<Mesh, AssetError> {
    let text = std::fs::read_to_string(path).map_err(io(path))?;
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut w = Welder::default();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let mut p = [0f32; 3];
                for c in &mut p {
                    *c = words
                        .next()
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| bad(path, "a vertex without three coordinates"))?;
                }
                positions.push(p);
            }
            Some("f") => {
                let corners = words
                    .map(|c| {
                        let i: i64 = c
                            .split('/')
                            .next()
                            .and_then(|s| s.parse().ok())
                            .ok_or_else(|| bad(path, "a face corner without a vertex index"))?;
                        let k = if i < 0 {
                            positions.len() as i64 + i
                        } else {
                            i - 1
                        };
                        usize::try_from(k)
                            .ok()
                            .and_then(|k| positions.get(k).copied())
                            .ok_or_else(|| bad(path, "a face index out of range"))
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                for k in 2..corners.len() {
                    w.triangle([corners[0], corners[k - 1], corners[k]]);
                }
            }
            _ => {}
        }
    }
    Ok(w.mesh)
}

/// Reads a binary or ASCII STL.
pub fn read_stl(path: &Path) -> Result<Mesh, AssetError> {
    let bytes = std::fs::read(path).map_err(io(path))?;
    let mut w = Welder::default();
    let binary_len = |n: usize| 84 + 50 * n;
    let count = bytes
        .get(80..84)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize);
    match count {
        Some(n) if bytes.len() == binary_len(n) => {
            for f in bytes[84..].chunks_exact(50) {
                let at = |k: usize| {
                    let o = 12 + 12 * k;
                    [0, 1, 2].map(|c| {
                        let b = &f[o + 4 * c..o + 4 * c + 4];
                        f32::from_le_bytes([b[0], b[1], b[2], b[3]])
                    })
                };
                w.triangle([at(0), at(1), at(2)]);
            }
        }
        _ => {
            let text = std::str::from_utf8(&bytes).map_err(|_| bad(path, "not an STL file"))?;
            let mut corner = Vec::with_capacity(3);
            for line in text.lines() {
                let mut words = line.split_whitespace();
                if words.next() != Some("vertex") {
                    continue;
                }
                let p: Vec<f32> = words.filter_map(|s| s.parse().ok()).collect();
                let p: [f32; 3] = p
                    .try_into()
                    .map_err(|_| bad(path, "a vertex without three coordinates"))?;
                corner.push(p);
                if corner.len() == 3 {
                    w.triangle([corner[0], corner[1], corner[2]]);
                    corner.clear();
                }
            }
        }
    }
    Ok(w.mesh)
}

/// The mesh simplified to within `relative_error` of its extent, towards `ratio` of its faces;
/// unused vertices are dropped.
pub fn simplify(mesh: &Mesh, ratio: f32, relative_error: f32) -> Mesh {
    if mesh.triangles.len() < MIN_FACES {
        return mesh.clone();
    }
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let bytes: &[u8] = bytemuck_positions(&mesh.positions);
    let Ok(vertices) = VertexDataAdapter::new(bytes, 12, 0) else {
        return mesh.clone();
    };
    let target = ((indices.len() as f32 * ratio) as usize / 3).max(MIN_FACES) * 3;
    let kept = meshopt::simplify(
        &indices,
        &vertices,
        target,
        relative_error,
        SimplifyOptions::LockBorder,
        None,
    );
    let mut remap: HashMap<u32, u32> = HashMap::new();
    let mut out = Mesh::default();
    for t in kept.chunks_exact(3) {
        let t = [t[0], t[1], t[2]].map(|i| {
            *remap.entry(i).or_insert_with(|| {
                out.positions.push(mesh.positions[i as usize]);
                (out.positions.len() - 1) as u32
            })
        });
        out.triangles.push(t);
    }
    out
}

fn bytemuck_positions(p: &[[f32; 3]]) -> &[u8] {
    // SAFETY: `[f32; 3]` is plain old data with no padding; the byte view covers the same memory
    // and lives as long as `p`.
    unsafe { std::slice::from_raw_parts(p.as_ptr().cast::<u8>(), std::mem::size_of_val(p)) }
}

/// The mesh as a position-only OBJ.
pub fn to_obj(mesh: &Mesh) -> String {
    let mut s = String::with_capacity(mesh.positions.len() * 32 + mesh.triangles.len() * 24);
    for p in &mesh.positions {
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for t in &mesh.triangles {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

fn is_mesh(p: &Path) -> bool {
    matches!(
        p.extension().and_then(|e| e.to_str()),
        Some("obj" | "stl" | "STL")
    )
}

/// The folder of simplified meshes for the meshes in `source` (each `name.obj` or `name.stl`
/// becomes `name.obj`), derived once under `cache` and reused while the sources and settings are
/// unchanged.
pub fn simplified_dir(source: &Path, cache: &Path) -> Result<PathBuf, AssetError> {
    static DONE: Mutex<Vec<(PathBuf, PathBuf)>> = Mutex::new(Vec::new());
    let mut done = DONE.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, d)) = done.iter().find(|(s, _)| s == source) {
        return Ok(d.clone());
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(source)
        .map_err(io(source))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| is_mesh(p))
        .collect();
    files.sort();
    let mut h = Sha256::new();
    h.update(format!("lod1 {RELATIVE_ERROR} {TARGET_RATIO}"));
    for f in &files {
        h.update(f.file_name().unwrap_or_default().as_encoded_bytes());
        h.update(std::fs::read(f).map_err(io(f))?);
    }
    let hash: String = h
        .finalize()
        .iter()
        .take(8)
        .map(|b| format!("{b:02x}"))
        .collect();
    let stem = source
        .parent()
        .and_then(|p| p.file_name())
        .and_then(|n| n.to_str())
        .unwrap_or("meshes");
    let dir = cache.join(format!("{stem}-{hash}"));
    let complete = dir.join(".complete");
    if !complete.exists() {
        std::fs::create_dir_all(&dir).map_err(io(&dir))?;
        for f in &files {
            let mesh = match f.extension().and_then(|e| e.to_str()) {
                Some("obj") => read_obj(f)?,
                _ => read_stl(f)?,
            };
            let simple = simplify(&mesh, TARGET_RATIO, RELATIVE_ERROR);
            let name = f.with_extension("obj");
            let name = name.file_name().unwrap_or_default();
            crate::assets::write_if_changed(&dir.join(name), &to_obj(&simple))?;
        }
        std::fs::write(&complete, b"").map_err(io(&complete))?;
        // Meshes derived from an earlier package version or other settings are stale.
        let current = dir.file_name().unwrap_or_default().to_owned();
        for old in std::fs::read_dir(cache).into_iter().flatten().flatten() {
            let name = old.file_name();
            let stale = name != current
                && name.to_str().is_some_and(|n| {
                    n.strip_prefix(stem)
                        .and_then(|rest| rest.strip_prefix('-'))
                        .is_some_and(|h| h.len() == 16 && h.bytes().all(|b| b.is_ascii_hexdigit()))
                });
            if stale {
                let _ = std::fs::remove_dir_all(old.path());
            }
        }
    }
    done.push((source.to_path_buf(), dir.clone()));
    Ok(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed UV sphere: `rings` x `segments` quads.
    fn sphere(rings: usize, segments: usize) -> Mesh {
        let mut w = Welder::default();
        let at = |i: usize, j: usize| {
            let th = std::f32::consts::PI * i as f32 / rings as f32;
            let ph = 2.0 * std::f32::consts::PI * (j % segments) as f32 / segments as f32;
            if i == 0 {
                return [0.0, 0.0, 1.0];
            }
            if i == rings {
                return [0.0, 0.0, -1.0];
            }
            [th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()]
        };
        for i in 0..rings {
            for j in 0..segments {
                w.triangle([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                w.triangle([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        w.mesh
    }

    #[test]
    fn welding_merges_equal_corners_and_drops_degenerate_faces() {
        let s = sphere(40, 80);
        // Poles are single vertices; the faces touching them twice are dropped.
        assert_eq!(s.positions.len(), 39 * 80 + 2);
        assert_eq!(s.triangles.len(), 2 * 40 * 80 - 2 * 80);
    }

    #[test]
    fn simplification_reduces_faces_within_the_error_bound() {
        let s = sphere(80, 160);
        let simple = simplify(&s, 0.02, 0.01);
        assert!(
            simple.triangles.len() * 10 < s.triangles.len(),
            "{}",
            simple.triangles.len()
        );
        assert!(simple.triangles.len() >= MIN_FACES);
        // Every kept vertex is an original vertex on the unit sphere; every face's centroid stays
        // within the bound (relative to the extent, 2) of the surface.
        for t in &simple.triangles {
            let c = [0, 1, 2].map(|k| {
                t.iter()
                    .map(|&i| simple.positions[i as usize][k])
                    .sum::<f32>()
                    / 3.0
            });
            let r = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            // The bound is 0.01 of the extent (2): 0.02. The simplifier's error is a quadric
            // estimate, not a distance; the worst centroid measured is 0.0215 in, so the test
            // allows a quarter over the bound, not more.
            assert!((1.0 - r) < 0.025, "centroid radius {r}");
        }
    }

    #[test]
    fn obj_round_trip_keeps_the_mesh() {
        let s = simplify(&sphere(20, 40), 0.5, 0.01);
        let dir = std::env::temp_dir().join(format!("autobio-lod-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("s.obj");
        std::fs::write(&p, to_obj(&s)).unwrap();
        let back = read_obj(&p).unwrap();
        assert_eq!(back.triangles.len(), s.triangles.len());
        assert_eq!(back.positions.len(), s.positions.len());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
