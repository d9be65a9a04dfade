//! CPU twin of `kernels/restrict.wgsl`.

use super::grain;
use crate::model::Csr;
use glam::Vec4;
use rayon::prelude::*;

/// Restriction Pᵀ: each coarse particle's `coarse` value is the sum of its children's `finer`
/// values times their weights, in order; the coarse level's correction `correction` starts at
/// zero. Particles are independent and run in parallel.
pub fn restrict(
    children: &Csr<(u32, f32)>,
    finer: &[Vec4],
    coarse: &mut [Vec4],
    correction: &mut [Vec4],
) {
    (coarse.par_iter_mut().zip(correction))
        .with_min_len(grain::ARRAY)
        .enumerate()
        .for_each(|(c, (out, e))| {
            let (start, end) = (children.offsets[c], children.offsets[c + 1]);
            let mut sum = Vec4::ZERO;
            for &(f, w) in &children.items[start as usize..end as usize] {
                sum += w * finer[f as usize];
            }
            *out = sum;
            *e = Vec4::ZERO;
        });
}
