//! What collision with a deforming body reads besides its rest pose's SDF: for every SDF node
//! the rest-pose triangle nearest to it, the rest mesh with each vertex's weights over the
//! collision parts, and each part's box in the rest pose. A query maps a world point back into
//! the rest pose through the parts' poses (inverse skinning) and reads the rest SDF there
//! (`kernels/deformed_body.wgsl`, CPU twin `cpu::deformed_body`).
//!
//! The arrays follow the SDF's nodes in one list of 32-bit words (floats, or integers stored as
//! their bits), in this order, with n SDF nodes, V vertices, T triangles and P parts:
//!
//! | words | what |
//! |---|---|
//! | n | the nearest triangle of each SDF node (index) |
//! | 2 | V, T |
//! | 3V | the rest vertices, m |
//! | 3T | the triangles' corners |
//! | 5V | each vertex's four parts (8 bits each, in one word) and four weights |
//! | 6P | each part's box in the rest pose: lowest corner, highest corner, m |

use super::exact::ExactBody;
use super::sdf::Sdf;
use super::skin::Influence;
use crate::mesh::TriMesh;
use glam::Vec3;
use std::path::Path;

/// Words per vertex of the weights block.
pub const WEIGHT_WORDS: usize = 5;

/// The words that follow a deforming body's SDF nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct DeformedGrid {
    /// The words (see the module's table).
    pub words: Vec<f32>,
    /// How many collision parts.
    pub parts: usize,
}

impl DeformedGrid {
    /// The words for `mesh` (the rest pose, whose SDF is `sdf`) with `influences` over `parts`
    /// parts, each part's box grown by `reach` m. The nearest triangles are read from
    /// `cache_dir` when a bake of the same mesh and grid is there, and written there otherwise.
    pub fn build(
        mesh: &TriMesh,
        influences: &[Influence],
        parts: usize,
        sdf: &Sdf,
        reach: f32,
        cache_dir: Option<&Path>,
    ) -> Result<DeformedGrid, String> {
        let nearest = nearest_triangles_cached(mesh, sdf, cache_dir)?;
        let mut words: Vec<f32> = nearest.iter().map(|&t| f32::from_bits(t)).collect();
        let bits = |u: u32| f32::from_bits(u);
        words.push(bits(mesh.positions.len() as u32));
        words.push(bits(mesh.triangles.len() as u32));
        words.extend(mesh.positions.iter().flat_map(|p| p.to_array()));
        words.extend(mesh.triangles.iter().flatten().map(|&i| bits(i)));
        for inf in influences {
            let packed = (inf.joints.iter().enumerate())
                .fold(0u32, |acc, (k, &j)| acc | ((j as u32 & 0xff) << (8 * k)));
            words.push(bits(packed));
            words.extend(inf.weights);
        }
        for p in 0..parts {
            let (lo, hi) = (mesh.positions.iter().zip(influences))
                .filter(|(_, inf)| {
                    (inf.joints.iter().zip(inf.weights)).any(|(j, w)| *j as usize == p && w > 0.0)
                })
                .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), (q, _)| {
                    (lo.min(*q), hi.max(*q))
                });
            // A part that moves no vertex gets an empty box (its lowest corner above its highest).
            let (lo, hi) = if lo.x > hi.x {
                (Vec3::ONE, Vec3::ZERO)
            } else {
                (lo - Vec3::splat(reach), hi + Vec3::splat(reach))
            };
            words.extend(lo.to_array());
            words.extend(hi.to_array());
        }
        Ok(DeformedGrid { words, parts })
    }
}

/// The nearest triangle of `mesh` to each node of `sdf`'s grid (x fastest), on all cores.
pub fn nearest_triangles(mesh: &TriMesh, sdf: &Sdf) -> Result<Vec<u32>, String> {
    let exact = ExactBody::new(mesh)?;
    let [nx, ny, nz] = sdf.dims.map(|d| d as usize);
    let mut out = vec![0u32; nx * ny * nz];
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let slab = nx * ny;
    let per_thread = nz.div_ceil(threads).max(1) * slab;
    std::thread::scope(|scope| {
        for (c, chunk) in out.chunks_mut(per_thread).enumerate() {
            let exact = &exact;
            scope.spawn(move || {
                for (k, v) in chunk.iter_mut().enumerate() {
                    let idx = c * per_thread + k;
                    let (i, j, l) = (idx % nx, (idx / nx) % ny, idx / slab);
                    let p = sdf.origin + sdf.cell * Vec3::new(i as f32, j as f32, l as f32);
                    *v = exact.query_triangle(p).2;
                }
            });
        }
    });
    Ok(out)
}

const MAGIC: &[u8; 8] = b"DKTRI01\0";

/// `nearest_triangles`, cached under `cache_dir` by the mesh's content and the grid.
fn nearest_triangles_cached(
    mesh: &TriMesh,
    sdf: &Sdf,
    cache_dir: Option<&Path>,
) -> Result<Vec<u32>, String> {
    let file = cache_dir.map(|d| {
        let body = super::Body {
            mesh: mesh.clone(),
            repairs: Default::default(),
        };
        d.join(format!(
            "nearest-{:016x}-{:08x}-{:08x}{:08x}{:08x}-{}x{}x{}.bin",
            body.hash(),
            sdf.cell.to_bits(),
            sdf.origin.x.to_bits(),
            sdf.origin.y.to_bits(),
            sdf.origin.z.to_bits(),
            sdf.dims[0],
            sdf.dims[1],
            sdf.dims[2]
        ))
    });
    let count = sdf.values.len();
    if let Some(bytes) = file.as_deref().and_then(|f| std::fs::read(f).ok()) {
        if bytes.len() == 8 + 4 * count && &bytes[..8] == MAGIC {
            let t: Vec<u32> = bytes[8..]
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
                .collect();
            if t.iter().all(|&i| (i as usize) < mesh.triangles.len()) {
                return Ok(t);
            }
        }
    }
    let t = nearest_triangles(mesh, sdf)?;
    if let Some(f) = &file {
        let mut bytes = MAGIC.to_vec();
        bytes.extend(t.iter().flat_map(|i| i.to_le_bytes()));
        // A cache that cannot be written only costs a re-bake next time.
        let _ = std::fs::create_dir_all(f.parent().unwrap_or(Path::new(".")));
        let _ = crate::atomic_file::write_atomic(f, &bytes);
    }
    Ok(t)
}
