//! The kernels of implicit Euler's solve: their WGSL files, the shared files composed into
//! them, and the resources each binds. Every solve kernel numbers a resource the same way (its
//! `Res` discriminant), so that a kernel file, the files composed into it and this list agree
//! by name and number; `tests/implicit_gpu.rs` checks each list against naga's reflection of
//! the composed kernel.

use crate::gpu::kernels::{keep_sections, Composed, VbdEnergies, COMMON_WGSL};

/// A WGSL file composed into solve kernels before the kernel's own.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Include {
    /// `kernels/hierarchy.wgsl`: the multigrid hierarchy's words and their accessors.
    Hierarchy,
    /// `kernels/implicit_terms.wgsl`: the incremental potential at one vertex.
    Terms,
    /// `kernels/block_texels.wgsl`: every level's matrix blocks, read as texels.
    BlockTexels,
    /// `kernels/multigrid.wgsl`: one row of each operation on a level's system.
    Multigrid,
    /// `kernels/deformed_body.wgsl`: a deforming body's contact (binds nothing of its own).
    DeformedBody,
}

impl Include {
    /// Every include.
    pub const ALL: [Include; 5] = [
        Include::Hierarchy,
        Include::Terms,
        Include::BlockTexels,
        Include::Multigrid,
        Include::DeformedBody,
    ];

    /// Its file in `kernels/`, without `.wgsl`.
    pub fn file(self) -> &'static str {
        match self {
            Include::Hierarchy => "hierarchy",
            Include::Terms => "implicit_terms",
            Include::BlockTexels => "block_texels",
            Include::Multigrid => "multigrid",
            Include::DeformedBody => "deformed_body",
        }
    }

    fn source(self) -> &'static str {
        match self {
            Include::Hierarchy => include_str!("../../../kernels/hierarchy.wgsl"),
            Include::Terms => include_str!("../../../kernels/implicit_terms.wgsl"),
            Include::BlockTexels => include_str!("../../../kernels/block_texels.wgsl"),
            Include::Multigrid => include_str!("../../../kernels/multigrid.wgsl"),
            Include::DeformedBody => include_str!("../../../kernels/deformed_body.wgsl"),
        }
    }
}

/// Every file composed into solve kernels (`solve.wgsl` first in all of them).
pub const SOLVE_WGSL: &str = include_str!("../../../kernels/solve.wgsl");

/// A resource a solve kernel binds; its discriminant is its binding number in every solve
/// kernel (group 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Res {
    /// `SimParams` (uniform).
    Params = 0,
    /// This substep's `SubstepParams` (uniform, dynamic offset).
    Step = 1,
    /// This dispatch's `OpParams` (uniform, dynamic offset).
    Op = 2,
    /// `SolveControl`.
    Control = 3,
    /// xₙ (texture).
    Pos = 4,
    /// The iterate D.
    Disp = 5,
    /// The inertial target Y.
    Target = 6,
    /// Each body's contact plane per vertex.
    Planes = 7,
    /// Each vertex's normal force per body.
    Lambdas = 8,
    /// Spring CSR offsets (texture).
    SpringOffsets = 9,
    /// Spring refs (texture).
    Springs = 10,
    /// Hinge CSR offsets (texture).
    HingeOffsets = 11,
    /// Hinge refs (texture).
    HingeRefs = 12,
    /// Hinges (texture).
    Hinges = 13,
    /// Seam CSR offsets (texture).
    SeamOffsets = 14,
    /// Seam refs (texture).
    SeamRefs = 15,
    /// Seam pairs (texture).
    Seams = 16,
    /// Every body's SDF nodes (texture).
    Sdf = 17,
    /// The packed multigrid hierarchy.
    Hier = 18,
    /// Every level's matrix blocks.
    Blocks = 19,
    /// The fine force at the last assembly.
    Force = 20,
    /// The Newton correction c.
    Correction = 21,
    /// Conjugate gradients' direction p.
    P = 22,
    /// H·p.
    Ap = 23,
    /// Every level's right-hand side (level 0: r).
    Rhs = 24,
    /// Every level's correction (level 0: z).
    E = 25,
    /// Every level's residual.
    Residual = 26,
    /// Per-workgroup partial sums of the reductions.
    Partials = 27,
    /// `SolveScalars`.
    Scalars = 28,
    /// The largest step of each sweep, then the sweeps run.
    Steps = 29,
    /// The op lists of `coarse_cycle`.
    OpList = 30,
    /// Every level's blocks as texels (a texture; written by `publish_blocks`).
    BlockTexels = 31,
    /// Every level's block columns (a texture).
    BlockColumns = 32,
    /// Membrane CSR offsets (texture).
    MembraneOffsets = 33,
    /// Membrane refs (texture).
    MembraneRefs = 34,
    /// Membrane triangles (texture).
    Membranes = 35,
}

impl Res {
    /// Its binding number.
    pub fn binding(self) -> u32 {
        self as u32
    }

    /// Whether it is a storage buffer (the rest are uniforms and textures).
    pub fn is_storage(self) -> bool {
        !matches!(
            self,
            Res::Params
                | Res::Step
                | Res::Op
                | Res::Pos
                | Res::SpringOffsets
                | Res::Springs
                | Res::HingeOffsets
                | Res::HingeRefs
                | Res::Hinges
                | Res::SeamOffsets
                | Res::SeamRefs
                | Res::Seams
                | Res::Sdf
                | Res::BlockTexels
                | Res::BlockColumns
                | Res::MembraneOffsets
                | Res::MembraneRefs
                | Res::Membranes
        )
    }
}

/// How a kernel binds a resource: read-only or writable (storage buffers only; uniforms and
/// textures are read).
pub type Binds = Vec<(Res, bool)>;

/// A kernel of the solve: one WGSL file and entry point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SolveKernel {
    /// `contact_planes`.
    ContactPlanes,
    /// `vbd_solve`: one colour of a Vertex Block Descent sweep.
    Sweep,
    /// `assemble`.
    Assemble,
    /// `coarse_operator`.
    CoarseOperator,
    /// `pcg_start`.
    PcgStart,
    /// `pcg_direction`'s per-workgroup r·z.
    PcgDot,
    /// `pcg_direction`.
    PcgDirection,
    /// `pcg_matvec`.
    PcgMatVec,
    /// `pcg_step`.
    PcgStep,
    /// `smooth`: one colour of a level.
    Smooth,
    /// `level_residual`.
    LevelResidual,
    /// `restrict`.
    Restrict,
    /// `prolong`.
    Prolong,
    /// `coarse_cycle`: a list of level operations in one workgroup.
    CoarseCycle,
    /// `correction_filter`.
    CorrectionFilter,
    /// `line_energy`.
    LineEnergy,
    /// `line_slopes`.
    LineSlopes,
    /// `line_search`.
    LineSearch,
    /// `apply_correction`.
    ApplyCorrection,
    /// `force_residual`'s per-workgroup partials.
    ForceResidual,
    /// `reduce_residual`.
    ReduceResidual,
    /// `publish_blocks`: one level's blocks copied to their texels.
    PublishBlocks,
}

impl SolveKernel {
    /// Every solve kernel.
    pub const ALL: [SolveKernel; 22] = [
        SolveKernel::ContactPlanes,
        SolveKernel::Sweep,
        SolveKernel::Assemble,
        SolveKernel::CoarseOperator,
        SolveKernel::PcgStart,
        SolveKernel::PcgDot,
        SolveKernel::PcgDirection,
        SolveKernel::PcgMatVec,
        SolveKernel::PcgStep,
        SolveKernel::Smooth,
        SolveKernel::LevelResidual,
        SolveKernel::Restrict,
        SolveKernel::Prolong,
        SolveKernel::CoarseCycle,
        SolveKernel::CorrectionFilter,
        SolveKernel::LineEnergy,
        SolveKernel::LineSlopes,
        SolveKernel::LineSearch,
        SolveKernel::ApplyCorrection,
        SolveKernel::ForceResidual,
        SolveKernel::ReduceResidual,
        SolveKernel::PublishBlocks,
    ];

    /// Its file in `kernels/`, without `.wgsl`.
    pub fn file(self) -> &'static str {
        match self {
            SolveKernel::ContactPlanes => "contact_planes",
            SolveKernel::Sweep => "vbd_solve",
            SolveKernel::Assemble => "assemble",
            SolveKernel::CoarseOperator => "coarse_operator",
            SolveKernel::PcgStart => "pcg_start",
            SolveKernel::PcgDot | SolveKernel::PcgDirection => "pcg_direction",
            SolveKernel::PcgMatVec => "pcg_matvec",
            SolveKernel::PcgStep => "pcg_step",
            SolveKernel::Smooth => "smooth",
            SolveKernel::LevelResidual => "level_residual",
            SolveKernel::Restrict => "restrict",
            SolveKernel::Prolong => "prolong",
            SolveKernel::CoarseCycle => "coarse_cycle",
            SolveKernel::CorrectionFilter => "correction_filter",
            SolveKernel::LineEnergy => "line_energy",
            SolveKernel::LineSlopes => "line_slopes",
            SolveKernel::LineSearch => "line_search",
            SolveKernel::ApplyCorrection => "apply_correction",
            SolveKernel::ForceResidual => "force_residual",
            SolveKernel::ReduceResidual => "reduce_residual",
            SolveKernel::PublishBlocks => "publish_blocks",
        }
    }

    /// Its entry point.
    pub fn entry(self) -> &'static str {
        match self {
            SolveKernel::PcgDot => "dot_partials",
            _ => "main",
        }
    }

    fn source(self) -> &'static str {
        match self {
            SolveKernel::ContactPlanes => include_str!("../../../kernels/contact_planes.wgsl"),
            SolveKernel::Sweep => include_str!("../../../kernels/vbd_solve.wgsl"),
            SolveKernel::Assemble => include_str!("../../../kernels/assemble.wgsl"),
            SolveKernel::CoarseOperator => include_str!("../../../kernels/coarse_operator.wgsl"),
            SolveKernel::PcgStart => include_str!("../../../kernels/pcg_start.wgsl"),
            SolveKernel::PcgDot | SolveKernel::PcgDirection => {
                include_str!("../../../kernels/pcg_direction.wgsl")
            }
            SolveKernel::PcgMatVec => include_str!("../../../kernels/pcg_matvec.wgsl"),
            SolveKernel::PcgStep => include_str!("../../../kernels/pcg_step.wgsl"),
            SolveKernel::Smooth => include_str!("../../../kernels/smooth.wgsl"),
            SolveKernel::LevelResidual => include_str!("../../../kernels/level_residual.wgsl"),
            SolveKernel::Restrict => include_str!("../../../kernels/restrict.wgsl"),
            SolveKernel::Prolong => include_str!("../../../kernels/prolong.wgsl"),
            SolveKernel::CoarseCycle => include_str!("../../../kernels/coarse_cycle.wgsl"),
            SolveKernel::CorrectionFilter => {
                include_str!("../../../kernels/correction_filter.wgsl")
            }
            SolveKernel::LineEnergy => include_str!("../../../kernels/line_energy.wgsl"),
            SolveKernel::LineSlopes => include_str!("../../../kernels/line_slopes.wgsl"),
            SolveKernel::LineSearch => include_str!("../../../kernels/line_search.wgsl"),
            SolveKernel::ApplyCorrection => include_str!("../../../kernels/apply_correction.wgsl"),
            SolveKernel::ForceResidual => include_str!("../../../kernels/force_residual.wgsl"),
            SolveKernel::ReduceResidual => include_str!("../../../kernels/reduce_residual.wgsl"),
            SolveKernel::PublishBlocks => include_str!("../../../kernels/publish_blocks.wgsl"),
        }
    }

    /// The files composed before its own, in order (after common.wgsl and solve.wgsl).
    pub fn includes(self) -> &'static [Include] {
        use Include::*;
        match self {
            SolveKernel::ContactPlanes => &[Terms, DeformedBody],
            SolveKernel::CorrectionFilter
            | SolveKernel::LineEnergy
            | SolveKernel::LineSlopes
            | SolveKernel::ForceResidual => &[Terms],
            SolveKernel::Sweep | SolveKernel::Assemble => &[Hierarchy, Terms],
            SolveKernel::CoarseOperator | SolveKernel::PcgMatVec => &[Hierarchy, BlockTexels],
            SolveKernel::PublishBlocks => &[Hierarchy],
            SolveKernel::Smooth
            | SolveKernel::LevelResidual
            | SolveKernel::Restrict
            | SolveKernel::Prolong
            | SolveKernel::CoarseCycle => &[Hierarchy, BlockTexels, Multigrid],
            SolveKernel::PcgStart
            | SolveKernel::PcgDot
            | SolveKernel::PcgDirection
            | SolveKernel::PcgStep
            | SolveKernel::LineSearch
            | SolveKernel::ApplyCorrection
            | SolveKernel::ReduceResidual => &[],
        }
    }

    /// Whether it writes the solve's control words (the others read them).
    pub fn writes_control(self) -> bool {
        self == SolveKernel::ReduceResidual
    }

    /// The complete WGSL module, with the bending, seam and membrane sections of `energies`.
    pub fn compose(self, energies: VbdEnergies) -> Composed {
        let enabled = |name: &str| match name {
            "bending" => energies.bending,
            "seams" => energies.seams,
            "membrane" => energies.membrane,
            "assemble" => self == SolveKernel::Assemble,
            "trial" => self == SolveKernel::LineSlopes,
            "writes_control" => self.writes_control(),
            _ => true,
        };
        let mut composed = Composed::default();
        composed.push("common", COMMON_WGSL.to_string());
        composed.push("solve", keep_sections(SOLVE_WGSL, enabled));
        for include in self.includes() {
            composed.push(include.file(), keep_sections(include.source(), enabled));
        }
        composed.push(self.file(), keep_sections(self.source(), enabled));
        composed
    }

    /// What it binds, in binding order, and which of its storage buffers it writes.
    pub fn binds(self, energies: VbdEnergies) -> Binds {
        use self::Res::*;
        let mut list = vec![
            (Params, false),
            (Step, false),
            (Op, false),
            (Control, self.writes_control()),
        ];
        for include in self.includes() {
            match include {
                Include::Hierarchy => list.push((Hier, false)),
                Include::Terms => {
                    list.extend([
                        (Pos, false),
                        (Disp, true),
                        (Target, false),
                        (Planes, true),
                        (Lambdas, true),
                        (SpringOffsets, false),
                        (Springs, false),
                    ]);
                    if energies.bending {
                        list.extend([(HingeOffsets, false), (HingeRefs, false), (Hinges, false)]);
                    }
                    if energies.seams {
                        list.extend([(SeamOffsets, false), (SeamRefs, false), (Seams, false)]);
                    }
                    if energies.membrane {
                        list.extend([
                            (MembraneOffsets, false),
                            (MembraneRefs, false),
                            (Membranes, false),
                        ]);
                    }
                }
                Include::BlockTexels => list.extend([(BlockTexels, false), (BlockColumns, false)]),
                Include::Multigrid => list.extend([(Rhs, true), (E, true), (Residual, true)]),
                Include::DeformedBody => {}
            }
        }
        list.extend(match self {
            SolveKernel::ContactPlanes => vec![(Sdf, false)],
            SolveKernel::Sweep => vec![(Steps, true)],
            SolveKernel::Assemble => vec![(Blocks, true), (Force, true)],
            SolveKernel::CoarseOperator => vec![(Blocks, true)],
            SolveKernel::PcgStart => {
                vec![(Force, false), (Correction, true), (Rhs, true), (E, true)]
            }
            SolveKernel::PcgDot | SolveKernel::PcgDirection => vec![
                (P, true),
                (Rhs, false),
                (E, false),
                (Partials, true),
                (Scalars, true),
            ],
            SolveKernel::PcgMatVec => {
                vec![(P, false), (Ap, true), (Partials, true)]
            }
            SolveKernel::PcgStep => vec![
                (Correction, true),
                (P, false),
                (Ap, false),
                (Rhs, true),
                (E, true),
                (Partials, false),
                (Scalars, true),
            ],
            SolveKernel::CoarseCycle => vec![(OpList, false)],
            SolveKernel::CorrectionFilter => vec![(Correction, true)],
            SolveKernel::LineEnergy => vec![(Correction, false), (Partials, true)],
            SolveKernel::LineSlopes => {
                vec![(Force, false), (Correction, false), (Partials, true)]
            }
            SolveKernel::LineSearch => vec![(Partials, false), (Scalars, true)],
            SolveKernel::ApplyCorrection => {
                vec![(Disp, true), (Correction, false), (Scalars, false)]
            }
            SolveKernel::ForceResidual => vec![(Partials, true)],
            SolveKernel::ReduceResidual => vec![(Partials, false)],
            SolveKernel::PublishBlocks => vec![(Blocks, false), (BlockTexels, true)],
            SolveKernel::Smooth
            | SolveKernel::LevelResidual
            | SolveKernel::Restrict
            | SolveKernel::Prolong => vec![],
        });
        list.sort_by_key(|(r, _)| r.binding());
        list
    }
}
