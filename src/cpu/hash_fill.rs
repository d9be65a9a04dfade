//! CPU twin of `kernels/hash_fill.wgsl` (particles in index order within a bucket; the GPU's
//! order within a bucket depends on its atomics).

use super::hash_count::{hash_bucket, hash_cell_of};
use crate::model::layout::SimParams;
use glam::Vec4;

/// Places each particle index in its bucket's range of `sorted`.
pub fn hash_fill(params: &SimParams, pos: &[Vec4], cursor: &mut [u32], sorted: &mut [u32]) {
    for (i, p) in pos.iter().enumerate().take(params.num_particles as usize) {
        let b = hash_bucket(params, hash_cell_of(params, p.truncate())) as usize;
        sorted[cursor[b] as usize] = i as u32;
        cursor[b] += 1;
    }
}
