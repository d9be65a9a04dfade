// Conjugate gradients' next search direction from the preconditioned residual z (level 0's e):
// p = z at the first iteration, else p = z + β·p with β = (r·z)/(r·z)_previous. Two
// dispatches: `dot_partials` sums r·z within each workgroup (tree_sum), then `main`, in every
// workgroup, sums those partials in order on one invocation (the CPU twin's sequential sum, so
// every workgroup finds the same r·z) and updates its particles' p. Workgroup 0 records r·z at
// the iteration's parity (op.slot); β divides by the other parity's, the previous iteration's.
// CPU twin: pcg_direction and dot in src/cpu/pcg.rs.

@group(0) @binding(22) var<storage, read_write> p: array<vec4<f32>>;
@group(0) @binding(24) var<storage, read> rhs: array<vec4<f32>>;
@group(0) @binding(25) var<storage, read> e: array<vec4<f32>>;
@group(0) @binding(27) var<storage, read_write> partials: array<vec4<f32>>;
@group(0) @binding(28) var<storage, read_write> scalars: SolveScalars;

var<workgroup> shared_beta: f32;

@compute @workgroup_size(WORKGROUP_SIZE)
fn dot_partials(
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
        lane.x = dot(rhs[i].xyz, e[i].xyz);
    }
    lanes[lid] = lane;
    let total = tree_sum(lid);
    if (lid == 0u) {
        partials[group_index(wid, groups)] = total;
    }
}

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
    if (lid == 0u) {
        var rz = 0.0;
        for (var g = 0u; g < groups_for(params.num_particles); g = g + 1u) {
            rz = rz + partials[g].x;
        }
        let previous = scalars.rz[1u - op.slot];
        var beta = 0.0;
        if (op.flag == 0u && previous != 0.0) {
            beta = rz / previous;
        }
        shared_beta = beta;
        if (all(wid == vec3<u32>(0u))) {
            scalars.rz[op.slot] = rz;
        }
    }
    let beta = workgroupUniformLoad(&shared_beta);
    let i = particle_index(gid, groups);
    if (i < params.num_particles) {
        p[i] = vec4<f32>(e[i].xyz + beta * p[i].xyz, 0.0);
    }
}
