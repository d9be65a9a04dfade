// Self-collision, step 4 of 5: place each particle's index in its bucket's range of `sorted`
// (an atomic cursor per bucket; the order within a bucket is whatever the atomics give).
// CPU twin: src/cpu/hash_fill.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> sorted: array<u32>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let b = hash_bucket(hash_cell_of(textureLoad(pos, texel(i), 0).xyz, params.hash_cell), params.hash_buckets);
    sorted[atomicAdd(&cursor[b], 1u)] = i;
}
