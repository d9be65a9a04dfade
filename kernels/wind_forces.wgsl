// Per-triangle normal drag ½ρ·C_d·A·(v_rel·n)|v_rel·n|·n, a third to each vertex, gathered per
// particle over its incident triangles. CPU twin: src/cpu/wind_forces.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<uniform> step: SubstepParams;          // dynamic offset per substep
@group(0) @binding(2) var<storage, read> pos: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> vel: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> force: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> triangle_offsets: array<u32>;
@group(0) @binding(6) var<storage, read> triangle_refs: array<u32>;
@group(0) @binding(7) var<storage, read> triangles: array<vec4<u32>>;  // xyz: vertices, w: unused

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    var f = vec3<f32>(0.0);
    for (var k = triangle_offsets[i]; k < triangle_offsets[i + 1u]; k = k + 1u) {
        let t = triangles[triangle_refs[k]];
        let x0 = pos[t.x].xyz;
        let x1 = pos[t.y].xyz;
        let x2 = pos[t.z].xyz;
        let c = cross(x1 - x0, x2 - x0);
        let twice_area = length(c);
        if (twice_area > 1e-12) {
            let n = c / twice_area;
            let v_mean = (vel[t.x].xyz + vel[t.y].xyz + vel[t.z].xyz) / 3.0;
            let vn = dot(step.wind.xyz - v_mean, n);
            let drag = 0.5 * params.air_density * params.drag_coefficient * (0.5 * twice_area) * vn * abs(vn);
            f = f + (drag / 3.0) * n;
        }
    }
    force[i] = force[i] + vec4<f32>(f, 0.0);
}
