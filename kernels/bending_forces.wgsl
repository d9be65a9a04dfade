// Dihedral bending (Bridson, Marino & Fedkiw 2003), gathered per particle: a particle visits each
// hinge it belongs to and takes its own share, so each hinge is evaluated four times.
// CPU twin: src/cpu/bending_forces.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var force_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var hinge_offsets: texture_2d<u32>;     // r32uint, N + 1 entries
@group(0) @binding(4) var hinge_refs: texture_2d<u32>;        // r32uint: hinge index * 4 + role
@group(0) @binding(5) var hinges: texture_2d<u32>;            // two texels per Hinge

fn position(i: u32) -> vec3<f32> {
    return textureLoad(pos, texel(i), 0).xyz;
}

// Force on vertex `role` of hinge h. Roles 0, 1: the shared edge (x3, x4 in the paper);
// roles 2, 3: the opposite vertices (x1, x2).
fn hinge_force(h: Hinge, role: u32) -> vec3<f32> {
    let x3 = position(h.v.x);
    let x4 = position(h.v.y);
    let x1 = position(h.v.z);
    let x2 = position(h.v.w);
    let e = x4 - x3;
    let n1 = cross(x1 - x3, x1 - x4);
    let n2 = cross(x2 - x4, x2 - x3);
    let e_len = length(e);
    let n1_sq = dot(n1, n1);
    let n2_sq = dot(n2, n2);
    // Degenerate triangles have no defined angle; they get no bending force.
    if (e_len < 1e-12 || n1_sq < 1e-24 || n2_sq < 1e-24) {
        return vec3<f32>(0.0);
    }
    let n1_len = sqrt(n1_sq);
    let n2_len = sqrt(n2_sq);
    let n1_hat = n1 / n1_len;
    let n2_hat = n2 / n2_len;
    let cos_theta = clamp(dot(n1_hat, n2_hat), -1.0, 1.0);
    var sin_half = sqrt(max(0.0, 0.5 * (1.0 - cos_theta)));
    if (dot(cross(n1_hat, n2_hat), e) < 0.0) {
        sin_half = -sin_half;
    }
    let magnitude = h.stiffness * e_len * e_len / (n1_len + n2_len) * (sin_half - h.rest_sin_half);
    let e_hat = e / e_len;
    let a = n1 / n1_sq;
    let b = n2 / n2_sq;
    var u = vec3<f32>(0.0);
    switch role {
        case 0u: { u = dot(x1 - x4, e_hat) * a + dot(x2 - x4, e_hat) * b; }
        case 1u: { u = -dot(x1 - x3, e_hat) * a - dot(x2 - x3, e_hat) * b; }
        case 2u: { u = e_len * a; }
        default: { u = e_len * b; }
    }
    return magnitude * u;
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
