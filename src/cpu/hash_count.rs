//! CPU twin of `kernels/hash_count.wgsl`, and the hash shared by the self-collision stages.

use crate::model::layout::SimParams;
use glam::{IVec3, Vec3, Vec4};

/// The hash cell containing `x`.
pub fn hash_cell_of(params: &SimParams, x: Vec3) -> IVec3 {
    (x / params.hash_cell).floor().as_ivec3()
}

/// The bucket of cell `c` (Teschner et al. 2003 primes, wrapping u32 arithmetic as in WGSL).
pub fn hash_bucket(params: &SimParams, c: IVec3) -> u32 {
    let u = c.as_uvec3();
    (u.x.wrapping_mul(73_856_093) ^ u.y.wrapping_mul(19_349_663) ^ u.z.wrapping_mul(83_492_791))
        % params.hash_buckets
}

/// Counts the particles in each bucket.
pub fn hash_count(params: &SimParams, pos: &[Vec4], counts: &mut [u32]) {
    for p in pos.iter().take(params.num_particles as usize) {
        counts[hash_bucket(params, hash_cell_of(params, p.truncate())) as usize] += 1;
    }
}
