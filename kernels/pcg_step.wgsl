// Conjugate gradients' step along p: α = (r·z)/(p·H·p) (0 when p·H·p is not positive: the
// direction has vanished), with p·H·p the in-order sum of pcg_matvec's partials on one
// invocation of every workgroup (workgroup 0 records α); then c += α·p, r −= α·H·p and z = 0
// for the next V-cycle. CPU twin: pcg_matvec's α and pcg_step in src/cpu/pcg.rs.

@group(0) @binding(21) var<storage, read_write> correction: array<vec4<f32>>;
@group(0) @binding(22) var<storage, read> p: array<vec4<f32>>;
@group(0) @binding(23) var<storage, read> ap: array<vec4<f32>>;
@group(0) @binding(24) var<storage, read_write> rhs: array<vec4<f32>>;
@group(0) @binding(25) var<storage, read_write> e: array<vec4<f32>>;
@group(0) @binding(27) var<storage, read> partials: array<vec4<f32>>;
@group(0) @binding(28) var<storage, read_write> scalars: SolveScalars;

var<workgroup> shared_alpha: f32;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    if (control.done != 0u) {
        return;
    }
    if (lid == 0u) {
        var pap = 0.0;
        for (var g = 0u; g < groups_for(params.num_particles); g = g + 1u) {
            pap = pap + partials[g].x;
        }
        var alpha = 0.0;
        if (pap > 0.0) {
            alpha = scalars.rz[op.slot] / pap;
        }
        shared_alpha = alpha;
        if (all(wid == vec3<u32>(0u))) {
            scalars.alpha = alpha;
        }
    }
    let a = workgroupUniformLoad(&shared_alpha);
    let i = particle_index(gid, groups);
    if (i < params.num_particles) {
        correction[i] = vec4<f32>(correction[i].xyz + a * p[i].xyz, 0.0);
        rhs[i] = vec4<f32>(rhs[i].xyz - a * ap[i].xyz, 0.0);
        e[i] = vec4<f32>(0.0);
    }
}
