// D += α·c for every particle, α the line search's step (the correction is zero at pins).
// CPU twin: apply_correction in src/cpu/line_energy.rs.

@group(0) @binding(5) var<storage, read_write> disp: array<vec4<f32>>;
@group(0) @binding(21) var<storage, read> correction: array<vec4<f32>>;
@group(0) @binding(28) var<storage, read> scalars: SolveScalars;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    let alpha = scalars.line_alpha;
    if (control.done != 0u || alpha == 0.0 || i >= params.num_particles) {
        return;
    }
    let d = disp[i];
    disp[i] = vec4<f32>(d.xyz + alpha * correction[i].xyz, d.w);
}
