//! CPU twin of `kernels/hash_scan.wgsl`.

use crate::model::layout::SimParams;

/// Exclusive prefix sum of the counts into `starts` (one more entry: the total) and `cursor`.
pub fn hash_scan(params: &SimParams, counts: &[u32], starts: &mut [u32], cursor: &mut [u32]) {
    let mut run = 0;
    for b in 0..params.hash_buckets as usize {
        starts[b] = run;
        cursor[b] = run;
        run += counts[b];
    }
    starts[params.hash_buckets as usize] = run;
}
