// Prolongation P from coarse level op.level: each particle of the level below adds the
// weighted sum of its three parents' corrections to its own. CPU twin: prolong in
// src/cpu/prolong.rs.

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    let finer = level(op.level - 1u);
    if (control.done != 0u || i >= finer.rows) {
        return;
    }
    let at = finer.vec_base + i;
    e[at] = e[at] + vec4<f32>(prolong_row(level(op.level), i), 0.0);
}
