//! Implicit Euler's solve on lavapipe, stage by stage: every GPU kernel of the solve run from the
//! same inputs as its CPU twin, on two cases: the T-shirt as placed (springs, hinges, seams,
//! three coarse levels; the level operations run in `coarse_cycle`'s single workgroup, as on
//! software adapters) and the pinched cloth (two bodies, contact and friction; every level
//! operation dispatched on its own, as on hardware GPUs); then both again with the fabric an
//! orthotropic membrane (its warp at 30°), whose springs carry nothing.
//!
//! The bounds: both backends evaluate the same f32 expressions in the same order, so they differ
//! only where an operation rounds differently (FMA contraction, the adapter's sqrt, divide and
//! asin), by about one rounding, ε = 2^-24 relative, of the quantities involved. Each bound is
//! that rounding times the scale of the terms a value sums (not of the value: sums cancel),
//! times the number of roundings on the way, with margin; the scales come from the CPU twins.

#[path = "../common/mod.rs"]
mod common;
mod linear;

use common::{fixture, gpu, max_abs_diff, max_norm, perturbed};
use drapekit::cpu::{self, Elements, Implicit, PcgScalars, VbdElements};
use drapekit::gpu::implicit::layout::SolveScalars;
use drapekit::gpu::implicit::{SolveArray, SolveOptions};
use drapekit::gpu::GpuSolver;
use drapekit::model::layout::SubstepParams;
use drapekit::model::multigrid::Multigrid;
use drapekit::model::Csr;
use drapekit::plan::{Pass, SolveOp};
use drapekit::scene::Scene;
use drapekit::sim::{prepare, substep_params, Prepared};
use drapekit::solver::{ParticleState, Solver};
use glam::{Mat3, Vec3, Vec4};
use linear::{check_coarse_operators, check_level_op, check_pcg, Level, Pcg};

/// f32's relative rounding.
const EPS: f32 = f32::EPSILON / 2.0;

/// The T-shirt as placed, with the body and gravity, its particles moved by up to 5 mm and
/// moving at up to 0.5 m/s: every element far from rest.
fn tshirt() -> (Prepared, ParticleState, SubstepParams) {
    tshirt_with(Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap())
}

/// `tshirt` from `scene` (the shipped T-shirt, or a variant of its fabric).
fn tshirt_with(mut scene: Scene) -> (Prepared, ParticleState, SubstepParams) {
    scene.gravity_start = 0.0;
    let mut prep = prepare(&scene).unwrap();
    prep.params.gravity = [0.0, -9.81, 0.0, 0.0];
    let mut cpu = cpu::CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let state = perturbed(&cpu.state().unwrap(), 11, 5e-3, 0.5);
    let step = substep_params(&prep, 3)[0];
    (prep, state, step)
}

#[test]
fn parity_solve_stages_tshirt() {
    let Some(ctx) = gpu() else { return };
    let (prep, state, step) = tshirt();
    // Every level in one workgroup, those of up to 1,024 rows smoothed in workgroup memory
    // (the coarse levels; how GPUs run them).
    let single = SolveOptions {
        small_rows: u32::MAX,
        cached_rows: 1024,
    };
    let g = GpuSolver::with_options(ctx, &prep.model, prep.params, &prep.plan, 1, single);
    check_stages("tshirt", g.unwrap(), Case::new(prep, state, step));
}

/// The T-shirt's whole substep, every level in one workgroup, with its coarse levels smoothed in
/// workgroup memory and without: the same bits. The stage checks above run one operation a
/// dispatch; here a V-cycle's operations hand the cached correction on within one dispatch
/// (copied in, swept, copied back before the residual, restriction and prolongation read it).
#[test]
fn workgroup_memory_changes_no_bit_of_a_substep() {
    let Some(ctx) = gpu() else { return };
    let (prep, state, step) = tshirt();
    let substep = |cached_rows| {
        let options = SolveOptions {
            small_rows: u32::MAX,
            cached_rows,
        };
        let plan = &prep.plan;
        let mut g = GpuSolver::with_options(ctx, &prep.model, prep.params, plan, 1, options);
        let g = g.as_mut().unwrap();
        g.set_state(&state);
        g.advance(&[step]).unwrap();
        g.state().unwrap()
    };
    let (plain, cached) = (substep(0), substep(1024));
    assert!(plain.positions != state.positions, "nothing moved");
    assert_eq!(plain.positions, cached.positions);
    assert_eq!(plain.velocities, cached.velocities);
}

#[test]
fn parity_solve_stages_pinched() {
    let Some(ctx) = gpu() else { return };
    let (prep, state, step) = common::pinched();
    let apart = SolveOptions {
        small_rows: 0,
        cached_rows: 0,
    };
    let g = GpuSolver::with_options(ctx, &prep.model, prep.params, &prep.plan, 1, apart);
    check_stages("pinched", g.unwrap(), Case::new(prep, state, step));
}

/// The T-shirt with springs that buckle: perturbed by 5 mm, many springs are compressed past
/// their Euler onset, where the force, the Hessian's axial term and the line search's energy
/// change take the buckled branch.
#[test]
fn parity_solve_stages_buckling_tshirt() {
    let Some(ctx) = gpu() else { return };
    let scene = common::scene_with_fabric("scenes/tshirt_drape_cotton.toml", common::BUCKLING);
    let (prep, state, step) = tshirt_with(scene);
    let buckled = common::buckled_springs(&prep, &state.positions);
    assert!(
        buckled * 5 > prep.model.springs.len(),
        "only {buckled} of {} springs buckled",
        prep.model.springs.len()
    );
    let single = SolveOptions {
        small_rows: u32::MAX,
        cached_rows: 0,
    };
    let g = GpuSolver::with_options(ctx, &prep.model, prep.params, &prep.plan, 1, single);
    check_stages("buckling tshirt", g.unwrap(), Case::new(prep, state, step));
}

/// The T-shirt as a cotton membrane with its warp at 30° on every panel: the membrane's terms
/// in every stage, its blocks in the assembled matrix, and an empty spring list.
#[test]
fn parity_solve_stages_membrane_tshirt() {
    let Some(ctx) = gpu() else { return };
    let scene =
        common::scene_with_fabric("scenes/tshirt_drape_cotton.toml", common::MEMBRANE_GRAIN_30);
    let (prep, state, step) = tshirt_with(scene);
    assert!(!prep.model.membranes.is_empty() && !prep.model.seams.is_empty());
    let single = SolveOptions {
        small_rows: u32::MAX,
        cached_rows: 1024,
    };
    let g = GpuSolver::with_options(ctx, &prep.model, prep.params, &prep.plan, 1, single);
    check_stages("membrane tshirt", g.unwrap(), Case::new(prep, state, step));
}

/// The T-shirt as a cotton membrane (warp at 30°) whose conditions buckle: perturbed by 5 mm,
/// many are compressed past their Euler strain, where the force, the Hessian's axial term and
/// the line search's energy change take the buckled branch.
#[test]
fn parity_solve_stages_membrane_buckling_tshirt() {
    let Some(ctx) = gpu() else { return };
    let fabric = format!("{}\n{}", common::MEMBRANE_GRAIN_30, common::BUCKLING);
    let scene = common::scene_with_fabric("scenes/tshirt_drape_cotton.toml", &fabric);
    let (prep, state, step) = tshirt_with(scene);
    let buckled = common::buckled_conditions(&prep, &state.positions);
    let conditions = 2 * prep.model.membranes.len();
    assert!(
        buckled * 5 > conditions,
        "only {buckled} of {conditions} buckled"
    );
    let single = SolveOptions {
        small_rows: u32::MAX,
        cached_rows: 0,
    };
    let g = GpuSolver::with_options(ctx, &prep.model, prep.params, &prep.plan, 1, single);
    check_stages(
        "membrane buckling tshirt",
        g.unwrap(),
        Case::new(prep, state, step),
    );
}

/// The T-shirt as a cotton membrane (warp at 30°) that stiffens in tension (its large-strain
/// tangents twice its warp and weft, `common::STIFFENING`): perturbed by 5 mm, many conditions are stretched
/// within the growth and some beyond it, where the force, the Hessian's axial (tangent) and
/// transverse (tension over |w|) terms and the line search's energy change take the
/// stiffening law.
#[test]
fn parity_solve_stages_membrane_stiffening_tshirt() {
    let Some(ctx) = gpu() else { return };
    let fabric = format!("{}\n{}", common::MEMBRANE_GRAIN_30, common::STIFFENING);
    let scene = common::scene_with_fabric("scenes/tshirt_drape_cotton.toml", &fabric);
    let (prep, state, step) = tshirt_with(scene);
    let (within, beyond) = common::stiffened_conditions(&prep, &state.positions);
    let conditions = 2 * prep.model.membranes.len();
    assert!(
        within * 5 > conditions && beyond > 0,
        "{within} within, {beyond} beyond of {conditions}"
    );
    let single = SolveOptions {
        small_rows: u32::MAX,
        cached_rows: 0,
    };
    let g = GpuSolver::with_options(ctx, &prep.model, prep.params, &prep.plan, 1, single);
    check_stages(
        "membrane stiffening tshirt",
        g.unwrap(),
        Case::new(prep, state, step),
    );
}

/// The pinched cloth as a cotton membrane (warp at 30°): the membrane's constant stiffness in
/// the contact stiffness, with contact and friction.
#[test]
fn parity_solve_stages_membrane_pinched() {
    let Some(ctx) = gpu() else { return };
    let (prep, state, step) = common::pinched_with(common::MEMBRANE_GRAIN_30);
    assert!(!prep.model.membranes.is_empty() && prep.params.num_bodies == 2);
    let apart = SolveOptions {
        small_rows: 0,
        cached_rows: 0,
    };
    let g = GpuSolver::with_options(ctx, &prep.model, prep.params, &prep.plan, 1, apart);
    check_stages("membrane pinched", g.unwrap(), Case::new(prep, state, step));
}

/// The CPU side of a substep's solve: the state at the start of the step and the solve's
/// arrays as the CPU twins leave them.
struct Case {
    prep: Prepared,
    state: ParticleState,
    step: SubstepParams,
    elements: Elements,
    x: Vec<Vec4>,
    y: Vec<Vec4>,
    planes: Vec<Vec4>,
    lambdas: Vec<Vec4>,
}

impl Case {
    /// `vbd_init`'s target and guess from `state`.
    fn new(prep: Prepared, state: ParticleState, step: SubstepParams) -> Case {
        let n = prep.model.len();
        let (mut x, mut y) = (vec![Vec4::ZERO; n], vec![Vec4::ZERO; n]);
        let mut force = vec![Vec4::ZERO; n];
        let p = &prep.params;
        let (pos, vel) = (&state.positions, &state.velocities);
        cpu::vbd_init(p, pos, vel, &mut force, &mut x, &mut y, &mut [0.0]);
        let bodies = (prep.params.num_bodies as usize).max(1);
        Case {
            elements: Elements::new(&prep.model),
            planes: vec![Vec4::ZERO; cpu::PLANE_BLOCKS * bodies * n],
            lambdas: vec![Vec4::ZERO; n],
            prep,
            state,
            step,
            x,
            y,
        }
    }

    fn mg(&self) -> Multigrid {
        (self.prep.model.multigrid.as_deref().cloned()).expect("the scene has coarse levels")
    }

    /// `f` on the stages' shared inputs, with the elements `el` (all of them: `None`).
    fn with_elements<T>(&self, el: Option<&VbdElements>, f: impl FnOnce(&Implicit) -> T) -> T {
        let all = self.elements.view();
        let s = Implicit {
            params: &self.prep.params,
            step: &self.step,
            prev: &self.state.positions,
            target: &self.y,
            el: el.unwrap_or(&all),
            planes: &self.planes,
            lambdas: &self.lambdas,
        };
        f(&s)
    }

    fn with<T>(&self, f: impl FnOnce(&Implicit) -> T) -> T {
        self.with_elements(None, f)
    }

    /// The largest spring length at the iterate, in m: the scale of the lengths whose rounding
    /// the forces carry.
    fn longest_edge(&self) -> f32 {
        let world = |i: u32| (self.state.positions[i as usize] + self.x[i as usize]).truncate();
        let springs = self.prep.model.springs.iter();
        springs
            .map(|s| world(s.ends[0]).distance(world(s.ends[1])))
            .fold(0.0, f32::max)
    }

    /// The largest entry of any free vertex's Hessian diagonal block (contact included,
    /// unfiltered), in N/m: it bounds every stiffness a vertex's force sums.
    fn stiffest(&self) -> f32 {
        self.with(|s| {
            (0..self.prep.model.len())
                .map(|i| mat_max(&s.vertex_system(i, &self.x, None, &mut |_, _| {}).hessian))
                .fold(0.0, f32::max)
        })
    }
}

/// How far buckled elements' Hessian blocks can move with the rounding of their stretch.
struct SecantJitter {
    /// Per vertex, a bound for any block of its row, in N/m.
    row: Vec<f32>,
    /// The moves of free vertices' diagonal blocks, one Jₑ·c²·n̂n̂ᵀ per buckled element and
    /// vertex: (the vertex, Jₑ·c², n̂), c the vertex's coefficient in the element, n̂ the
    /// element's direction.
    diagonal: Vec<(usize, f32, Vec3)>,
}

impl Case {
    /// A buckled element's axial stiffness is the secant T(s)/s (`StretchLaw::axial`),
    /// whose derivative in s is k·o·(1 − r)/s² (o the onset, r the buckled fraction, |s| ≥ o):
    /// the rounding δs of the stretch moves it by Jₑ = k·o·(1 − r)·δs/s², up to k·δs/o, where
    /// the linear law's k does not move at all. The stretch rounds a few times the length it is
    /// taken from: δs = 4ε·|e| for a spring (m), 4ε·|w| for a membrane condition (|w| − 1),
    /// whose blocks are its stiffness times c_r·c_s (1/m each) times the axial term. Zero
    /// without buckling.
    fn secant_jitter(&self, x: &[Vec4]) -> SecantJitter {
        let p = &self.prep.params;
        let r = p.buckled_fraction;
        let mut out = SecantJitter {
            row: vec![0.0; x.len()],
            diagonal: Vec::new(),
        };
        if r == 0.0 {
            return out;
        }
        let world: Vec<Vec4> = (self.state.positions.iter().zip(x))
            .map(|(p, d)| (p.truncate() + d.truncate()).extend(p.w))
            .collect();
        // With a membrane the springs carry no force: the solve leaves them out.
        let springs = match self.prep.model.membranes.is_empty() {
            true => &self.prep.model.springs[..],
            false => &[],
        };
        for spring in springs {
            let [a, b] = spring.ends.map(|e| e as usize);
            let e = world[a].truncate() - world[b].truncate();
            let (s, o) = (
                e.length() - spring.rest_length,
                p.euler_onset / spring.rest_length,
            );
            if s < -o {
                let ds = 4.0 * EPS * e.length().max(spring.rest_length);
                let moved = spring.stiffness * o * (1.0 - r) * ds / (s * s);
                for v in [a, b] {
                    out.row[v] += moved;
                    out.diagonal.push((v, moved, e.normalize()));
                }
            }
        }
        let zero = vec![Vec4::ZERO; x.len()];
        for m in &self.prep.model.membranes {
            let step = cpu::membrane::MembraneStep::at(m, &world, &zero);
            let w = step.images();
            for (c, w) in w.into_iter().enumerate() {
                let (s, o) = (step.stretch(c), p.membrane_onset / m.stiffness[c]);
                if s < -o {
                    let ds = 4.0 * EPS * w.length().max(1.0);
                    let moved = m.stiffness[c] * o * (1.0 - r) * ds / (s * s);
                    let coefficient = |v: usize| step.coefficient(c, v).abs();
                    let largest = (0..3).map(coefficient).fold(0.0f32, f32::max);
                    for (role, &v) in m.v[..3].iter().enumerate() {
                        out.row[v as usize] += largest * largest * moved;
                        let own = coefficient(role) * coefficient(role) * moved;
                        out.diagonal.push((v as usize, own, w.normalize()));
                    }
                }
            }
        }
        // A pinned vertex has no block to move.
        out.diagonal
            .retain(|&(v, _, _)| self.state.positions[v].w != 0.0);
        out
    }
}

fn mat_max(m: &Mat3) -> f32 {
    m.to_cols_array().iter().fold(0.0f32, |a, v| a.max(v.abs()))
}

fn block_diff(a: &[Mat3], b: &[Mat3]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| mat_max(&(*x - *y)))
        .fold(0.0, f32::max)
}

fn abs_vecs(a: &[Vec4]) -> Vec<Vec4> {
    a.iter().map(|v| v.abs()).collect()
}

fn abs_blocks(a: &[Mat3]) -> Vec<Mat3> {
    (a.iter())
        .map(|m| Mat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs()))
        .collect()
}

fn abs_weights(c: &Csr<(u32, f32)>) -> Csr<(u32, f32)> {
    Csr {
        offsets: c.offsets.clone(),
        items: c.items.iter().map(|&(i, w)| (i, w.abs())).collect(),
    }
}

fn longest_run<T>(c: &Csr<T>) -> usize {
    c.offsets
        .windows(2)
        .map(|w| (w[1] - w[0]) as usize)
        .max()
        .unwrap_or(0)
}

/// Asserts `diff <= bound` and says both.
fn within(what: &str, diff: f32, bound: f32) {
    eprintln!("  {what}: {diff:.2e} (bound {bound:.2e})");
    assert!(diff <= bound, "{what}: differs by {diff}, bound {bound}");
}

fn check_stages(label: &str, mut g: GpuSolver, mut c: Case) {
    eprintln!("{label}:");
    let n = c.prep.model.len();
    let mg = c.mg();
    let step = c.step;
    g.set_state(&c.state);

    // vbd_init: D⁰ = h·v and Y = D⁰ + h²·a, at most two roundings each that FMA contraction may
    // merge: one rounding of the largest |Y| (and |D⁰| ≤ that).
    g.run_passes(&[Pass::VbdInit], &[step]).unwrap();
    let scale = max_norm(&c.y).max(max_norm(&c.x));
    let x = g.solve_array(SolveArray::Displacement).unwrap();
    let y = g.solve_array(SolveArray::Target).unwrap();
    within("vbd_init D", max_abs_diff(&x, &c.x), 2.0 * EPS * scale);
    within("vbd_init Y", max_abs_diff(&y, &c.y), 2.0 * EPS * scale);
    g.set_solve_array(SolveArray::Displacement, &c.x).unwrap();
    g.set_solve_array(SolveArray::Target, &c.y).unwrap();

    check_contact_planes(&mut g, &mut c);
    check_sweep(&mut g, &mut c);
    let (force, blocks) = check_assemble(&mut g, &c, &mg);

    // The linear system's levels.
    let mut lv = vec![Level::new(n, blocks)];
    lv.extend(
        (mg.levels.iter()).map(|l| Level::new(l.len(), vec![Mat3::ZERO; l.pattern.blocks()])),
    );
    check_coarse_operators(&mut g, &mut lv, &mg, step);
    let mut correction = vec![Vec4::ZERO; n];
    let l0 = &mut lv[0];
    cpu::pcg_start(&force, &mut correction, &mut l0.rhs, &mut l0.e);
    g.set_solve_array(SolveArray::Force, &force).unwrap();
    g.run_solve_ops(&[SolveOp::PcgStart], &step).unwrap();
    // c = 0, r = f and z = 0 are copies: exact.
    assert_eq!(g.solve_array(SolveArray::Rhs(0)).unwrap(), lv[0].rhs);
    assert_eq!(
        g.solve_array(SolveArray::LevelCorrection(0)).unwrap(),
        lv[0].e
    );
    assert_eq!(g.solve_array(SolveArray::Correction).unwrap(), correction);

    // Two conjugate-gradient iterations, each after a V-cycle checked operation by operation.
    let schedule = g.solve_schedule().unwrap();
    let start = schedule
        .iter()
        .position(|op| matches!(op, SolveOp::Smooth { .. }));
    let end = schedule
        .iter()
        .position(|op| matches!(op, SolveOp::PcgDirection { .. }));
    let v_cycle = &schedule[start.unwrap()..end.unwrap()];
    let coloring = c.prep.model.vertex_coloring();
    let fine: Vec<Vec<u32>> = (coloring.offsets.windows(2))
        .map(|w| coloring.order[w[0] as usize..w[1] as usize].to_vec())
        .collect();
    let mut cg = Pcg {
        p: vec![Vec4::ZERO; n],
        correction,
        scalars: PcgScalars::default(),
    };
    for first in [true, false] {
        for &op in v_cycle {
            check_level_op(&mut g, &mut lv, (&mg, &fine), op, step);
        }
        check_pcg(&mut g, &mut lv, &mg, &mut cg, first, step);
    }
    let mut correction = cg.correction;

    check_line_search(&mut g, &mut c, &mut correction, &force);
    check_force_residual(&mut g, &c);
}

fn check_contact_planes(g: &mut GpuSolver, c: &mut Case) {
    let bodies = c.prep.params.num_bodies as usize;
    if bodies == 0 {
        return;
    }
    g.run_solve_ops(&[SolveOp::ContactPlanes], &c.step).unwrap();
    let sdfs: Vec<&[f32]> = (c.prep.model.colliders.iter())
        .map(|k| &k.sdf.values[..])
        .collect();
    let (mut planes, mut lambdas) = (c.planes.clone(), c.lambdas.clone());
    c.with(|s| cpu::contact_planes(s, &c.x, &sdfs, &mut planes, &mut lambdas));
    (c.planes, c.lambdas) = (planes, lambdas);
    let all = g.solve_array(SolveArray::Planes).unwrap();
    let (got, velocities) = all.split_at(bodies * c.prep.model.len());
    let (cpu_planes, cpu_velocities) = c.planes.split_at(bodies * c.prep.model.len());
    // The surface velocities: v + ω × (xₙ − t), each a few roundings (FMA may round each
    // differently) of terms up to |v| + |ω|·2 m (the scenes lie within 2 m of the bodies'
    // origins): 4ε of that.
    let v_scale = (c.step.bodies.iter().take(bodies))
        .map(|p| {
            Vec3::from_slice(&p.velocity).length()
                + 2.0 * Vec3::from_slice(&p.angular_velocity).length()
        })
        .fold(1e-3f32, f32::max);
    within(
        "contact_planes surface velocity (m/s)",
        max_abs_diff(velocities, cpu_velocities),
        4.0 * EPS * v_scale,
    );
    // Far from a body the plane is (0, SDF_FAR) on both.
    let near: Vec<(Vec4, Vec4)> = (got.iter().zip(cpu_planes))
        .filter(|(_, p)| p.w < 1.0)
        .map(|(a, b)| (*a, *b))
        .collect();
    assert!((got.iter().zip(cpu_planes)).all(|(a, b)| b.w < 1.0 || a == b));
    // The vertex's world position and its body-frame point are a few f32 operations on
    // coordinates of up to ~1.5 m (FMA may round one differently: 2ε·1.5 m ≈ 2e-7 m); that moves
    // the point within its 5 mm SDF cell by a fraction 4e-5 of the cell, so the trilinear
    // gradient (which changes by at most ~1 across a cell near a corner) by 4e-5, and φ by
    // 2e-7 m plus the interpolation's own rounding (a few ε of the node values, ≲ 1 m).
    // Bounds: 10× those.
    let cell_shift = 2.0 * EPS * 1.5 / 5e-3;
    let dn = (near.iter())
        .map(|(a, b)| (a.truncate() - b.truncate()).abs().max_element())
        .fold(0.0f32, f32::max);
    let dc = near
        .iter()
        .map(|(a, b)| (a.w - b.w).abs())
        .fold(0.0f32, f32::max);
    within("contact_planes normals", dn, 10.0 * cell_shift);
    within(
        "contact_planes c (m)",
        dc,
        10.0 * (2.0 * EPS * 1.5 + 8.0 * EPS),
    );
    // λ = max(−n̂·f, 0) with f the force without contact: the normal's difference times |f|,
    // plus f's own rounding (see check_assemble).
    let f_max = c.with(|s| {
        let free = drapekit::model::layout::SimParams {
            num_bodies: 0,
            ..*s.params
        };
        let s = Implicit {
            params: &free,
            ..*s
        };
        (0..c.prep.model.len())
            .map(|i| {
                s.vertex_system(i, &c.x, None, &mut |_, _| {})
                    .force
                    .length()
            })
            .fold(0.0f32, f32::max)
    });
    let force_bound = 16.0 * EPS * c.stiffest() * c.longest_edge();
    let dl = max_abs_diff(&g.solve_array(SolveArray::Lambdas).unwrap(), &c.lambdas);
    let touching = c.lambdas.iter().filter(|l| l.max_element() > 0.0).count();
    eprintln!(
        "  {} vertices near a body, {touching} with a normal force",
        near.len()
    );
    within(
        "contact_planes λ (N)",
        dl,
        10.0 * cell_shift * f_max + force_bound,
    );
    g.set_solve_array(SolveArray::Planes, &c.planes).unwrap();
    g.set_solve_array(SolveArray::Lambdas, &c.lambdas).unwrap();
}

fn check_sweep(g: &mut GpuSolver, c: &mut Case) {
    // One sweep over every colour (in place on both).
    let coloring = c.prep.model.vertex_coloring();
    let mut x = c.x.clone();
    let (mut steps, mut next) = ([0.0f32], Vec::new());
    let plan = cpu::SweepPlan::new(coloring.order.clone(), &coloring.offsets, x.len());
    c.with(|s| cpu::vbd_solve(s, (&plan, 0), &mut x, &mut steps, &mut next));
    // The solver's sweeps read the element lists laid out in their own order
    // (`Elements::in_order`): the same elements in the same order per vertex, so the same bits.
    let in_sweep_order = c.elements.in_order(&coloring.order);
    let mut x_in_order = c.x.clone();
    c.with_elements(Some(&in_sweep_order.view()), |s| {
        cpu::vbd_solve(s, (&plan, 0), &mut x_in_order, &mut steps, &mut next)
    });
    let bits = |v: &[Vec4]| -> Vec<u32> {
        v.iter()
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    assert!(
        bits(&x_in_order) == bits(&x),
        "a sweep over the lists in the sweep's order"
    );
    g.run_solve_ops(&[SolveOp::Sweep { iteration: 0 }], &c.step)
        .unwrap();
    let moved = max_abs_diff(&x, &c.x);
    assert!(moved > 1e-3, "the sweep moved nothing");
    // A vertex's Newton step is H⁻¹f; f's terms carry the rounding of the lengths they cancel
    // (|e| − L with |e| ≤ the longest edge ℓ: ε·ℓ relative to the stiffness that H⁻¹ divides
    // out), a few roundings per term: ≲ 16ε·ℓ per step. Later colours read the earlier ones'
    // new positions, and a Gauss–Seidel sweep passes such differences on undamped at most (H is
    // diagonally dominant), so they add up over the colours.
    // With buckling, a vertex's block H moves by δH = Σₑ Jₑ·c²·n̂ₑn̂ₑᵀ over its buckled
    // elements (`secant_jitter`), and its step Δ = H⁻¹f by H⁻¹·δH·Δ to first order, at most
    // Σₑ Jₑ·c²·|H⁻¹n̂ₑ|·|n̂ₑ·Δ| (H and Δ as the CPU's sweep has them, H taken at the sweep's
    // start); passed on over the colours alike.
    let mut secant = vec![0.0f32; x.len()];
    c.with(|s| {
        let mut inverse = std::collections::HashMap::new();
        for (v, moved, n) in c.secant_jitter(&c.x).diagonal {
            let h_inv = *inverse.entry(v).or_insert_with(|| {
                let h = s.vertex_system(v, &c.x, None, &mut |_, _| {}).hessian;
                h.inverse()
            });
            let step = (x[v] - c.x[v]).truncate();
            secant[v] += moved * (h_inv * n).length() * n.dot(step).abs();
        }
    });
    let secant = secant.into_iter().fold(0.0f32, f32::max);
    let bound = (16.0 * EPS * c.longest_edge() + secant) * coloring.colors() as f32;
    let got = g.solve_array(SolveArray::Displacement).unwrap();
    c.x = x;
    within("vbd_solve D (m)", max_abs_diff(&got, &c.x), bound);
    g.set_solve_array(SolveArray::Displacement, &c.x).unwrap();
}

fn check_assemble(g: &mut GpuSolver, c: &Case, mg: &Multigrid) -> (Vec<Vec4>, Vec<Mat3>) {
    g.run_solve_ops(&[SolveOp::Assemble], &c.step).unwrap();
    let n = c.prep.model.len();
    let mut force = vec![Vec4::ZERO; n];
    let mut blocks = vec![Mat3::ZERO; mg.fine.blocks()];
    let eb = &mg.element_blocks;
    c.with(|s| cpu::assemble(s, &c.x, &mg.fine, eb, &mut force, &mut blocks));
    // A force sums ≲ 40 terms, each at most the vertex's stiffness times the longest edge ℓ
    // (a spring's k·(|e| − L), contact's k_c·depth), each carrying a rounding or two of that:
    // 16ε·H·ℓ, as in check_sweep. A block sums ≲ 40 element blocks, each at most the largest
    // stiffness H, and the contact filter's products add a few roundings: 16ε·H.
    let stiffest = c
        .stiffest()
        .max(mat_max(&blocks.iter().fold(Mat3::ZERO, |a, b| {
            Mat3::from_cols(
                a.x_axis.max(b.x_axis.abs()),
                a.y_axis.max(b.y_axis.abs()),
                a.z_axis.max(b.z_axis.abs()),
            )
        })));
    let got_force = g.solve_array(SolveArray::Force).unwrap();
    let bound = 16.0 * EPS * stiffest * c.longest_edge();
    within(
        "assemble force (N)",
        max_abs_diff(&got_force, &force),
        bound,
    );
    let got_blocks = g.solve_blocks(0).unwrap();
    // Buckled elements' blocks also move with the rounding of their stretch (`secant_jitter`).
    let jitter = (c.secant_jitter(&c.x).row.into_iter()).fold(0.0f32, f32::max);
    within(
        "assemble blocks (N/m)",
        block_diff(&got_blocks, &blocks),
        16.0 * EPS * stiffest + jitter,
    );
    // Both go on from the CPU's.
    g.set_solve_blocks(0, &blocks).unwrap();
    (force, blocks)
}

/// The in-order total of per-workgroup partials (x, y, z: one trial step each).
fn total(partials: &[Vec4]) -> Vec4 {
    partials.iter().fold(Vec4::ZERO, |a, p| a + *p)
}

fn check_line_search(g: &mut GpuSolver, c: &mut Case, correction: &mut [Vec4], force: &[Vec4]) {
    let n = c.prep.model.len();
    let step = c.step;
    // The correction filter: c plus (or less) multiples of the normal that a few roundings of
    // |c| and of the distances to the layer (|φ|, ≲ the near planes' c + n̂·D) bound.
    let near_phi = (0..c.planes.len())
        .filter(|&k| c.planes[k].w < 1.0)
        .map(|k| (c.planes[k].w + c.planes[k].truncate().dot(c.x[k % n].truncate())).abs())
        .fold(0.0f32, f32::max);
    g.set_solve_array(SolveArray::Correction, correction)
        .unwrap();
    g.run_solve_ops(&[SolveOp::CorrectionFilter], &step)
        .unwrap();
    let before = max_norm(correction);
    c.with(|s| cpu::correction_filter(s, &c.x, correction));
    let got = g.solve_array(SolveArray::Correction).unwrap();
    within(
        "correction_filter",
        max_abs_diff(&got, correction),
        8.0 * EPS * (before + near_phi),
    );
    g.set_solve_array(SolveArray::Correction, correction)
        .unwrap();

    // The change of G at each trial step, summed over the vertices: compare the totals.
    g.run_solve_ops(&[SolveOp::LineEnergy], &step).unwrap();
    let mut partials = vec![Vec4::ZERO; n.div_ceil(64)];
    c.with(|s| cpu::line_energy(s, &c.x, correction, &mut partials));
    let got = g.solve_array(SolveArray::Partials).unwrap();
    let groups = partials.len();
    let (got_total, want_total) = (total(&got[..groups]), total(&partials));
    let diff = (got_total - want_total).truncate().abs().max_element();
    within("line_energy ΔG (J)", diff, line_energy_bound(c, correction));
    // The scale: a sum of sizes, each a few roundings of its own (the same 32ε).
    within(
        "line_energy scale (J)",
        (got_total.w - want_total.w).abs(),
        32.0 * EPS * want_total.w,
    );

    // G's slopes −f·c at the iterate (the assembled force, as set) and at the full step: a
    // force's difference (check_assemble's 16ε·H·ℓ per vertex) times |cᵢ|, summed, and the
    // sums' roundings relative to Σ|fᵢ·cᵢ| (≲ 64 + groups additions).
    g.run_solve_ops(&[SolveOp::LineSlopes], &step).unwrap();
    let mut slopes = vec![Vec4::ZERO; groups];
    c.with(|s| cpu::line_slopes(s, &c.x, correction, force, &mut slopes));
    let got = g.solve_array(SolveArray::Partials).unwrap();
    let sum_c: f32 = correction.iter().map(|v| v.truncate().length()).sum();
    let sum_fc: f32 = (force.iter().zip(correction.iter()))
        .map(|(f, v)| f.truncate().dot(v.truncate()).abs())
        .sum();
    let df = 16.0 * EPS * c.stiffest() * c.longest_edge();
    let slope_bound = df * sum_c + (64.0 + groups as f32) * EPS * 4.0 * sum_fc;
    let diff = (total(&got[groups..2 * groups]) - total(&slopes)).abs();
    within("line_slopes G′(0) (J)", diff.x, slope_bound);
    within("line_slopes G′(1) (J)", diff.y, slope_bound);

    // The line search from the CPU's partials: the same additions in the same order, the
    // same comparisons: the same step.
    let both: Vec<Vec4> = partials.iter().chain(&slopes).copied().collect();
    g.set_solve_array(SolveArray::Partials, &both).unwrap();
    g.run_solve_ops(&[SolveOp::LineSearch], &step).unwrap();
    let alpha = cpu::line_search(&partials, &slopes);
    assert_eq!(g.solve_scalars().unwrap().line_alpha, alpha, "line_search");
    eprintln!(
        "  line_search: α = {alpha} on both (ΔG {:?}, slopes {:?})",
        total(&partials),
        total(&slopes)
    );
    same_step_from_full_step(c, correction, force);

    // D += α·c with α = ½ (whatever the search chose): a rounding of |D| + |α·c|, FMA or not.
    let half = SolveScalars {
        line_alpha: 0.5,
        ..Default::default()
    };
    g.set_solve_scalars(half).unwrap();
    g.run_solve_ops(&[SolveOp::ApplyCorrection], &step).unwrap();
    let mut x = c.x.clone();
    cpu::apply_correction(0.5, correction, &mut x);
    let bound = 2.0 * EPS * (max_norm(&c.x) + 0.5 * max_norm(correction));
    let got = g.solve_array(SolveArray::Displacement).unwrap();
    within("apply_correction D (m)", max_abs_diff(&got, &x), bound);
    assert!(max_abs_diff(&x, &c.x) > 0.0, "the correction moved nothing");
    c.x = x;
    g.set_solve_array(SolveArray::Displacement, &c.x).unwrap();
}

/// The CPU solve's line search, which sums the shorter steps' changes only when the full step
/// raises G, chooses the step that the search over all three partials chooses, from the same
/// partials to the bit where it summed them: along the correction, along a sixteenth of it
/// (a short step down G: the full step is taken) and along 64 times it, whose full step (and
/// its half and quarter) overshoot the minimum along it, so that the shorter steps are summed
/// too. The partials start as NaN, as stale values from another step would be.
fn same_step_from_full_step(c: &Case, correction: &[Vec4], force: &[Vec4]) {
    for scale in [1.0f32, 1.0 / 16.0, 64.0] {
        let along: Vec<Vec4> = correction.iter().map(|v| *v * scale).collect();
        let mut all = vec![Vec4::ZERO; c.x.len().div_ceil(64)];
        let mut slopes = all.clone();
        c.with(|s| cpu::line_energy(s, &c.x, &along, &mut all));
        c.with(|s| cpu::line_slopes(s, &c.x, &along, force, &mut slopes));
        let (mut lazy, mut lazy_slopes) = (vec![Vec4::NAN; all.len()], vec![Vec4::NAN; all.len()]);
        let alpha = c.with(|s| {
            let partials = (&mut lazy[..], &mut lazy_slopes[..]);
            cpu::line_search_from_full_step(s, &c.x, &along, force, partials)
        });
        assert_eq!(
            alpha,
            cpu::line_search(&all, &slopes),
            "the step along {scale}·c"
        );
        let summed = if alpha == cpu::LINE_ALPHAS[0] { 1 } else { 3 };
        for (a, b) in all.iter().zip(&lazy) {
            assert_eq!(a.w.to_bits(), b.w.to_bits(), "the scale along {scale}·c");
            for k in 0..summed {
                assert_eq!(
                    a[k].to_bits(),
                    b[k].to_bits(),
                    "partial {k} along {scale}·c"
                );
            }
        }
        // Slopes the lazy search summed are the full search's, to the bit.
        if !lazy_slopes[0].x.is_nan() {
            for (a, b) in slopes.iter().zip(&lazy_slopes) {
                assert_eq!(a.x.to_bits(), b.x.to_bits(), "G′(0) along {scale}·c");
                assert_eq!(a.y.to_bits(), b.y.to_bits(), "G′(1) along {scale}·c");
            }
        }
        if scale > 1.0 {
            assert!(
                alpha < 1.0,
                "the full step along {scale}·c does not raise G"
            );
        }
        if scale < 1.0 {
            assert_eq!(alpha, 1.0, "the full step along {scale}·c raises G");
        }
    }
}

/// The scale of the terms the line energy sums: per vertex, the magnitude of the change of its
/// own terms (inertia, air, contact, friction) and of each kind of element it owns, each from
/// the CPU twin with only those elements (a membrane's change is already a difference of nearby
/// quantities, as a spring's); and each hinge's energy w₀·ψ, whose difference at two
/// angles cancels (|ψ| ≤ 2 + π·|sin(θ₀/2)|, evaluated four times). A term rounds a few times
/// relative to its own size, and ~10⁴ of them are added: 32ε of the total magnitude.
fn line_energy_bound(c: &Case, correction: &[Vec4]) -> f32 {
    let n = c.prep.model.len();
    let all = c.elements.view();
    let zeros = vec![0u32; n + 1];
    let none = VbdElements {
        row_of: None,
        springs: (&zeros, &[]),
        hinges: None,
        seams: None,
        membranes: None,
    };
    let springs = VbdElements {
        row_of: None,
        springs: all.springs,
        hinges: None,
        seams: None,
        membranes: None,
    };
    let hinges = VbdElements {
        row_of: None,
        springs: (&zeros, &[]),
        hinges: all.hinges,
        seams: None,
        membranes: None,
    };
    let seams = VbdElements {
        row_of: None,
        springs: (&zeros, &[]),
        hinges: None,
        seams: all.seams,
        membranes: None,
    };
    let membranes = VbdElements {
        row_of: None,
        springs: (&zeros, &[]),
        hinges: None,
        seams: None,
        membranes: all.membranes,
    };
    let change = |el: &VbdElements, i: usize| {
        c.with_elements(Some(el), |s| {
            Vec3::from(s.energy_change(i, &c.x, correction, cpu::LINE_ALPHAS))
        })
    };
    let mut magnitude = 0.0f32;
    for i in 0..n {
        let own = change(&none, i);
        magnitude += own.abs().max_element();
        for el in [&springs, &hinges, &seams, &membranes] {
            magnitude += (change(el, i) - own).abs().max_element();
        }
    }
    let psi = (c.prep.model.hinges.iter())
        .map(|h| h.rest_weight * (2.0 + std::f32::consts::PI * h.rest_sin_half.abs()))
        .sum::<f32>();
    32.0 * EPS * (magnitude + 4.0 * psi)
}

fn check_force_residual(g: &mut GpuSolver, c: &Case) {
    g.run_solve_ops(&[SolveOp::ForceResidual], &c.step).unwrap();
    let control = g.solve_control().unwrap();
    let mut partials = vec![Vec4::ZERO; c.prep.model.len().div_ceil(64)];
    c.with(|s| cpu::force_residual(s, &c.x, &mut partials));
    let (largest, rms) = cpu::reduce_residual(&partials);
    // |fᵢ|/(mᵢ·g): a force's difference (check_assemble's bound) over the lightest particle's
    // weight; the RMS differs by at most the largest difference, plus its sum's rounding.
    let g_mag = cpu::residual_gravity(c.prep.params.gravity);
    let lightest = c.state.positions.iter().map(|p| p.w).fold(0.0f32, f32::max);
    let df = 16.0 * EPS * c.stiffest() * c.longest_edge() * lightest / g_mag;
    within(
        "force_residual largest",
        (control.residual_max - largest).abs(),
        df + 4.0 * EPS * largest,
    );
    let groups = partials.len() as f32;
    within(
        "force_residual RMS",
        (control.residual_rms - rms).abs(),
        df + (groups + 9.0) * EPS * rms,
    );
    assert_eq!(control.done, 0, "no tolerance check ran");
}

/// A flat cotton sheet of 5 mm squares at 1.3 m (a shoulder's height), one interior vertex
/// lifted 5e-8 m, under half an f32 ulp of that height: the change of its assembled force is
/// its hinges' (the springs' change is of second order in the lift; inertia's is m/h² ≈ 0.2
/// N/m times the lift, 1e-8 N), and the GPU must resolve it as the CPU does. From world
/// positions xₙ + D the lift rounds away and the hinges' share (1.5e-6 N) is lost;
/// `tests/converged.rs` checks the CPU's against the hinge force in f64. Each backend's
/// hinge force is good to a few roundings of sin(θ/2) per hinge: w₀·|u|·8·EPS (EPS = 2⁻²⁴,
/// this file's rounding), doubled for the difference of two evaluations.
#[test]
fn a_lift_under_the_world_rounding_bends_the_hinges_on_the_gpu_as_on_the_cpu() {
    let Some(ctx) = gpu() else { return };
    let text = r#"
[cloth.grid]
width_m = 0.08
height_m = 0.08
columns = 17
rows = 17
center_m = [0.0, 1.3, 0.0]
plane = "xz"
[fabric]
preset = "cotton"
[world]
gravity_m_s2 = [0.0, 0.0, 0.0]
[solver]
fps = 24
frames = 1
substeps = 8
integrator = "implicit"
"#;
    let scene = Scene::parse(text, std::path::Path::new("lifted_sheet.toml")).unwrap();
    let prep = prepare(&scene).unwrap();
    assert!(
        prep.model.multigrid.is_some(),
        "the sheet has coarse levels"
    );
    let mut cpu = cpu::CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let state = cpu.state().unwrap();
    let step = substep_params(&prep, 1)[0];
    let mut g = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
    g.set_state(&state);
    g.run_passes(&[Pass::VbdInit], &[step]).unwrap();
    let c = Case::new(prep, state, step);
    // The middle vertex: 8 rows and 8 columns in.
    let i = 8 * 17 + 8;
    let lift = 5e-8f32;
    // An f32 in [1, 2) is a multiple of 2⁻²³: half of that rounds away.
    assert!(lift < 0.5 * f32::EPSILON, "under half an ulp at 1.3 m");
    let (flat, mut lifted) = (c.x.clone(), c.x.clone());
    lifted[i].y += lift;
    let mut change = |d: &[Vec4]| {
        g.set_solve_array(SolveArray::Displacement, d).unwrap();
        g.run_solve_ops(&[SolveOp::Assemble], &c.step).unwrap();
        let gpu = g.solve_array(SolveArray::Force).unwrap()[i].truncate();
        let cpu = c.with(|s| s.vertex_system(i, d, None, &mut |_, _| {}).force);
        (gpu, cpu)
    };
    let (gpu_flat, cpu_flat) = change(&flat);
    let (gpu_lifted, cpu_lifted) = change(&lifted);
    let (gpu, cpu) = (gpu_lifted - gpu_flat, cpu_lifted - cpu_flat);
    // w₀·|u| over the vertex's hinges, |u| ≤ |e|·(1/|n₁| + 1/|n₂|) for any role.
    let world = |v: u32| c.state.positions[v as usize].truncate();
    let el = c.elements.view();
    let (offsets, _, hinges) = el.hinges.expect("the sheet bends");
    let mut scale = 0.0f32;
    for h in &hinges[offsets[i] as usize..offsets[i + 1] as usize] {
        let [x3, x4, x1, x2] = h.v.map(world);
        let e = (x4 - x3).length();
        let (n1, n2) = ((x1 - x3).cross(x1 - x4), (x2 - x4).cross(x2 - x3));
        scale += h.rest_weight * e * (1.0 / n1.length() + 1.0 / n2.length());
    }
    let bound = 2.0 * 8.0 * EPS * scale;
    eprintln!("force change: gpu {gpu}, cpu {cpu} N; bound {bound} N");
    // A GPU that lost the hinges' share would be off by nearly the whole change: it must be
    // beyond the bound for the check to tell (measured: 2.7 times the bound).
    assert!(
        cpu.length() > 2.0 * bound,
        "the lift's force change {cpu} N stands out of the bound {bound} N"
    );
    within("lifted hinge force change (N)", (gpu - cpu).length(), bound);
}
