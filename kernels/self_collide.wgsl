// Self-collision, step 5 of 5: particle-particle repulsion. Each particle looks through the 27
// hash cells around it; a particle closer than self_thickness that is not a mesh neighbour
// pushes it away by half the overlap and cancels half of their approaching normal velocity
// (the other particle does the same from its side, so momentum is conserved for equal
// masses). Reads the state, writes the other ping-pong textures. CPU twin:
// src/cpu/self_collide.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var vel: texture_2d<f32>;
@group(0) @binding(3) var<storage, read> starts: array<u32>;
@group(0) @binding(4) var<storage, read> sorted: array<u32>;
@group(0) @binding(5) var spring_offsets: texture_2d<u32>;    // mesh neighbours to skip
@group(0) @binding(6) var springs: texture_2d<u32>;
@group(0) @binding(7) var pos_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(8) var vel_out: texture_storage_2d<rgba32float, write>;

fn is_neighbour(i: u32, j: u32) -> bool {
    let end = textureLoad(spring_offsets, texel(i + 1u), 0).x;
    for (var k = textureLoad(spring_offsets, texel(i), 0).x; k < end; k = k + 1u) {
        if (textureLoad(springs, texel(k), 0).x == j) {
            return true;
        }
    }
    return false;
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i >= params.num_particles) {
        return;
    }
    let p = textureLoad(pos, texel(i), 0);
    let xi = p.xyz;
    let vi = textureLoad(vel, texel(i), 0).xyz;
    var dx = vec3<f32>(0.0);
    var dv = vec3<f32>(0.0);
    if (p.w != 0.0) {
        let h = params.self_thickness;
        let c = hash_cell_of(xi, params.hash_cell);
        // Two of the 27 cells may share a bucket; visit each bucket once.
        var seen: array<u32, 27>;
        var visited = 0u;
        for (var oz = -1; oz <= 1; oz = oz + 1) {
            for (var oy = -1; oy <= 1; oy = oy + 1) {
                for (var ox = -1; ox <= 1; ox = ox + 1) {
                    let b = hash_bucket(c + vec3<i32>(ox, oy, oz), params.hash_buckets);
                    var repeat = false;
                    for (var s = 0u; s < visited; s = s + 1u) {
                        repeat = repeat || seen[s] == b;
                    }
                    if (repeat) {
                        continue;
                    }
                    seen[visited] = b;
                    visited = visited + 1u;
                    for (var k = starts[b]; k < starts[b + 1u]; k = k + 1u) {
                        let j = sorted[k];
                        if (j == i) {
                            continue;
                        }
                        let xj = textureLoad(pos, texel(j), 0).xyz;
                        let d = xi - xj;
                        let dist = length(d);
                        if (dist >= h || dist < 1e-9 || is_neighbour(i, j)) {
                            continue;
                        }
                        let n = d / dist;
                        dx = dx + 0.5 * (h - dist) * n;
                        let vn = dot(vi - textureLoad(vel, texel(j), 0).xyz, n);
                        if (vn < 0.0) {
                            dv = dv - 0.5 * vn * n;
                        }
                    }
                }
            }
        }
    }
    textureStore(pos_out, texel(i), vec4<f32>(xi + dx, p.w));
    textureStore(vel_out, texel(i), vec4<f32>(vi + dv, 0.0));
}
