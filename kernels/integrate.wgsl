// Euler integration of every free particle. Reads this substep's state and the forces the force
// stages summed, adds the bending forces hinge_forces wrote for the particle (a contiguous run
// of texels in CSR order, when the scene bends), and writes the next state into the other
// texture of each ping-pong pair. Gathering here rather than in a stage of its own saves a
// dispatch and a round trip of the force texture.
// pos.w holds the inverse mass: 0 pins the particle. CPU twin: src/cpu/integrate.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var vel: texture_2d<f32>;
@group(0) @binding(3) var force: texture_2d<f32>;
@group(0) @binding(4) var pos_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var vel_out: texture_storage_2d<rgba32float, write>;
// section bending
@group(0) @binding(6) var hinge_offsets: texture_2d<u32>;     // r32uint, N + 1 entries
@group(0) @binding(7) var hinge_forces: texture_2d<f32>;      // one per hinge ref, CSR order
// end bending

// The particle's bending force: the sum of what hinge_forces wrote for it.
fn bending_force(i: u32) -> vec3<f32> {
    var f = vec3<f32>(0.0);
    // section bending
    let first = textureLoad(hinge_offsets, texel(i), 0).x;
    let end = textureLoad(hinge_offsets, texel(i + 1u), 0).x;
    for (var k = first; k < end; k = k + 1u) {
        f = f + textureLoad(hinge_forces, texel(k), 0).xyz;
    }
    // end bending
    return f;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let p = textureLoad(pos, texel(i), 0);
    let inv_mass = p.w;
    if (inv_mass == 0.0) {
        textureStore(pos_out, texel(i), p);
        textureStore(vel_out, texel(i), vec4<f32>(0.0));
        return;
    }
    let f = textureLoad(force, texel(i), 0).xyz + bending_force(i);
    let v = textureLoad(vel, texel(i), 0).xyz;
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
    textureStore(pos_out, texel(i), vec4<f32>(x_new, inv_mass));
    textureStore(vel_out, texel(i), vec4<f32>(v_new, 0.0));
}
