//! `#[repr(C)]` mirrors of the structs in `kernels/solve.wgsl`. Keep in sync with that file;
//! `tests/implicit_gpu.rs` checks every size and field offset against naga's reflection of it.

use bytemuck::{Pod, Zeroable};

/// What one dispatch of the solve works on (WGSL `OpParams`), one entry per distinct dispatch
/// at a dynamic uniform offset.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct OpParams {
    /// The multigrid level (0: the fine level).
    pub level: u32,
    /// A colour's first entry in its level's colour order, or an op list's first entry.
    pub first: u32,
    /// The colour's rows, or the op list's entries.
    pub count: u32,
    /// A sweep's slot in `steps`; conjugate gradients' r·z parity.
    pub slot: u32,
    /// `pcg_direction`: the first direction; `reduce_residual`: check the tolerance.
    pub flag: u32,
    /// Padding.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}

/// What the solve decides on the device (WGSL `SolveControl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SolveControl {
    /// 1 once a tolerance check found the substep's solve converged.
    pub done: u32,
    /// Padding.
    pub _pad0: u32,
    /// The last force residual measured: largest |f|/(m·g) of the free vertices.
    pub residual_max: f32,
    /// Its RMS.
    pub residual_rms: f32,
}

/// The scalars of the Newton step's conjugate gradients and line search (WGSL
/// `SolveScalars`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SolveScalars {
    /// r·z of the current direction at the iteration's parity; the other entry: the previous.
    pub rz: [f32; 2],
    /// The last conjugate-gradient step length.
    pub alpha: f32,
    /// The last line search's step length.
    pub line_alpha: f32,
    /// Line searches run, one per Newton step (it wraps at 2³²).
    pub newton_steps: u32,
    /// Padding.
    pub _pad0: u32,
}

/// A 3×3 block as a WGSL `mat3x3<f32>` in a storage buffer: three columns, each padded to 16
/// bytes.
pub type GpuMat3 = [[f32; 4]; 3];

/// `m` as the kernels store it.
pub fn to_gpu(m: glam::Mat3) -> GpuMat3 {
    [
        m.x_axis.extend(0.0).to_array(),
        m.y_axis.extend(0.0).to_array(),
        m.z_axis.extend(0.0).to_array(),
    ]
}

/// A stored block back as a `Mat3`.
pub fn from_gpu(m: &GpuMat3) -> glam::Mat3 {
    let col = |c: &[f32; 4]| glam::Vec3::new(c[0], c[1], c[2]);
    glam::Mat3::from_cols(col(&m[0]), col(&m[1]), col(&m[2]))
}
