// Conjugate gradients on the Newton step's H·c = f start: c = 0, r = f, and the preconditioned
// residual z = 0 for the first V-cycle (r and z are level 0's rhs and e). CPU twin: pcg_start in
// src/cpu/pcg.rs.

@group(0) @binding(20) var<storage, read> force: array<vec4<f32>>;
@group(0) @binding(21) var<storage, read_write> correction: array<vec4<f32>>;
@group(0) @binding(24) var<storage, read_write> rhs: array<vec4<f32>>;
@group(0) @binding(25) var<storage, read_write> e: array<vec4<f32>>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (control.done != 0u || i >= params.num_particles) {
        return;
    }
    correction[i] = vec4<f32>(0.0);
    rhs[i] = force[i];
    e[i] = vec4<f32>(0.0);
}
