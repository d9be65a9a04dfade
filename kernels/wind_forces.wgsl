// Per-triangle normal drag ½ρ·C_d·A·(v_rel·n)|v_rel·n|·n, a third to each vertex, gathered per
// particle over its incident triangles. CPU twin: src/cpu/wind_forces.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<uniform> step: SubstepParams;          // dynamic offset per substep
@group(0) @binding(2) var pos: texture_2d<f32>;
@group(0) @binding(3) var vel: texture_2d<f32>;
@group(0) @binding(4) var force_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var triangle_offsets: texture_2d<u32>;  // r32uint, N + 1 entries
@group(0) @binding(6) var triangle_refs: texture_2d<u32>;     // r32uint: triangle index
@group(0) @binding(7) var triangles: texture_2d<u32>;         // xyz: vertices, w: unused

fn position(i: u32) -> vec3<f32> {
    return textureLoad(pos, texel(i), 0).xyz;
}

fn velocity(i: u32) -> vec3<f32> {
    return textureLoad(vel, texel(i), 0).xyz;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let first = textureLoad(triangle_offsets, texel(i), 0).x;
    let end = textureLoad(triangle_offsets, texel(i + 1u), 0).x;
    var f = vec3<f32>(0.0);
    for (var k = first; k < end; k = k + 1u) {
        let t = textureLoad(triangles, texel(textureLoad(triangle_refs, texel(k), 0).x), 0);
        let x0 = position(t.x);
        let x1 = position(t.y);
        let x2 = position(t.z);
        let c = cross(x1 - x0, x2 - x0);
        let twice_area = length(c);
        if (twice_area > 1e-12) {
            let n = c / twice_area;
            let v_mean = (velocity(t.x) + velocity(t.y) + velocity(t.z)) / 3.0;
            let vn = dot(step.wind.xyz - v_mean, n);
            let drag = 0.5 * params.air_density * params.drag_coefficient * (0.5 * twice_area) * vn * abs(vn);
            f = f + (drag / 3.0) * n;
        }
    }
    textureStore(force_out, texel(i), vec4<f32>(previous_force(i) + f, 0.0));
}
