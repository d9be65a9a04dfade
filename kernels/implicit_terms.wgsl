// Implicit Euler's incremental potential at one vertex: its force (−gradient), its Hessian
// diagonal block (and, composed into `assemble`, the off-diagonal blocks of its row), the
// vertex's constant stiffness, the contact filter and the force residual. Composed into every
// kernel that evaluates the potential (contact_planes, vbd_solve, assemble, correction_filter,
// line_energy, line_slopes, force_residual). CPU twin: src/cpu/implicit_terms.rs, where the terms and their
// choices are documented; the functions here follow it line for line, in the same order of
// sums.
//
// The iterate is each vertex's displacement D over the step (`disp`, w = inverse mass), the
// inertial target Y (`inertial`) a displacement too; world positions are xₙ + D.

@group(0) @binding(4) var pos: texture_2d<f32>;                   // xₙ, w = inverse mass (0: pinned)
@group(0) @binding(5) var<storage, read_write> disp: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> inertial: array<vec4<f32>>;
// Each body's contact plane at each vertex, body after body (num_bodies × N): normal (xyz) and
// c (w), φ ≈ c + n̂·D; then each body's surface velocity at each vertex (xyz, m/s), as many
// again; written by contact_planes.
@group(0) @binding(7) var<storage, read_write> planes: array<vec4<f32>>;
// Each vertex's normal force per body at the start of the step (friction's λ), in N.
@group(0) @binding(8) var<storage, read_write> lambdas: array<vec4<f32>>;
@group(0) @binding(9) var spring_offsets: texture_2d<u32>;        // r32uint, N + 1 entries
@group(0) @binding(10) var springs: texture_2d<u32>;              // one SpringRef per texel

// Contact is this many times stiffer than the vertex's own stiffness (cpu: CONTACT_RATIO).
const CONTACT_RATIO: f32 = 100.0;
// A vertex within this fraction of the thickness outside a body's contact layer touches it
// (cpu: CONTACT_SLACK_FRACTION).
const CONTACT_SLACK_FRACTION: f32 = 0.01;

// section trial
// Vertex j's displacement where the terms are evaluated: the full step D + c of a Newton
// correction (line_slopes; cpu: the displacements line_slopes builds).
fn d_at(j: u32) -> vec3<f32> {
    return disp[j].xyz + correction[j].xyz;
}
// else trial
// Vertex j's displacement where the terms are evaluated: the iterate D.
fn d_at(j: u32) -> vec3<f32> {
    return disp[j].xyz;
}
// end trial

fn prev(i: u32) -> vec4<f32> {
    return textureLoad(pos, texel(i), 0);
}

fn is_free(j: u32) -> bool {
    return prev(j).w != 0.0;
}

// Vertex i's plane for body b.
fn plane(b: u32, i: u32) -> vec4<f32> {
    return planes[b * params.num_particles + i];
}

// Hessian of a spring's energy in d, made positive semi-definite: axial·n̂n̂ᵀ (axial: the law's
// axial stiffness, law_axial) plus the transverse term, dropped for a compressed spring.
fn spring_hessian(axial: f32, k: f32, rest: f32, d: vec3<f32>, len: f32) -> mat3x3<f32> {
    let n = d / len;
    let nn = outer(n, n);
    let transverse = max(1.0 - rest / len, 0.0);
    return axial * nn + (k * transverse) * (identity() - nn);
}

// Body b's surface velocity at vertex i's start of step (a deforming body's skin, not its root).
fn surface_velocity(b: u32, i: u32) -> vec3<f32> {
    return planes[(params.num_bodies + b) * params.num_particles + i].xyz;
}

// Body b's slip of vertex i over the step relative to the body surface, in the plane with
// normal n: the displacement less the body's own over the step.
fn slip(b: u32, i: u32, d: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let u = d - params.dt * surface_velocity(b, i);
    return u - dot(u, n) * n;
}

// Whether vertex i at displacement d touches body b (within CONTACT_SLACK_FRACTION of its
// contact layer, or inside it).
fn touching(b: u32, i: u32, d: vec3<f32>) -> bool {
    let pl = plane(b, i);
    return pl.w + dot(pl.xyz, d) < params.bodies[b].thickness * (1.0 + CONTACT_SLACK_FRACTION);
}

// The vertex's constant stiffness times CONTACT_RATIO: the mean diagonal of what does not
// depend on the state (inertia, air damping, each spring's (k + c/h)/3, each seam pair's
// share²·(k + c/h), each membrane's constant_stiffness).
fn contact_stiffness(i: u32) -> f32 {
    let h = params.dt;
    let mass = 1.0 / prev(i).w;
    var sum = mass / (h * h) + params.air_damping * mass / h;
    let first = textureLoad(spring_offsets, texel(i), 0).x;
    let end = textureLoad(spring_offsets, texel(i + 1u), 0).x;
    for (var k = first; k < end; k = k + 1u) {
        let s = unpack_spring(textureLoad(springs, texel(k), 0));
        sum = sum + (s.stiffness + s.damping / h) / 3.0;
    }
    sum = add_seam_stiffness(i, sum);
    sum = add_membrane_stiffness(i, sum);
    return CONTACT_RATIO * sum;
}

// A vertex's force and Hessian diagonal block.
struct VertexSystem {
    force: vec3<f32>,            // f = −∇ᵢG, in N
    hessian: mat3x3<f32>,        // ∂²G/∂Dᵢ², in N/m
}

// A spring's stretch |e| − L for e = start + change, as (|start| − L) plus the change's share
// (2·start·change + |change|²)/(|e| + |start|): smooth in the change down to its own rounding,
// where |e| in f32 moves in steps of its ulp (CPU twin: stretch in src/cpu/implicit_terms.rs,
// which says why).
fn stretch(start: vec3<f32>, start_len: f32, change: vec3<f32>, len: f32, rest: f32) -> f32 {
    let grow = 2.0 * dot(start, change) + dot(change, change);
    let sum = len + start_len;
    var share = 0.0;
    if (sum > 0.0) {
        share = grow / sum;
    }
    return (start_len - rest) + share;
}

// Vertex i's force and Hessian diagonal block at the iterate, with the contact of the first
// `bodies` bodies (contact_planes asks for none); a pinned vertex's are zero. When
// `assembling`, each off-diagonal block of the vertex's Hessian row is added to its slot of
// the fine matrix (sink; blocks towards pinned vertices are left out).
fn vertex_system(i: u32, bodies: u32, assembling: bool) -> VertexSystem {
    let h = params.dt;
    let p = prev(i);
    if (p.w == 0.0) {
        return VertexSystem(vec3<f32>(0.0), mat3x3<f32>());
    }
    let mass = 1.0 / p.w;
    let di = d_at(i);
    let inertia = mass / (h * h);
    let air = params.air_damping * mass / h;
    var f = -inertia * (di - inertial[i].xyz) - air * di;
    var hess = diagonal(inertia + air);

    let first = textureLoad(spring_offsets, texel(i), 0).x;
    let end = textureLoad(spring_offsets, texel(i + 1u), 0).x;
    for (var k = first; k < end; k = k + 1u) {
        let s = unpack_spring(textureLoad(springs, texel(k), 0));
        let j = s.other;
        let start = p.xyz - prev(j).xyz;
        let change = di - d_at(j);
        let e = start + change;
        let len = length(e);
        let start_len = length(start);
        var block = mat3x3<f32>();
        if (len > 1e-12) {
            let law = StretchLaw(params.euler_onset / s.rest_length, params.buckled_fraction, 0.0, 0.0);
            let s_len = stretch(start, start_len, change, len, s.rest_length);
            f = f - law_tension(law, s.stiffness, s_len) / len * e;
            let axial = law_axial(law, s.stiffness, s_len);
            block = block + spring_hessian(axial, s.stiffness, s.rest_length, e, len);
        }
        if (start_len > 1e-12) {
            let n = start / start_len;
            f = f - s.damping / h * dot(n, change) * n;
            block = block + (s.damping / h) * outer(n, n);
        }
        hess = hess + block;
        if (assembling && is_free(j)) {
            sink(spring_slot(k), -1.0 * block);
        }
    }

    add_hinges(i, assembling, &f, &hess);
    add_membranes(i, assembling, &f, &hess);
    add_seams(i, assembling, &f, &hess);

    if (bodies > 0u) {
        let k_c = contact_stiffness(i);
        for (var b = 0u; b < bodies; b = b + 1u) {
            let body = params.bodies[b];
            let pl = plane(b, i);
            let n = pl.xyz;
            let phi = pl.w + dot(n, di);
            if (phi < body.thickness) {
                f = f + k_c * (body.thickness - phi) * n;
                hess = hess + k_c * outer(n, n);
            }
            let lambda = lambdas[i][b];
            if (lambda > 0.0 && body.friction > 0.0) {
                let u = slip(b, i, di, n);
                let scale = body.friction * lambda / max(length(u), body.friction_slip_speed * h);
                f = f - scale * u;
                hess = hess + scale * (identity() - outer(n, n));
            }
        }
    }
    return VertexSystem(f, hess);
}

// The projection that removes the normals of the bodies vertex i touches (Gram–Schmidt over
// the bodies in order), and whether it removed any; the identity without contact.
struct Filter {
    s: mat3x3<f32>,
    filtered: bool,
}

fn contact_filter(i: u32) -> Filter {
    var out = Filter(identity(), false);
    if (prev(i).w == 0.0) {
        return out;
    }
    let di = d_at(i);
    for (var b = 0u; b < params.num_bodies; b = b + 1u) {
        let n = plane(b, i).xyz;
        if (touching(b, i, di)) {
            let m = out.s * n;
            let len = length(m);
            if (len > 1e-3) {
                let u = m / len;
                out.s = out.s - outer(u, u);
                out.filtered = true;
            }
        }
    }
    return out;
}

// Gravity's magnitude that weighs the residual: the scene's, or standard gravity when it is off
// (cpu: residual_gravity).
fn residual_gravity() -> f32 {
    let g = length(params.gravity.xyz);
    if (g > 0.0) {
        return g;
    }
    return 9.80665;
}

// |fᵢ| / (mᵢ·g) at vertex i with the normals of the bodies it touches left out; 0 for a pinned
// vertex.
fn force_residual_at(i: u32, g: f32) -> f32 {
    let w = prev(i).w;
    if (w == 0.0) {
        return 0.0;
    }
    let f = vertex_system(i, params.num_bodies, false).force;
    return length(contact_filter(i).s * f) * w / g;
}

// Hinge energy w₀·ψ(θ) from s = sin(θ/2) and s₀ = sin(θ₀/2) (cpu: hinge_psi).
fn hinge_psi(s_in: f32, s0: f32) -> f32 {
    let s = clamp(s_in, -1.0, 1.0);
    return -2.0 * sqrt(max(1.0 - s * s, 0.0)) - 2.0 * s0 * asin(s);
}

// The share of a seam pair's force that its vertex of `role` takes.
fn seam_share(s: Seam, role: u32) -> f32 {
    switch role {
        case 0u: { return 1.0; }
        case 1u: { return -(1.0 - s.weight); }
        default: { return -s.weight; }
    }
}

// A seam pair's rest gap now: its open gap, shrinking to 0 at the sewing rate (cpu: rest_gap).
fn rest_gap(s: Seam) -> f32 {
    return s.open_gap * max(1.0 - params.sewing_rate * step.time, 0.0);
}

// section bending
@group(0) @binding(11) var hinge_offsets: texture_2d<u32>;       // r32uint, N + 1 entries
@group(0) @binding(12) var hinge_refs: texture_2d<u32>;          // r32uint: hinge index * 4 + role
@group(0) @binding(13) var hinges: texture_2d<u32>;              // two texels per Hinge

fn hinge_at(h: u32) -> Hinge {
    return unpack_hinge(textureLoad(hinges, texel(2u * h), 0), textureLoad(hinges, texel(2u * h + 1u), 0));
}

// Hinge vertex j relative to the hinge's first vertex, which started at x_o and moved d_o,
// at displacement dj: the start's difference plus the displacements' (cpu: hinge_corners,
// where the precision is argued: world positions round to 6e-8 m at 1.3 m).
fn hinge_corner(j: u32, x_o: vec3<f32>, dj: vec3<f32>, d_o: vec3<f32>) -> vec3<f32> {
    return (prev(j).xyz - x_o) + (dj - d_o);
}

// The hinge's frame at the iterate plus a·c (c: the correction; a = 0 for the iterate itself).
fn hinge_frame_at(hinge: Hinge, c: array<vec3<f32>, 4>, a: f32) -> HingeFrame {
    let v = hinge.v;
    let x_o = prev(v.x).xyz;
    let d_o = d_at(v.x) + a * c[0];
    return hinge_frame(
        hinge.stiffness,
        hinge_corner(v.x, x_o, d_o, d_o),
        hinge_corner(v.y, x_o, d_at(v.y) + a * c[1], d_o),
        hinge_corner(v.z, x_o, d_at(v.z) + a * c[2], d_o),
        hinge_corner(v.w, x_o, d_at(v.w) + a * c[3], d_o),
    );
}

// The hinge's frame at the iterate (in line_slopes: at the full step, d_at): d + 0·0 equals d
// (to the bit but for the sign of a zero).
fn hinge_frame_here(hinge: Hinge) -> HingeFrame {
    let zero = vec3<f32>(0.0);
    return hinge_frame_at(hinge, array<vec3<f32>, 4>(zero, zero, zero, zero), 0.0);
}

fn add_hinges(i: u32, assembling: bool, f: ptr<function, vec3<f32>>, hess: ptr<function, mat3x3<f32>>) {
    let first = textureLoad(hinge_offsets, texel(i), 0).x;
    let end = textureLoad(hinge_offsets, texel(i + 1u), 0).x;
    for (var k = first; k < end; k = k + 1u) {
        let r = textureLoad(hinge_refs, texel(k), 0).x;
        let hinge = hinge_at(r / 4u);
        let v = hinge.v;
        let t = hinge_frame_here(hinge);
        if (!t.valid) {
            continue;
        }
        let role = r % 4u;
        let u = hinge_direction(t, role);
        *f = *f + hinge.rest_weight * (t.sin_half - hinge.rest_sin_half) * u;
        let cos_half = sqrt(max(1.0 - t.sin_half * t.sin_half, 0.0));
        let c = 0.5 * cos_half * hinge.rest_weight;
        *hess = *hess + c * outer(u, u);
        if (assembling) {
            for (var other = 0u; other < 4u; other = other + 1u) {
                if (other != role && is_free(v[other])) {
                    sink(hinge_slot(k, other), c * outer(u, hinge_direction(t, other)));
                }
            }
        }
    }
}
// else bending
fn add_hinges(i: u32, assembling: bool, f: ptr<function, vec3<f32>>, hess: ptr<function, mat3x3<f32>>) {}
// end bending

// section seams
@group(0) @binding(14) var seam_offsets: texture_2d<u32>;        // r32uint, N + 1 entries
@group(0) @binding(15) var seam_refs: texture_2d<u32>;           // r32uint: pair index * 4 + role
@group(0) @binding(16) var seams: texture_2d<u32>;               // two texels per Seam

fn seam_at(p: u32) -> Seam {
    return unpack_seam(textureLoad(seams, texel(2u * p), 0), textureLoad(seams, texel(2u * p + 1u), 0));
}

// A seam pair's gap (partner point minus seam vertex) and opening (its change over the step).
struct SeamGap {
    gap: vec3<f32>,
    opening: vec3<f32>,
}

fn seam_gap(s: Seam) -> SeamGap {
    let w = s.weight;
    let a = prev(s.v.x).xyz;
    let b0 = prev(s.v.y).xyz;
    let b1 = prev(s.v.z).xyz;
    let opening = (1.0 - w) * d_at(s.v.y) + w * d_at(s.v.z) - d_at(s.v.x);
    let start = (1.0 - w) * (b0 - a) + w * (b1 - a);
    return SeamGap(start + opening, opening);
}

// A seam pair's spring and damping force on its seam vertex, and that force's Hessian.
struct SeamSystem {
    fa: vec3<f32>,
    ha: mat3x3<f32>,
}

fn seam_system(s: Seam) -> SeamSystem {
    let h = params.dt;
    let g = seam_gap(s);
    let rest = rest_gap(s);
    var fa = s.damping / h * g.opening;
    var ha = diagonal(s.damping / h);
    if (rest <= 0.0) {
        fa = fa + s.stiffness * g.gap;
        ha = ha + diagonal(s.stiffness);
    } else {
        let len = length(g.gap);
        if (len > rest) {
            fa = fa + s.stiffness * (len - rest) / len * g.gap;
            ha = ha + spring_hessian(s.stiffness, s.stiffness, rest, g.gap, len);
        }
    }
    return SeamSystem(fa, ha);
}

fn add_seams(i: u32, assembling: bool, f: ptr<function, vec3<f32>>, hess: ptr<function, mat3x3<f32>>) {
    let first = textureLoad(seam_offsets, texel(i), 0).x;
    let end = textureLoad(seam_offsets, texel(i + 1u), 0).x;
    for (var k = first; k < end; k = k + 1u) {
        let r = textureLoad(seam_refs, texel(k), 0).x;
        let s = seam_at(r / 4u);
        let sys = seam_system(s);
        let role = r % 4u;
        let share = seam_share(s, role);
        *f = *f + share * sys.fa;
        *hess = *hess + (share * share) * sys.ha;
        if (assembling) {
            for (var other = 0u; other < 3u; other = other + 1u) {
                let share_j = seam_share(s, other);
                if (other != role && is_free(s.v[other]) && share_j != 0.0) {
                    sink(seam_slot(k, other), (share * share_j) * sys.ha);
                }
            }
        }
    }
}

fn add_seam_stiffness(i: u32, sum_in: f32) -> f32 {
    let h = params.dt;
    var sum = sum_in;
    let first = textureLoad(seam_offsets, texel(i), 0).x;
    let end = textureLoad(seam_offsets, texel(i + 1u), 0).x;
    for (var k = first; k < end; k = k + 1u) {
        let r = textureLoad(seam_refs, texel(k), 0).x;
        let s = seam_at(r / 4u);
        let share = seam_share(s, r % 4u);
        sum = sum + share * share * (s.stiffness + s.damping / h);
    }
    return sum;
}
// else seams
fn add_seams(i: u32, assembling: bool, f: ptr<function, vec3<f32>>, hess: ptr<function, mat3x3<f32>>) {}
fn add_seam_stiffness(i: u32, sum_in: f32) -> f32 {
    return sum_in;
}
// end seams

// ---- The orthotropic membrane (warp, weft and shear conditions on each triangle). ----
// CPU twin: MembraneStep in src/cpu/membrane.rs, which documents the terms; the functions here
// follow it line for line, in the same order of sums.
// section membrane
@group(0) @binding(33) var membrane_offsets: texture_2d<u32>;    // r32uint, N + 1 entries
@group(0) @binding(34) var membrane_refs: texture_2d<u32>;       // r32uint: triangle * 4 + role
@group(0) @binding(35) var membranes: texture_2d<u32>;           // three texels per Membrane

fn membrane_at(t: u32) -> Membrane {
    return unpack_membrane(
        textureLoad(membranes, texel(3u * t), 0),
        textureLoad(membranes, texel(3u * t + 1u), 0),
        textureLoad(membranes, texel(3u * t + 2u), 0),
    );
}

// Σ c_r·xₙ[v_r] as c₁(x₁ − x₀) + c₂(x₂ − x₀) (cpu: membrane::image over the start positions).
fn membrane_start_image(m: Membrane, c: vec3<f32>) -> vec3<f32> {
    let x0 = prev(m.v.x).xyz;
    return c.y * (prev(m.v.y).xyz - x0) + c.z * (prev(m.v.z).xyz - x0);
}

// The same combination of the displacements D.
fn membrane_disp_image(m: Membrane, c: vec3<f32>) -> vec3<f32> {
    let d0 = d_at(m.v.x);
    return c.y * (d_at(m.v.y) - d0) + c.z * (d_at(m.v.z) - d0);
}

// A membrane in the step: coefficients a (of w_u) and b (of w_v), the images at the start of
// the step and their changes so far (cpu: MembraneStep::at).
struct MembraneStep {
    a: vec3<f32>,
    b: vec3<f32>,
    start_u: vec3<f32>,
    start_v: vec3<f32>,
    change_u: vec3<f32>,
    change_v: vec3<f32>,
}

fn membrane_step(m: Membrane) -> MembraneStep {
    let a = membrane_coefficients(m.shape.x, m.shape.y);
    let b = membrane_coefficients(m.shape.z, m.shape.w);
    return MembraneStep(
        a,
        b,
        membrane_start_image(m, a),
        membrane_start_image(m, b),
        membrane_disp_image(m, a),
        membrane_disp_image(m, b),
    );
}

// |w| − 1 for w = s + dw: a spring of unit rest length (cpu: MembraneStep::stretch).
fn membrane_stretch(s: vec3<f32>, dw: vec3<f32>) -> f32 {
    return stretch(s, length(s), dw, length(s + dw), 1.0);
}

// Hessian of a stretch condition's energy per unit stiffness in w, made positive semi-definite,
// with axial the law's axial stiffness per unit stiffness (cpu: membrane::stretch_hessian).
fn membrane_stretch_hessian(axial: f32, secant: f32, n: vec3<f32>, len: f32) -> mat3x3<f32> {
    let nn = outer(n, n);
    return axial * nn + (max(1.0 - 1.0 / len, 0.0) * secant) * (identity() - nn);
}

// A membrane's force on one vertex and its Hessian blocks towards the triangle's three
// vertices (cpu: the return value of MembraneStep::system).
struct MembraneSystem {
    f: vec3<f32>,
    blocks: array<mat3x3<f32>, 3>,
}

// One stretch condition (start image s, change dw, stiffness k, per-vertex coefficients c) added
// to `sys` for vertex `role` (cpu: one pass of the condition loop in MembraneStep::system).
fn add_stretch_condition(
    sys: ptr<function, MembraneSystem>,
    s: vec3<f32>,
    dw: vec3<f32>,
    k: f32,
    condition: u32,
    c: vec3<f32>,
    role: u32,
    damp: f32,
) {
    let w = s + dw;
    let len = length(w);
    let cr = c[role];
    if (len > 1e-12) {
        let n = w / len;
        let law = StretchLaw(params.membrane_onset / k, params.buckled_fraction, params.stiffening[condition], params.stiffening.z);
        let strain = membrane_stretch(s, dw);
        (*sys).f = (*sys).f - k * cr * law_tension(law, 1.0, strain) * n;
        let hess = k * membrane_stretch_hessian(law_axial(law, 1.0, strain), law_secant_ratio(law, strain), n, len);
        for (var o = 0u; o < 3u; o = o + 1u) {
            (*sys).blocks[o] = (*sys).blocks[o] + (cr * c[o]) * hess;
        }
    }
    let start_len = length(s);
    if (start_len > 1e-12) {
        let n = s / start_len;
        (*sys).f = (*sys).f - damp * k * cr * dot(n, dw) * n;
        let nn = outer(n, n);
        for (var o = 0u; o < 3u; o = o + 1u) {
            (*sys).blocks[o] = (*sys).blocks[o] + (damp * k * cr * c[o]) * nn;
        }
    }
}

// The force −∇G on vertex `role` and the Hessian blocks (role, o) of membrane m in a step of
// h s (cpu: MembraneStep::system).
fn membrane_system(st: MembraneStep, m: Membrane, role: u32, h: f32) -> MembraneSystem {
    let k = m.stiffness;
    let damp = k.w / h;
    var sys = MembraneSystem(vec3<f32>(0.0), array<mat3x3<f32>, 3>());
    add_stretch_condition(&sys, st.start_u, st.change_u, k.x, 0u, st.a, role, damp);
    add_stretch_condition(&sys, st.start_v, st.change_v, k.y, 1u, st.b, role, damp);
    let wu = st.start_u + st.change_u;
    let wv = st.start_v + st.change_v;
    let g = st.a[role] * wv + st.b[role] * wu;
    sys.f = sys.f - k.z * dot(wu, wv) * g;
    let g0 = st.a[role] * st.start_v + st.b[role] * st.start_u;
    let q = dot(st.start_v, st.change_u) + dot(st.start_u, st.change_v);
    sys.f = sys.f - damp * k.z * q * g0;
    for (var o = 0u; o < 3u; o = o + 1u) {
        let go = st.a[o] * wv + st.b[o] * wu;
        let go0 = st.a[o] * st.start_v + st.b[o] * st.start_u;
        sys.blocks[o] = sys.blocks[o] + (k.z * outer(g, go) + (damp * k.z) * outer(g0, go0));
    }
    return sys;
}

// One stretch condition's share of the energy change when its image changes by `step`, added
// to e (cpu: one pass of the condition loop in MembraneStep::energy_change).
fn add_stretch_change(e_in: f32, s: vec3<f32>, dw: vec3<f32>, step: vec3<f32>, k: f32, condition: u32, damp: f32) -> f32 {
    let w = s + dw;
    let len = length(w);
    let len2 = length(w + step);
    let grow = 2.0 * dot(w, step) + dot(step, step);
    // (|w'| − 1)² − (|w| − 1)² = ds·(2s + ds), ds = |w'| − |w| without cancellation.
    var ds = 0.0;
    if (len + len2 > 0.0) {
        ds = grow / (len + len2);
    }
    let law = StretchLaw(params.membrane_onset / k, params.buckled_fraction, params.stiffening[condition], params.stiffening.z);
    let strain = membrane_stretch(s, dw);
    var e = e_in + law_energy_change(law, k, strain, strain + ds, 2.0 * strain + ds, ds);
    let start_len = length(s);
    if (start_len > 1e-12) {
        let n = s / start_len;
        let q = dot(n, dw);
        let dq = dot(n, step);
        e = e + 0.5 * damp * k * dq * (2.0 * q + dq);
    }
    return e;
}

// The change of membrane m's energy (elastic and damping) when its images change by du, dv
// (cpu: MembraneStep::energy_change).
fn membrane_energy_change(st: MembraneStep, m: Membrane, du: vec3<f32>, dv: vec3<f32>, h: f32) -> f32 {
    let k = m.stiffness;
    let damp = k.w / h;
    let wu = st.start_u + st.change_u;
    let wv = st.start_v + st.change_v;
    var e = add_stretch_change(0.0, st.start_u, st.change_u, du, k.x, 0u, damp);
    e = add_stretch_change(e, st.start_v, st.change_v, dv, k.y, 1u, damp);
    let shear = dot(wu, wv);
    let d_shear = dot(du, wv) + dot(wu, dv) + dot(du, dv);
    e = e + 0.5 * k.z * d_shear * (2.0 * shear + d_shear);
    let q = dot(st.start_v, st.change_u) + dot(st.start_u, st.change_v);
    let dq = dot(st.start_v, du) + dot(st.start_u, dv);
    return e + 0.5 * damp * k.z * dq * (2.0 * q + dq);
}

fn add_membranes(i: u32, assembling: bool, f: ptr<function, vec3<f32>>, hess: ptr<function, mat3x3<f32>>) {
    let h = params.dt;
    let first = textureLoad(membrane_offsets, texel(i), 0).x;
    let end = textureLoad(membrane_offsets, texel(i + 1u), 0).x;
    for (var k = first; k < end; k = k + 1u) {
        let r = textureLoad(membrane_refs, texel(k), 0).x;
        let m = membrane_at(r / 4u);
        let role = r % 4u;
        var sys = membrane_system(membrane_step(m), m, role, h);
        *f = *f + sys.f;
        *hess = *hess + sys.blocks[role];
        if (assembling) {
            for (var other = 0u; other < 3u; other = other + 1u) {
                if (other != role && is_free(m.v[other])) {
                    sink(membrane_slot(k, other), sys.blocks[other]);
                }
            }
        }
    }
}

// Each membrane's k·c_r²·(1 + τ/h) per condition, over 3 (cpu: MembraneStep::constant_stiffness).
fn add_membrane_stiffness(i: u32, sum_in: f32) -> f32 {
    let h = params.dt;
    var sum = sum_in;
    let first = textureLoad(membrane_offsets, texel(i), 0).x;
    let end = textureLoad(membrane_offsets, texel(i + 1u), 0).x;
    for (var k = first; k < end; k = k + 1u) {
        let r = textureLoad(membrane_refs, texel(k), 0).x;
        let m = membrane_at(r / 4u);
        let role = r % 4u;
        let ar = membrane_coefficients(m.shape.x, m.shape.y)[role];
        let br = membrane_coefficients(m.shape.z, m.shape.w)[role];
        let s = m.stiffness;
        sum = sum + (1.0 + s.w / h) * (s.x * ar * ar + s.y * br * br + s.z * (ar * ar + br * br)) / 3.0;
    }
    return sum;
}
// else membrane
fn add_membranes(i: u32, assembling: bool, f: ptr<function, vec3<f32>>, hess: ptr<function, mat3x3<f32>>) {}
fn add_membrane_stiffness(i: u32, sum_in: f32) -> f32 {
    return sum_in;
}
// end membrane
// ---- end of the membrane ----

// section assemble
// The fine matrix's blocks and where each element's go (assemble.wgsl binds them).
fn sink(slot: u32, m: mat3x3<f32>) {
    blocks[slot] = blocks[slot] + m;
}
fn spring_slot(k: u32) -> u32 {
    return hier[hier[HIER_SPRING_SLOTS] + k];
}
fn hinge_slot(k: u32, role: u32) -> u32 {
    return hier[hier[HIER_HINGE_SLOTS] + 4u * k + role];
}
fn seam_slot(k: u32, role: u32) -> u32 {
    return hier[hier[HIER_SEAM_SLOTS] + 4u * k + role];
}
fn membrane_slot(k: u32, role: u32) -> u32 {
    return hier[hier[HIER_MEMBRANE_SLOTS] + 4u * k + role];
}
// else assemble
fn sink(slot: u32, m: mat3x3<f32>) {}
fn spring_slot(k: u32) -> u32 {
    return 0u;
}
fn hinge_slot(k: u32, role: u32) -> u32 {
    return 0u;
}
fn seam_slot(k: u32, role: u32) -> u32 {
    return 0u;
}
fn membrane_slot(k: u32, role: u32) -> u32 {
    return 0u;
}
// end assemble
