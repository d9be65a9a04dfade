// Implicit Euler 1/3: the inertial target Y = h·vₙ + h²·a of every particle and the solve's
// starting guess D⁰ = h·vₙ, both displacements from xₙ (w = inverse mass), with a = g + f/m and
// f the external forces the force stages summed (wind; zero without). Pinned particles do not
// move: both are zero. Also clears the largest Newton step of every sweep, which this substep's
// sweeps record (the count of sweeps run, in the last entry, accumulates), and the solve's
// `done` flag. CPU twin: src/cpu/vbd_init.rs (why this guess: see there).

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var pos: texture_2d<f32>;
@group(0) @binding(2) var vel: texture_2d<f32>;
@group(0) @binding(3) var<storage, read_write> x: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> y: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> steps: array<atomic<u32>>;
// The solve's SolveControl (kernels/solve.wgsl) as words: word 0 is `done`.
@group(0) @binding(6) var<storage, read_write> control_words: array<u32>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (i == 0u) {
        for (var k = 0u; k + 1u < arrayLength(&steps); k = k + 1u) {
            atomicStore(&steps[k], 0u);
        }
        control_words[0] = 0u;
    }
    if (i >= params.num_particles) {
        return;
    }
    let p = textureLoad(pos, texel(i), 0);
    if (p.w == 0.0) {
        y[i] = vec4<f32>(0.0);
        x[i] = vec4<f32>(0.0);
        return;
    }
    let h = params.dt;
    let a = previous_force(i) * p.w + params.gravity.xyz;
    let start = h * textureLoad(vel, texel(i), 0).xyz;
    y[i] = vec4<f32>(start + h * h * a, p.w);
    x[i] = vec4<f32>(start, p.w);
}
