// Particle-versus-body collision against a signed distance field baked in the body frame: a
// particle closer than the thickness is projected out along the SDF gradient, its inward
// velocity relative to the (moving) body is cancelled and Coulomb friction acts on the rest.
// Reads this substep's state and writes the other texture of each pair, like integrate.
// CPU twin: src/cpu/collide_body.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<uniform> step: SubstepParams;          // dynamic offset per substep
@group(0) @binding(2) var pos: texture_2d<f32>;
@group(0) @binding(3) var vel: texture_2d<f32>;
@group(0) @binding(4) var sdf: texture_2d<f32>;               // r32float, one node per texel, x fastest
@group(0) @binding(5) var pos_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var vel_out: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let p = textureLoad(pos, texel(i), 0);
    let v = textureLoad(vel, texel(i), 0).xyz;
    var x = p.xyz;
    var v_new = v;
    if (p.w != 0.0) {
        let d = x - step.body_translation.xyz;
        let xb = vec3<f32>(dot(step.body_x.xyz, d), dot(step.body_y.xyz, d), dot(step.body_z.xyz, d));
        let s = sdf_sample(sdf, params.sdf_origin, params.sdf_dims, xb);
        if (s.w < params.thickness) {
            let n = safe_normalize(step.body_x.xyz * s.x + step.body_y.xyz * s.y + step.body_z.xyz * s.z);
            if (dot(n, n) > 0.0) {
                x = x + (params.thickness - s.w) * n;
                let v_body = step.body_velocity.xyz + cross(step.body_angular_velocity.xyz, x - step.body_translation.xyz);
                let v_rel = v - v_body;
                var vn = dot(v_rel, n);
                var vt = v_rel - vn * n;
                if (vn < 0.0) {
                    // Coulomb: tangential speed drops by μ times the normal speed taken away.
                    let vt_len = length(vt);
                    if (vt_len > 0.0) {
                        vt = vt * max(0.0, 1.0 - params.friction * (-vn) / vt_len);
                    }
                    vn = 0.0;
                } else {
                    vn = vn * (1.0 - params.normal_loss);
                }
                vt = vt * (1.0 - params.tangential_loss);
                v_new = v_body + vt + vn * n;
            }
        }
    }
    textureStore(pos_out, texel(i), vec4<f32>(x, p.w));
    textureStore(vel_out, texel(i), vec4<f32>(v_new, 0.0));
}
