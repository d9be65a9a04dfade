// Implicit Euler's Vertex Block Descent sweep (Chen, Macklin et al. 2024) over the vertices of
// one colour of the fine level: each free vertex takes one Newton step on the incremental
// potential with every other vertex held fixed, D += H⁻¹f, unless the step would end inside a
// body's contact layer (then newton_step's contact rule). Vertices of one colour share no
// element, so they update in place without reading each other. Dispatched once per colour per
// sweep (op: the colour's entries in the fine colour order, and the sweep's slot in `steps`,
// where it records its largest step as f32 bits: for non-negative floats the u32 order is the
// float order, so atomicMax works). CPU twin: src/cpu/vbd_solve.rs.

@group(0) @binding(29) var<storage, read_write> steps: array<atomic<u32>>;  // then the sweeps run

var<workgroup> group_step: atomic<u32>;   // the workgroup's largest step, f32 bits

// The vertex's Newton step H⁻¹f, or, where it would end inside a body's contact layer (along
// the step's contact plane, body by body), the step that lands on the layer plus the best step
// in the layer's tangent plane given that (cpu: newton_step, which says why).
fn newton_step(i: u32, d: vec3<f32>, f: vec3<f32>, hess: mat3x3<f32>) -> vec3<f32> {
    var delta = solve3(hess, f);
    for (var b = 0u; b < params.num_bodies; b = b + 1u) {
        let pl = plane(b, i);
        let n = pl.xyz;
        let phi = pl.w + dot(n, d);
        let thickness = params.bodies[b].thickness;
        if (phi + dot(n, delta) < thickness) {
            let a = thickness - phi;
            let t = identity() - outer(n, n);
            let mean = (hess[0].x + hess[1].y + hess[2].z) / 3.0;
            let system = t * hess * t + mean * outer(n, n);
            delta = t * solve3(system, t * (f - a * (hess * n))) + a * n;
        }
    }
    return delta;
}

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
        atomicStore(&group_step, 0u);
    }
    workgroupBarrier();
    let k = particle_index(gid, groups);
    var len = 0.0;
    if (k < op.count) {
        let i = order_at(level(0u), op.first + k);
        let w = prev(i).w;
        if (w != 0.0) {
            let sys = vertex_system(i, params.num_bodies, false);
            let d = disp[i].xyz;
            let delta = newton_step(i, d, sys.force, sys.hessian);
            disp[i] = vec4<f32>(d + delta, w);
            len = length(delta);
        }
    }
    atomicMax(&group_step, bitcast<u32>(len));
    workgroupBarrier();
    if (lid == 0u) {
        atomicMax(&steps[op.slot], atomicLoad(&group_step));
        // A sweep counts once, by the first workgroup of its first colour.
        if (op.first == 0u && all(wid == vec3<u32>(0u))) {
            atomicAdd(&steps[arrayLength(&steps) - 1u], 1u);
        }
    }
}
