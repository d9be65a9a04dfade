// Implicit Euler 2/3: one Vertex Block Descent sweep (Chen, Macklin et al. 2024) over the
// vertices of one colour. Each vertex takes one Newton step x += H⁻¹f on the incremental
// potential ½‖x − y‖²_M / h² + E(x) with its neighbours held fixed; vertices of one colour share
// no element, so they never read each other's new position. Dispatched once per colour per
// iteration, the sweep chosen by a dynamic offset. Each sweep records its largest Newton step
// in its iteration's slot of `steps` (f32 bits: for non-negative floats the u32 order is the
// float order, so atomicMax works); with a tolerance, a sweep whose substep has converged does
// nothing (the rule: converged_before in src/solver.rs). The bending and seam sections are
// composed in only when the scene has hinges, seams or a body. CPU twin: src/cpu/vbd_solve.rs
// (energies and Hessians documented there).

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<uniform> step: SubstepParams;          // dynamic offset per substep
@group(0) @binding(2) var<uniform> sweep: Sweep;                 // dynamic offset per sweep
@group(0) @binding(3) var pos: texture_2d<f32>;                   // xₙ, w = inverse mass
@group(0) @binding(4) var<storage, read_write> x: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> y: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> steps: array<atomic<u32>>;  // then the iterations run
@group(0) @binding(7) var order: texture_2d<u32>;                // r32uint: vertices by colour
@group(0) @binding(8) var spring_offsets: texture_2d<u32>;       // r32uint, N + 1 entries
@group(0) @binding(9) var springs: texture_2d<u32>;              // one SpringRef per texel

var<workgroup> group_step: atomic<u32>;   // the workgroup's largest step, f32 bits
var<workgroup> group_skip: u32;            // 1: the substep has converged

// Whether iteration k's sweeps are skipped (converged_before in src/solver.rs).
fn converged_before(k: u32) -> bool {
    if (k == 0u || params.tolerance <= 0.0) {
        return false;
    }
    let first = bitcast<f32>(atomicLoad(&steps[0]));
    let last = bitcast<f32>(atomicLoad(&steps[k - 1u]));
    return last <= max(params.tolerance * first, VBD_STEP_FLOOR);
}

fn outer(a: vec3<f32>, b: vec3<f32>) -> mat3x3<f32> {
    return mat3x3<f32>(a * b.x, a * b.y, a * b.z);
}

fn diagonal(v: f32) -> mat3x3<f32> {
    return mat3x3<f32>(v, 0.0, 0.0, 0.0, v, 0.0, 0.0, 0.0, v);
}

// How far vertex j has moved from xₙ in this step.
fn moved(j: u32) -> vec3<f32> {
    return x[j].xyz - textureLoad(pos, texel(j), 0).xyz;
}

// Hessian of ½k(|d| − L)², made positive semi-definite (the transverse term of a compressed
// spring is dropped).
fn spring_hessian(k: f32, rest: f32, d: vec3<f32>, len: f32) -> mat3x3<f32> {
    let n = d / len;
    let nn = outer(n, n);
    let transverse = max(1.0 - rest / len, 0.0);
    return k * nn + (k * transverse) * (diagonal(1.0) - nn);
}

fn add_springs(i: u32, xi: vec3<f32>, f: ptr<function, vec3<f32>>, hs: ptr<function, mat3x3<f32>>) {
    let h = params.dt;
    let first = textureLoad(spring_offsets, texel(i), 0).x;
    let end = textureLoad(spring_offsets, texel(i + 1u), 0).x;
    for (var k = first; k < end; k = k + 1u) {
        let s = unpack_spring(textureLoad(springs, texel(k), 0));
        let d = xi - x[s.other].xyz;
        let len = length(d);
        if (len > 1e-12) {
            let n = d / len;
            let closing = dot(n, moved(i) - moved(s.other));
            *f = *f - (s.stiffness * (len - s.rest_length) + s.damping / h * closing) * n;
            *hs = *hs + (spring_hessian(s.stiffness, s.rest_length, d, len) + (s.damping / h) * outer(n, n));
        }
    }
}

// section bending
@group(0) @binding(10) var hinge_offsets: texture_2d<u32>;     // r32uint, N + 1 entries
@group(0) @binding(11) var hinge_refs: texture_2d<u32>;        // r32uint: hinge index * 4 + role
@group(0) @binding(12) var hinges: texture_2d<u32>;            // two texels per Hinge

// The bending force on vertex `role` of h at the iterate (as hinge_forces.wgsl) plus its
// Gauss–Newton Hessian ½cos(θ/2)·weight·uuᵀ.
fn add_hinge(hinge: Hinge, role: u32, f: ptr<function, vec3<f32>>, hs: ptr<function, mat3x3<f32>>) {
    let t = hinge_terms(hinge.stiffness, x[hinge.v.x].xyz, x[hinge.v.y].xyz, x[hinge.v.z].xyz, x[hinge.v.w].xyz, role);
    if (!t.valid) {
        return;
    }
    *f = *f + t.weight * (t.sin_half - hinge.rest_sin_half) * t.u;
    let cos_half = sqrt(max(1.0 - t.sin_half * t.sin_half, 0.0));
    *hs = *hs + (0.5 * cos_half * t.weight) * outer(t.u, t.u);
}

fn add_bending(i: u32, f: ptr<function, vec3<f32>>, hs: ptr<function, mat3x3<f32>>) {
    let first = textureLoad(hinge_offsets, texel(i), 0).x;
    let end = textureLoad(hinge_offsets, texel(i + 1u), 0).x;
    for (var k = first; k < end; k = k + 1u) {
        let r = textureLoad(hinge_refs, texel(k), 0).x;
        let h = r / 4u;
        let hinge = unpack_hinge(textureLoad(hinges, texel(2u * h), 0), textureLoad(hinges, texel(2u * h + 1u), 0));
        add_hinge(hinge, r % 4u, f, hs);
    }
}
// else bending
fn add_bending(i: u32, f: ptr<function, vec3<f32>>, hs: ptr<function, mat3x3<f32>>) {}
// end bending

// section seams
@group(0) @binding(13) var seam_offsets: texture_2d<u32>;      // r32uint, N + 1 entries
@group(0) @binding(14) var seam_refs: texture_2d<u32>;         // r32uint: pair index * 4 + role
@group(0) @binding(15) var seams: texture_2d<u32>;             // two texels per Seam

fn add_seams(i: u32, f: ptr<function, vec3<f32>>, hs: ptr<function, mat3x3<f32>>) {
    let h = params.dt;
    let first = textureLoad(seam_offsets, texel(i), 0).x;
    let end = textureLoad(seam_offsets, texel(i + 1u), 0).x;
    for (var k = first; k < end; k = k + 1u) {
        let r = textureLoad(seam_refs, texel(k), 0).x;
        let p = r / 4u;
        let s = unpack_seam(textureLoad(seams, texel(2u * p), 0), textureLoad(seams, texel(2u * p + 1u), 0));
        let w = s.weight;
        let xa = x[s.v.x].xyz;
        let gap = (1.0 - w) * x[s.v.y].xyz + w * x[s.v.z].xyz - xa;
        let opening = (1.0 - w) * moved(s.v.y) + w * moved(s.v.z) - moved(s.v.x);
        let rest = s.open_gap * max(1.0 - params.sewing_rate * step.time, 0.0);
        // Force and Hessian on the seam vertex; the partner's ends take shares of them.
        var fa = s.damping / h * opening;
        var ha = diagonal(s.damping / h);
        if (rest <= 0.0) {
            fa = fa + s.stiffness * gap;
            ha = ha + diagonal(s.stiffness);
        } else {
            let d = length(gap);
            if (d > rest) {
                fa = fa + s.stiffness * (d - rest) / d * gap;
                ha = ha + spring_hessian(s.stiffness, rest, gap, d);
            }
        }
        var share = 1.0;
        switch r % 4u {
            case 0u: { share = 1.0; }
            case 1u: { share = -(1.0 - w); }
            default: { share = -w; }
        }
        *f = *f + share * fa;
        *hs = *hs + (share * share) * ha;
    }
}
// else seams
fn add_seams(i: u32, f: ptr<function, vec3<f32>>, hs: ptr<function, mat3x3<f32>>) {}
// end seams

// The contact penalty's stiffness over the mean diagonal of the vertex's other terms.
const CONTACT_RATIO: f32 = 100.0;

// section body
@group(0) @binding(16) var sdf: texture_2d<f32>;               // r32float, every body's nodes in turn

// Body contact inside the solve, at each body's pose at the end of the step (CPU twin documents
// the choices): a penalty ½k_c(thickness − φ)² where φ < thickness with Hessian k_c·n̂n̂ᵀ, k_c
// CONTACT_RATIO times the mean diagonal of everything else on the vertex; and Coulomb friction
// lagged on the penalty's normal force λ, opposing the slip u over the step, smoothed below the
// body's slip speed: f = −μλ·u / max(|u|, friction_slip_speed·h).

// Body b's outward normal (xyz) and signed distance φ (w) at the vertex.
fn body_surface(b: u32, xi: vec3<f32>) -> vec4<f32> {
    let pose = step.bodies[b];
    let d = xi - pose.translation.xyz;
    let xb = vec3<f32>(dot(pose.x.xyz, d), dot(pose.y.xyz, d), dot(pose.z.xyz, d));
    let s = sdf_sample(sdf, params.bodies[b].sdf_origin, params.bodies[b].sdf_dims, xb);
    let n = safe_normalize(pose.x.xyz * s.x + pose.y.xyz * s.y + pose.z.xyz * s.z);
    return vec4<f32>(n, s.w);
}

// Body b's contact terms for a vertex with surface s (from body_surface).
fn add_contact(b: u32, i: u32, xi: vec3<f32>, s: vec4<f32>, k_c: f32, f: ptr<function, vec3<f32>>, hs: ptr<function, mat3x3<f32>>) {
    let body = params.bodies[b];
    if (s.w >= body.thickness) {
        return;
    }
    let n = s.xyz;
    let lambda = k_c * (body.thickness - s.w);
    *f = *f + lambda * n;
    *hs = *hs + k_c * outer(n, n);
    let h = params.dt;
    let pose = step.bodies[b];
    let v_body = pose.velocity.xyz + cross(pose.angular_velocity.xyz, xi - pose.translation.xyz);
    let slip = moved(i) - h * v_body;
    let u = slip - dot(slip, n) * n;
    let scale = body.friction * lambda / max(length(u), body.friction_slip_speed * h);
    *f = *f - scale * u;
    *hs = *hs + scale * (diagonal(1.0) - outer(n, n));
}
// else body
fn body_surface(b: u32, xi: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(0.0, 0.0, 0.0, 3.4e38);
}
fn add_contact(b: u32, i: u32, xi: vec3<f32>, s: vec4<f32>, k_c: f32, f: ptr<function, vec3<f32>>, hs: ptr<function, mat3x3<f32>>) {}
// end body

// How far inside the contact layer, as a fraction of the thickness, a vertex that reaches it
// from outside stops (why: newton_step in the CPU twin).
const CONTACT_ENTRY: f32 = 1e-2;

// H⁻¹f through the adjugate: its rows are cross products of H's columns.
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

// One vertex's Newton step; returns its length (0 for a pinned vertex).
fn newton_step(i: u32) -> f32 {
    let prev = textureLoad(pos, texel(i), 0);
    if (prev.w == 0.0) {
        return 0.0;
    }
    let h = params.dt;
    let mass = 1.0 / prev.w;
    let xi = x[i].xyz;
    let inertia = mass / (h * h);
    let air = params.air_damping * mass / h;
    var f = -inertia * (xi - y[i].xyz) - air * moved(i);
    var hs = diagonal(inertia + air);
    add_springs(i, xi, &f, &hs);
    add_bending(i, &f, &hs);
    add_seams(i, &f, &hs);
    let k_c = CONTACT_RATIO * (hs[0].x + hs[1].y + hs[2].z) / 3.0;
    var surfaces: array<vec4<f32>, MAX_BODIES>;
    for (var b = 0u; b < params.num_bodies; b = b + 1u) {
        surfaces[b] = body_surface(b, xi);
        add_contact(b, i, xi, surfaces[b], k_c, &f, &hs);
    }
    var delta = solve3(hs, f);
    for (var b = 0u; b < params.num_bodies; b = b + 1u) {
        let thickness = params.bodies[b].thickness;
        if (surfaces[b].w >= thickness) {
            // A step that would enter the contact layer from outside stops just inside it.
            let entry = thickness * (1.0 - CONTACT_ENTRY);
            let landing = surfaces[b].w + dot(surfaces[b].xyz, delta);
            if (landing < entry) {
                delta = delta + (entry - landing) * surfaces[b].xyz;
            }
        }
    }
    x[i] = vec4<f32>(xi + delta, prev.w);
    return length(delta);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    if (lid == 0u) {
        group_skip = select(0u, 1u, converged_before(sweep.iteration));
        atomicStore(&group_step, 0u);
    }
    // Every invocation sees the same decision (and the cleared maximum) after this barrier.
    if (workgroupUniformLoad(&group_skip) != 0u) {
        return;
    }
    let k = particle_index(gid, groups);
    var len = 0.0;
    if (k < sweep.count) {
        len = newton_step(textureLoad(order, texel(sweep.first + k), 0).x);
    }
    atomicMax(&group_step, bitcast<u32>(len));
    workgroupBarrier();
    if (lid == 0u) {
        atomicMax(&steps[sweep.iteration], atomicLoad(&group_step));
        // An iteration counts once, by the first workgroup of its first colour.
        if (sweep.first == 0u && all(gid == vec3<u32>(0u))) {
            atomicAdd(&steps[params.iterations], 1u);
        }
    }
}
