// Shared structs and helpers, prepended to every stage in kernels/.
// Keep in sync with src/model/layout.rs (tests/layout.rs checks sizes and offsets via naga).

const WORKGROUP_SIZE: u32 = 64u;

// Every per-particle and per-element array is written here as a 2D texture, TEXELS_PER_ROW
// texels wide, one 16-byte texel per element (positions, springs, ...) or one 4-byte texel (CSR
// offsets). Reads are textureLoad, writes textureStore: software rasterisers such as llvmpipe
// fetch texels as whole vectors, whereas storage-buffer reads go lane by lane and component by
// component. On GPUs the same arrays are storage buffers: src/gpu/array_layout.rs rewrites the
// declarations and every `textureLoad(a, texel(i), 0)` / `textureStore(a, texel(i), v)` of them
// into indexing before compiling, so accesses must keep exactly that form.
const TEXELS_PER_ROW: u32 = 2048u;

fn texel(i: u32) -> vec2<u32> {
    return vec2<u32>(i % TEXELS_PER_ROW, i / TEXELS_PER_ROW);
}

// Values that stay constant for a whole run.
struct SimParams {
    gravity: vec4<f32>,          // xyz: m/s², w: unused
    num_particles: u32,
    integrator: u32,             // 0 = explicit, 1 = semi-implicit (symplectic), 2 = implicit Euler
    dt: f32,                     // s, one substep
    air_damping: f32,            // 1/s, a = -air_damping * v
    air_density: f32,            // kg/m³, wind drag
    drag_coefficient: f32,       // 1, wind drag
    sewing_rate: f32,            // 1/s, fraction of each seam's open gap closed per second
    iterations: u32,             // Vertex Block Descent sweeps per substep (implicit Euler)
    self_thickness: f32,         // m, particles of the cloth keep this far apart (self-collision)
    hash_cell: f32,              // m, spatial hash cell size (at least self_thickness)
    hash_buckets: u32,           // spatial hash table size
    strain_limit: f32,           // 1, largest edge stretch strain_limit lets through (0.1 = 10%)
    strain_iterations: u32,      // Jacobi iterations of strain_limit per substep
    tolerance: f32,              // 1, implicit Euler stops sweeping once the largest step falls below tolerance × the first (0: never)
    num_bodies: u32,             // collision bodies in `bodies`
    smoothing: u32,              // implicit Euler with coarse levels: fine sweeps around each coarse correction
    euler_onset: f32,            // m², π²B/Y: a spring of rest length L buckles at compression euler_onset / L
    membrane_onset: f32,         // N·m, (√3/4)π²B: a membrane condition of stiffness K buckles at strain membrane_onset / K
    buckled_fraction: f32,       // 1, stiffness a buckled element keeps beyond (0: linear in compression)
    _pad0: u32,
    stiffening: vec4<f32>,       // membrane in tension: x, y the warp's and weft's tangent growth per unit strain, z the strain where it stops growing (0: linear)
    bodies: array<BodyParams, MAX_BODIES>,
}

// Most collision bodies a scene may have: every substep's uniform carries each one's pose.
const MAX_BODIES: u32 = 4u;

// One collision body's SDF and contact response.
struct BodyParams {
    sdf_origin: vec4<f32>,       // xyz: body-frame position of SDF node (0,0,0) in m, w: node spacing in m
    sdf_dims: vec4<u32>,         // xyz: SDF nodes along x, y, z; w: the body's first node in the SDF texture
    thickness: f32,              // m, collision thickness around the body
    friction: f32,               // 1, Coulomb coefficient against the body
    normal_loss: f32,            // 1, fraction of outward normal relative speed lost in contact
    tangential_loss: f32,        // 1, fraction of tangential relative speed lost in contact
    friction_slip_speed: f32,    // m/s, implicit Euler's friction is static (smoothed) below this slip speed
    parts: u32,                  // a deforming body's collision parts (0: rigid), see deformed_body.wgsl
    first_part: u32,             // its first part in SubstepParams.parts
    _pad2: u32,
}

// One collision body's pose and velocity at the end of a substep, where collision is resolved.
struct BodyPose {
    x: vec4<f32>,                // rotation, columns (body to world); w: unused
    y: vec4<f32>,
    z: vec4<f32>,
    translation: vec4<f32>,      // m
    velocity: vec4<f32>,         // m/s of the body frame's origin
    angular_velocity: vec4<f32>, // rad/s, world frame
}

// Values that change per substep. One entry per substep of a frame, at a stride of the adapter's uniform offset alignment,
// selected with a dynamic uniform offset so that a whole frame encodes in one submission.
struct SubstepParams {
    wind: vec4<f32>,             // xyz: wind velocity in m/s at this substep, w: unused
    time: f32,                   // s, simulated time at the start of the substep
    substep: u32,
    _pad0: u32,
    _pad1: u32,
    bodies: array<BodyPose, MAX_BODIES>,
    parts: array<BodyPose, MAX_PARTS>, // deforming bodies' collision parts, rest pose to world
}

// Most collision parts of all deforming bodies together: every substep's uniform carries each
// one's pose.
const MAX_PARTS: u32 = 24u;

// One incident spring seen from a particle (CSR entry): the spring is stored once per end.
// Uploaded as one rgba32uint texel, floats as their bits.
struct SpringRef {
    other: u32,
    rest_length: f32,            // m
    stiffness: f32,              // N/m
    damping: f32,                // N·s/m, along the spring
}

// A dihedral hinge: v.x, v.y are the shared edge, v.z and v.w the opposite vertices.
// Uploaded as two rgba32uint texels, floats as their bits.
struct Hinge {
    v: vec4<u32>,
    stiffness: f32,              // N·m
    rest_sin_half: f32,          // sin(θ0 / 2)
    rest_weight: f32,            // N·m, k·|E|²/(|N1| + |N2|) of the rest shape (implicit Euler's bending energy)
    _pad1: u32,
}

// A membrane triangle (mirrors layout::Membrane): particles v.xyz; shape = (α1, α2, β1, β2) in
// 1/m, the warp and weft images w_u = Σ αj·xj, w_v = Σ βj·xj with α0 = −α1 − α2,
// β0 = −β1 − β2; stiffness = (warp·A, weft·A, shear·A in N·m, damping time constant τ in s).
struct Membrane {
    v: vec4<u32>,
    shape: vec4<f32>,
    stiffness: vec4<f32>,
}

// A seam pair: vertex v.x is pulled towards the partner point (1 − weight)·x[v.y] + weight·x[v.z]
// on the other edge by a spring whose rest gap shrinks from open_gap to 0 at
// SimParams.sewing_rate (0 from the start when open_gap is 0); the partner's ends take the
// reaction. Uploaded as two rgba32uint texels, floats as their bits.
struct Seam {
    v: vec4<u32>,                // x: seam vertex, y, z: partner segment, w: unused
    weight: f32,                 // of v.z
    stiffness: f32,              // N/m
    damping: f32,                // N·s/m, on the relative velocity
    open_gap: f32,               // m, rest gap at time 0
}

// One Vertex Block Descent sweep of one colour (implicit Euler), at a stride of the adapter's uniform offset alignment, selected
// with a dynamic uniform offset: the vertices order[first .. first + count].
struct Sweep {
    first: u32,
    count: u32,
    iteration: u32,              // 0-based: where the sweep records its largest Newton step
    _pad0: u32,
}

// Newton steps shorter than this (m) count as converged; as VBD_STEP_FLOOR in layout.rs.
const VBD_STEP_FLOOR: f32 = 1e-6;

fn unpack_spring(t: vec4<u32>) -> SpringRef {
    return SpringRef(t.x, bitcast<f32>(t.y), bitcast<f32>(t.z), bitcast<f32>(t.w));
}

// How cloth's tension follows its stretch: linearly, buckling in compression, stiffening in
// tension (cpu: src/cpu/stretch_law.rs, which says why), for a spring's stretch |d| − L (onset
// params.euler_onset / L, no stiffening: StretchLaw(params.euler_onset / L,
// params.buckled_fraction, 0.0, 0.0)) and a membrane condition's strain |w| − 1 (onset
// params.membrane_onset / K, stiffening params.stiffening[0 warp, 1 weft] up to
// params.stiffening.z) alike.
struct StretchLaw {
    onset: f32,                  // the compression at which the element buckles
    fraction: f32,               // the share of its stiffness it keeps beyond (0: linear)
    growth: f32,                 // g, the tangent's relative growth per unit stretch in tension (0: linear)
    end: f32,                    // e, the stretch beyond which the tangent stays k·(1 + g·e)
}

fn law_buckled(law: StretchLaw, s: f32) -> bool {
    return law.fraction > 0.0 && s < -law.onset;
}

fn law_stiffening(law: StretchLaw, s: f32) -> bool {
    return law.growth != 0.0 && s > 0.0;
}

// The element's tension at stretch s for stiffness k (positive pulls).
fn law_tension(law: StretchLaw, k: f32, s: f32) -> f32 {
    if (law_buckled(law, s)) {
        return -k * law.onset + law.fraction * k * (s + law.onset);
    }
    if (law_stiffening(law, s)) {
        let t = min(s, law.end);
        return k * (s + law.growth * t * (s - 0.5 * t));
    }
    return k * s;
}

// The tension over its linear value k·s (1 when linear): the transverse Hessian's scale.
fn law_secant_ratio(law: StretchLaw, s: f32) -> f32 {
    if (law_stiffening(law, s)) {
        return law_tension(law, 1.0, s) / s;
    }
    return 1.0;
}

// The axial stiffness the solves take at stretch s: k, buckled the secant tension/s (cpu:
// StretchLaw::axial says why), stiffening the tangent.
fn law_axial(law: StretchLaw, k: f32, s: f32) -> f32 {
    if (law_buckled(law, s)) {
        return law_tension(law, k, s) / s;
    }
    if (law_stiffening(law, s)) {
        return k * (1.0 + law.growth * min(s, law.end));
    }
    return k;
}

// The stiffening's share of the energy per unit stiffness at stretch s (0 in compression).
fn law_stiffening_energy(law: StretchLaw, s: f32) -> f32 {
    if (!law_stiffening(law, s)) {
        return 0.0;
    }
    let t = min(s, law.end);
    return law.growth * t * (0.5 * s * s - 0.5 * t * s + t * t / 6.0);
}

// Its change from s1 to s2 = s1 + ds (sum = s1 + s2): a product with ds within one piece.
fn law_stiffening_change(law: StretchLaw, s1: f32, s2: f32, sum: f32, ds: f32) -> f32 {
    let g = law.growth;
    let e = law.end;
    if (s1 > 0.0 && s1 <= e && s2 > 0.0 && s2 <= e) {
        return g * ds * (s1 * s1 + s1 * s2 + s2 * s2) / 6.0;
    }
    if (s1 > e && s2 > e) {
        return 0.5 * g * e * ds * (sum - e);
    }
    return law_stiffening_energy(law, s2) - law_stiffening_energy(law, s1);
}

// The energy at stretch s.
fn law_energy(law: StretchLaw, k: f32, s: f32) -> f32 {
    if (law_buckled(law, s)) {
        let o = law.onset;
        let u = s + o;
        return 0.5 * k * o * o - k * o * u + 0.5 * law.fraction * k * u * u;
    }
    return 0.5 * k * s * s + k * law_stiffening_energy(law, s);
}

// The change of the energy from stretch s1 to s2 = s1 + ds, sum = s1 + s2 as the caller
// computes it without cancellation: a product with ds where both are on one branch.
fn law_energy_change(law: StretchLaw, k: f32, s1: f32, s2: f32, sum: f32, ds: f32) -> f32 {
    let b1 = law_buckled(law, s1);
    let b2 = law_buckled(law, s2);
    if (!b1 && !b2) {
        if (law.growth != 0.0) {
            return 0.5 * k * ds * sum + k * law_stiffening_change(law, s1, s2, sum, ds);
        }
        return 0.5 * k * ds * sum;
    }
    if (b1 && b2) {
        return k * ds * (0.5 * law.fraction * (sum + 2.0 * law.onset) - law.onset);
    }
    return law_energy(law, k, s2) - law_energy(law, k, s1);
}

fn unpack_hinge(a: vec4<u32>, b: vec4<u32>) -> Hinge {
    return Hinge(a, bitcast<f32>(b.x), bitcast<f32>(b.y), bitcast<f32>(b.z), b.w);
}

// The per-vertex coefficients (−c1 − c2, c1, c2) of a membrane image from its shape pair (cpu:
// Membrane::coefficients).
fn membrane_coefficients(c1: f32, c2: f32) -> vec3<f32> {
    return vec3<f32>(-c1 - c2, c1, c2);
}

fn unpack_membrane(a: vec4<u32>, b: vec4<u32>, c: vec4<u32>) -> Membrane {
    return Membrane(a, bitcast<vec4<f32>>(b), bitcast<vec4<f32>>(c));
}

fn unpack_seam(a: vec4<u32>, b: vec4<u32>) -> Seam {
    return Seam(a, bitcast<f32>(b.x), bitcast<f32>(b.y), bitcast<f32>(b.z), bitcast<f32>(b.w));
}

// The spatial hash bucket of the cell containing x (Teschner et al. 2003 primes).
fn hash_cell_of(x: vec3<f32>, cell: f32) -> vec3<i32> {
    return vec3<i32>(floor(x / cell));
}

fn hash_bucket(c: vec3<i32>, buckets: u32) -> u32 {
    let u = bitcast<vec3<u32>>(c);
    return ((u.x * 73856093u) ^ (u.y * 19349663u) ^ (u.z * 83492791u)) % buckets;
}

// Flattened particle index for a 2D dispatch (x up to 65535 workgroups).
fn particle_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * WORKGROUP_SIZE;
}

fn safe_normalize(v: vec3<f32>) -> vec3<f32> {
    let len = length(v);
    if (len > 1e-12) {
        return v / len;
    }
    return vec3<f32>(0.0);
}

// A dihedral hinge's shared terms (Bridson, Marino & Fedkiw 2003): its force on vertex `role` is
// weight·(sin(θ/2) − sin(θ0/2))·u_role, u from hinge_direction. Roles 0, 1: the shared edge x3,
// x4; roles 2, 3: the opposite vertices x1, x2. A degenerate hinge (no defined angle) is not
// valid. CPU twin: cpu::hinge_forces::hinge_frame.
struct HingeFrame {
    x1: vec3<f32>,
    x2: vec3<f32>,
    x3: vec3<f32>,
    x4: vec3<f32>,
    e_hat: vec3<f32>,
    e_len: f32,
    a: vec3<f32>,                // n1 / |n1|²
    b: vec3<f32>,                // n2 / |n2|²
    weight: f32,                 // stiffness·|e|²/(|n1| + |n2|)
    sin_half: f32,               // sin(θ/2) of the signed dihedral angle
    valid: bool,
}

fn hinge_frame(stiffness: f32, x3: vec3<f32>, x4: vec3<f32>, x1: vec3<f32>, x2: vec3<f32>) -> HingeFrame {
    var t = HingeFrame(x1, x2, x3, x4, vec3<f32>(0.0), 0.0, vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0, false);
    let e = x4 - x3;
    let n1 = cross(x1 - x3, x1 - x4);
    let n2 = cross(x2 - x4, x2 - x3);
    let e_len = length(e);
    let n1_sq = dot(n1, n1);
    let n2_sq = dot(n2, n2);
    if (e_len < 1e-12 || n1_sq < 1e-24 || n2_sq < 1e-24) {
        return t;
    }
    let n1_len = sqrt(n1_sq);
    let n2_len = sqrt(n2_sq);
    let n1_hat = n1 / n1_len;
    let n2_hat = n2 / n2_len;
    // sin(θ/2) = |n̂1 − n̂2|/2, without the cancellation of √(½(1 − cos θ)) at small θ
    // (see cpu/hinge_forces.rs).
    var sin_half = min(0.5 * length(n1_hat - n2_hat), 1.0);
    if (dot(cross(n1_hat, n2_hat), e) < 0.0) {
        sin_half = -sin_half;
    }
    t.weight = stiffness * e_len * e_len / (n1_len + n2_len);
    t.sin_half = sin_half;
    t.e_hat = e / e_len;
    t.e_len = e_len;
    t.a = n1 / n1_sq;
    t.b = n2 / n2_sq;
    t.valid = true;
    return t;
}

// The direction u of vertex `role` (the gradient of θ up to sign).
fn hinge_direction(t: HingeFrame, role: u32) -> vec3<f32> {
    switch role {
        case 0u: { return dot(t.x1 - t.x4, t.e_hat) * t.a + dot(t.x2 - t.x4, t.e_hat) * t.b; }
        case 1u: { return -dot(t.x1 - t.x3, t.e_hat) * t.a - dot(t.x2 - t.x3, t.e_hat) * t.b; }
        case 2u: { return t.e_len * t.a; }
        default: { return t.e_len * t.b; }
    }
}

// One vertex's terms of a hinge, for vbd_solve.
struct HingeTerms {
    u: vec3<f32>,
    weight: f32,
    sin_half: f32,
    valid: bool,
}

fn hinge_terms(stiffness: f32, x3: vec3<f32>, x4: vec3<f32>, x1: vec3<f32>, x2: vec3<f32>, role: u32) -> HingeTerms {
    let f = hinge_frame(stiffness, x3, x4, x1, x2);
    var t = HingeTerms(vec3<f32>(0.0), f.weight, f.sin_half, f.valid);
    if (f.valid) {
        t.u = hinge_direction(f, role);
    }
    return t;
}

// φ outside the grid: no contact.
const SDF_FAR: f32 = 1e30;

fn sdf_node(sdf: texture_2d<f32>, d: vec4<u32>, i: u32, j: u32, k: u32) -> f32 {
    return textureLoad(sdf, texel(d.w + i + d.x * (j + d.y * k)), 0).x;
}

// Trilinear φ (w) and its gradient (xyz) at body-frame point p of a body's SDF (r32float, one
// node per texel, x fastest, every body's nodes one after another) with node (0,0,0) at
// origin.xyz, spacing origin.w, dims.xyz nodes and its first node at dims.w (BodyParams.sdf_origin
// and sdf_dims). CPU twin: body::sdf::sdf_sample on the body's own nodes.
fn sdf_sample(sdf: texture_2d<f32>, origin: vec4<f32>, dims: vec4<u32>, p: vec3<f32>) -> vec4<f32> {
    let g = (p - origin.xyz) / origin.w;
    let last = vec3<f32>(dims.xyz) - vec3<f32>(1.0);
    if (any(g < vec3<f32>(0.0)) || any(g >= last)) {
        return vec4<f32>(0.0, 0.0, 0.0, SDF_FAR);
    }
    let c = vec3<u32>(floor(g));
    let f = g - floor(g);
    let c000 = sdf_node(sdf, dims, c.x, c.y, c.z);
    let c100 = sdf_node(sdf, dims, c.x + 1u, c.y, c.z);
    let c010 = sdf_node(sdf, dims, c.x, c.y + 1u, c.z);
    let c110 = sdf_node(sdf, dims, c.x + 1u, c.y + 1u, c.z);
    let c001 = sdf_node(sdf, dims, c.x, c.y, c.z + 1u);
    let c101 = sdf_node(sdf, dims, c.x + 1u, c.y, c.z + 1u);
    let c011 = sdf_node(sdf, dims, c.x, c.y + 1u, c.z + 1u);
    let c111 = sdf_node(sdf, dims, c.x + 1u, c.y + 1u, c.z + 1u);
    let x00 = c000 + f.x * (c100 - c000);
    let x10 = c010 + f.x * (c110 - c010);
    let x01 = c001 + f.x * (c101 - c001);
    let x11 = c011 + f.x * (c111 - c011);
    let y0 = x00 + f.y * (x10 - x00);
    let y1 = x01 + f.y * (x11 - x01);
    let phi = y0 + f.z * (y1 - y0);
    let d00 = c100 - c000;
    let d10 = c110 - c010;
    let d01 = c101 - c001;
    let d11 = c111 - c011;
    let dy0 = d00 + f.y * (d10 - d00);
    let dy1 = d01 + f.y * (d11 - d01);
    let gx = dy0 + f.z * (dy1 - dy0);
    let gy = (x10 - x00) + f.z * ((x11 - x01) - (x10 - x00));
    let gz = y1 - y0;
    return vec4<f32>(vec3<f32>(gx, gy, gz) / origin.w, phi);
}
