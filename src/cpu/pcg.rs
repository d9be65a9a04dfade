//! CPU twins of the conjugate-gradient stages (`kernels/pcg_*.wgsl`): the Newton step's
//! linear system H·c = f solved by conjugate gradients preconditioned with a multigrid
//! V-cycle. Dot products are summed as the kernels sum them: `tree_sum` within each block of
//! `WORKGROUP_SIZE` particles, then the blocks in order.

use super::grain;
use super::line_energy::tree_sum;
use super::smooth::row_product;
use crate::model::layout::WORKGROUP_SIZE;
use crate::model::multigrid::BlockPattern;
use glam::{Mat3, Vec4};
use rayon::prelude::*;

/// The scalars of a conjugate-gradient solve.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PcgScalars {
    /// r·z of the current residual.
    pub rz: f32,
    /// The step length α of the last step.
    pub alpha: f32,
}

/// Σ a·b over particles, as the kernels reduce it.
pub fn dot(a: &[Vec4], b: &[Vec4]) -> f32 {
    let group = WORKGROUP_SIZE as usize;
    let partials: Vec<f32> = (0..a.len().div_ceil(group))
        .into_par_iter()
        .with_min_len(grain::blocks(grain::ARRAY))
        .map(|g| {
            let mut lanes = [Vec4::ZERO; WORKGROUP_SIZE as usize];
            for (k, lane) in lanes.iter_mut().enumerate() {
                let i = g * group + k;
                if i < a.len() {
                    lane.x = a[i].truncate().dot(b[i].truncate());
                }
            }
            tree_sum(&mut lanes).x
        })
        .collect();
    let mut total = 0.0f32;
    for p in partials {
        total += p;
    }
    total
}

/// Starts the solve: c = 0, r = f, and the preconditioned residual z = 0 for the first V-cycle.
pub fn pcg_start(force: &[Vec4], c: &mut [Vec4], r: &mut [Vec4], z: &mut [Vec4]) {
    c.fill(Vec4::ZERO);
    r.copy_from_slice(force);
    z.fill(Vec4::ZERO);
}

/// The next search direction from the preconditioned residual z: p = z at the first, else
/// p = z + β·p with β = (r·z)/(r·z)_previous; records r·z.
pub fn pcg_direction(first: bool, r: &[Vec4], z: &[Vec4], p: &mut [Vec4], s: &mut PcgScalars) {
    let rz = dot(r, z);
    let beta = if first || s.rz == 0.0 { 0.0 } else { rz / s.rz };
    s.rz = rz;
    (p.par_iter_mut().zip(z).with_min_len(grain::ARRAY)).for_each(|(p, z)| {
        *p = (z.truncate() + beta * p.truncate()).extend(0.0);
    });
}

/// H·p into `ap`, and the step length α = (r·z)/(p·H·p) (0 when p·H·p is not positive: the
/// direction has vanished).
pub fn pcg_matvec(
    pattern: &BlockPattern,
    blocks: &[Mat3],
    p: &[Vec4],
    ap: &mut [Vec4],
    s: &mut PcgScalars,
) {
    (ap.par_iter_mut().with_min_len(grain::ROW))
        .enumerate()
        .for_each(|(i, out)| {
            let row = pattern.offsets[i] as usize..pattern.offsets[i + 1] as usize;
            *out = row_product(&blocks[row.clone()], &pattern.columns[row], p);
        });
    pcg_step_length(p, ap, s);
}

/// The step length α = (r·z)/(p·H·p) from p and H·p (0 when p·H·p is not positive: the
/// direction has vanished).
pub fn pcg_step_length(p: &[Vec4], ap: &[Vec4], s: &mut PcgScalars) {
    let pap = dot(p, ap);
    s.alpha = if pap > 0.0 { s.rz / pap } else { 0.0 };
}

/// c += α·p and r −= α·H·p; z = 0 for the next V-cycle.
pub fn pcg_step(
    s: &PcgScalars,
    p: &[Vec4],
    ap: &[Vec4],
    c: &mut [Vec4],
    r: &mut [Vec4],
    z: &mut [Vec4],
) {
    let a = s.alpha;
    (c.par_iter_mut().zip(r.par_iter_mut()).zip(z.par_iter_mut()))
        .with_min_len(grain::ARRAY)
        .enumerate()
        .for_each(|(i, ((c, r), z))| {
            *c = (c.truncate() + a * p[i].truncate()).extend(0.0);
            *r = (r.truncate() - a * ap[i].truncate()).extend(0.0);
            *z = Vec4::ZERO;
        });
}
