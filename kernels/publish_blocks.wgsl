// Copies one level's blocks (op.level) from the blocks buffer, where assemble and
// coarse_operator write them, to the block texels the sweeping, multiplying and coarsening
// kernels read (block_texels.wgsl). A copy: no CPU twin.

@group(0) @binding(19) var<storage, read> blocks: array<mat3x3<f32>>;
@group(0) @binding(31) var block_out: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = particle_index(gid, groups);
    let lv = level(op.level);
    if (control.done != 0u || k >= lv.blocks) {
        return;
    }
    let b = lv.block_base + k;
    let m = blocks[b];
    for (var c = 0u; c < 3u; c = c + 1u) {
        textureStore(block_out, texel(3u * b + c), vec4<f32>(m[c], 0.0));
    }
}
