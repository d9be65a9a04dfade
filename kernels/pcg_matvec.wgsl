// Conjugate gradients' product H·p, row by row over the fine matrix's blocks, and p·H·p
// summed within each workgroup (tree_sum) for pcg_step's step length. CPU twin: pcg_matvec in
// src/cpu/pcg.rs.

@group(0) @binding(22) var<storage, read> p: array<vec4<f32>>;
@group(0) @binding(23) var<storage, read_write> ap: array<vec4<f32>>;
@group(0) @binding(27) var<storage, read_write> partials: array<vec4<f32>>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    if (control.done != 0u) {
        return;
    }
    let i = particle_index(gid, groups);
    var lane = vec4<f32>(0.0);
    if (i < params.num_particles) {
        let fine = level(0u);
        var sum = vec3<f32>(0.0);
        for (var b = row_start(fine, i); b < row_start(fine, i + 1u); b = b + 1u) {
            sum = sum + block_at(b) * p[block_column(fine, b)].xyz;
        }
        ap[i] = vec4<f32>(sum, 0.0);
        lane.x = dot(p[i].xyz, sum);
    }
    lanes[lid] = lane;
    let total = tree_sum(lid);
    if (lid == 0u) {
        partials[group_index(wid, groups)] = total;
    }
}
