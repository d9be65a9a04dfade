//! `drapekit bench convergence SCENE`: how fast implicit Euler's solve balances the forces,
//! plain Vertex Block Descent against Newton steps with multigrid-preconditioned conjugate
//! gradients, on one fixed substep, at the scene's particle spacing and finer.
//!
//! The scene runs on the CPU at its own spacing to a representative frame (until it settles, or
//! `--frames`); that state is carried onto the finer meshings through the pattern (or grid)
//! coordinates, as the coarse start does, the finer mesh runs `relax_frames` frames from it
//! (the carried state's chords and penetrations are not what a run at that spacing meets), and
//! every method then solves the next substep from the same state.
//! Cost is counted in fine-sweep equivalents: the method's wall time over that of one Vertex
//! Block Descent sweep of the same mesh, measured in the same run.

use super::cpu_threads_description;
use super::fas::{Fas, FAS_COARSENING, FAS_COARSEST_PARTICLES, FAS_COARSE_SWEEPS};
use super::fas_levels::fas_levels;
use super::measured_state::{chart_of, continue_run, map_state, refined, representative_state};
use crate::atomic_file::write_atomic;
use crate::cpu::CpuSolver;
use crate::error::{Error, InputError};
use crate::model::layout::SubstepParams;
use crate::plan::{
    newton_correction, newton_correction_block_jacobi, Pass, SolveOp, SolveShape, LINEAR_ITERATIONS,
};
use crate::plot::{log_log_svg, Series};
use crate::scene::{ClothSource, Scene, INTEGRATOR_IMPLICIT};
use crate::sim::{phase_params, prepare, substep_params, Prepared, RunStats};
use crate::solver::{ParticleState, Solver};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What `drapekit bench convergence` measures.
#[derive(Clone, Debug)]
pub struct ConvergenceOptions {
    /// The scene (implicit Euler; a pattern or grid cloth).
    pub scene: PathBuf,
    /// Output folder.
    pub out: PathBuf,
    /// Frames to run before the measured substep (default: until the scene settles, at most
    /// its frames).
    pub frames: Option<u32>,
    /// Spacing divisors: 1 is the scene's, 2 and 4 twice and four times finer.
    pub refinements: Vec<u32>,
    /// The most Vertex Block Descent sweeps the plain solve runs.
    pub max_sweeps: u32,
    /// The most Newton steps.
    pub max_newton: u32,
    /// Frames a finer mesh runs from the carried state before its measured substep.
    pub relax_frames: u32,
    /// Conjugate-gradient iterations in each measured multigrid Newton step (the frames
    /// before it run the scene's solve, `LINEAR_ITERATIONS`).
    pub linear_iterations: u32,
    /// The FAS V-cycle's coarsening: each level's spacing this many times the one above
    /// (below 2: no FAS curve).
    pub fas_coarsening: u32,
    /// Sweeps on the FAS V-cycle's coarsest level in each cycle.
    pub fas_sweeps: u32,
}

/// One point of a method's curve.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvergenceRow {
    /// Spacing divisor.
    pub refinement: u32,
    /// Particles.
    pub particles: usize,
    /// "vbd", "newton-multigrid", "newton-block-jacobi" or "fas".
    pub method: &'static str,
    /// Sweeps (vbd), Newton steps or FAS cycles run so far.
    pub iterations: u32,
    /// Wall time so far over one sweep's.
    pub sweep_equivalents: f64,
    /// Wall time so far, in s.
    pub seconds: f64,
    /// Largest |f|/(m·g) over free particles.
    pub residual_max: f32,
    /// Its RMS.
    pub residual_rms: f32,
    /// Newton steps: how far the step's linear solve got, |f − H·c|/|f| for the Newton system
    /// H·c = f and the correction c its conjugate gradients found; `None` for sweeps.
    pub linear_residual: Option<f32>,
    /// Newton steps and FAS cycles: the step length α the line search took along the
    /// correction (0: refused); `None` for sweeps.
    pub step_length: Option<f32>,
}

/// Runs the benchmark and writes `convergence.csv`, `convergence.md` and `convergence.svg`.
pub fn run_cli(opts: &ConvergenceOptions) -> Result<Vec<ConvergenceRow>, Error> {
    let scene = Scene::load(&opts.scene)?;
    check_scene(&scene)?;
    let (base, state, stats, frame) = representative_state(&scene, opts.frames)?;
    let mut rows = Vec::new();
    for &r in &opts.refinements {
        let fine = refined(&scene, r);
        let prep = prepare(&fine)?;
        if prep.model.multigrid.is_none() {
            return Err(bad(
                &scene,
                "multigrid",
                &format!(
                    "the cloth of {} particles has no coarser levels, which the Newton steps \
                     measured here need",
                    prep.model.len()
                ),
                "use a cloth of more than 40 particles (a grid of at least 4 by 4), or a finer \
                 --refinements",
            ));
        }
        let mapped = map_state((&scene, &base), &state, (&fine, &prep), frame)?;
        let relax = if r == 1 { 0 } else { opts.relax_frames };
        let (relaxed, at) = continue_run(&prep, mapped, &stats, frame, relax)?;
        let level = Level {
            scene: &fine,
            prep: &prep,
            refinement: r,
        };
        rows.extend(measure(&level, &relaxed, &stats, at, opts)?);
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    write_atomic(&opts.out.join("convergence.csv"), csv(&rows).as_bytes())?;
    write_atomic(
        &opts.out.join("convergence.md"),
        report(opts, &rows, frame).as_bytes(),
    )?;
    plot(&rows, &opts.out.join("convergence.svg"))?;
    Ok(rows)
}

fn bad(scene: &Scene, key: &str, problem: &str, fix: &str) -> Error {
    Error::Input(scene.error("solver", key, problem, fix))
}

fn check_scene(scene: &Scene) -> Result<(), Error> {
    if scene.solver.integrator != INTEGRATOR_IMPLICIT {
        return Err(bad(
            scene,
            "integrator",
            "the benchmark compares implicit Euler's solves; this scene is not implicit",
            "use a scene with integrator = \"implicit\"",
        ));
    }
    if matches!(scene.cloth, ClothSource::Mesh { .. }) {
        return Err(Error::Input(InputError::new(
            &scene.path,
            "cloth.mesh",
            "a cloth loaded from a mesh has no coarser meshings for the multigrid solve",
            "use a scene whose cloth is a [cloth.grid] or a [cloth.pattern]",
        )));
    }
    Ok(())
}

/// The meshing a curve is measured on.
struct Level<'a> {
    scene: &'a Scene,
    prep: &'a Prepared,
    /// Its spacing divisor.
    refinement: u32,
}

/// One point of a curve, before it is costed in sweeps: sweeps, steps or cycles so far, their
/// wall time, the force residual (largest, RMS), the linear solve's residual and the step
/// length.
struct Point {
    iterations: u32,
    seconds: f64,
    residual: (f32, f32),
    linear: Option<f32>,
    alpha: Option<f32>,
}

/// Every method's curve on the substep after `frame`.
fn measure(
    level: &Level,
    state: &ParticleState,
    stats: &RunStats,
    frame: u32,
    opts: &ConvergenceOptions,
) -> Result<Vec<ConvergenceRow>, Error> {
    let prep = level.prep;
    let params = phase_params(prep, frame, stats);
    let step = substep_params(prep, frame + 1)[0];
    let mut solver = CpuSolver::new(&prep.model, params, &prep.plan);
    let shape = SolveShape::for_run(&prep.model, &params, &prep.plan);
    let fresh = |solver: &mut CpuSolver| {
        solver.set_state(state);
        solver.run_pass(Pass::VbdInit, &step);
        if shape.bodies {
            run_ops(solver, &[SolveOp::ContactPlanes], &step);
        }
    };
    fresh(&mut solver);
    let sweeps = sweep_curve(&mut solver, &step, opts.max_sweeps);
    let last = sweeps.last().expect("at least one sweep");
    let sweep = last.seconds / last.iterations as f64;
    let mut curves = vec![("vbd", sweeps)];
    // Newton steps, each after its sweeps: preconditioned by the V-cycle, and by the block
    // diagonal alone (the single-level alternative).
    let methods = [
        (
            "newton-multigrid",
            newton_correction(SolveShape {
                linear_iterations: opts.linear_iterations,
                ..shape
            }),
        ),
        (
            "newton-block-jacobi",
            newton_correction_block_jacobi(BLOCK_JACOBI_ITERATIONS),
        ),
    ];
    for (method, ops) in methods {
        fresh(&mut solver);
        let mut correction = vec![SolveOp::Sweep { iteration: 0 }; shape.smoothing as usize];
        correction.extend(ops);
        curves.push((
            method,
            newton_curve(&mut solver, &step, &correction, opts.max_newton),
        ));
    }
    let fas = fas_levels(
        (level.scene, level.prep),
        (frame, stats),
        (shape.smoothing, opts.fas_coarsening, opts.fas_sweeps),
        chart_of,
    )?;
    if let Some(mut fas) = fas {
        fresh(&mut solver);
        let cycles = opts.max_newton;
        curves.push((
            "fas",
            fas_curve(&mut fas, &mut solver, (state, &step), shape, cycles),
        ));
    }
    let row = |method, p: Point| ConvergenceRow {
        refinement: level.refinement,
        particles: prep.model.len(),
        method,
        iterations: p.iterations,
        sweep_equivalents: p.seconds / sweep,
        seconds: p.seconds,
        residual_max: p.residual.0,
        residual_rms: p.residual.1,
        linear_residual: p.linear,
        step_length: p.alpha,
    };
    Ok((curves.into_iter())
        .flat_map(|(method, points)| points.into_iter().map(move |p| row(method, p)))
        .collect())
}

/// Plain sweeps of one solve: the residual after 1, 2, 4, … and `max` sweeps.
fn sweep_curve(solver: &mut CpuSolver, step: &SubstepParams, max: u32) -> Vec<Point> {
    let mut curve = Vec::new();
    let (mut seconds, mut done) = (0.0, 0);
    let mut next = 1;
    while done < max {
        let chunk = next - done;
        seconds += run_ops(
            solver,
            &vec![SolveOp::Sweep { iteration: 0 }; chunk as usize],
            step,
        );
        done = next;
        curve.push(Point {
            iterations: done,
            seconds,
            residual: residual(solver, step),
            linear: None,
            alpha: None,
        });
        next = (next * 2).min(max);
    }
    curve
}

/// `steps` Newton steps, each the operations `correction` (its sweeps, then the correction).
fn newton_curve(
    solver: &mut CpuSolver,
    step: &SubstepParams,
    correction: &[SolveOp],
    steps: u32,
) -> Vec<Point> {
    // The linear solve's residual is measured (untimed) where its conjugate gradients end,
    // before the contact filter and the line search change the correction.
    let solved = (correction.iter())
        .position(|&op| op == SolveOp::CorrectionFilter)
        .unwrap_or(correction.len());
    let (linear_solve, rest) = correction.split_at(solved);
    let mut seconds = 0.0;
    let mut curve = Vec::new();
    for k in 1..=steps {
        seconds += run_ops(solver, linear_solve, step);
        let linear = linear_residual(solver);
        seconds += run_ops(solver, rest, step);
        curve.push(Point {
            iterations: k,
            seconds,
            residual: residual(solver, step),
            linear,
            alpha: last_step_length(solver),
        });
    }
    curve
}

/// `cycles` FAS cycles on `solver`'s substep `step` from `state` (the solve fresh from
/// `vbd_init`). A cycle is `shape.smoothing` sweeps, the coarse correction and as many sweeps
/// again (the prolongated correction is smooth only to the coarse triangles' size; the sweeps
/// take out what it leaves at the fine scale).
fn fas_curve(
    fas: &mut Fas,
    solver: &mut CpuSolver,
    (state, step): (&ParticleState, &SubstepParams),
    shape: SolveShape,
    cycles: u32,
) -> Vec<Point> {
    let timer = Instant::now();
    fas.start(state, step, shape.bodies);
    let mut seconds = timer.elapsed().as_secs_f64();
    let sweeps = vec![SolveOp::Sweep { iteration: 0 }; shape.smoothing as usize];
    let mut curve = Vec::new();
    for k in 1..=cycles {
        seconds += run_ops(solver, &sweeps, step);
        let timer = Instant::now();
        let alpha = fas.cycle(solver, step);
        seconds += timer.elapsed().as_secs_f64();
        seconds += run_ops(solver, &sweeps, step);
        curve.push(Point {
            iterations: k,
            seconds,
            residual: residual(solver, step),
            linear: None,
            alpha: Some(alpha),
        });
    }
    curve
}

/// Conjugate-gradient iterations per Newton step with the block-Jacobi preconditioner: a
/// one-level preconditioner needs iterations in proportion to the cloth's width in particles to
/// carry load across it (64: the 2 cm T-shirt is about 30 rings from shoulder to hem).
pub const BLOCK_JACOBI_ITERATIONS: u32 = 64;

/// Runs `ops` on the solver's implicit solve and returns their wall time.
fn run_ops(solver: &mut CpuSolver, ops: &[SolveOp], step: &SubstepParams) -> f64 {
    let start = Instant::now();
    solver.run_solve_ops(ops, step);
    start.elapsed().as_secs_f64()
}

/// |f − H·c|/|f| of the Newton system H·c = f as its conjugate gradients left it: the true
/// residual, recomputed from the correction (not the iteration's running residual, which
/// drifts from it by rounding), both norms summed as the kernels sum them.
fn linear_residual(solver: &CpuSolver) -> Option<f32> {
    let newton = solver.vbd.as_ref()?.newton.as_ref()?;
    let f = &newton.force;
    let mut r = vec![glam::Vec4::ZERO; f.len()];
    (newton.levels[0].by_colour).residual(f, &newton.correction, &mut r);
    let ff = crate::cpu::dot(f, f);
    // A balanced start (f = 0) leaves nothing to solve: no ratio.
    (ff > 0.0).then(|| (crate::cpu::dot(&r, &r) / ff).sqrt())
}

/// The step length of the last Newton step's line search.
fn last_step_length(solver: &CpuSolver) -> Option<f32> {
    let newton = solver.vbd.as_ref()?.newton.as_ref()?;
    newton.alphas.last().copied()
}

/// The force residual at the iterate (not timed).
fn residual(solver: &mut CpuSolver, step: &SubstepParams) -> (f32, f32) {
    solver.run_solve_ops(&[SolveOp::ForceResidual], step);
    solver.vbd.as_ref().map_or((0.0, 0.0), |v| v.residual)
}

fn csv(rows: &[ConvergenceRow]) -> String {
    let mut out = String::from(
        "refinement,particles,method,iterations,sweep_equivalents,seconds,residual_max,residual_rms,linear_residual,step_length\n",
    );
    for r in rows {
        out += &format!(
            "{},{},{},{},{:.3},{:.6},{:.4e},{:.4e},{},{}\n",
            r.refinement,
            r.particles,
            r.method,
            r.iterations,
            r.sweep_equivalents,
            r.seconds,
            r.residual_max,
            r.residual_rms,
            r.linear_residual
                .map_or(String::new(), |l| format!("{l:.4e}")),
            r.step_length.map_or(String::new(), |a| a.to_string()),
        );
    }
    out
}

/// The cheapest point of a method's curve at `refinement` with an RMS residual at most
/// `target`: its sweep equivalents.
fn cost_to(rows: &[ConvergenceRow], refinement: u32, method: &str, target: f32) -> Option<f64> {
    rows.iter()
        .filter(|r| r.refinement == refinement && r.method == method && r.residual_rms <= target)
        .map(|r| r.sweep_equivalents)
        .fold(None, |best: Option<f64>, c| {
            Some(best.map_or(c, |b| b.min(c)))
        })
}

/// How many of `method`'s steps at `refinement` the line search refused (α = 0), as "k of n"
/// ("-" without steps).
fn refused(rows: &[ConvergenceRow], refinement: u32, method: &str) -> String {
    let steps: Vec<f32> = (rows.iter())
        .filter(|r| r.refinement == refinement && r.method == method)
        .filter_map(|r| r.step_length)
        .collect();
    if steps.is_empty() {
        return "-".into();
    }
    let zero = steps.iter().filter(|&&a| a == 0.0).count();
    format!("{zero} of {}", steps.len())
}

/// The Newton steps' mean RMS reduction per step over the first `steps` (geometric mean).
pub fn reduction_per_step(rows: &[ConvergenceRow], refinement: u32, steps: u32) -> Option<f64> {
    let curve: Vec<&ConvergenceRow> = rows
        .iter()
        .filter(|r| r.refinement == refinement && r.method == "newton-multigrid")
        .collect();
    let first = rows
        .iter()
        .find(|r| r.refinement == refinement && r.method == "vbd" && r.iterations == 1)?;
    let last = curve.iter().find(|r| r.iterations == steps)?;
    Some((last.residual_rms as f64 / first.residual_rms as f64).powf(1.0 / steps as f64))
}

/// The options that repeat this measurement, as `drapekit bench convergence` takes them.
fn command_options(opts: &ConvergenceOptions) -> String {
    let list = |v: &[u32]| v.iter().map(u32::to_string).collect::<Vec<_>>().join(",");
    let mut s = format!(
        " --refinements {} --max-sweeps {} --max-newton {} --relax-frames {}",
        list(&opts.refinements),
        opts.max_sweeps,
        opts.max_newton,
        opts.relax_frames
    );
    if opts.linear_iterations != LINEAR_ITERATIONS {
        s += &format!(" --linear-iterations {}", opts.linear_iterations);
    }
    if opts.fas_coarsening != FAS_COARSENING {
        s += &format!(" --fas-coarsening {}", opts.fas_coarsening);
    }
    if opts.fas_sweeps != FAS_COARSE_SWEEPS {
        s += &format!(" --fas-sweeps {}", opts.fas_sweeps);
    }
    if let Some(f) = opts.frames {
        s += &format!(" --frames {f}");
    }
    s
}

fn report(opts: &ConvergenceOptions, rows: &[ConvergenceRow], frame: u32) -> String {
    let mut md = format!(
        "# Convergence of implicit Euler's solve\n\n\
         `drapekit bench convergence {} --out {}{}`: the substep after frame {frame}, from the \
         same state, on the CPU ({}). Cost in fine-sweep equivalents (wall time over one Vertex \
         Block Descent sweep of the same mesh); residual |f|/(m·g) over the free particles.\n\n\
         | spacing ÷ | particles | VBD to RMS 0.1 | Newton to RMS 0.1 | VBD to RMS 0.01 | Newton to RMS 0.01 | Newton, block Jacobi, to RMS 0.01 | FAS to RMS 0.01 | FAS cycles refused | Newton's RMS reduction per step (first 4) |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
        opts.scene.display(),
        opts.out.display(),
        command_options(opts),
        cpu_threads_description(),
    );
    let cell = |c: Option<f64>| c.map_or("not reached".to_string(), |v| format!("{v:.0}"));
    for &r in &opts.refinements {
        let particles = rows
            .iter()
            .find(|x| x.refinement == r)
            .map_or(0, |x| x.particles);
        md += &format!(
            "| {r} | {particles} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            cell(cost_to(rows, r, "vbd", 0.1)),
            cell(cost_to(rows, r, "newton-multigrid", 0.1)),
            cell(cost_to(rows, r, "vbd", 0.01)),
            cell(cost_to(rows, r, "newton-multigrid", 0.01)),
            cell(cost_to(rows, r, "newton-block-jacobi", 0.01)),
            cell(cost_to(rows, r, "fas", 0.01)),
            refused(rows, r, "fas"),
            reduction_per_step(rows, r, 4).map_or("-".into(), |v| format!("{v:.2}")),
        );
    }
    md += &format!(
        "\nVBD ran at most {} sweeps; Newton at most {} steps, each with {} \
         conjugate-gradient iterations preconditioned by a multigrid V-cycle, or with \
         {BLOCK_JACOBI_ITERATIONS} \
         preconditioned by the block diagonal, each after the scene's `smoothing_sweeps` \
         sweeps.{} The full curves are \
         in convergence.csv and convergence.svg (`linear_residual`: how far each Newton \
         step's linear solve got, |f − H·c|/|f|; `step_length`: the line search's α).{}\n",
        opts.max_sweeps,
        opts.max_newton,
        opts.linear_iterations,
        fas_note(opts),
        if opts.linear_iterations == LINEAR_ITERATIONS {
            String::new()
        } else {
            format!(
                " The frames before the measured substep solved as the scene does, with \
                 {LINEAR_ITERATIONS} iterations."
            )
        }
    );
    md
}

/// The report's sentence on the FAS curve, if there is one.
fn fas_note(opts: &ConvergenceOptions) -> String {
    if opts.fas_coarsening < 2 {
        return String::new();
    }
    format!(
        " FAS: at most {} V-cycles of nonlinear multigrid, each between those sweeps and as \
         many again, each level the cloth meshed {}× coarser, down to at most \
         {FAS_COARSEST_PARTICLES} particles or the first level with no coarse levels of its \
         own, {} sweeps on the coarsest, the correction taken through the Newton step's line \
         search (a refused cycle is its sweeps alone).",
        opts.max_newton, opts.fas_coarsening, opts.fas_sweeps
    )
}

fn plot(rows: &[ConvergenceRow], path: &Path) -> Result<(), Error> {
    let mut series: Vec<Series> = Vec::new();
    for r in rows {
        let name = format!("{} ({} particles)", r.method, r.particles);
        let point = (
            r.sweep_equivalents.max(1e-3),
            (r.residual_rms as f64).max(1e-9),
        );
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push(point),
            None => series.push(Series {
                name,
                points: vec![point],
            }),
        }
    }
    log_log_svg(
        &series,
        "Force residual against cost, one substep",
        "fine-sweep equivalents",
        "RMS |f| / (m g)",
        path,
    )
}
