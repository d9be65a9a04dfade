// The force residual |fᵢ|/(mᵢ·g) of the free vertices at the iterate, per workgroup: its
// largest value (x), the sum of its squares (y, by tree_sum's order) and the free vertices
// counted (z). reduce_residual finishes it. CPU twin: force_residual in
// src/cpu/force_residual.rs.

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
    if (i < params.num_particles && prev(i).w != 0.0) {
        let r = force_residual_at(i, residual_gravity());
        lane = vec4<f32>(r, r * r, 1.0, 0.0);
    }
    lanes[lid] = lane;
    // The largest value by a tree of maxima beside the sums: max is exact in any order.
    workgroupBarrier();
    for (var stride = WORKGROUP_SIZE / 2u; stride > 0u; stride = stride / 2u) {
        if (lid < stride) {
            let other = lanes[lid + stride];
            let mine = lanes[lid];
            lanes[lid] = vec4<f32>(max(mine.x, other.x), mine.yzw + other.yzw);
        }
        workgroupBarrier();
    }
    if (lid == 0u) {
        partials[group_index(wid, groups)] = lanes[0];
    }
}
