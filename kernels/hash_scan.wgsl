// Self-collision, step 3 of 5: exclusive prefix sum of the bucket counts into bucket starts
// (and the fill cursors). One workgroup: each thread sums a contiguous block, one thread scans
// the block sums, then each thread writes its block's starts. CPU twin: src/cpu/hash_scan.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<storage, read> counts: array<u32>;
@group(0) @binding(2) var<storage, read_write> starts: array<u32>;   // hash_buckets + 1
@group(0) @binding(3) var<storage, read_write> cursor: array<u32>;   // hash_buckets

var<workgroup> block_sum: array<u32, WORKGROUP_SIZE>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(local_invocation_index) t: u32) {
    let buckets = params.hash_buckets;
    let per = (buckets + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    let lo = min(t * per, buckets);
    let hi = min(lo + per, buckets);
    var sum = 0u;
    for (var b = lo; b < hi; b = b + 1u) {
        sum = sum + counts[b];
    }
    block_sum[t] = sum;
    workgroupBarrier();
    if (t == 0u) {
        var run = 0u;
        for (var k = 0u; k < WORKGROUP_SIZE; k = k + 1u) {
            let s = block_sum[k];
            block_sum[k] = run;
            run = run + s;
        }
        starts[buckets] = run;
    }
    workgroupBarrier();
    var run = block_sum[t];
    for (var b = lo; b < hi; b = b + 1u) {
        starts[b] = run;
        cursor[b] = run;
        run = run + counts[b];
    }
}
