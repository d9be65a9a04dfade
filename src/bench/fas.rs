//! Nonlinear multigrid, a full approximation scheme (FAS) V-cycle around Vertex Block Descent,
//! for `bench convergence` to measure beside the Newton steps that drapekit ships; no run uses
//! it.
//!
//! Each coarse level is the same cloth meshed at a coarser spacing, with its own springs,
//! hinges, seams, masses and contacts: its own incremental potential G_c. A cycle, after the
//! finer level's sweeps, restricts its iterate D_f to the coarse particles (R: the barycentric
//! blend of the finer triangle each lies in), solves the coarse problem ∇G_c(D_c) = τ with
//! τ = ∇G_c(R·D_f) − Pᵀ∇G_f(D_f) (sweeps, the next level's cycle, sweeps; on the coarsest level
//! sweeps alone), prolongates the coarse change P·(D_c − R·D_f) (P: the blend of the coarse
//! triangle each finer particle lies in, as `pattern::transfer` carries a coarse start) and
//! takes it as a correction of the finer iterate, through the same contact filter and line
//! search on the finer G as a Newton step's (so a cycle never raises it). With f = −∇G the
//! coarse problem is f_c(D_c) + τ = 0: a constant force τ on each coarse particle, which is
//! its inertial target moved by τ·h²/m, all a sweep needs.

use crate::cpu::{CpuSolver, Vbd};
use crate::model::layout::SubstepParams;
use crate::pattern::transfer::{Charted, Transfer};
use crate::plan::{Pass, SolveOp};
use crate::sim::carried;
use crate::solver::{ParticleState, Solver};
use glam::Vec4;

/// Each level's spacing over the finer one's, by default.
pub const FAS_COARSENING: u32 = 2;

/// Sweeps on the coarsest level each cycle, by default.
pub const FAS_COARSE_SWEEPS: u32 = 64;

/// A level of at most this many particles is the coarsest.
pub const FAS_COARSEST_PARTICLES: usize = 150;

/// One coarse level of a FAS V-cycle, for one substep, and the levels below it.
pub struct Fas {
    coarse: CpuSolver,
    /// Where its pinned particles are, and each particle's inverse mass.
    packed: Vec<Vec4>,
    /// Each coarse particle in the finer mesh (R).
    down: Transfer,
    /// Each finer particle in the coarse mesh (P).
    up: Transfer,
    /// The coarse inertial target of the substep, before τ shifts it.
    target: Vec<Vec4>,
    /// The next coarser level; the coarsest has none and is solved by `sweeps` sweeps.
    next: Option<Box<Fas>>,
    /// Sweeps before and after the next level's correction (or on the coarsest, `sweeps`).
    sweeps: u32,
    /// The step, in s.
    dt: f32,
}

/// A coarse level as `Fas::new` takes it: its solver (at the finer level's step), its model's
/// packed positions at the measured frame and its chart.
pub struct CoarseLevel {
    /// The level's solver, with its phase parameters.
    pub solver: CpuSolver,
    /// `sim::packed_at` of its run at the measured frame: where its held particles are, and
    /// each particle's inverse mass then.
    pub packed: Vec<Vec4>,
    /// Its particles' chart coordinates.
    pub chart: Charted,
}

impl Fas {
    /// The V-cycle from the level of chart `fine_chart` through `levels`, finest first, at
    /// the step `dt`: `smoothing` sweeps before and after each coarser correction, and
    /// `coarsest_sweeps` on the last level. `None` without levels.
    pub fn new(
        fine_chart: &Charted,
        mut levels: Vec<CoarseLevel>,
        (smoothing, coarsest_sweeps): (u32, u32),
        dt: f32,
    ) -> Option<Fas> {
        if levels.is_empty() {
            return None;
        }
        let level = levels.remove(0);
        let next = Fas::new(&level.chart, levels, (smoothing, coarsest_sweeps), dt);
        Some(Fas {
            down: Transfer::between(fine_chart, &level.chart),
            up: Transfer::between(&level.chart, fine_chart),
            coarse: level.solver,
            packed: level.packed,
            target: Vec::new(),
            sweeps: if next.is_some() {
                smoothing
            } else {
                coarsest_sweeps
            },
            next: next.map(Box::new),
            dt,
        })
    }

    /// Starts the substep `step` from the finer level's start of step `fine` (positions,
    /// velocities): each level's start restricted from the one above (pinned particles where
    /// its model puts them), its inertial target and, with `bodies`, its contact planes.
    pub fn start(&mut self, fine: &ParticleState, step: &SubstepParams, bodies: bool) {
        let state = carried(&self.down, fine, &self.packed);
        self.coarse.set_state(&state);
        self.coarse.run_pass(Pass::VbdInit, step);
        if bodies {
            self.coarse.run_solve_ops(&[SolveOp::ContactPlanes], step);
        }
        self.target = vbd(&self.coarse).y.clone();
        if let Some(next) = &mut self.next {
            next.start(&state, step, bodies);
        }
    }

    /// One cycle on the finer solver's iterate (after its sweeps): the coarse correction,
    /// filtered and line-searched on the finer level's G as a Newton step's is. Returns the
    /// step length taken.
    pub fn cycle(&mut self, fine: &mut CpuSolver, step: &SubstepParams) -> f32 {
        let fine_force = fine.solve_forces(step);
        let start = self.restrict_iterate(fine);
        self.add_tau(&fine_force, step);
        self.solve_coarse(step);
        let change: Vec<Vec4> = (vbd(&self.coarse).x.iter().zip(&start))
            .map(|(x, s)| (x.truncate() - s.truncate()).extend(0.0))
            .collect();
        let prolonged = self.up.apply(&change);
        take_correction(fine, &prolonged, fine_force, step)
    }

    /// The coarse iterate set to the restriction of the finer one, R·D_f, and the coarse
    /// target to the substep's own; returns R·D_f.
    fn restrict_iterate(&mut self, fine: &CpuSolver) -> Vec<Vec4> {
        let restricted = self.down.apply(&vbd(fine).x);
        let coarse = vbd_mut(&mut self.coarse);
        for (x, r) in coarse.x.iter_mut().zip(&restricted) {
            if x.w != 0.0 {
                *x = r.extend(x.w);
            }
        }
        coarse.y.clone_from(&self.target);
        coarse.x.clone()
    }

    /// The coarse problem's τ = Pᵀf_f − f_c(R·D_f) (f = −∇G): the coarse solve is to balance
    /// f_c(D_c) + τ, so each coarse particle's inertial target moves by τ·h²/m.
    fn add_tau(&mut self, fine_force: &[Vec4], step: &SubstepParams) {
        let coarse_force = self.coarse.solve_forces(step);
        // Pᵀ f_f: each finer particle's force shared among its coarse triangle's corners.
        let mut restricted_force = vec![Vec4::ZERO; coarse_force.len()];
        for (f, (tri, w)) in fine_force.iter().zip(self.up.corners()) {
            for k in 0..3 {
                restricted_force[tri[k] as usize] += w[k] * *f;
            }
        }
        let h = self.dt;
        let coarse = vbd_mut(&mut self.coarse);
        for (i, y) in coarse.y.iter_mut().enumerate() {
            let inverse_mass = coarse.x[i].w;
            if inverse_mass != 0.0 {
                let tau = restricted_force[i] - coarse_force[i];
                *y += (tau * h * h * inverse_mass).truncate().extend(0.0);
            }
        }
    }

    /// The coarse problem solved: sweeps, the next level's cycle and sweeps again, or on the
    /// coarsest level its sweeps alone.
    fn solve_coarse(&mut self, step: &SubstepParams) {
        let sweeps = vec![SolveOp::Sweep { iteration: 0 }; self.sweeps as usize];
        self.coarse.run_solve_ops(&sweeps, step);
        if let Some(next) = &mut self.next {
            next.cycle(&mut self.coarse, step);
            self.coarse.run_solve_ops(&sweeps, step);
        }
    }
}

/// Takes the correction `c` (one per particle) on `solver`'s iterate through the contact
/// filter and the line search on its G, as a Newton step's. The line search's slope at the
/// iterate reads `force`: here f = −∇G itself, so G′(0) = −f·c exactly (a Newton step gives
/// the assembled force, filtered at touching particles as its correction is), as the slope at
/// the full step is taken from the unfiltered force too. Returns α.
fn take_correction(
    solver: &mut CpuSolver,
    c: &[glam::Vec3],
    force: Vec<Vec4>,
    step: &SubstepParams,
) -> f32 {
    let v = vbd_mut(solver);
    // The Newton arrays hold the correction and the line search's partials.
    let newton = (v.newton.as_mut()).expect("a FAS level has Newton arrays");
    for ((out, c), x) in newton.correction.iter_mut().zip(c).zip(&v.x) {
        *out = if x.w == 0.0 {
            Vec4::ZERO
        } else {
            c.extend(0.0)
        };
    }
    newton.force = force;
    solver.run_solve_ops(
        &[
            SolveOp::CorrectionFilter,
            SolveOp::LineEnergy,
            SolveOp::LineSlopes,
            SolveOp::LineSearch,
            SolveOp::ApplyCorrection,
        ],
        step,
    );
    let newton = vbd(solver).newton.as_ref().expect("checked above");
    newton.alphas.last().copied().unwrap_or(0.0)
}

fn vbd_mut(solver: &mut CpuSolver) -> &mut Vbd {
    solver.vbd.as_mut().expect("implicit Euler is in the plan")
}

fn vbd(solver: &CpuSolver) -> &Vbd {
    solver.vbd.as_ref().expect("implicit Euler is in the plan")
}
