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
    pub const ALL: [Pass; 17] = [
        Pass::HingeForces,
        Pass::SpringForces,
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
            Pass::SpringForces | Pass::BendingForces | Pass::WindForces | Pass::SeamForces
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
            // Implicit Euler evaluates springs, hinges and seams inside its solve.
            Pass::SpringForces => !effects.implicit && !model.springs.is_empty(),
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
