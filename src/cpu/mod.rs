//! The CPU reference path: one plain-Rust twin per GPU stage, run in the same order on the
//! same data, so that it is the readable definition of the physics.
//!
//! The per-particle stages are rayon parallel iterators over particles, each particle writing
//! only its own result from reads of the previous arrays and summing its elements in a fixed
//! order: no atomics, and the same bits on any number of threads (`tests/threads.rs`). They run
//! on the caller's rayon pool (`--threads`), in tasks of at least a grain of work each
//! (`grain`), so that a short loop runs on the calling thread; a Gauss–Seidel sweep runs all
//! its colours in one parallel region (`colour_run`). The spatial-hash build (a
//! scatter) and the point–triangle self-collision reference (Gauss–Seidel) stay serial.

mod assemble;
mod bending_forces;
mod coarse_operator;
mod collide_body;
mod colour_run;
mod contact_planes;
mod deformed_body;
mod force_residual;
pub mod grain;
mod hash_clear;
mod hash_count;
mod hash_fill;
mod hash_scan;
mod hinge_forces;
mod implicit;
mod implicit_terms;
mod integrate;
mod line_energy;
pub mod membrane;
mod monitor;
mod pcg;
mod prolong;
mod restrict;
mod seam_forces;
mod self_collide;
mod smooth;
mod spring_forces;
mod strain_limit;
pub mod stretch_law;
mod vbd_finish;
mod vbd_init;
mod vbd_solve;
mod wind_forces;

pub use assemble::assemble;
pub use bending_forces::bending_forces;
pub use coarse_operator::coarse_operator;
pub use collide_body::{
    collide_body, collide_deformed, collide_edge, collide_edges, collide_particle, to_body_frame,
};
pub use contact_planes::contact_planes;
pub use deformed_body::{
    closest_barycentric, deformed_sample, DeformedSample, REFINEMENTS, SETTLED_STEP,
};
pub use force_residual::{force_residual, reduce_residual, residual_gravity};
pub use hash_clear::hash_clear;
pub use hash_count::{hash_bucket, hash_cell_of, hash_count};
pub use hash_fill::hash_fill;
pub use hash_scan::hash_scan;
pub use hinge_forces::{hinge_force, hinge_forces, hinge_frame, HingeFrame};
pub use implicit::{Elements, LevelArrays, Newton, Vbd};
pub use implicit_terms::{
    hinge_psi, Implicit, VbdElements, VertexSystem, CONTACT_RATIO, PLANE_BLOCKS,
};
pub use integrate::{integrate, HingeGather};
pub use line_energy::{
    apply_correction, line_energy, line_search, line_search_from_full_step, line_slopes,
    slope_change, tree_sum, LINE_ALPHAS, LINE_ROUNDING,
};
pub use monitor::monitor;
pub use pcg::{dot, pcg_direction, pcg_matvec, pcg_start, pcg_step, PcgScalars};
pub use prolong::{correction_filter, prolong};
pub use restrict::restrict;
pub use seam_forces::{rest_gap, seam_force, seam_forces};
pub use self_collide::{point_triangle_impulses, self_collide};
pub use smooth::{level_residual, smooth, ColourRows};
pub use spring_forces::spring_forces;
pub use strain_limit::strain_limit;
pub use vbd_finish::vbd_finish;
pub use vbd_init::vbd_init;
pub use vbd_solve::{newton_step, solve3, vbd_solve, SweepPlan};
pub use wind_forces::wind_forces;

use crate::error::Error;
use crate::model::layout::{BodyParams, Hinge, Seam, SimParams, SpringRef, SubstepParams};
use crate::model::{ClothModel, Csr};
use crate::plan::{implicit_schedule, HingeEvaluation, Pass, PassPlan, SolveShape};
use crate::solver::{relative_residual, AdapterReport, ParticleState, SolveProgress, Solver};
use glam::Vec4;

/// The CPU backend. Holds data only for the stages in its plan.
pub struct CpuSolver {
    params: SimParams,
    plan: PassPlan,
    /// Positions, w = inverse mass.
    pub pos: Vec<Vec4>,
    /// Velocities.
    pub vel: Vec<Vec4>,
    /// Force accumulator, cleared by `integrate`.
    pub force: Vec<Vec4>,
    springs: Option<Csr<SpringRef>>,
    membranes: Option<(Vec<crate::model::layout::Membrane>, Csr<u32>)>,
    hinges: Option<Hinges>,
    /// The hinges and each particle's hinge refs, for `bending_forces` (per vertex).
    vertex_hinges: Option<(Vec<Hinge>, Csr<u32>)>,
    triangles: Option<(Vec<[u32; 4]>, Csr<u32>)>,
    seams: Option<(Vec<Seam>, Csr<u32>)>,
    /// The collision bodies, when the plan collides (empty otherwise).
    colliders: Vec<std::sync::Arc<crate::body::Collider>>,
    /// The spatial hash of self-collision (public for per-stage parity tests).
    pub hash: Option<SpatialHash>,
    /// Self-collision by point–triangle impulses (the CPU-only reference) instead of the
    /// particle repulsion that the GPU runs.
    point_triangle_reference: bool,
    self_triangles: Vec<[u32; 3]>,
    /// The cloth's edges (its stretch springs), when the body takes edge contacts.
    cloth_edges: Vec<[u32; 2]>,
    /// Implicit Euler's data (public for per-stage parity tests).
    pub vbd: Option<Vbd>,
    /// Every particle's springs, for the frame-health `monitor` stage.
    monitor_springs: Csr<SpringRef>,
    /// Strain limiting's springs and its Jacobi scratch pair (positions, velocities).
    strain: Option<(Csr<SpringRef>, Vec<Vec4>, Vec<Vec4>)>,
}

/// The hinges, each particle's hinge refs, and the forces `hinge_forces` evaluated once per
/// hinge (four per hinge, at the refs' indices) for `integrate` to gather.
struct Hinges {
    hinges: Vec<Hinge>,
    csr: Csr<u32>,
    forces: Vec<Vec4>,
}

/// The self-collision hash table and the mesh neighbours it skips.
pub struct SpatialHash {
    /// Particles per bucket.
    pub counts: Vec<u32>,
    /// Bucket starts into `sorted` (one more: the total).
    pub starts: Vec<u32>,
    /// Fill cursors.
    pub cursor: Vec<u32>,
    /// Particle indices grouped by bucket.
    pub sorted: Vec<u32>,
    neighbours: Csr<SpringRef>,
    pos_out: Vec<Vec4>,
    vel_out: Vec<Vec4>,
}

impl CpuSolver {
    /// How the CPU evaluates hinges unless the plan says otherwise: once per hinge, measured
    /// faster here than once per vertex (docs/src/benchmarks/throughput.md).
    pub const HINGES: HingeEvaluation = HingeEvaluation::Once;

    /// A CPU solver for `model` running `plan` (with hinges as `HINGES` if the plan leaves it
    /// open).
    ///
    /// ```
    /// use drapekit::cpu::CpuSolver;
    /// use drapekit::scene::Scene;
    /// use drapekit::sim::{prepare, substep_params};
    /// use drapekit::solver::Solver;
    /// use std::path::Path;
    ///
    /// let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    /// let scene = Scene::load(&dir.join("fixtures/scenes/free_fall.toml"))?;
    /// let prep = prepare(&scene)?;
    /// let mut solver = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    /// // One output frame: its substeps in one call, then read the state back.
    /// solver.advance(&substep_params(&prep, 1))?;
    /// let state = solver.state()?;
    /// // Falling from rest: everything moves down.
    /// assert!(state.velocities.iter().all(|v| v.y < 0.0));
    /// # Ok::<(), drapekit::Error>(())
    /// ```
    pub fn new(model: &ClothModel, params: SimParams, plan: &PassPlan) -> Self {
        let plan = &plan.for_backend(Self::HINGES);
        let n = model.len();
        CpuSolver {
            params,
            plan: plan.clone(),
            pos: model.packed_positions(),
            vel: model.packed_velocities(),
            force: vec![Vec4::ZERO; n],
            springs: plan
                .contains(Pass::SpringForces)
                .then(|| model.spring_csr()),
            membranes: plan
                .contains(Pass::MembraneForces)
                .then(|| (model.membranes.clone(), model.membrane_csr())),
            hinges: plan.contains(Pass::HingeForces).then(|| Hinges {
                hinges: model.hinges.clone(),
                csr: model.hinge_csr(),
                forces: vec![Vec4::ZERO; 4 * model.hinges.len()],
            }),
            vertex_hinges: plan
                .contains(Pass::BendingForces)
                .then(|| (model.hinges.clone(), model.hinge_csr())),
            triangles: plan
                .contains(Pass::WindForces)
                .then(|| (model.packed_triangles(), model.triangle_csr())),
            seams: plan
                .contains(Pass::SeamForces)
                .then(|| (model.seams.clone(), model.seam_csr())),
            point_triangle_reference: false,
            cloth_edges: if model.colliders.iter().any(|c| c.edges.is_some()) {
                model.springs.iter().map(|s| s.ends).collect()
            } else {
                Vec::new()
            },
            self_triangles: if plan.contains(Pass::SelfCollide) {
                model.triangles.clone()
            } else {
                Vec::new()
            },
            hash: plan.contains(Pass::SelfCollide).then(|| {
                let buckets = params.hash_buckets as usize;
                SpatialHash {
                    counts: vec![0; buckets],
                    starts: vec![0; buckets + 1],
                    cursor: vec![0; buckets],
                    sorted: vec![0; n],
                    neighbours: model.spring_csr(),
                    pos_out: vec![Vec4::ZERO; n],
                    vel_out: vec![Vec4::ZERO; n],
                }
            }),
            // The implicit solve takes contact only where the plan collides, as on the GPU.
            colliders: if plan.contains(Pass::CollideBody) {
                model.colliders.clone()
            } else {
                Vec::new()
            },
            monitor_springs: model.spring_csr(),
            strain: plan
                .contains(Pass::StrainLimit)
                .then(|| (model.spring_csr(), vec![Vec4::ZERO; n], vec![Vec4::ZERO; n])),
            vbd: plan.contains(Pass::VbdSolve).then(|| {
                let shape = SolveShape::for_run(model, &params, plan);
                Vbd::new(model, &params, implicit_schedule(shape))
            }),
        }
    }

    /// The stages this solver holds data for (its plan).
    pub fn plan(&self) -> &PassPlan {
        &self.plan
    }

    /// The forces `hinge_forces` wrote, four per hinge (for per-stage parity tests).
    pub fn hinge_forces(&self) -> Option<&[Vec4]> {
        self.hinges.as_ref().map(|h| &h.forces[..])
    }

    /// The `monitor` stage's per-block partials of the current state.
    pub fn health_partials(&self) -> Vec<crate::solver::HealthPartial> {
        let csr = &self.monitor_springs;
        monitor(&self.params, &self.pos, &self.vel, &csr.offsets, &csr.items)
    }

    /// Runs one stage once. Panics if the stage is not in the plan: that is a caller bug.
    pub fn run_pass(&mut self, pass: Pass, step: &SubstepParams) {
        let p = &self.params;
        match pass {
            Pass::SpringForces => {
                let csr = self
                    .springs
                    .as_ref()
                    .expect("spring_forces is not in the plan");
                spring_forces(
                    p,
                    &self.pos,
                    &self.vel,
                    &mut self.force,
                    &csr.offsets,
                    &csr.items,
                );
            }
            Pass::MembraneForces => {
                let (membranes, csr) = self
                    .membranes
                    .as_ref()
                    .expect("membrane_forces is not in the plan");
                membrane::membrane_forces(
                    p,
                    &self.pos,
                    &self.vel,
                    &mut self.force,
                    &csr.offsets,
                    &csr.items,
                    membranes,
                );
            }
            Pass::HingeForces => {
                let h = self
                    .hinges
                    .as_mut()
                    .expect("hinge_forces is not in the plan");
                hinge_forces(&self.pos, &h.hinges, &mut h.forces);
            }
            Pass::BendingForces => {
                let (hinges, csr) = self
                    .vertex_hinges
                    .as_ref()
                    .expect("bending_forces is not in the plan");
                bending_forces(
                    p,
                    &self.pos,
                    &mut self.force,
                    &csr.offsets,
                    &csr.items,
                    hinges,
                );
            }
            Pass::WindForces => {
                let (tris, csr) = self
                    .triangles
                    .as_ref()
                    .expect("wind_forces is not in the plan");
                wind_forces(
                    p,
                    step,
                    &self.pos,
                    &self.vel,
                    &mut self.force,
                    &csr.offsets,
                    &csr.items,
                    tris,
                );
            }
            Pass::SeamForces => {
                let (seams, csr) = self.seams.as_ref().expect("seam_forces is not in the plan");
                seam_forces(
                    p,
                    step,
                    &self.pos,
                    &self.vel,
                    &mut self.force,
                    &csr.offsets,
                    &csr.items,
                    seams,
                );
            }
            Pass::HashClear => {
                let h = self.hash.as_mut().expect("hash_clear is not in the plan");
                hash_clear(p, &mut h.counts);
            }
            Pass::HashCount => {
                let h = self.hash.as_mut().expect("hash_count is not in the plan");
                hash_count(p, &self.pos, &mut h.counts);
            }
            Pass::HashScan => {
                let h = self.hash.as_mut().expect("hash_scan is not in the plan");
                hash_scan(p, &h.counts, &mut h.starts, &mut h.cursor);
            }
            Pass::HashFill => {
                let h = self.hash.as_mut().expect("hash_fill is not in the plan");
                hash_fill(p, &self.pos, &mut h.cursor, &mut h.sorted);
            }
            Pass::SelfCollide if self.point_triangle_reference => {
                point_triangle_impulses(p, &self.pos, &mut self.vel, &self.self_triangles);
            }
            Pass::SelfCollide => {
                let h = self.hash.as_mut().expect("self_collide is not in the plan");
                let csr = &h.neighbours;
                // Writes the next state into the scratch pair, then swaps, as the kernel
                // ping-pongs its textures (no allocation per substep).
                self_collide(
                    p,
                    &self.pos,
                    &self.vel,
                    &h.starts,
                    &h.sorted,
                    &csr.offsets,
                    &csr.items,
                    &mut h.pos_out,
                    &mut h.vel_out,
                );
                std::mem::swap(&mut self.pos, &mut h.pos_out);
                std::mem::swap(&mut self.vel, &mut h.vel_out);
            }
            Pass::CollideBody => self.collide(step),
            Pass::VbdInit => {
                let v = self.vbd.as_mut().expect("vbd_init is not in the plan");
                let (x, y, steps) = (&mut v.x, &mut v.y, &mut v.steps);
                vbd_init(p, &self.pos, &self.vel, &mut self.force, x, y, steps);
            }
            Pass::VbdSolve => {
                let v = self.vbd.as_mut().expect("vbd_solve is not in the plan");
                let sdfs: Vec<&[f32]> = self.colliders.iter().map(|c| &c.sdf.values[..]).collect();
                v.solve(p, step, &self.pos, &sdfs);
            }
            Pass::VbdFinish => {
                let v = self.vbd.as_ref().expect("vbd_finish is not in the plan");
                vbd_finish(p, &v.x, &mut self.pos, &mut self.vel);
            }
            Pass::Integrate => {
                let hinges = self.hinges.as_ref().map(|h| HingeGather {
                    offsets: &h.csr.offsets,
                    refs: &h.csr.items,
                    forces: &h.forces,
                });
                integrate(p, &mut self.pos, &mut self.vel, &mut self.force, hinges);
            }
            Pass::Monitor => {
                panic!("monitor runs per frame through health(), not as a substep stage")
            }
            Pass::StrainLimit => {
                let (csr, pos_out, vel_out) = self
                    .strain
                    .as_mut()
                    .expect("strain_limit is not in the plan");
                // Jacobi: each iteration reads one state and writes the other, as the kernel
                // ping-pongs its textures.
                for _ in 0..p.strain_iterations {
                    strain_limit(
                        p,
                        &self.pos,
                        &self.vel,
                        &csr.offsets,
                        &csr.items,
                        pos_out,
                        vel_out,
                    );
                    std::mem::swap(&mut self.pos, pos_out);
                    std::mem::swap(&mut self.vel, vel_out);
                }
            }
        }
    }
}

impl CpuSolver {
    /// Runs implicit Euler's solve operations `ops` on the current iterate, from the current
    /// state (after `vbd_init`): part of a substep's schedule, for benchmarks and tests.
    /// Panics without implicit Euler in the plan.
    pub fn run_solve_ops(&mut self, ops: &[crate::plan::SolveOp], step: &SubstepParams) {
        let v = self
            .vbd
            .as_mut()
            .expect("implicit Euler is not in the plan");
        let sdfs: Vec<&[f32]> = self.colliders.iter().map(|c| &c.sdf.values[..]).collect();
        let (params, pos) = (&self.params, &self.pos);
        rayon::scope(|_| v.run_ops(ops, params, step, pos, &sdfs));
    }

    /// Implicit Euler's force at the current iterate, f = −∇G per particle (`Vbd::forces`):
    /// for benchmarks and tests. Panics without implicit Euler in the plan.
    pub fn solve_forces(&self, step: &SubstepParams) -> Vec<Vec4> {
        let v = (self.vbd.as_ref()).expect("implicit Euler is not in the plan");
        let mut out = vec![Vec4::ZERO; self.pos.len()];
        v.forces(&self.params, step, &self.pos, &mut out);
        out
    }

    /// Switches self-collision to the point–triangle impulse reference (CPU only).
    pub fn use_point_triangle_reference(&mut self) {
        self.point_triangle_reference = true;
    }

    /// The collision stage with each body's CPU strategy: the SDF (the GPU's twin) or exact
    /// queries, all driving the same response, body after body for each particle as the kernel
    /// does; then the edge contacts of the bodies that take them.
    fn collide(&mut self, step: &SubstepParams) {
        let p = &self.params;
        let colliders = &self.colliders[..(p.num_bodies as usize).min(self.colliders.len())];
        let words: Vec<&[f32]> = colliders.iter().map(|c| &c.sdf.values[..]).collect();
        collide_body(
            p,
            step,
            &mut self.pos,
            &mut self.vel,
            colliders.len(),
            &words,
            |b, x| strategy_query(&p.bodies[b], &colliders[b], x),
        );
        for (b, c) in colliders.iter().enumerate() {
            if c.edges.is_some() {
                let (body, pose) = (&p.bodies[b], &step.bodies[b]);
                collide_edges(
                    body,
                    pose,
                    &mut self.pos,
                    &mut self.vel,
                    &self.cloth_edges,
                    c,
                );
            }
        }
    }
}

/// φ (w) and ∇φ (xyz) at body-frame point `x` by the collider's CPU strategy.
fn strategy_query(body: &BodyParams, c: &crate::body::Collider, x: glam::Vec3) -> Vec4 {
    if c.strategy == crate::body::Strategy::Sdf {
        return collide_body::sample_body_sdf(body, &c.sdf.values, x);
    }
    let (phi, nearest) = c.query(x);
    // ∇φ points away from the surface outside and towards it inside.
    let d = x - nearest;
    let len = d.length();
    let grad = if len > 0.0 {
        d / len * phi.signum()
    } else {
        glam::Vec3::ZERO
    };
    grad.extend(phi)
}

impl Solver for CpuSolver {
    fn backend_name(&self) -> &'static str {
        "cpu"
    }

    fn adapter(&self) -> Option<AdapterReport> {
        None
    }

    /// Runs the substeps on a worker of the rayon pool: the stages' parallel loops then
    /// split work by stealing within the pool instead of each waking the pool from outside
    /// (thousands of small loops a frame in implicit Euler's solve).
    fn advance(&mut self, steps: &[SubstepParams]) -> Result<(), Error> {
        rayon::scope(|_| {
            for (k, step) in steps.iter().enumerate() {
                // The final force residual is read at the frame's end only.
                if let Some(v) = &mut self.vbd {
                    v.measure_final = k + 1 == steps.len();
                }
                for i in 0..self.plan.passes.len() {
                    self.run_pass(self.plan.passes[i], step);
                }
            }
        });
        Ok(())
    }

    fn set_params(&mut self, params: &SimParams) {
        self.params = *params;
    }

    fn health(&mut self) -> Result<crate::solver::Health, Error> {
        Ok(crate::solver::Health::from_partials(
            &self.health_partials(),
        ))
    }

    fn residual(&mut self) -> Result<Option<SolveProgress>, Error> {
        Ok(self.vbd.as_mut().map(|v| {
            let (run, reported) = v.iterations_run;
            v.iterations_run.1 = run;
            let newton = v.newton_run.0 - v.newton_run.1;
            v.newton_run.1 = v.newton_run.0;
            SolveProgress {
                relative_residual: relative_residual(&v.steps),
                iterations: run - reported,
                newton_steps: newton,
                force_residual: v.residual,
            }
        }))
    }

    /// Replaces positions and velocities and clears forces.
    fn set_state(&mut self, state: &ParticleState) {
        self.pos.clone_from(&state.positions);
        self.vel.clone_from(&state.velocities);
        self.force.fill(Vec4::ZERO);
    }

    fn positions(&mut self) -> Result<Vec<Vec4>, Error> {
        Ok(self.pos.clone())
    }

    fn state(&mut self) -> Result<ParticleState, Error> {
        Ok(ParticleState {
            positions: self.pos.clone(),
            velocities: self.vel.clone(),
        })
    }
}
