// Self-collision, step 1 of 5: zero the spatial hash's per-bucket particle counts.
// One thread per bucket. CPU twin: src/cpu/hash_clear.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<storage, read_write> counts: array<atomic<u32>>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let b = particle_index(gid, groups);
    if (b >= params.hash_buckets) {
        return;
    }
    atomicStore(&counts[b], 0u);
}
