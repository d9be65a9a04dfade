// Particle-versus-body collision against each body's signed distance field, baked in its own
// frame: a particle closer than the thickness is projected out along the SDF gradient, its
// inward velocity relative to the (moving) body is cancelled and Coulomb friction acts on the
// rest. Bodies are taken in scene order, each seeing the previous one's result, so where two
// bodies pinch the cloth closer than their thicknesses allow, the later body wins.
// Reads this substep's state and writes the other texture of each pair, like integrate.
// A deforming body is sampled by deformed_body.wgsl, composed after this file.
// CPU twin: src/cpu/collide_body.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<uniform> step: SubstepParams;          // dynamic offset per substep
@group(0) @binding(2) var pos: texture_2d<f32>;
@group(0) @binding(3) var vel: texture_2d<f32>;
@group(0) @binding(4) var sdf: texture_2d<f32>;               // r32float, every body's nodes in turn
@group(0) @binding(5) var pos_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var vel_out: texture_storage_2d<rgba32float, write>;

// The response to a contact at distance phi along unit normal n (zero: none) of a surface
// whose velocity around the contact is linear + angular × (p − center): the particle moves out
// to the thickness, its inward velocity relative to the surface is cancelled and Coulomb
// friction acts on the rest (x and v updated in place).
fn respond(body: BodyParams, phi: f32, n: vec3<f32>, center: vec3<f32>, linear: vec3<f32>, angular: vec3<f32>, x: ptr<function, vec3<f32>>, v: ptr<function, vec3<f32>>) {
    if (dot(n, n) == 0.0) {
        return;
    }
    *x = *x + (body.thickness - phi) * n;
    let v_body = linear + cross(angular, *x - center);
    let v_rel = *v - v_body;
    var vn = dot(v_rel, n);
    var vt = v_rel - vn * n;
    if (vn < 0.0) {
        // Coulomb: tangential speed drops by μ times the normal speed taken away.
        let vt_len = length(vt);
        if (vt_len > 0.0) {
            vt = vt * max(0.0, 1.0 - body.friction * (-vn) / vt_len);
        }
        vn = 0.0;
    } else {
        vn = vn * (1.0 - body.normal_loss);
    }
    vt = vt * (1.0 - body.tangential_loss);
    *v = v_body + vt + vn * n;
}

// One body's response to a particle at x with velocity v (both updated in place): a rigid
// body's SDF in its frame, or a deforming body's parts (deformed_body.wgsl).
fn collide(b: u32, x: ptr<function, vec3<f32>>, v: ptr<function, vec3<f32>>) {
    let body = params.bodies[b];
    if (body.parts > 0u) {
        let s = deformed_sample(sdf, body, *x);
        if (s.phi >= body.thickness) {
            return;
        }
        respond(body, s.phi, s.normal, s.center, s.linear, s.angular, x, v);
        return;
    }
    let pose = step.bodies[b];
    let d = *x - pose.translation.xyz;
    let xb = vec3<f32>(dot(pose.x.xyz, d), dot(pose.y.xyz, d), dot(pose.z.xyz, d));
    let s = sdf_sample(sdf, body.sdf_origin, body.sdf_dims, xb);
    if (s.w >= body.thickness) {
        return;
    }
    let n = safe_normalize(pose.x.xyz * s.x + pose.y.xyz * s.y + pose.z.xyz * s.z);
    respond(body, s.w, n, pose.translation.xyz, pose.velocity.xyz, pose.angular_velocity.xyz, x, v);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let p = textureLoad(pos, texel(i), 0);
    var x = p.xyz;
    var v = textureLoad(vel, texel(i), 0).xyz;
    if (p.w != 0.0) {
        for (var b = 0u; b < params.num_bodies; b = b + 1u) {
            collide(b, &x, &v);
        }
    }
    textureStore(pos_out, texel(i), vec4<f32>(x, p.w));
    textureStore(vel_out, texel(i), vec4<f32>(v, 0.0));
}
