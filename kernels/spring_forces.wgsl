// Stretch springs on mesh edges, gathered per particle: each spring is evaluated once from each
// end, so no float atomics are needed and the sum order is fixed (CPU twin: src/cpu/spring_forces.rs).

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var vel: texture_2d<f32>;
@group(0) @binding(3) var force_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var spring_offsets: texture_2d<u32>;    // r32uint, N + 1 entries
@group(0) @binding(5) var springs: texture_2d<u32>;           // one SpringRef per texel

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let xi = textureLoad(pos, texel(i), 0).xyz;
    let vi = textureLoad(vel, texel(i), 0).xyz;
    let first = textureLoad(spring_offsets, texel(i), 0).x;
    let end = textureLoad(spring_offsets, texel(i + 1u), 0).x;
    var f = vec3<f32>(0.0);
    for (var k = first; k < end; k = k + 1u) {
        let s = unpack_spring(textureLoad(springs, texel(k), 0));
        let d = textureLoad(pos, texel(s.other), 0).xyz - xi;
        let len = length(d);
        if (len > 1e-12) {
            let dir = d / len;
            let stretch = len - s.rest_length;
            let closing_speed = dot(textureLoad(vel, texel(s.other), 0).xyz - vi, dir);
            let law = StretchLaw(params.euler_onset / s.rest_length, params.buckled_fraction, 0.0, 0.0);
            let tension = law_tension(law, s.stiffness, stretch);
            f = f + (tension + s.damping * closing_speed) * dir;
        }
    }
    textureStore(force_out, texel(i), vec4<f32>(previous_force(i) + f, 0.0));
}
