// Shared structs and helpers, prepended to every stage in kernels/.
// Keep in sync with src/gpu/layout.rs (tests/layout.rs checks sizes and offsets via naga).

const WORKGROUP_SIZE: u32 = 64u;

// Values that stay constant for a whole run.
struct SimParams {
    gravity: vec4<f32>,          // xyz: m/s², w: unused
    num_particles: u32,
    integrator: u32,             // 0 = explicit Euler, 1 = semi-implicit (symplectic) Euler
    dt: f32,                     // s, one substep
    air_damping: f32,            // 1/s, a = -air_damping * v
    air_density: f32,            // kg/m³, wind drag
    drag_coefficient: f32,       // 1, wind drag
    _pad0: u32,
    _pad1: u32,
}

// Values that change per substep. One entry per substep of a frame, at a 256-byte stride,
// selected with a dynamic uniform offset so that a whole frame encodes in one submission.
struct SubstepParams {
    wind: vec4<f32>,             // xyz: wind velocity in m/s at this substep, w: unused
    time: f32,                   // s, simulated time at the start of the substep
    substep: u32,
    _pad0: u32,
    _pad1: u32,
}

// One incident spring seen from a particle (CSR entry): the spring is stored once per end.
struct SpringRef {
    other: u32,
    rest_length: f32,            // m
    stiffness: f32,              // N/m
    damping: f32,                // N·s/m, along the spring
}

// A dihedral hinge: v.x, v.y are the shared edge, v.z and v.w the opposite vertices.
struct Hinge {
    v: vec4<u32>,
    stiffness: f32,              // N·m
    rest_sin_half: f32,          // sin(θ0 / 2)
    _pad0: u32,
    _pad1: u32,
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
