// Linearises each body's contact at every free vertex for the step: the body's SDF sampled once
// at the starting guess xₙ + D⁰ gives a plane φ ≈ c + n̂·D (planes[b·N + i] = (n̂, c)), which
// the step's sweeps, assembly and line search all use; a vertex in contact (within
// CONTACT_SLACK_FRACTION of the layer) gets friction's normal force λ from its load at the
// guess (the inward component of everything but contact), others 0. Far from a body (outside
// its grid) the plane is (0, SDF_FAR). After the planes, each body's surface velocity at the
// vertex's start of step (planes[(num_bodies + b)·N + i], m/s): friction's slip is measured
// against it. A deforming body is sampled by deformed_body.wgsl,
// composed before this file. CPU twin: src/cpu/contact_planes.rs.

@group(0) @binding(17) var sdf: texture_2d<f32>;                  // r32float, every body's nodes in turn

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    let n = params.num_particles;
    if (control.done != 0u || i >= n) {
        return;
    }
    var lambda = vec4<f32>(0.0);
    let p = prev(i);
    if (p.w == 0.0) {
        for (var b = 0u; b < params.num_bodies; b = b + 1u) {
            planes[b * n + i] = vec4<f32>(0.0);
            planes[(params.num_bodies + b) * n + i] = vec4<f32>(0.0);
        }
        lambdas[i] = lambda;
        return;
    }
    let d0 = disp[i].xyz;
    let x = p.xyz + d0;
    var load = vec3<f32>(0.0);
    var load_known = false;
    for (var b = 0u; b < params.num_bodies; b = b + 1u) {
        let body = params.bodies[b];
        var phi: f32;
        var normal = vec3<f32>(0.0);
        var velocity: vec3<f32>;
        if (body.parts > 0u) {
            // A deforming body: its parts posed at the substep's end.
            let s = deformed_sample(sdf, body, x);
            phi = s.phi;
            normal = s.normal;
            velocity = deformed_velocity_at(s, p.xyz);
        } else {
            let pose = step.bodies[b];
            let rel = x - pose.translation.xyz;
            let xb = vec3<f32>(dot(pose.x.xyz, rel), dot(pose.y.xyz, rel), dot(pose.z.xyz, rel));
            let sample = sdf_sample(sdf, body.sdf_origin, body.sdf_dims, xb);
            let g = pose.x.xyz * sample.x + pose.y.xyz * sample.y + pose.z.xyz * sample.z;
            let len = length(g);
            if (len > 1e-12) {
                normal = g / len;
            }
            phi = sample.w;
            velocity = pose.velocity.xyz + cross(pose.angular_velocity.xyz, p.xyz - pose.translation.xyz);
        }
        planes[b * n + i] = vec4<f32>(normal, phi - dot(normal, d0));
        planes[(params.num_bodies + b) * n + i] = vec4<f32>(velocity, 0.0);
        if (phi < body.thickness * (1.0 + CONTACT_SLACK_FRACTION)) {
            if (!load_known) {
                load = vertex_system(i, 0u, false).force;
                load_known = true;
            }
            lambda[b] = max(-dot(normal, load), 0.0);
        }
    }
    lambdas[i] = lambda;
}
