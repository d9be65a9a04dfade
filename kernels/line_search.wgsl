// The line search, on one invocation: the change of G at each trial step length
// (line_energy's partials summed in order; w: the scale its rounding is relative to), G's
// slopes along c (line_slopes' partials, after them, summed in order), and the first step
// length that does not raise G, or 0 when each does, into scalars.line_alpha. A change above
// zero by less than its rounding is taken when G falls by the slopes. CPU twin: line_search in
// src/cpu/line_energy.rs, where the rule is argued.

@group(0) @binding(27) var<storage, read> partials: array<vec4<f32>>;
@group(0) @binding(28) var<storage, read_write> scalars: SolveScalars;

// The step lengths the line search tries, in order (cpu: LINE_ALPHAS).
const LINE_ALPHAS: vec3<f32> = vec3<f32>(1.0, 0.5, 0.25);
// G's change's rounding per unit of its scale, 32ε = 2⁻¹⁸ (cpu: LINE_ROUNDING).
const LINE_ROUNDING: f32 = 3.814697265625e-6;

// G's change at step length a from its slopes at 0 and 1, G quadratic along c between them
// (cpu: slope_change).
fn slope_change(a: f32, slopes: vec4<f32>) -> f32 {
    return a * slopes.x + 0.5 * a * a * (slopes.y - slopes.x);
}

@compute @workgroup_size(1)
fn main() {
    if (control.done != 0u) {
        return;
    }
    let count = groups_for(params.num_particles);
    var total = vec4<f32>(0.0);
    for (var g = 0u; g < count; g = g + 1u) {
        total = total + partials[g];
    }
    var slopes = vec4<f32>(0.0);
    for (var g = 0u; g < count; g = g + 1u) {
        slopes = slopes + partials[count + g];
    }
    var alpha = 0.0;
    for (var k = 0u; k < 3u; k = k + 1u) {
        let change = total[k];
        let a = LINE_ALPHAS[k];
        if (change <= 0.0 || (change <= LINE_ROUNDING * total.w && slope_change(a, slopes) <= 0.0)) {
            alpha = a;
            break;
        }
    }
    scalars.line_alpha = alpha;
    // Every Newton step that runs ends in one line search (the CPU twin counts its assemblies).
    scalars.newton_steps = scalars.newton_steps + 1u;
}
