// A level's residual rhs − A·e, row by row (op.level). CPU twin: level_residual in
// src/cpu/smooth.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let r = particle_index(gid, groups);
    let lv = level(op.level);
    if (control.done != 0u || r >= lv.rows) {
        return;
    }
    res[lv.vec_base + r] = vec4<f32>(residual_row(lv, r), 0.0);
}
