// Restriction Pᵀ onto coarse level op.level: each coarse particle's right-hand side is its
// finer children's residuals times their weights, summed in order, and its correction starts
// at zero. CPU twin: src/cpu/restrict.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let c = particle_index(gid, groups);
    let coarse = level(op.level);
    if (control.done != 0u || c >= coarse.rows) {
        return;
    }
    rhs[coarse.vec_base + c] = restrict_row(coarse, level(op.level - 1u), c);
    e[coarse.vec_base + c] = vec4<f32>(0.0);
}
