// Self-collision, step 2 of 5: count the particles in each hash bucket (u32 atomics).
// CPU twin: src/cpu/hash_count.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let b = hash_bucket(hash_cell_of(textureLoad(pos, texel(i), 0).xyz, params.hash_cell), params.hash_buckets);
    atomicAdd(&counts[b], 1u);
}
