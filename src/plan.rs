//! The pass plan: the ordered stages a scene needs. A stage the scene does not use is absent,
//! and both backends build pipelines, buffers and CPU data only for the stages in the plan.

use crate::model::ClothModel;
pub use crate::scene::Effects;
use serde::Serialize;

/// One simulation stage: one kernel in `kernels/`, one CPU twin in `src/cpu/`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Pass {
    /// Dihedral bending, each hinge evaluated once: its forces on its four vertices, which
    /// `integrate` gathers per particle.
    HingeForces,
    /// Stretch springs on mesh edges.
    SpringForces,
    /// The orthotropic membrane (warp, weft and shear per triangle), in place of the springs.
    MembraneForces,
    /// Dihedral bending, each hinge evaluated from each of its four vertices (the other way to
    /// evaluate hinges; see `HingeEvaluation`).
    BendingForces,
    /// Per-triangle wind drag.
    WindForces,
    /// Seam penalty springs between sewn edges.
    SeamForces,
    /// Implicit Euler 1/3: the inertial target y = x + h·v + h²·(g + f_wind/m), and the
    /// starting guess x = y.
    VbdInit,
    /// Implicit Euler 2/3: Vertex Block Descent, one dispatch per colour per iteration.
    VbdSolve,
    /// Implicit Euler 3/3: v = (x − xₙ)/h, the next state.
    VbdFinish,
    /// Euler integration; after every force stage. Gathers the bending forces `hinge_forces`
    /// wrote.
    Integrate,
    /// Jacobi projection of over-stretched edges back to the strain limit (positions, and
    /// velocities by the same displacement over the step); after the step, before collisions.
    StrainLimit,
    /// Self-collision 1/5: zero the spatial hash counts.
    HashClear,
    /// Self-collision 2/5: count particles per hash bucket.
    HashCount,
    /// Self-collision 3/5: prefix-sum the counts into bucket starts.
    HashScan,
    /// Self-collision 4/5: sort particle indices into their buckets.
    HashFill,
    /// Self-collision 5/5: particle-particle repulsion.
    SelfCollide,
    /// Particle-versus-body collision through the body's SDF; last, so the body wins.
    CollideBody,
    /// Frame health (kinetic energy, speed, strain, finiteness), reduced per workgroup. Runs
    /// once per output frame on every backend, never per substep: it is not in `PassPlan`.
    Monitor,
}

impl Pass {
    /// Every stage, in execution order.
    pub const ALL: [Pass; 18] = [
        Pass::HingeForces,
        Pass::SpringForces,
        Pass::MembraneForces,
        Pass::BendingForces,
        Pass::WindForces,
        Pass::SeamForces,
        Pass::VbdInit,
        Pass::VbdSolve,
        Pass::VbdFinish,
        Pass::Integrate,
        Pass::StrainLimit,
        Pass::HashClear,
        Pass::HashCount,
        Pass::HashScan,
        Pass::HashFill,
        Pass::SelfCollide,
        Pass::CollideBody,
        Pass::Monitor,
    ];

    /// The stage name shared by the kernel file, the CPU twin, tests and bench ids.
    pub fn name(self) -> &'static str {
        match self {
            Pass::HingeForces => "hinge_forces",
            Pass::SpringForces => "spring_forces",
            Pass::MembraneForces => "membrane_forces",
            Pass::BendingForces => "bending_forces",
            Pass::WindForces => "wind_forces",
            Pass::SeamForces => "seam_forces",
            Pass::VbdInit => "vbd_init",
            Pass::VbdSolve => "vbd_solve",
            Pass::VbdFinish => "vbd_finish",
            Pass::Integrate => "integrate",
            Pass::StrainLimit => "strain_limit",
            Pass::HashClear => "hash_clear",
            Pass::HashCount => "hash_count",
            Pass::HashScan => "hash_scan",
            Pass::HashFill => "hash_fill",
            Pass::SelfCollide => "self_collide",
            Pass::CollideBody => "collide_body",
            Pass::Monitor => "monitor",
        }
    }

    /// Whether the stage reads the forces the force stages summed (`previous_force`).
    pub fn reads_forces(self) -> bool {
        self.is_force() || self == Pass::VbdInit
    }

    /// Whether the stage adds forces.
    pub fn is_force(self) -> bool {
        matches!(
            self,
            Pass::SpringForces
                | Pass::MembraneForces
                | Pass::BendingForces
                | Pass::WindForces
                | Pass::SeamForces
        )
    }

    /// Whether the stage writes positions and velocities (the next state).
    pub fn writes_state(self) -> bool {
        matches!(
            self,
            Pass::Integrate
                | Pass::VbdFinish
                | Pass::StrainLimit
                | Pass::SelfCollide
                | Pass::CollideBody
        )
    }

    /// The stage's WGSL source, without `common.wgsl`.
    pub fn kernel_source(self) -> &'static str {
        match self {
            Pass::HingeForces => include_str!("../kernels/hinge_forces.wgsl"),
            Pass::SpringForces => include_str!("../kernels/spring_forces.wgsl"),
            Pass::MembraneForces => include_str!("../kernels/membrane_forces.wgsl"),
            Pass::BendingForces => include_str!("../kernels/bending_forces.wgsl"),
            Pass::WindForces => include_str!("../kernels/wind_forces.wgsl"),
            Pass::SeamForces => include_str!("../kernels/seam_forces.wgsl"),
            Pass::VbdInit => include_str!("../kernels/vbd_init.wgsl"),
            Pass::VbdSolve => include_str!("../kernels/vbd_solve.wgsl"),
            Pass::VbdFinish => include_str!("../kernels/vbd_finish.wgsl"),
            Pass::Integrate => include_str!("../kernels/integrate.wgsl"),
            Pass::StrainLimit => include_str!("../kernels/strain_limit.wgsl"),
            Pass::HashClear => include_str!("../kernels/hash_clear.wgsl"),
            Pass::HashCount => include_str!("../kernels/hash_count.wgsl"),
            Pass::HashScan => include_str!("../kernels/hash_scan.wgsl"),
            Pass::HashFill => include_str!("../kernels/hash_fill.wgsl"),
            Pass::SelfCollide => include_str!("../kernels/self_collide.wgsl"),
            Pass::CollideBody => include_str!("../kernels/collide_body.wgsl"),
            Pass::Monitor => include_str!("../kernels/monitor.wgsl"),
        }
    }
}

/// How the plan evaluates dihedral hinges. Both ways exist on both backends (a kernel and its
/// CPU twin each, with parity tests); each backend takes the one measured faster on it (docs/src/benchmarks/throughput.md,
/// "Benchmarks"), and the results agree to rounding (bit for bit on the CPU when bending is the
/// only force after the springs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HingeEvaluation {
    /// `bending_forces`: each particle evaluates every hinge it belongs to and keeps its own
    /// share, four evaluations per hinge. Faster on lavapipe.
    PerVertex,
    /// `hinge_forces` evaluates each hinge once into four forces, and `integrate` gathers each
    /// particle's share. Faster on the CPU.
    Once,
}

/// The ordered passes of one substep.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassPlan {
    /// Stages in execution order.
    pub passes: Vec<Pass>,
    /// How hinges are evaluated when the plan bends; `None`: as the backend prefers.
    pub hinges: Option<HingeEvaluation>,
}

impl PassPlan {
    /// The plan for a model and the effects its scene asks for. Bending is listed as
    /// `bending_forces`; each backend may evaluate it its own way (`for_backend`).
    pub fn new(model: &ClothModel, effects: Effects) -> Self {
        let wanted = |pass: &Pass| match pass {
            // Implicit Euler evaluates springs, membranes, hinges and seams inside its solve;
            // a membrane's springs carry no force.
            Pass::SpringForces => {
                !effects.implicit && !model.springs.is_empty() && model.membranes.is_empty()
            }
            Pass::MembraneForces => !effects.implicit && !model.membranes.is_empty(),
            Pass::BendingForces => !effects.implicit && effects.bending && !model.hinges.is_empty(),
            Pass::HingeForces => false,
            Pass::WindForces => effects.wind && !model.triangles.is_empty(),
            Pass::SeamForces => !effects.implicit && !model.seams.is_empty(),
            Pass::VbdInit | Pass::VbdSolve | Pass::VbdFinish => effects.implicit,
            Pass::Integrate => !effects.implicit,
            Pass::StrainLimit => effects.strain_limit && !model.springs.is_empty(),
            Pass::HashClear
            | Pass::HashCount
            | Pass::HashScan
            | Pass::HashFill
            | Pass::SelfCollide => effects.self_collision,
            Pass::CollideBody => effects.body && !model.colliders.is_empty(),
            Pass::Monitor => false,
        };
        PassPlan {
            passes: Pass::ALL.into_iter().filter(wanted).collect(),
            hinges: None,
        }
    }

    /// The plan with hinges evaluated `how` (the stages in their canonical order).
    pub fn with_hinges(&self, how: HingeEvaluation) -> Self {
        let bends = self.contains(Pass::BendingForces) || self.contains(Pass::HingeForces);
        let want = |p: Pass| match p {
            Pass::BendingForces => bends && how == HingeEvaluation::PerVertex,
            Pass::HingeForces => bends && how == HingeEvaluation::Once,
            _ => self.contains(p),
        };
        PassPlan {
            passes: Pass::ALL.into_iter().filter(|&p| want(p)).collect(),
            hinges: Some(how),
        }
    }

    /// The plan a backend runs: hinges as the plan says, or as the backend `prefers` if the
    /// plan leaves it open.
    pub fn for_backend(&self, prefers: HingeEvaluation) -> Self {
        self.with_hinges(self.hinges.unwrap_or(prefers))
    }

    /// Whether the plan runs `pass`.
    pub fn contains(&self, pass: Pass) -> bool {
        self.passes.contains(&pass)
    }

    /// Stage names in order.
    pub fn names(&self) -> Vec<&'static str> {
        self.passes.iter().map(|p| p.name()).collect()
    }
}

/// One operation of implicit Euler's solve within a substep. `implicit_schedule` lists them in
/// the order both backends run them. Levels are numbered from the fine level, 0; the linear
/// system of a Newton step lives on every level (level 0: the assembled fine Hessian).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SolveOp {
    /// Linearise each body's contact for the step (`contact_planes`).
    ContactPlanes,
    /// One Vertex Block Descent sweep over every colour of the fine level (`vbd_solve`).
    Sweep {
        /// Its index in the substep, where it records its largest Newton step.
        iteration: u32,
    },
    /// The fine level's force f and Hessian H at the iterate (`assemble`).
    Assemble,
    /// A coarse level's matrix PᵀAP from the level below (`coarse_operator`).
    CoarseOperator {
        /// The coarse level (1 or more).
        level: u32,
    },
    /// Conjugate gradients on H·c = f start: c = 0, r = f (`pcg_start`).
    PcgStart,
    /// One block Gauss–Seidel sweep over every colour of a level (`smooth`).
    Smooth {
        /// The level.
        level: u32,
        /// Colours in reverse order (after the coarser correction: the V-cycle stays
        /// symmetric, as conjugate gradients need of a preconditioner).
        backward: bool,
    },
    /// A level's residual r − A·e (`level_residual`).
    Residual {
        /// The level.
        level: u32,
    },
    /// The next coarser level's right-hand side Pᵀ(r − A·e), its correction zeroed
    /// (`restrict`).
    Restrict {
        /// The coarser level it writes.
        to: u32,
    },
    /// A coarser level's correction added to the level below's (`prolong`).
    Prolong {
        /// The coarser level it reads.
        from: u32,
    },
    /// z·r of the preconditioned residual, and the next search direction (`pcg_direction`).
    PcgDirection {
        /// The first direction (p = z) rather than p = z + β·p.
        first: bool,
    },
    /// H·p and p·H·p (`pcg_matvec`).
    PcgMatVec,
    /// The step along p: c += α·p, r −= α·H·p (`pcg_step`).
    PcgStep,
    /// The Newton correction: c masked at pins and filtered at contacts (`correction_filter`).
    CorrectionFilter,
    /// The change of G along c at each trial step (`line_energy`). The CPU solve also chooses
    /// the step here (`line_search_from_full_step`, the same step), so that it sums the
    /// shorter steps only when the full one raises G.
    LineEnergy,
    /// G's slopes along c at the iterate and at the full step (`line_slopes`; on the CPU,
    /// computed by `LineEnergy` when the search needs them).
    LineSlopes,
    /// The step length: the first trial that does not raise G (`line_search`; on the CPU,
    /// chosen by `LineEnergy`).
    LineSearch,
    /// D += α·c (`apply_correction`).
    ApplyCorrection,
    /// The force residual at the iterate (`force_residual`).
    ForceResidual,
    /// z = D⁻¹r on the fine level, D its diagonal blocks (`block_jacobi`): the one-level
    /// preconditioner `bench convergence` compares the V-cycle with (the CPU runs it; no shipped
    /// schedule does).
    BlockJacobi,
    /// Ends the substep's solve if the last force residual is within the tolerance.
    CheckConverged,
}

impl SolveOp {
    /// The operation's stage name (its kernel's and CPU twin's), without its level.
    pub fn kind(self) -> &'static str {
        match self {
            SolveOp::ContactPlanes => "contact_planes",
            SolveOp::Sweep { .. } => "vbd_solve",
            SolveOp::Assemble => "assemble",
            SolveOp::CoarseOperator { .. } => "coarse_operator",
            SolveOp::PcgStart => "pcg_start",
            SolveOp::Smooth { level: 0, .. } => "smooth (fine)",
            SolveOp::Smooth { .. } => "smooth (coarse)",
            SolveOp::Residual { .. } => "level_residual",
            SolveOp::Restrict { .. } => "restrict",
            SolveOp::Prolong { .. } => "prolong",
            SolveOp::PcgDirection { .. } => "pcg_direction",
            SolveOp::PcgMatVec => "pcg_matvec",
            SolveOp::PcgStep => "pcg_step",
            SolveOp::CorrectionFilter => "correction_filter",
            SolveOp::LineEnergy => "line_energy",
            SolveOp::LineSlopes => "line_slopes",
            SolveOp::LineSearch => "line_search",
            SolveOp::ApplyCorrection => "apply_correction",
            SolveOp::ForceResidual => "force_residual",
            SolveOp::BlockJacobi => "block_jacobi",
            SolveOp::CheckConverged => "check_converged",
        }
    }
}

/// How implicit Euler solves a substep.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct SolveShape {
    /// Outer iterations: sweeps without coarse levels, Newton steps with them.
    pub iterations: u32,
    /// Fine sweeps before each Newton step and after the last one.
    pub smoothing: u32,
    /// Coarse levels (0: plain Vertex Block Descent).
    pub levels: u32,
    /// Conjugate-gradient iterations per Newton step.
    pub linear_iterations: u32,
    /// Whether the scene has bodies (contact planes are linearised once per substep).
    pub bodies: bool,
    /// Whether a force-residual tolerance can end the substep early.
    pub tolerance: bool,
}

impl SolveShape {
    /// The shape of a run's implicit solve: its iterations, smoothing and tolerance from
    /// `params`, the model's coarse levels, and contact where the plan collides.
    pub fn for_run(
        model: &ClothModel,
        params: &crate::model::layout::SimParams,
        plan: &PassPlan,
    ) -> SolveShape {
        SolveShape {
            iterations: params.iterations,
            smoothing: params.smoothing,
            levels: model
                .multigrid
                .as_ref()
                .map_or(0, |m| m.levels.len() as u32),
            linear_iterations: LINEAR_ITERATIONS,
            bodies: plan.contains(Pass::CollideBody) && params.num_bodies > 0,
            tolerance: params.tolerance > 0.0,
        }
    }
}

/// Conjugate-gradient iterations per Newton step: each reduces the linear residual about
/// threefold on the hanging sheet at any resolution (README, "Implicit Euler").
pub const LINEAR_ITERATIONS: u32 = 8;
/// Block Gauss–Seidel sweeps on each level of a V-cycle before and after the coarser
/// level's correction: `[fine, coarse]`. Sewn garments have stiff local couplings (seam
/// junctions, free hem corners) that vertex-by-vertex sweeps relax slowly; on the fine level
/// four sweeps (each far cheaper than a Vertex Block Descent sweep: a block product per
/// neighbour, no element geometry) took the cotton T-shirt's linear solve from 6e-4 to 1e-5 of
/// its residual in 40 iterations.
pub const LEVEL_SMOOTHING: [u32; 2] = [4, 2];
/// Symmetric block Gauss–Seidel sweeps (forward then backward) on the coarsest level.
pub const COARSEST_SWEEPS: u32 = 10;

/// The operations of one implicit substep. Without coarse levels: `iterations` sweeps (with a
/// tolerance, the force residual checked before each but the first). With
/// them, `iterations` Newton steps, each after `smoothing` fine sweeps: the fine system
/// assembled, its coarse levels' Galerkin matrices, `linear_iterations` of conjugate gradients
/// preconditioned by a multigrid V-cycle, and a line search on G along the result; then
/// `smoothing` final sweeps. With a tolerance, the force residual is checked before each Newton
/// step. The final force residual is always measured (`ForceResidual` last).
pub fn implicit_schedule(shape: SolveShape) -> Vec<SolveOp> {
    let mut ops = Vec::new();
    if shape.bodies {
        ops.push(SolveOp::ContactPlanes);
    }
    let mut sweep = 0;
    let mut sweeps = |ops: &mut Vec<SolveOp>, count: u32| {
        for _ in 0..count {
            ops.push(SolveOp::Sweep { iteration: sweep });
            sweep += 1;
        }
    };
    if shape.levels == 0 {
        for k in 0..shape.iterations {
            // A tolerance is checked before every sweep but the first (each check costs about
            // what a sweep does).
            if shape.tolerance && k > 0 {
                ops.extend([SolveOp::ForceResidual, SolveOp::CheckConverged]);
            }
            sweeps(&mut ops, 1);
        }
        ops.push(SolveOp::ForceResidual);
        return ops;
    }
    for _ in 0..shape.iterations {
        sweeps(&mut ops, shape.smoothing);
        if shape.tolerance {
            ops.extend([SolveOp::ForceResidual, SolveOp::CheckConverged]);
        }
        ops.extend(newton_correction(shape));
    }
    sweeps(&mut ops, shape.smoothing);
    ops.push(SolveOp::ForceResidual);
    ops
}

/// One Newton step's correction (after its sweeps): the fine system assembled, the coarse
/// levels' Galerkin matrices, `linear_iterations` of conjugate gradients preconditioned by a
/// V-cycle, and the line search along the filtered result.
pub fn newton_correction(shape: SolveShape) -> Vec<SolveOp> {
    let mut ops = vec![SolveOp::Assemble];
    for level in 1..=shape.levels {
        ops.push(SolveOp::CoarseOperator { level });
    }
    ops.push(SolveOp::PcgStart);
    for k in 0..shape.linear_iterations {
        v_cycle(&mut ops, shape.levels);
        ops.push(SolveOp::PcgDirection { first: k == 0 });
        ops.extend([SolveOp::PcgMatVec, SolveOp::PcgStep]);
    }
    ops.extend([
        SolveOp::CorrectionFilter,
        SolveOp::LineEnergy,
        SolveOp::LineSlopes,
        SolveOp::LineSearch,
        SolveOp::ApplyCorrection,
    ]);
    ops
}

/// One Newton step's correction as `newton_correction`'s, preconditioned by the fine matrix's
/// block diagonal instead of a V-cycle, with `iterations` conjugate-gradient iterations: the
/// single-level alternative (Newton with block-Jacobi conjugate gradients) that
/// `bench convergence` measures against the multigrid one.
pub fn newton_correction_block_jacobi(iterations: u32) -> Vec<SolveOp> {
    let mut ops = vec![SolveOp::Assemble, SolveOp::PcgStart];
    for k in 0..iterations {
        ops.push(SolveOp::BlockJacobi);
        ops.push(SolveOp::PcgDirection { first: k == 0 });
        ops.extend([SolveOp::PcgMatVec, SolveOp::PcgStep]);
    }
    ops.extend([
        SolveOp::CorrectionFilter,
        SolveOp::LineEnergy,
        SolveOp::LineSlopes,
        SolveOp::LineSearch,
        SolveOp::ApplyCorrection,
    ]);
    ops
}

/// A V-cycle from the fine level (right-hand side: the residual r) to level `levels`,
/// leaving z ≈ H⁻¹r in level 0's correction.
fn v_cycle(ops: &mut Vec<SolveOp>, levels: u32) {
    let sweeps = |level: u32| LEVEL_SMOOTHING[(level > 0) as usize];
    for level in 0..levels {
        for _ in 0..sweeps(level) {
            ops.push(SolveOp::Smooth {
                level,
                backward: false,
            });
        }
        ops.push(SolveOp::Residual { level });
        ops.push(SolveOp::Restrict { to: level + 1 });
    }
    for _ in 0..COARSEST_SWEEPS {
        for backward in [false, true] {
            ops.push(SolveOp::Smooth {
                level: levels,
                backward,
            });
        }
    }
    for level in (0..levels).rev() {
        ops.push(SolveOp::Prolong { from: level + 1 });
        for _ in 0..sweeps(level) {
            ops.push(SolveOp::Smooth {
                level,
                backward: true,
            });
        }
    }
}
