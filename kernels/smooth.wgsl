// One block Gauss–Seidel update of the rows of one colour of a level's system A·e = rhs
// (op: the level, and the colour's entries in the level's colour order). Rows of one colour
// share no block, so they update in place at once. CPU twin: smooth in src/cpu/smooth.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = particle_index(gid, groups);
    if (control.done != 0u || k >= op.count) {
        return;
    }
    let lv = level(op.level);
    let r = order_at(lv, op.first + k);
    e[lv.vec_base + r] = vec4<f32>(smooth_row(lv, r), 0.0);
}
