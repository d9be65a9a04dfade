// Shared by every kernel of implicit Euler's solve (composed after common.wgsl): the bindings
// every solve dispatch has, the solve's control words, the reductions' tree sum and the small
// matrix helpers. Binding numbers are the same in every solve kernel: src/gpu/solve_kernels.rs
// lists what each kernel binds. Keep the structs in sync with src/gpu/solve_layout.rs
// (tests/implicit_gpu.rs checks their layouts through naga).

// What one dispatch of the solve works on: one entry per distinct dispatch, selected with a
// dynamic uniform offset.
struct OpParams {
    level: u32,                  // the multigrid level (0: the fine level)
    first: u32,                  // a colour's first entry in its level's colour order, or an op list's first entry
    count: u32,                  // the colour's rows, or the op list's entries
    slot: u32,                   // a sweep's slot in `steps`; conjugate gradients' r·z parity
    flag: u32,                   // pcg_direction: the first direction; reduce_residual: check the tolerance
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// What the solve decides on the device, read back at output frames only.
struct SolveControl {
    done: u32,                   // 1 once a tolerance check found this substep's solve converged (vbd_init clears it)
    _pad0: u32,
    residual_max: f32,           // the last force residual measured: largest |f|/(m·g) of the free vertices
    residual_rms: f32,           // and its RMS
}

// The scalars of the Newton step's conjugate gradients and line search.
struct SolveScalars {
    rz: vec2<f32>,               // r·z of the current direction, at the iteration's parity (the other: the previous)
    alpha: f32,                  // the last conjugate-gradient step length
    line_alpha: f32,             // the last line search's step length
    newton_steps: u32,           // line searches run, one per Newton step (it wraps)
    _pad0: u32,
}

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<uniform> step: SubstepParams;          // dynamic offset per substep
@group(0) @binding(2) var<uniform> op: OpParams;                 // dynamic offset per dispatch
// section writes_control
@group(0) @binding(3) var<storage, read_write> control: SolveControl;
// else writes_control
// Read-only, so that every invocation reads the same value (naga's uniformity analysis agrees)
// and a converged substep's dispatches return before their barriers.
@group(0) @binding(3) var<storage, read> control: SolveControl;
// end writes_control

// Workgroups of a dispatch over `threads` invocations of WORKGROUP_SIZE: the partial sums of a
// reduction over particles, one per workgroup.
fn groups_for(threads: u32) -> u32 {
    return (threads + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
}

// A workgroup's index in a (possibly 2D) dispatch.
fn group_index(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * groups.x;
}

// The workgroup's values for tree_sum.
var<workgroup> lanes: array<vec4<f32>, WORKGROUP_SIZE>;

// The sum of `lanes` in the order of the CPU twin's tree_sum (src/cpu/line_energy.rs): lane k
// adds lane k + stride for stride 32, 16, …, 1. Every invocation of the workgroup calls it after
// writing its lane; lane 0's result is the workgroup's partial.
fn tree_sum(lid: u32) -> vec4<f32> {
    workgroupBarrier();
    for (var stride = WORKGROUP_SIZE / 2u; stride > 0u; stride = stride / 2u) {
        if (lid < stride) {
            lanes[lid] = lanes[lid] + lanes[lid + stride];
        }
        workgroupBarrier();
    }
    return lanes[0];
}

fn outer(a: vec3<f32>, b: vec3<f32>) -> mat3x3<f32> {
    return mat3x3<f32>(a * b.x, a * b.y, a * b.z);
}

fn diagonal(v: f32) -> mat3x3<f32> {
    return mat3x3<f32>(v, 0.0, 0.0, 0.0, v, 0.0, 0.0, 0.0, v);
}

fn identity() -> mat3x3<f32> {
    return diagonal(1.0);
}

// H⁻¹f through the adjugate, whose rows are cross products of H's columns; zero when H is
// singular. CPU twin: cpu::solve3.
fn solve3(hs: mat3x3<f32>, f: vec3<f32>) -> vec3<f32> {
    let r0 = cross(hs[1], hs[2]);
    let r1 = cross(hs[2], hs[0]);
    let r2 = cross(hs[0], hs[1]);
    let det = dot(hs[0], r0);
    if (abs(det) < 1e-30) {
        return vec3<f32>(0.0);
    }
    return vec3<f32>(dot(r0, f), dot(r1, f), dot(r2, f)) / det;
}
