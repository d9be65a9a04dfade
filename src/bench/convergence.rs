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
use crate::atomic_file::write_atomic;
use crate::cpu::CpuSolver;
use crate::error::{Error, InputError};
use crate::mesh::Charted;
use crate::plan::{
    newton_correction, newton_correction_block_jacobi, Pass, SolveOp, SolveShape, LINEAR_ITERATIONS,
};
use crate::plot::{log_log_svg, Series};
use crate::scene::{ClothSource, Scene, INTEGRATOR_IMPLICIT};
use crate::sim::{phase_params, prepare, simulate, substep_params, Prepared, RunStats};
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
}

/// One point of a method's curve.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvergenceRow {
    /// Spacing divisor.
    pub refinement: u32,
    /// Particles.
    pub particles: usize,
    /// "vbd", "newton-multigrid" or "newton-block-jacobi".
    pub method: &'static str,
    /// Sweeps (vbd) or Newton steps run so far.
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
        let mapped = map_state(&scene, &base, &state, &fine, &prep)?;
        let relax = if r == 1 { 0 } else { opts.relax_frames };
        let (relaxed, at) = continue_run(&prep, mapped, &stats, frame, relax)?;
        rows.extend(measure(&prep, &relaxed, &stats, at, r, opts)?);
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

/// The scene with its particle spacing divided by `r`.
fn refined(scene: &Scene, r: u32) -> Scene {
    let mut s = scene.clone();
    match &mut s.cloth {
        ClothSource::Pattern { options, .. } => options.particle_distance /= r as f64,
        ClothSource::Grid { columns, rows, .. } => {
            *columns = (*columns - 1) * r + 1;
            *rows = (*rows - 1) * r + 1;
        }
        ClothSource::Mesh { .. } => {}
    }
    s.solver.multigrid = true;
    s.solver.strain_limit = None;
    s
}

/// The scene run on the CPU to its representative frame: its prepared run, the state, the run's
/// stats and the frame.
fn representative_state(
    scene: &Scene,
    frames: Option<u32>,
) -> Result<(Prepared, ParticleState, RunStats, u32), Error> {
    let mut prep = prepare(&refined(scene, 1))?;
    if let Some(f) = frames {
        prep.frames = f;
        prep.settle_speed = None;
    }
    let mut solver = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut stats = RunStats::default();
    let mut last = solver.state()?;
    simulate(&prep, &mut solver, &mut stats, |_, s| {
        last = s.clone();
        Ok(())
    })?;
    let frame = stats.frames_run;
    Ok((prep, last, stats, frame))
}

/// `frames` more frames of `prep` from `state` at the end of frame `frame`: the state then, and
/// the frame.
fn continue_run(
    prep: &Prepared,
    state: ParticleState,
    stats: &RunStats,
    frame: u32,
    frames: u32,
) -> Result<(ParticleState, u32), Error> {
    if frames == 0 {
        return Ok((state, frame));
    }
    let params = phase_params(prep, frame, stats);
    let mut solver = CpuSolver::new(&prep.model, params, &prep.plan);
    solver.set_state(&state);
    for f in frame + 1..=frame + frames {
        solver.advance(&substep_params(prep, f))?;
    }
    Ok((solver.state()?, frame + frames))
}

/// The cloth's chart coordinates (pattern panels or grid plane).
fn charted(scene: &Scene, prep: &Prepared) -> Option<Charted> {
    match &scene.cloth {
        ClothSource::Grid {
            width,
            height,
            columns,
            rows,
            ..
        } => Some(Charted::grid(*width, *height, *columns, *rows)),
        _ => prep.garment.as_ref().map(|g| g.charted()),
    }
}

/// `state` of the scene's own meshing carried onto `fine`'s particles through the charts.
fn map_state(
    scene: &Scene,
    base: &Prepared,
    state: &ParticleState,
    fine_scene: &Scene,
    fine: &Prepared,
) -> Result<ParticleState, Error> {
    let (Some(from), Some(to)) = (charted(scene, base), charted(fine_scene, fine)) else {
        return Err(bad(
            scene,
            "multigrid",
            "the cloth has no chart coordinates to carry its state between meshings",
            "use a grid or pattern cloth",
        ));
    };
    let transfer = crate::pattern::transfer::Transfer::between(&from, &to);
    let positions = transfer.apply(&state.positions);
    let velocities = transfer.apply(&state.velocities);
    let packed = fine.model.packed_positions();
    Ok(ParticleState {
        positions: (positions.iter().zip(&packed))
            .map(|(p, q)| if q.w == 0.0 { *q } else { p.extend(q.w) })
            .collect(),
        velocities: (velocities.iter().zip(&packed))
            .map(|(v, q)| {
                if q.w == 0.0 {
                    glam::Vec4::ZERO
                } else {
                    v.extend(0.0)
                }
            })
            .collect(),
    })
}

/// Both methods' curves on the substep after `frame`.
fn measure(
    prep: &Prepared,
    state: &ParticleState,
    stats: &RunStats,
    frame: u32,
    refinement: u32,
    opts: &ConvergenceOptions,
) -> Result<Vec<ConvergenceRow>, Error> {
    let params = phase_params(prep, frame, stats);
    let step = substep_params(prep, frame + 1)[0];
    let mut solver = CpuSolver::new(&prep.model, params, &prep.plan);
    let shape = SolveShape::for_run(&prep.model, &params, &prep.plan);
    let bodies = shape.bodies;
    let fresh = |solver: &mut CpuSolver| -> Result<(), Error> {
        solver.set_state(state);
        solver.run_pass(Pass::VbdInit, &step);
        if bodies {
            run_ops(solver, &[SolveOp::ContactPlanes], &step);
        }
        Ok(())
    };
    let row =
        |method, iterations, seconds: f64, sweep: f64, r: (f32, f32), linear| ConvergenceRow {
            refinement,
            particles: prep.model.len(),
            method,
            iterations,
            sweep_equivalents: seconds / sweep,
            seconds,
            residual_max: r.0,
            residual_rms: r.1,
            linear_residual: linear,
        };
    let mut rows = Vec::new();
    // Plain sweeps: the residual after 1, 2, 4, … sweeps of one solve.
    fresh(&mut solver)?;
    let mut curve = Vec::new();
    let (mut seconds, mut done) = (0.0, 0);
    let mut next = 1;
    while done < opts.max_sweeps {
        let chunk = next - done;
        seconds += run_ops(
            &mut solver,
            &vec![SolveOp::Sweep { iteration: 0 }; chunk as usize],
            &step,
        );
        done = next;
        curve.push((done, seconds, residual(&mut solver, &step)));
        next = (next * 2).min(opts.max_sweeps);
    }
    let sweep = seconds / done as f64;
    rows.extend(
        curve
            .into_iter()
            .map(|(k, s, r)| row("vbd", k, s, sweep, r, None)),
    );
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
        fresh(&mut solver)?;
        let mut correction = vec![SolveOp::Sweep { iteration: 0 }; shape.smoothing as usize];
        correction.extend(ops);
        // The linear solve's residual is measured (untimed) where its conjugate gradients end,
        // before the contact filter and the line search change the correction.
        let solved = (correction.iter())
            .position(|&op| op == SolveOp::CorrectionFilter)
            .unwrap_or(correction.len());
        let (linear_solve, rest) = correction.split_at(solved);
        let mut seconds = 0.0;
        for k in 1..=opts.max_newton {
            seconds += run_ops(&mut solver, linear_solve, &step);
            let linear = linear_residual(&solver);
            seconds += run_ops(&mut solver, rest, &step);
            let r = residual(&mut solver, &step);
            rows.push(row(method, k, seconds, sweep, r, linear));
        }
    }
    Ok(rows)
}

/// Conjugate-gradient iterations per Newton step with the block-Jacobi preconditioner: a
/// one-level preconditioner needs iterations in proportion to the cloth's width in particles to
/// carry load across it (64: the 2 cm T-shirt is about 30 rings from shoulder to hem).
pub const BLOCK_JACOBI_ITERATIONS: u32 = 64;

/// Runs `ops` on the solver's implicit solve and returns their wall time.
fn run_ops(
    solver: &mut CpuSolver,
    ops: &[SolveOp],
    step: &crate::model::layout::SubstepParams,
) -> f64 {
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

/// The force residual at the iterate (not timed).
fn residual(solver: &mut CpuSolver, step: &crate::model::layout::SubstepParams) -> (f32, f32) {
    solver.run_solve_ops(&[SolveOp::ForceResidual], step);
    solver.vbd.as_ref().map_or((0.0, 0.0), |v| v.residual)
}

fn csv(rows: &[ConvergenceRow]) -> String {
    let mut out = String::from(
        "refinement,particles,method,iterations,sweep_equivalents,seconds,residual_max,residual_rms,linear_residual\n",
    );
    for r in rows {
        out += &format!(
            "{},{},{},{},{:.3},{:.6},{:.4e},{:.4e},{}\n",
            r.refinement,
            r.particles,
            r.method,
            r.iterations,
            r.sweep_equivalents,
            r.seconds,
            r.residual_max,
            r.residual_rms,
            r.linear_residual
                .map_or(String::new(), |l| format!("{l:.4e}"))
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
         | spacing ÷ | particles | VBD to RMS 0.1 | Newton to RMS 0.1 | VBD to RMS 0.01 | Newton to RMS 0.01 | Newton, block Jacobi, to RMS 0.01 | Newton's RMS reduction per step (first 4) |\n\
         |---|---|---|---|---|---|---|---|\n",
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
            "| {r} | {particles} | {} | {} | {} | {} | {} | {} |\n",
            cell(cost_to(rows, r, "vbd", 0.1)),
            cell(cost_to(rows, r, "newton-multigrid", 0.1)),
            cell(cost_to(rows, r, "vbd", 0.01)),
            cell(cost_to(rows, r, "newton-multigrid", 0.01)),
            cell(cost_to(rows, r, "newton-block-jacobi", 0.01)),
            reduction_per_step(rows, r, 4).map_or("-".into(), |v| format!("{v:.2}")),
        );
    }
    md += &format!(
        "\nVBD ran at most {} sweeps; Newton at most {} steps, each with {} \
         conjugate-gradient iterations preconditioned by a multigrid V-cycle, or with \
         {BLOCK_JACOBI_ITERATIONS} \
         preconditioned by the block diagonal. The full curves are in convergence.csv and \
         convergence.svg (`linear_residual`: how far each Newton step's linear solve got, \
         |f − H·c|/|f|).{}\n",
        opts.max_sweeps,
        opts.max_newton,
        opts.linear_iterations,
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
