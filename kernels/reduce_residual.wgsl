// The force residual of all free vertices from force_residual's partials, on one invocation:
// the largest and the RMS |f|/(m·g), into the solve's control words; with op.flag (a tolerance
// check) the substep's solve is done once the RMS is within params.tolerance, and every later
// dispatch of the substep's solve returns at once. CPU twin: reduce_residual in
// src/cpu/force_residual.rs and Vbd::solve's CheckConverged.

@group(0) @binding(27) var<storage, read> partials: array<vec4<f32>>;

@compute @workgroup_size(1)
fn main() {
    if (control.done != 0u) {
        return;
    }
    var largest = 0.0;
    var sum_sq = 0.0;
    var count = 0.0;
    for (var g = 0u; g < groups_for(params.num_particles); g = g + 1u) {
        let p = partials[g];
        largest = max(largest, p.x);
        sum_sq = sum_sq + p.y;
        count = count + p.z;
    }
    var rms = 0.0;
    if (count > 0.0) {
        rms = sqrt(sum_sq / count);
    }
    control.residual_max = largest;
    control.residual_rms = rms;
    if (op.flag != 0u && rms <= params.tolerance) {
        control.done = 1u;
    }
}
