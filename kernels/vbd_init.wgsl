// Implicit Euler 1/3: the inertial target y = xₙ + h·vₙ + h²·a of every particle, with
// a = g + f/m and f the external forces the force stages summed (wind; zero without), and the
// starting guess x⁰ = xₙ + h·vₙ (why this guess: see the CPU twin). Pinned particles (w = 0)
// stay where they are. Also clears the largest Newton step of every iteration, which the sweeps
// of this substep record (the count of iterations run, after them, accumulates). CPU twin:
// src/cpu/vbd_init.rs.

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var vel: texture_2d<f32>;
@group(0) @binding(3) var<storage, read_write> x: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> y: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> steps: array<atomic<u32>>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i == 0u) {
        for (var k = 0u; k < params.iterations; k = k + 1u) {
            atomicStore(&steps[k], 0u);
        }
    }
    if (i >= params.num_particles) {
        return;
    }
    let p = textureLoad(pos, texel(i), 0);
    if (p.w == 0.0) {
        y[i] = p;
        x[i] = p;
        return;
    }
    let h = params.dt;
    let a = previous_force(i) * p.w + params.gravity.xyz;
    let start = p.xyz + h * textureLoad(vel, texel(i), 0).xyz;
    y[i] = vec4<f32>(start + h * h * a, p.w);
    x[i] = vec4<f32>(start, p.w);
}
