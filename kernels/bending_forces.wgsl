// Dihedral bending (Bridson, Marino & Fedkiw 2003), gathered per particle: a particle visits each
// hinge it belongs to and takes its own share, so each hinge is evaluated four times. On lavapipe
// this runs faster than hinge_forces (each hinge once) followed by integrate's gather, so the
// GPU backend takes it (README, "Benchmarks"). CPU twin: src/cpu/bending_forces.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var force_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var hinge_offsets: texture_2d<u32>;     // r32uint, N + 1 entries
@group(0) @binding(4) var hinge_refs: texture_2d<u32>;        // r32uint: hinge index * 4 + role
@group(0) @binding(5) var hinges: texture_2d<u32>;            // two texels per Hinge

fn position(i: u32) -> vec3<f32> {
    return textureLoad(pos, texel(i), 0).xyz;
}

// Force on vertex `role` of hinge h (hinge_terms in common.wgsl; CPU: cpu::hinge_force).
fn hinge_force(h: Hinge, role: u32) -> vec3<f32> {
    let t = hinge_terms(h.stiffness, position(h.v.x), position(h.v.y), position(h.v.z), position(h.v.w), role);
    if (!t.valid) {
        return vec3<f32>(0.0);
    }
    return t.weight * (t.sin_half - h.rest_sin_half) * t.u;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let first = textureLoad(hinge_offsets, texel(i), 0).x;
    let end = textureLoad(hinge_offsets, texel(i + 1u), 0).x;
    var f = vec3<f32>(0.0);
    for (var k = first; k < end; k = k + 1u) {
        let r = textureLoad(hinge_refs, texel(k), 0).x;
        let h = r / 4u;
        let hinge = unpack_hinge(textureLoad(hinges, texel(2u * h), 0), textureLoad(hinges, texel(2u * h + 1u), 0));
        f = f + hinge_force(hinge, r % 4u);
    }
    textureStore(force_out, texel(i), vec4<f32>(previous_force(i) + f, 0.0));
}
