// The Newton correction c filtered before the line search: zero at pinned vertices; at a vertex
// touching a body, without its component into the body (Tamstorf et al. 2015's prefiltering);
// elsewhere stopped at the layer where it would enter it, as a sweep's step is. CPU twin:
// correction_filter in src/cpu/prolong.rs.

@group(0) @binding(21) var<storage, read_write> correction: array<vec4<f32>>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (control.done != 0u || i >= params.num_particles) {
        return;
    }
    if (prev(i).w == 0.0) {
        correction[i] = vec4<f32>(0.0);
        return;
    }
    let d = disp[i].xyz;
    var v = correction[i].xyz;
    for (var b = 0u; b < params.num_bodies; b = b + 1u) {
        let pl = plane(b, i);
        let normal = pl.xyz;
        let phi = pl.w + dot(normal, d);
        let thickness = params.bodies[b].thickness;
        let inward = dot(v, normal);
        if (touching(b, i, d)) {
            if (inward < 0.0) {
                v = v - inward * normal;
            }
        } else {
            let landing = phi + inward;
            if (landing < thickness) {
                v = v + (thickness - landing) * normal;
            }
        }
    }
    correction[i] = vec4<f32>(v, 0.0);
}
