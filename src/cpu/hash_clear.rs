//! CPU twin of `kernels/hash_clear.wgsl`.

use crate::model::layout::SimParams;

/// Zeroes the per-bucket particle counts.
pub fn hash_clear(params: &SimParams, counts: &mut [u32]) {
    counts[..params.hash_buckets as usize].fill(0);
}
