//! Signed distance fields baked on a dense grid from exact point-to-mesh queries, cached on
//! disk by mesh hash and resolution.

use super::exact::ExactBody;
use super::Body;
use glam::{Vec3, Vec4};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// φ outside the grid: no contact.
pub const SDF_FAR: f32 = 1e30;

/// Trilinear φ (w) and its gradient (xyz), as `kernels/collide_body.wgsl` samples it, at body-frame point `p` of a grid with `dims` nodes
/// from `origin` at `cell` spacing (x fastest).
pub fn sdf_sample(values: &[f32], dims: [u32; 3], origin: Vec3, cell: f32, p: Vec3) -> Vec4 {
    let g = (p - origin) / cell;
    let last = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) - Vec3::ONE;
    if g.cmplt(Vec3::ZERO).any() || g.cmpge(last).any() {
        return Vec4::new(0.0, 0.0, 0.0, SDF_FAR);
    }
    let c = g.floor().as_uvec3();
    let f = g - g.floor();
    let node = |i: u32, j: u32, k: u32| values[(i + dims[0] * (j + dims[1] * k)) as usize];
    let c000 = node(c.x, c.y, c.z);
    let c100 = node(c.x + 1, c.y, c.z);
    let c010 = node(c.x, c.y + 1, c.z);
    let c110 = node(c.x + 1, c.y + 1, c.z);
    let c001 = node(c.x, c.y, c.z + 1);
    let c101 = node(c.x + 1, c.y, c.z + 1);
    let c011 = node(c.x, c.y + 1, c.z + 1);
    let c111 = node(c.x + 1, c.y + 1, c.z + 1);
    let x00 = c000 + f.x * (c100 - c000);
    let x10 = c010 + f.x * (c110 - c010);
    let x01 = c001 + f.x * (c101 - c001);
    let x11 = c011 + f.x * (c111 - c011);
    let y0 = x00 + f.y * (x10 - x00);
    let y1 = x01 + f.y * (x11 - x01);
    let phi = y0 + f.z * (y1 - y0);
    let d00 = c100 - c000;
    let d10 = c110 - c010;
    let d01 = c101 - c001;
    let d11 = c111 - c011;
    let dy0 = d00 + f.y * (d10 - d00);
    let dy1 = d01 + f.y * (d11 - d01);
    let gx = dy0 + f.z * (dy1 - dy0);
    let gy = (x10 - x00) + f.z * ((x11 - x01) - (x10 - x00));
    let gz = y1 - y0;
    (Vec3::new(gx, gy, gz) / cell).extend(phi)
}

/// Signed distances (negative inside) at the nodes of a regular grid, x fastest.
#[derive(Clone, Debug, PartialEq)]
pub struct Sdf {
    /// Position of node (0, 0, 0) in m, body frame.
    pub origin: Vec3,
    /// Node spacing in m.
    pub cell: f32,
    /// Nodes along x, y, z.
    pub dims: [u32; 3],
    /// One value per node, in m.
    pub values: Vec<f32>,
}

/// How a bake went.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BakeReport {
    /// Seconds spent baking (0 when read from the cache).
    pub bake_seconds: f64,
    /// Bytes of the grid.
    pub bytes: usize,
    /// Grid nodes along x, y, z.
    pub dims: [u32; 3],
    /// Node spacing in m.
    pub cell_m: f32,
    /// Whether the grid came from the cache.
    pub from_cache: bool,
    /// The cache file, if caching was possible.
    pub cache_file: Option<String>,
}

/// The grid a body needs at `cell` spacing with `margin` around its bounding box.
pub fn grid_for(body: &Body, cell: f32, margin: f32) -> (Vec3, [u32; 3]) {
    let (lo, hi) = body.mesh.positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let origin = lo - Vec3::splat(margin);
    let size = hi - lo + Vec3::splat(2.0 * margin);
    // In f64 and saturating: a fine cell over a large body must be refused by its byte count,
    // not wrap around to a small grid.
    let nodes = |extent: f32| ((extent as f64 / cell as f64).ceil() + 1.0).min(u32::MAX as f64);
    let n = [nodes(size.x), nodes(size.y), nodes(size.z)];
    (origin, n.map(|d| d as u32))
}

/// Bytes of a grid with these dimensions (saturating at `u64::MAX`).
pub fn grid_bytes(dims: [u32; 3]) -> u64 {
    dims.iter()
        .fold(4u64, |bytes, &d| bytes.saturating_mul(d as u64))
}

impl Sdf {
    /// Bakes with exact queries on all cores.
    pub fn bake(body: &Body, cell: f32, margin: f32) -> Result<Sdf, String> {
        let exact = ExactBody::new(&body.mesh)?;
        let (origin, dims) = grid_for(body, cell, margin);
        let [nx, ny, nz] = dims.map(|d| d as usize);
        let mut values = vec![0.0f32; nx * ny * nz];
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let slab = nx * ny;
        let per_thread = nz.div_ceil(threads).max(1) * slab;
        // A first bake of a fine grid takes seconds (the mannequin at 5 mm: 6.5 million
        // nodes); the bar counts rows of nodes, so that it moves smoothly.
        let bar = crate::progress::bar(
            values.len() as u64,
            format!(
                "drapekit: baking the body's distance field ({nx}×{ny}×{nz} nodes at {} mm)",
                1000.0 * cell
            ),
        );
        std::thread::scope(|scope| {
            for (c, chunk) in values.chunks_mut(per_thread).enumerate() {
                let (exact, bar) = (&exact, &bar);
                scope.spawn(move || {
                    for (k, v) in chunk.iter_mut().enumerate() {
                        let idx = c * per_thread + k;
                        let (i, j, l) = (idx % nx, (idx / nx) % ny, idx / slab);
                        let p = origin + cell * Vec3::new(i as f32, j as f32, l as f32);
                        *v = exact.query(p).0;
                        if i + 1 == nx {
                            bar.inc(nx as u64);
                        }
                    }
                });
            }
        });
        bar.finish_and_clear();
        Ok(Sdf {
            origin,
            cell,
            dims,
            values,
        })
    }

    /// Bakes, or reads the grid cached under `cache_dir` for the same mesh, cell and margin.
    pub fn bake_cached(
        body: &Body,
        cell: f32,
        margin: f32,
        cache_dir: Option<&Path>,
    ) -> Result<(Sdf, BakeReport), String> {
        let file: Option<PathBuf> = cache_dir.map(|d| {
            d.join(format!(
                "sdf-{:016x}-{:08x}-{:08x}.bin",
                body.hash(),
                cell.to_bits(),
                margin.to_bits()
            ))
        });
        let report = |sdf: &Sdf, seconds: f64, from_cache: bool| BakeReport {
            bake_seconds: seconds,
            bytes: 4 * sdf.values.len(),
            dims: sdf.dims,
            cell_m: sdf.cell,
            from_cache,
            cache_file: file.as_ref().map(|f| f.display().to_string()),
        };
        let cached = file.as_deref().and_then(Sdf::read);
        if let Some(sdf) = cached.filter(|s| s.cell == cell) {
            let r = report(&sdf, 0.0, true);
            return Ok((sdf, r));
        }
        let start = Instant::now();
        let sdf = Sdf::bake(body, cell, margin)?;
        let seconds = start.elapsed().as_secs_f64();
        if let Some(f) = &file {
            // A cache that cannot be written only costs a re-bake next time.
            let _ = std::fs::create_dir_all(f.parent().unwrap_or(Path::new(".")));
            let _ = crate::atomic_file::write_atomic(f, &sdf.to_bytes());
        }
        let r = report(&sdf, seconds, false);
        Ok((sdf, r))
    }

    const MAGIC: &'static [u8; 8] = b"DKSDF01\0";

    fn to_bytes(&self) -> Vec<u8> {
        let mut out = Self::MAGIC.to_vec();
        out.extend_from_slice(bytemuck::cast_slice(&self.dims));
        out.extend_from_slice(bytemuck::cast_slice(&self.origin.to_array()));
        out.extend_from_slice(&self.cell.to_le_bytes());
        out.extend_from_slice(bytemuck::cast_slice(&self.values));
        out
    }

    /// A cached grid, or `None` for a file that is not one a bake wrote (damaged, truncated, or
    /// holding numbers no bake gives): the body is then baked again.
    fn read(path: &Path) -> Option<Sdf> {
        let bytes = std::fs::read(path).ok()?;
        let header = 8 + 12 + 12 + 4;
        if bytes.len() < header || &bytes[..8] != Self::MAGIC {
            return None;
        }
        let u = |k: usize| u32::from_le_bytes(bytes[k..k + 4].try_into().unwrap());
        let f = |k: usize| f32::from_le_bytes(bytes[k..k + 4].try_into().unwrap());
        let dims = [u(8), u(12), u(16)];
        // Trilinear sampling needs two nodes along each axis; a product that overflows is no size.
        let count = (dims.iter().map(|&d| d as usize))
            .try_fold(1usize, |n, d| (d >= 2).then(|| n.checked_mul(d)).flatten())?;
        if Some(bytes.len()) != count.checked_mul(4).and_then(|b| b.checked_add(header)) {
            return None;
        }
        let values: Vec<f32> = bytes[header..]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        let (origin, cell) = (Vec3::new(f(20), f(24), f(28)), f(32));
        let finite = origin.is_finite() && cell > 0.0 && cell.is_finite();
        (finite && values.iter().all(|v| v.is_finite())).then_some(Sdf {
            origin,
            cell,
            dims,
            values,
        })
    }

    /// Trilinear φ (w) and its gradient (xyz) at body-frame point `p`; outside the grid φ is
    /// `SDF_FAR` and the gradient zero.
    pub fn sample(&self, p: Vec3) -> Vec4 {
        sdf_sample(&self.values, self.dims, self.origin, self.cell, p)
    }
}
