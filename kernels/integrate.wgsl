// Euler integration of every free particle; consumes and clears the force accumulator.
// pos.w holds the inverse mass: 0 pins the particle. CPU twin: src/cpu/integrate.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> vel: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> force: array<vec4<f32>>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let p = pos[i];
    let inv_mass = p.w;
    let f = force[i].xyz;
    force[i] = vec4<f32>(0.0);
    if (inv_mass == 0.0) {
        vel[i] = vec4<f32>(0.0);
        return;
    }
    let v = vel[i].xyz;
    let a = f * inv_mass + params.gravity.xyz - params.air_damping * v;
    var x_new = p.xyz;
    var v_new = v;
    if (params.integrator == 0u) {
        // explicit: position from the old velocity
        x_new = p.xyz + params.dt * v;
        v_new = v + params.dt * a;
    } else {
        // semi-implicit: position from the new velocity
        v_new = v + params.dt * a;
        x_new = p.xyz + params.dt * v_new;
    }
    pos[i] = vec4<f32>(x_new, inv_mass);
    vel[i] = vec4<f32>(v_new, 0.0);
}
