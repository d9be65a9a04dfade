// The line search, on one invocation: the change of G at each trial step length (line_energy's
// partials summed in order) and the first step length that does not raise it, or 0 when each
// does, into scalars.line_alpha. CPU twin: line_search in src/cpu/line_energy.rs.

@group(0) @binding(27) var<storage, read> partials: array<vec4<f32>>;
@group(0) @binding(28) var<storage, read_write> scalars: SolveScalars;

// The step lengths the line search tries, in order (cpu: LINE_ALPHAS).
const LINE_ALPHAS: vec3<f32> = vec3<f32>(1.0, 0.5, 0.25);

@compute @workgroup_size(1)
fn main() {
    if (control.done != 0u) {
        return;
    }
    var total = vec4<f32>(0.0);
    for (var g = 0u; g < groups_for(params.num_particles); g = g + 1u) {
        total = total + partials[g];
    }
    var alpha = 0.0;
    for (var k = 0u; k < 3u; k = k + 1u) {
        if (total[k] <= 0.0) {
            alpha = LINE_ALPHAS[k];
            break;
        }
    }
    scalars.line_alpha = alpha;
    // Every Newton step that runs ends in one line search (the CPU twin counts its assemblies).
    scalars.newton_steps = scalars.newton_steps + 1u;
}
