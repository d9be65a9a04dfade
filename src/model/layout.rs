//! `#[repr(C)]` mirrors of the structs in `kernels/common.wgsl`. Keep in sync with that file;
//! `tests/layout.rs` checks every size and field offset against naga's reflection of it.

use bytemuck::{Pod, Zeroable};

/// Run-constant values (WGSL `SimParams`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SimParams {
    /// Gravity in m/s² (xyz); w unused.
    pub gravity: [f32; 4],
    /// Number of particles.
    pub num_particles: u32,
    /// 0 = explicit Euler, 1 = semi-implicit Euler.
    pub integrator: u32,
    /// Substep length in s.
    pub dt: f32,
    /// Air damping rate in 1/s.
    pub air_damping: f32,
    /// Air density in kg/m³ for wind drag.
    pub air_density: f32,
    /// Drag coefficient for wind drag.
    pub drag_coefficient: f32,
    /// Fraction of each seam's open gap closed per second (1 / sewing time), in 1/s.
    pub sewing_rate: f32,
    /// Vertex Block Descent sweeps per substep (implicit Euler; unused otherwise).
    pub iterations: u32,
    /// Self-collision distance in m.
    pub self_thickness: f32,
    /// Spatial hash cell size in m.
    pub hash_cell: f32,
    /// Spatial hash table size.
    pub hash_buckets: u32,
    /// Largest edge stretch that `strain_limit` lets through (0.1 = 10% over rest).
    pub strain_limit: f32,
    /// Jacobi iterations of `strain_limit` per substep (0 when the stage is off).
    pub strain_iterations: u32,
    /// Implicit Euler stops sweeping once an iteration's largest Newton step falls below this
    /// fraction of the first iteration's (or below `VBD_STEP_FLOOR`); 0: always `iterations`.
    pub tolerance: f32,
    /// Bodies in `bodies` (the rest are zero).
    pub num_bodies: u32,
    /// Implicit Euler with coarse levels: fine sweeps before each coarse correction and after
    /// the last one.
    pub smoothing: u32,
    /// Cloth that buckles (`[fabric] compression = "buckling"`, `cpu::stretch_law`):
    /// π²B/Y in m², B the bending rigidity and Y the stretch stiffness; a spring of rest
    /// length L buckles at compression `euler_onset / L`.
    pub euler_onset: f32,
    /// (√3/4)·π²B in N·m: a membrane condition of stiffness K (k·A) buckles at strain
    /// `membrane_onset / K`.
    pub membrane_onset: f32,
    /// The share of its stiffness a buckled element keeps; 0: cloth is linear in compression
    /// (the default).
    pub buckled_fraction: f32,
    /// Padding to 16-byte alignment.
    pub _pad0: u32,
    /// Membrane that stiffens in tension (`[fabric] tension = "stiffening"`,
    /// `cpu::stretch_law`): the warp's and the weft's relative growth of tangent stiffness per
    /// unit strain g, the strain e beyond which it stays k·(1 + g·e), unused; zeros: linear.
    pub stiffening: [f32; 4],
    /// Each collision body's SDF and contact response.
    pub bodies: [BodyParams; MAX_BODIES],
}

/// Most collision bodies a scene may have, as `MAX_BODIES` in common.wgsl.
pub use crate::scene::MAX_BODIES;

/// Most collision parts of all deforming bodies together, as `MAX_PARTS` in common.wgsl.
pub use crate::body::deform::MAX_PARTS;

/// One collision body's SDF and contact response (WGSL `BodyParams`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BodyParams {
    /// Body-frame position of SDF node (0, 0, 0) in m (xyz); w: node spacing in m.
    pub sdf_origin: [f32; 4],
    /// SDF nodes along x, y, z; w: the body's first node in the shared SDF texture.
    pub sdf_dims: [u32; 4],
    /// Collision thickness in m.
    pub thickness: f32,
    /// Coulomb friction coefficient against the body.
    pub friction: f32,
    /// Fraction of outward normal relative speed lost in contact.
    pub normal_loss: f32,
    /// Fraction of tangential relative speed lost in contact.
    pub tangential_loss: f32,
    /// Implicit Euler's friction: slip speed relative to the body below which friction grows in
    /// proportion to the slip (static friction, smoothed), in m/s.
    pub friction_slip_speed: f32,
    /// A deforming body's collision parts (0 for a rigid body): their poses are
    /// `SubstepParams::parts[first_part..first_part + parts]`, and its words after the SDF
    /// nodes are described in `body::deformed_sdf`.
    pub parts: u32,
    /// A deforming body's first part in `SubstepParams::parts`.
    pub first_part: u32,
    /// Padding.
    pub _pad2: u32,
}

/// One collision body's pose and velocity at the end of a substep (WGSL `BodyPose`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BodyPose {
    /// Body rotation (body to world), first column; w unused.
    pub x: [f32; 4],
    /// Second column.
    pub y: [f32; 4],
    /// Third column.
    pub z: [f32; 4],
    /// Body translation in m.
    pub translation: [f32; 4],
    /// Velocity of the body frame's origin in m/s.
    pub velocity: [f32; 4],
    /// Body angular velocity in rad/s (world frame).
    pub angular_velocity: [f32; 4],
}

/// Per-substep values (WGSL `SubstepParams`), one per substep at a stride of the adapter's uniform offset alignment.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SubstepParams {
    /// Wind velocity in m/s (xyz); w unused.
    pub wind: [f32; 4],
    /// Simulated time at the start of the substep, in s.
    pub time: f32,
    /// Index of the substep within its frame.
    pub substep: u32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Each body's pose at the end of the substep, where collision is resolved.
    pub bodies: [BodyPose; MAX_BODIES],
    /// The deforming bodies' collision parts' poses (rest pose to world) at the end of the
    /// substep, body after body.
    pub parts: [BodyPose; MAX_PARTS],
}

/// One spring seen from one of its ends (WGSL `SpringRef`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SpringRef {
    /// The particle at the other end.
    pub other: u32,
    /// Rest length in m.
    pub rest_length: f32,
    /// Stiffness in N/m.
    pub stiffness: f32,
    /// Damping along the spring in N·s/m.
    pub damping: f32,
}

/// A dihedral bending hinge (WGSL `Hinge`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Hinge {
    /// Shared edge (x, y) and opposite vertices (z, w).
    pub v: [u32; 4],
    /// Bending stiffness in N·m.
    pub stiffness: f32,
    /// sin(θ0/2) of the rest angle θ0.
    pub rest_sin_half: f32,
    /// k·|E|²/(|N1| + |N2|) of the rest shape, in N·m: implicit Euler's bending energy is
    /// this weight times ψ(θ) = −2·cos(θ/2) − sin(θ0/2)·θ, a potential whose gradient is the
    /// hinge force (`Implicit::hinge_energy` in `cpu/implicit_terms/energy_change.rs`).
    pub rest_weight: f32,
    /// Padding.
    pub _pad1: u32,
}

/// A membrane triangle (WGSL `Membrane`): an orthotropic sheet with its own warp, weft and
/// shear stiffness (Baraff and Witkin 1998's stretch and shear conditions on the deformation
/// gradient in the fabric's warp/weft frame; see `cpu::membrane`). The warp and weft
/// directions' images are w_u = Σⱼ αⱼxⱼ and w_v = Σⱼ βⱼxⱼ, with α₀ = −α₁ − α₂ and
/// β₀ = −β₁ − β₂; at rest both are unit and orthogonal.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Membrane {
    /// The triangle's three particles; w unused.
    pub v: [u32; 4],
    /// α₁, α₂, β₁, β₂ in 1/m.
    pub shape: [f32; 4],
    /// Warp, weft and shear stiffness times the rest area (N·m), and the damping time
    /// constant τ in s (damping is τ times the stiffness, along the conditions' gradients).
    pub stiffness: [f32; 4],
}

impl Membrane {
    /// The per-vertex coefficients (α₀, α₁, α₂) of w_u and (β₀, β₁, β₂) of w_v.
    pub fn coefficients(&self) -> ([f32; 3], [f32; 3]) {
        let [a1, a2, b1, b2] = self.shape;
        ([-a1 - a2, a1, a2], [-b1 - b2, b1, b2])
    }
}

/// A seam pair (WGSL `Seam`): vertex `v[0]` is pulled towards
/// `(1 − weight)·x[v[1]] + weight·x[v[2]]`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Seam {
    /// Seam vertex, partner segment ends, unused.
    pub v: [u32; 4],
    /// Weight of `v[2]` in the partner point.
    pub weight: f32,
    /// Stiffness in N/m.
    pub stiffness: f32,
    /// Damping on the relative velocity in N·s/m.
    pub damping: f32,
    /// Rest gap at time 0 in m; it shrinks to 0 at `SimParams::sewing_rate`.
    pub open_gap: f32,
}

/// One Vertex Block Descent sweep of one colour: the `count` vertices at `first` in the colour
/// order. One entry per (iteration, colour), selected by a dynamic uniform offset.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Sweep {
    /// First entry of the colour in the colour order.
    pub first: u32,
    /// Vertices of the colour.
    pub count: u32,
    /// The iteration the sweep belongs to (0-based): where it records its largest step.
    pub iteration: u32,
    /// Padding to 16 bytes.
    pub _pad0: u32,
}

/// Newton steps shorter than this, in m, count as converged: a 2 m coordinate's f32 rounding
/// is 1.2e-7 m, so an iterate cannot settle much closer than that.
pub const VBD_STEP_FLOOR: f32 = 1e-6;

/// Integrator codes shared with `integrate.wgsl`.
pub use crate::scene::{INTEGRATOR_EXPLICIT, INTEGRATOR_IMPLICIT, INTEGRATOR_SYMPLECTIC};
/// Width in texels of every data texture, as `TEXELS_PER_ROW` in common.wgsl.
pub const TEXELS_PER_ROW: u32 = 2048;
/// Threads per workgroup, as `WORKGROUP_SIZE` in common.wgsl.
pub const WORKGROUP_SIZE: u32 = 64;
