// Dihedral bending (Bridson, Marino & Fedkiw 2003), each hinge evaluated once: one thread per
// hinge writes its forces on its four vertices to the CSR slots of their hinge refs, so that
// integrate reads each particle's bending forces as one contiguous run of texels, in CSR order.
// CPU twin: src/cpu/hinge_forces.rs (which keeps them in ref order and gathers through the refs).

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var hinge_offsets: texture_2d<u32>;     // r32uint, N + 1 entries
@group(0) @binding(3) var hinges: texture_2d<u32>;            // two texels per Hinge
@group(0) @binding(4) var hinge_slots: texture_2d<u32>;       // per hinge: its roles' CSR slots
@group(0) @binding(5) var hinge_forces: texture_storage_2d<rgba32float, write>; // one per slot

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
    let t = hinge_frame(hinge.stiffness, position(hinge.v.x), position(hinge.v.y), position(hinge.v.z), position(hinge.v.w));
    var f0 = vec3<f32>(0.0);
    var f1 = vec3<f32>(0.0);
    var f2 = vec3<f32>(0.0);
    var f3 = vec3<f32>(0.0);
    if (t.valid) {
        let c = t.weight * (t.sin_half - hinge.rest_sin_half);
        f0 = c * (dot(t.x1 - t.x4, t.e_hat) * t.a + dot(t.x2 - t.x4, t.e_hat) * t.b);
        f1 = c * (-dot(t.x1 - t.x3, t.e_hat) * t.a - dot(t.x2 - t.x3, t.e_hat) * t.b);
        f2 = c * (t.e_len * t.a);
        f3 = c * (t.e_len * t.b);
    }
    let slot = textureLoad(hinge_slots, texel(h), 0);
    textureStore(hinge_forces, texel(slot.x), vec4<f32>(f0, 0.0));
    textureStore(hinge_forces, texel(slot.y), vec4<f32>(f1, 0.0));
    textureStore(hinge_forces, texel(slot.z), vec4<f32>(f2, 0.0));
    textureStore(hinge_forces, texel(slot.w), vec4<f32>(f3, 0.0));
}
