//! CPU twin of `kernels/coarse_operator.wgsl`.

use super::grain;
use crate::model::Csr;
use glam::Mat3;
use rayon::prelude::*;

/// A coarse level's matrix as the Galerkin product PᵀAP of the finer level's `finer` blocks:
/// each coarse block sums its list of (finer block, P_iI·P_jJ) terms in order. Blocks are
/// independent and run in parallel.
pub fn coarse_operator(galerkin: &Csr<(u32, f32)>, finer: &[Mat3], coarse: &mut [Mat3]) {
    (coarse.par_iter_mut().with_min_len(grain::ROW))
        .enumerate()
        .for_each(|(b, out)| {
            let (start, end) = (galerkin.offsets[b], galerkin.offsets[b + 1]);
            let mut sum = Mat3::ZERO;
            for &(f, w) in &galerkin.items[start as usize..end as usize] {
                sum += w * finer[f as usize];
            }
            *out = sum;
        });
}
