// Strain limiting, one Jacobi iteration: every edge stretched past (1 + strain_limit) × its rest
// length is pulled back to that length, each end moving by its inverse-mass share, and a
// particle moves by the mean of its edges' corrections (averaging keeps Jacobi from
// overshooting where several edges pull the same way). The velocity changes by the same
// displacement over the step, so x − xₙ = h·v still holds. CPU twin: src/cpu/strain_limit.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var vel: texture_2d<f32>;
@group(0) @binding(3) var spring_offsets: texture_2d<u32>;    // r32uint, N + 1 entries
@group(0) @binding(4) var springs: texture_2d<u32>;           // one SpringRef per texel
@group(0) @binding(5) var pos_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var vel_out: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let p = textureLoad(pos, texel(i), 0);
    let v = textureLoad(vel, texel(i), 0);
    let wi = p.w;
    var delta = vec3<f32>(0.0);
    var violated = 0u;
    if (wi > 0.0) {
        let first = textureLoad(spring_offsets, texel(i), 0).x;
        let end = textureLoad(spring_offsets, texel(i + 1u), 0).x;
        for (var k = first; k < end; k = k + 1u) {
            let s = unpack_spring(textureLoad(springs, texel(k), 0));
            let q = textureLoad(pos, texel(s.other), 0);
            let d = q.xyz - p.xyz;
            let len = length(d);
            let longest = (1.0 + params.strain_limit) * s.rest_length;
            if (len > longest) {
                let share = wi / (wi + q.w);
                delta = delta + (share * (len - longest) / len) * d;
                violated = violated + 1u;
            }
        }
    }
    if (violated > 0u) {
        delta = delta / f32(violated);
    }
    textureStore(pos_out, texel(i), vec4<f32>(p.xyz + delta, wi));
    textureStore(vel_out, texel(i), vec4<f32>(v.xyz + delta / params.dt, 0.0));
}
