// The fine level's linear system at the iterate, row by row: every vertex's force f = −∇G
// into `force` and its Hessian row (diagonal block first, then a block per neighbour, in the
// fine pattern's order) into `blocks`, gathered over its elements (vertex_system's sink adds
// each element's off-diagonal block to its slot, in element order), both filtered by the
// contact projections S: f ← Sᵢf, H_ij ← Sᵢ·H_ij·Sⱼ, and the diagonal block gets the vertex's
// constant stiffness in its filtered directions. Each invocation owns its row's blocks, and
// recomputes each neighbour's filter (the CPU twin computes them once; the numbers are the
// same). CPU twin: src/cpu/assemble.rs.

@group(0) @binding(19) var<storage, read_write> blocks: array<mat3x3<f32>>;
@group(0) @binding(20) var<storage, read_write> force: array<vec4<f32>>;

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = particle_index(gid, groups);
    if (control.done != 0u || i >= params.num_particles) {
        return;
    }
    let fine = level(0u);
    let start = row_start(fine, i);
    let end = row_start(fine, i + 1u);
    for (var b = start; b < end; b = b + 1u) {
        blocks[b] = mat3x3<f32>();
    }
    let sys = vertex_system(i, params.num_bodies, true);
    let own = contact_filter(i);
    let si = own.s;
    if (own.filtered) {
        let fixed = contact_stiffness(i) / CONTACT_RATIO;
        blocks[start] = si * sys.hessian * si + fixed * (identity() - si);
    } else {
        blocks[start] = sys.hessian;
    }
    for (var b = start + 1u; b < end; b = b + 1u) {
        let other = contact_filter(column(fine, b));
        // Most rows meet no body: I·H·I is H (up to the sign of a zero), so it is skipped.
        if (own.filtered || other.filtered) {
            blocks[b] = si * blocks[b] * other.s;
        }
    }
    force[i] = vec4<f32>(si * sys.force, 0.0);
}
