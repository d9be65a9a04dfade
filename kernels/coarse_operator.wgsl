// A coarse level's matrix as the Galerkin product PᵀAP of the level below's blocks (read from
// their published texels): each coarse block (one invocation) sums its list of (finer block,
// P_iI·P_jJ) terms in order. op.level is the coarse level. CPU twin: src/cpu/coarse_operator.rs.

@group(0) @binding(19) var<storage, read_write> blocks: array<mat3x3<f32>>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let b = particle_index(gid, groups);
    let coarse = level(op.level);
    if (control.done != 0u || b >= coarse.blocks) {
        return;
    }
    let finer = level(op.level - 1u);
    let start = hier[coarse.galerkin_at + b];
    let end = hier[coarse.galerkin_at + b + 1u];
    var sum = mat3x3<f32>();
    for (var t = start; t < end; t = t + 1u) {
        let f = hier[coarse.galerkin_items_at + 2u * t];
        let w = bitcast<f32>(hier[coarse.galerkin_items_at + 2u * t + 1u]);
        sum = sum + w * block_at(finer.block_base + f);
    }
    blocks[coarse.block_base + b] = sum;
}
