// Implicit Euler 3/3: the next state from the solved displacements D, x_{n+1} = xₙ + D and
// v_{n+1} = D/h, written to the other texture of each ping-pong pair. Pinned particles keep
// their position and have zero velocity. CPU twin: src/cpu/vbd_finish.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var<storage, read> x: array<vec4<f32>>;
@group(0) @binding(3) var pos_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var vel_out: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let p = textureLoad(pos, texel(i), 0);
    if (p.w == 0.0) {
        textureStore(pos_out, texel(i), p);
        textureStore(vel_out, texel(i), vec4<f32>(0.0));
        return;
    }
    let d = x[i].xyz;
    textureStore(pos_out, texel(i), vec4<f32>(p.xyz + d, p.w));
    textureStore(vel_out, texel(i), vec4<f32>(d / params.dt, 0.0));
}
