// Stretch springs on mesh edges, gathered per particle: each spring is evaluated once from each
// end, so no float atomics are needed and the sum order is fixed (CPU twin: src/cpu/spring_forces.rs).

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<storage, read> pos: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> vel: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> force: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> spring_offsets: array<u32>;
@group(0) @binding(5) var<storage, read> springs: array<SpringRef>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let xi = pos[i].xyz;
    let vi = vel[i].xyz;
    var f = vec3<f32>(0.0);
    for (var k = spring_offsets[i]; k < spring_offsets[i + 1u]; k = k + 1u) {
        let s = springs[k];
        let d = pos[s.other].xyz - xi;
        let len = length(d);
        if (len > 1e-12) {
            let dir = d / len;
            let stretch = len - s.rest_length;
            let closing_speed = dot(vel[s.other].xyz - vi, dir);
            f = f + (s.stiffness * stretch + s.damping * closing_speed) * dir;
        }
    }
    force[i] = force[i] + vec4<f32>(f, 0.0);
}
