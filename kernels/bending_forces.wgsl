// Bending forces gathered per particle: a particle sums the forces that hinge_forces wrote for
// it, one texel per hinge ref (h·4 + role), in CSR order. CPU twin: src/cpu/bending_forces.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var force_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(2) var hinge_offsets: texture_2d<u32>;     // r32uint, N + 1 entries
@group(0) @binding(3) var hinge_refs: texture_2d<u32>;        // r32uint: hinge index * 4 + role
@group(0) @binding(4) var hinge_forces: texture_2d<f32>;      // four texels per hinge

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
        f = f + textureLoad(hinge_forces, hinge_force_texel(r / 4u, r % 4u), 0).xyz;
    }
    textureStore(force_out, texel(i), vec4<f32>(previous_force(i) + f, 0.0));
}
