// G's slopes along the Newton correction c (G′ = −f·c), at the iterate (x: from the assembled
// force, filtered as c is, which leaves the product as it is) and at the full step D + c (y:
// the force there, vertex_system with implicit_terms' trial section), summed per workgroup by
// tree_sum into the partials' second half, after line_energy's. line_search reads them. CPU
// twin: line_slopes in src/cpu/line_energy.rs.

@group(0) @binding(20) var<storage, read> force: array<vec4<f32>>;
@group(0) @binding(21) var<storage, read> correction: array<vec4<f32>>;
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
        let c = correction[i].xyz;
        let at_full = vertex_system(i, params.num_bodies, false).force;
        lane = vec4<f32>(-dot(force[i].xyz, c), -dot(at_full, c), 0.0, 0.0);
    }
    lanes[lid] = lane;
    let total = tree_sum(lid);
    if (lid == 0u) {
        partials[groups_for(params.num_particles) + group_index(wid, groups)] = total;
    }
}
