// Seam forces: penalty springs from each seam vertex to its partner point on the other edge,
// gathered per particle. A vertex visits each pair it belongs to (as the seam vertex or as one
// end of the partner segment) and takes its share. A pair's rest gap shrinks from its open gap
// to 0 at the sewing rate, so that all seams are drawn together over the same time instead of
// snapping shut. CPU twin: src/cpu/seam_forces.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<uniform> step: SubstepParams;          // dynamic offset per substep
@group(0) @binding(2) var pos: texture_2d<f32>;
@group(0) @binding(3) var vel: texture_2d<f32>;
@group(0) @binding(4) var force_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var seam_offsets: texture_2d<u32>;      // r32uint, N + 1 entries
@group(0) @binding(6) var seam_refs: texture_2d<u32>;         // r32uint: pair index * 4 + role
@group(0) @binding(7) var seams: texture_2d<u32>;             // two texels per Seam

// The force on the seam vertex; the partner segment's ends get −(1 − w) and −w of it.
fn seam_force(s: Seam) -> vec3<f32> {
    let w = s.weight;
    let xa = textureLoad(pos, texel(s.v.x), 0).xyz;
    let va = textureLoad(vel, texel(s.v.x), 0).xyz;
    let xp = (1.0 - w) * textureLoad(pos, texel(s.v.y), 0).xyz + w * textureLoad(pos, texel(s.v.z), 0).xyz;
    let vp = (1.0 - w) * textureLoad(vel, texel(s.v.y), 0).xyz + w * textureLoad(vel, texel(s.v.z), 0).xyz;
    let gap = xp - xa;
    let damping = s.damping * (vp - va);
    let rest = s.open_gap * max(1.0 - params.sewing_rate * step.time, 0.0);
    if (rest <= 0.0) {
        return s.stiffness * gap + damping;
    }
    // Pulls only: a pair closer than its rest gap feels no spring.
    let d = length(gap);
    return s.stiffness * max(d - rest, 0.0) / max(d, 1e-12) * gap + damping;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let first = textureLoad(seam_offsets, texel(i), 0).x;
    let end = textureLoad(seam_offsets, texel(i + 1u), 0).x;
    var f = vec3<f32>(0.0);
    for (var k = first; k < end; k = k + 1u) {
        let r = textureLoad(seam_refs, texel(k), 0).x;
        let p = r / 4u;
        let s = unpack_seam(textureLoad(seams, texel(2u * p), 0), textureLoad(seams, texel(2u * p + 1u), 0));
        let fa = seam_force(s);
        switch r % 4u {
            case 0u: { f = f + fa; }
            case 1u: { f = f - (1.0 - s.weight) * fa; }
            default: { f = f - s.weight * fa; }
        }
    }
    textureStore(force_out, texel(i), vec4<f32>(previous_force(i) + f, 0.0));
}
