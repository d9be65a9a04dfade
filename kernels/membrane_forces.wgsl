// Membrane forces: the orthotropic membrane's warp, weft and shear conditions (Baraff and
// Witkin 1998) on each triangle's deformation gradient F = [w_u w_v], gathered per particle: a
// vertex visits each triangle it belongs to and keeps its own share. Energy per triangle
// A·(½k_u(|w_u| − 1)² + ½k_v(|w_v| − 1)² + ½k_s(w_u·w_v)²), damping τ times the stiffness along
// the conditions' gradients. CPU twin: src/cpu/membrane.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var vel: texture_2d<f32>;
@group(0) @binding(3) var force_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var membrane_offsets: texture_2d<u32>;  // r32uint, N + 1 entries
@group(0) @binding(5) var membrane_refs: texture_2d<u32>;     // r32uint: triangle * 4 + role
@group(0) @binding(6) var membranes: texture_2d<u32>;         // three texels per Membrane

// Σ c_r·values[v_r] as c1·(v1 − v0) + c2·(v2 − v0), over positions (which = 0) or velocities.
fn membrane_image(m: Membrane, c1: f32, c2: f32, which: u32) -> vec3<f32> {
    var x0: vec3<f32>;
    var x1: vec3<f32>;
    var x2: vec3<f32>;
    if (which == 0u) {
        x0 = textureLoad(pos, texel(m.v.x), 0).xyz;
        x1 = textureLoad(pos, texel(m.v.y), 0).xyz;
        x2 = textureLoad(pos, texel(m.v.z), 0).xyz;
    } else {
        x0 = textureLoad(vel, texel(m.v.x), 0).xyz;
        x1 = textureLoad(vel, texel(m.v.y), 0).xyz;
        x2 = textureLoad(vel, texel(m.v.z), 0).xyz;
    }
    return c1 * (x1 - x0) + c2 * (x2 - x0);
}

// One stretch condition's force on a vertex with coefficient c: −k·c·(t(|w| − 1) + τ·n̂·ẇ)·n̂,
// t the stretch law's tension per unit stiffness (the strain itself when linear).
fn stretch_condition(w: vec3<f32>, dw: vec3<f32>, k: f32, condition: u32, c: f32, tau: f32) -> vec3<f32> {
    let len = length(w);
    if (len <= 1e-12) {
        return vec3<f32>(0.0);
    }
    let n = w / len;
    let law = StretchLaw(params.membrane_onset / k, params.buckled_fraction, params.stiffening[condition], params.stiffening.z);
    let strain = law_tension(law, 1.0, len - 1.0);
    return -k * c * (strain + tau * dot(n, dw)) * n;
}

fn membrane_force(m: Membrane, role: u32) -> vec3<f32> {
    let s = m.shape;
    let wu = membrane_image(m, s.x, s.y, 0u);
    let wv = membrane_image(m, s.z, s.w, 0u);
    let du = membrane_image(m, s.x, s.y, 1u);
    let dv = membrane_image(m, s.z, s.w, 1u);
    let a = membrane_coefficients(s.x, s.y)[role];
    let b = membrane_coefficients(s.z, s.w)[role];
    let k = m.stiffness;
    let g = a * wv + b * wu;
    var f = -k.z * dot(wu, wv) * g - k.w * k.z * (dot(du, wv) + dot(wu, dv)) * g;
    f = f + stretch_condition(wu, du, k.x, 0u, a, k.w);
    f = f + stretch_condition(wv, dv, k.y, 1u, b, k.w);
    return f;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let first = textureLoad(membrane_offsets, texel(i), 0).x;
    let end = textureLoad(membrane_offsets, texel(i + 1u), 0).x;
    var f = vec3<f32>(0.0);
    for (var k = first; k < end; k = k + 1u) {
        let r = textureLoad(membrane_refs, texel(k), 0).x;
        let t = r / 4u;
        let m = unpack_membrane(
            textureLoad(membranes, texel(3u * t), 0),
            textureLoad(membranes, texel(3u * t + 1u), 0),
            textureLoad(membranes, texel(3u * t + 2u), 0),
        );
        f = f + membrane_force(m, r % 4u);
    }
    textureStore(force_out, texel(i), vec4<f32>(previous_force(i) + f, 0.0));
}
