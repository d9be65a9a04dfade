// Dihedral bending (Bridson, Marino & Fedkiw 2003), each hinge evaluated once: one thread per
// hinge writes its forces on its four vertices to texels 4·h + role, the same numbers the
// particles' hinge refs (h·4 + role) point at, so a particle gathers its share by reading the
// texel its ref names. CPU twin: src/cpu/hinge_forces.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var hinge_offsets: texture_2d<u32>;     // r32uint, N + 1 entries
@group(0) @binding(3) var hinges: texture_2d<u32>;            // two texels per Hinge
@group(0) @binding(4) var hinge_forces: texture_storage_2d<rgba32float, write>; // four per hinge

fn position(i: u32) -> vec3<f32> {
    return textureLoad(pos, texel(i), 0).xyz;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let h = particle_index(gid, groups);
    // Every hinge has one ref per vertex, so the CSR's total is four per hinge.
    let count = textureLoad(hinge_offsets, texel(params.num_particles), 0).x / 4u;
    if (h >= count) {
        return;
    }
    let hinge = unpack_hinge(textureLoad(hinges, texel(2u * h), 0), textureLoad(hinges, texel(2u * h + 1u), 0));
    let frame = hinge_frame(hinge.stiffness, position(hinge.v.x), position(hinge.v.y), position(hinge.v.z), position(hinge.v.w));
    for (var role = 0u; role < 4u; role = role + 1u) {
        var f = vec3<f32>(0.0);
        if (frame.valid) {
            f = frame.weight * (frame.sin_half - hinge.rest_sin_half) * hinge_direction(frame, role);
        }
        textureStore(hinge_forces, texel(4u * h + role), vec4<f32>(f, 0.0));
    }
}
