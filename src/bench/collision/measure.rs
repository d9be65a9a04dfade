//! The contenders' structures, the warm-up that records the states every contender sees, and
//! the timing and contact comparison on those states.

use super::{deforming, CollisionOptions, CollisionRow, Contender};
use crate::body::bvh::BodyBvh;
use crate::body::edges::BodyEdges;
use crate::body::exact::ExactBody;
use crate::body::sdf::Sdf;
use crate::body::{Collider, Strategy};
use crate::cpu::{to_body_frame, CpuSolver};
use crate::error::Error;
use crate::gpu::{GpuContext, GpuSolver};
use crate::model::layout::{SimParams, SubstepParams};
use crate::plan::{Pass, PassPlan};
use crate::scene::BodySettings;
use crate::sim::{phase_params, simulate_from, substep_params, Prepared, RunStats};
use crate::solver::{ParticleState, Solver};
use glam::{Vec3, Vec4};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// A contender's collider, with what building it cost.
pub struct Built {
    /// The contender.
    pub contender: Contender,
    /// Its collider (the same body, SDF and motion as the scene's).
    pub collider: Arc<Collider>,
    /// Seconds to build its structure.
    pub build_s: f64,
    /// Bytes of its structure.
    pub memory_bytes: usize,
}

/// Builds every contender's collider from the prepared scene's body, timing each structure.
/// `exact` is always built: it is the reference for contacts.
pub fn build_all(
    prep: &Prepared,
    settings: &BodySettings,
    contenders: &[Contender],
) -> Result<Vec<Built>, Error> {
    let base = prep.model.colliders.first().expect("the scene has a body");
    let failed = |e: String| Error::Unstable(format!("building a collision structure: {e}"));
    // The scene's SDF may have come from the cache: bake it again to time the bake.
    let start = Instant::now();
    let sdf =
        Sdf::bake(&base.body, settings.sdf_resolution, settings.sdf_margin).map_err(failed)?;
    let bake_s = start.elapsed().as_secs_f64();
    // A deforming body's SDF also holds the words its collision reads after the rest pose's
    // nodes: the scene's, whose rest-pose part was just timed.
    let sdf = match base.deformed {
        Some(_) => base.sdf.clone(),
        None => sdf,
    };
    let mesh = &base.body.mesh;
    let mut all: Vec<Contender> = contenders.to_vec();
    if !all.contains(&Contender::Cpu(Strategy::Exact)) {
        all.push(Contender::Cpu(Strategy::Exact));
    }
    let mut built = Vec::new();
    for contender in all {
        let exact_start = Instant::now();
        let exact = ExactBody::new(mesh).map_err(failed)?;
        let exact_s = exact_start.elapsed().as_secs_f64();
        let (strategy, mut bvh, mut edges) = (Strategy::Exact, None, None);
        let (strategy, build_s, memory_bytes) = match contender {
            Contender::GpuSdf | Contender::Cpu(Strategy::Sdf) => {
                (Strategy::Sdf, bake_s, 4 * sdf.values.len())
            }
            Contender::Cpu(Strategy::Exact) => (strategy, exact_s, exact.heap_bytes()),
            Contender::ExactEdges => {
                let start = Instant::now();
                let e = BodyEdges::new(mesh);
                let edge_s = start.elapsed().as_secs_f64();
                let bytes = exact.heap_bytes() + e.heap_bytes();
                edges = Some(e);
                (strategy, exact_s + edge_s, bytes)
            }
            Contender::Cpu(Strategy::Brute) => {
                let bytes = std::mem::size_of_val(&mesh.positions[..])
                    + std::mem::size_of_val(&mesh.triangles[..]);
                (Strategy::Brute, 0.0, bytes)
            }
            Contender::Cpu(s) => {
                let kind = s.volume().expect("the remaining strategies are BVHs");
                let start = Instant::now();
                let b = BodyBvh::new(mesh, kind);
                let seconds = start.elapsed().as_secs_f64();
                let bytes = b.heap_bytes();
                bvh = Some(b);
                (s, seconds, bytes)
            }
        };
        let collider = Collider {
            body: base.body.clone(),
            sdf: sdf.clone(),
            exact,
            motion: base.motion.clone(),
            strategy,
            bvh,
            edges,
            bake: base.bake.clone(),
            deformed: base.deformed.clone(),
        };
        built.push(Built {
            contender,
            collider: Arc::new(collider),
            build_s,
            memory_bytes,
        });
    }
    Ok(built)
}

/// A state every contender starts from.
pub struct Sample {
    /// The output frame whose end it is.
    pub frame: u32,
    /// The state at the end of the frame.
    pub state: ParticleState,
    /// The run-constant parameters then (gravity on, friction as sewn).
    pub params: SimParams,
    /// The next frame's substeps.
    pub steps: Vec<SubstepParams>,
    /// The state the collision stage receives in the next frame's first substep.
    pub pre: ParticleState,
}

/// `count` frames spread evenly over the body's motion (over the second half of the run if the
/// body holds still).
pub fn sample_frames(prep: &Prepared, count: usize) -> Vec<u32> {
    let end = prep.frames as f32 * prep.frame_dt;
    let body = prep.model.colliders.first().expect("a body");
    let motion = &body.motion;
    let (t0, t1) = match (motion.moves(), motion.keys.first(), motion.keys.last()) {
        (true, Some(a), Some(b)) => (a.time.min(end), b.time.min(end)),
        // A deforming body: over its last play of the motion that the run reaches.
        _ if body.deformed.is_some() => {
            let d = &body.deformed.as_ref().expect("checked").deformation;
            let last = d.end().min(end);
            ((last - d.motion_length()).max(0.0), last)
        }
        _ => (0.5 * end, end),
    };
    let mut frames: Vec<u32> = (0..count)
        .map(|k| {
            let t = t0 + (k as f32 + 0.5) * (t1 - t0) / count as f32;
            let frame = ((t / prep.frame_dt).round() as u32).clamp(1, prep.frames.max(1));
            // Attached particles are released after their last frame: a sample there would
            // still hold them, which no substep of the next frame does.
            match !prep.attached.is_empty() && frame == prep.attach_frames {
                true => frame + 1,
                false => frame,
            }
        })
        .collect();
    frames.dedup();
    frames
}

/// Runs the scene on the CPU (SDF strategy) to the last sample frame and records each sample
/// and the state its collision stage receives.
pub fn warm_up(prep: &Prepared, count: usize) -> Result<Vec<Sample>, Error> {
    let frames = sample_frames(prep, count);
    let mut run = prep.clone();
    run.frames = *frames.last().expect("at least one sample");
    let mut solver = CpuSolver::new(&run.model, run.params, &run.plan);
    let mut stats = RunStats::default();
    let mut taken: Vec<(u32, ParticleState, SimParams)> = Vec::new();
    simulate_from(
        &run,
        &mut solver,
        &mut stats,
        None,
        |frame, state, stats| {
            if frame > 0 && frame % 12 == 0 {
                println!("  warm-up frame {frame} of {}", run.frames);
            }
            if frames.contains(&frame) {
                taken.push((frame, state.clone(), phase_params(prep, frame, stats)));
            }
            Ok(())
        },
    )?;
    // The whole plan, so that an implicit solve keeps its contact term, less the stage itself.
    let mut stage = Backend::Cpu(Box::new(CpuSolver::new(
        &prep.model,
        prep.params,
        &prep.plan,
    )));
    taken
        .into_iter()
        .map(|(frame, state, params)| {
            let steps = substep_params(prep, frame + 1);
            stage.solver().set_params(&params);
            stage.solver().set_state(&state);
            stage.advance_without_collision(&steps[..1])?;
            let pre = stage.solver().state()?;
            Ok(Sample {
                frame,
                state,
                params,
                steps,
                pre,
            })
        })
        .collect()
}

/// A solver of either backend that can also run its plan less the collision stage.
enum Backend {
    Cpu(Box<CpuSolver>),
    Gpu(Box<GpuSolver>),
}

impl Backend {
    fn solver(&mut self) -> &mut dyn Solver {
        match self {
            Backend::Cpu(s) => s.as_mut(),
            Backend::Gpu(s) => s.as_mut(),
        }
    }

    /// Every stage of the plan but `collide_body`, once per step.
    fn advance_without_collision(&mut self, steps: &[SubstepParams]) -> Result<(), Error> {
        let without = |passes: &[Pass]| -> Vec<Pass> {
            (passes.iter().copied())
                .filter(|&p| p != Pass::CollideBody)
                .collect()
        };
        match self {
            Backend::Cpu(s) => {
                let passes = without(&s.plan().passes);
                for step in steps {
                    for &pass in &passes {
                        s.run_pass(pass, step);
                    }
                }
                Ok(())
            }
            Backend::Gpu(s) => s.run_passes(&without(s.passes()), steps),
        }
    }
}

/// Substeps per timed batch of the GPU's stage alone: one stage is too short to time, and a
/// batch of 100 puts it well above the batch's fixed cost on lavapipe.
pub(super) const GPU_STAGE_BATCH: usize = 100;

/// The particles a collision stage moved (position or velocity changed; pinned ones never).
fn moved(before: &ParticleState, after: &ParticleState) -> Vec<bool> {
    (before.positions.iter().zip(&after.positions))
        .zip(before.velocities.iter().zip(&after.velocities))
        .map(|((p, q), (v, w))| {
            p.w != 0.0 && (p.truncate() != q.truncate() || v.truncate() != w.truncate())
        })
        .collect()
}

/// The deepest any particle, and any cloth-edge midpoint, lies inside the exact body at
/// `step` (a rigid body at its pose then, a deforming one rebuilt then), in m (0 when nothing
/// is inside).
fn deepest(
    reference: &Collider,
    step: &SubstepParams,
    dt: f32,
    pos: &[Vec4],
    edges: &[[u32; 2]],
) -> Result<(f32, f32), Error> {
    if reference.deformed.is_some() {
        let exact = deforming::exact(&deforming::mesh_at(reference, step, dt))?;
        let depth = |x: Vec3| (-exact.query(x).0).max(0.0);
        return Ok(deepest_by(depth, pos, edges));
    }
    let pose = &step.bodies[0];
    let exact = &reference.exact;
    let depth = |x: Vec3| (-exact.query(to_body_frame(pose, x).0).0).max(0.0);
    Ok(deepest_by(depth, pos, edges))
}

fn deepest_by(depth: impl Fn(Vec3) -> f32 + Sync, pos: &[Vec4], edges: &[[u32; 2]]) -> (f32, f32) {
    let particles = pos
        .par_iter()
        .map(|p| depth(p.truncate()))
        .reduce(|| 0.0, f32::max);
    let midpoints = (edges.par_iter())
        .map(|e| depth(0.5 * (pos[e[0] as usize] + pos[e[1] as usize]).truncate()))
        .reduce(|| 0.0, f32::max);
    (particles, midpoints)
}

/// One contender's solvers at one size: its collision stage alone, a whole substep, and (GPU)
/// a plan with no pass, whose batch cost the stage's time excludes.
struct Runner {
    alone: Backend,
    whole: Backend,
    empty: Option<Backend>,
    repeats: usize,
    window: usize,
    row: CollisionRow,
}

fn solver(
    ctx: Option<&GpuContext>,
    prep: &Prepared,
    collider: &Arc<Collider>,
    passes: Vec<Pass>,
    batch: usize,
) -> Result<Backend, Error> {
    let mut model = prep.model.clone();
    model.colliders = vec![collider.clone()];
    let plan = PassPlan {
        passes,
        hinges: prep.plan.hinges,
    };
    Ok(match ctx {
        None => Backend::Cpu(Box::new(CpuSolver::new(&model, prep.params, &plan))),
        Some(ctx) => Backend::Gpu(Box::new(GpuSolver::new(
            ctx,
            &model,
            prep.params,
            &plan,
            batch,
        )?)),
    })
}

/// Seconds per substep of `steps` from the sample's state, with the collision stage or
/// without it: the faster of two runs, since a window's first run on a fresh solver also pays
/// for first use (on the GPU, the first dispatch of each pipeline).
fn window_seconds(
    b: &mut Backend,
    s: &Sample,
    steps: &[SubstepParams],
    collide: bool,
) -> Result<f64, Error> {
    let mut fastest = f64::INFINITY;
    for _ in 0..2 {
        b.solver().set_params(&s.params);
        b.solver().set_state(&s.state);
        let start = Instant::now();
        match collide {
            true => b.solver().advance(steps)?,
            false => b.advance_without_collision(steps)?,
        }
        b.solver().finish()?;
        fastest = fastest.min(start.elapsed().as_secs_f64() / steps.len() as f64);
    }
    Ok(fastest)
}

/// Times every contender on every sample (in turns, so that a change in the machine's load
/// falls on all alike) and compares its contacts with `exact`'s.
pub fn measure(
    prep: &Prepared,
    samples: &[Sample],
    built: &[&Built],
    ctx: Option<&GpuContext>,
    opts: &CollisionOptions,
) -> Result<Vec<CollisionRow>, Error> {
    // A deforming body's rebuilt contenders, timed apart from the solver.
    let body = &prep.model.colliders.first().expect("a body");
    let mut rebuilt: Vec<CollisionRow> = match body.deformed.is_some() {
        true => (deforming::REBUILT.iter())
            .filter(|c| built.iter().any(|b| b.contender == **c))
            .filter(|c| opts.contenders.is_empty() || opts.contenders.iter().any(|n| n == c.name()))
            .map(|&c| {
                let (n, t) = (prep.model.len(), body.body.mesh.triangles.len());
                let mut row = deforming::row(c, n, t, samples.len(), opts.repeats.max(1));
                row.window_substeps = opts.window.clamp(1, prep.substeps as usize);
                row
            })
            .collect(),
        false => Vec::new(),
    };
    let window = opts.window.clamp(1, prep.substeps as usize);
    let reference = (built.iter())
        .find(|b| b.contender == Contender::Cpu(Strategy::Exact))
        .expect("exact is always built");
    let alone_plan = || vec![Pass::CollideBody];
    let mut exact_alone = solver(None, prep, &reference.collider, alone_plan(), 1)?;
    let edges: Vec<[u32; 2]> = prep.model.springs.iter().map(|s| s.ends).collect();
    let exact = &reference.collider;
    let deformed = exact.deformed.is_some();
    let dt = prep.params.dt;
    // The plan less the collision stage, per backend: what a substep costs without it.
    let sdf = (built.iter())
        .find(|b| {
            matches!(
                b.contender,
                Contender::GpuSdf | Contender::Cpu(Strategy::Sdf)
            )
        })
        .map_or(&reference.collider, |b| &b.collider);
    let full = || prep.plan.passes.clone();
    let mut without_cpu = solver(None, prep, sdf, full(), window)?;
    let mut without_gpu = match ctx {
        Some(_) if built.iter().any(|b| b.contender == Contender::GpuSdf) => {
            Some(solver(ctx, prep, sdf, full(), window)?)
        }
        _ => None,
    };
    let mut runners = Vec::new();
    for &b in built {
        if !opts.contenders.is_empty() && !opts.contenders.iter().any(|n| n == b.contender.name()) {
            continue;
        }
        // On a deforming body only the SDF contenders run through the solver.
        if deformed
            && !matches!(
                b.contender,
                Contender::GpuSdf | Contender::Cpu(Strategy::Sdf)
            )
        {
            continue;
        }
        let gpu = (b.contender == Contender::GpuSdf).then_some(ctx).flatten();
        let brute = b.contender == Contender::Cpu(Strategy::Brute);
        // Every particle against every triangle takes about a second a stage: at most two
        // stages and two substeps.
        let (repeats, window) = if brute {
            (opts.repeats.clamp(1, 2), window.min(2))
        } else {
            (opts.repeats.max(1), window)
        };
        let collider = &b.collider;
        runners.push(Runner {
            alone: solver(gpu, prep, collider, alone_plan(), GPU_STAGE_BATCH)?,
            whole: solver(gpu, prep, collider, full(), window)?,
            empty: match gpu {
                Some(_) => Some(solver(gpu, prep, collider, Vec::new(), GPU_STAGE_BATCH)?),
                None => None,
            },
            repeats,
            window,
            row: CollisionRow {
                samples: samples.len(),
                repeats,
                window_substeps: window,
                build_s: b.build_s,
                memory_bytes: b.memory_bytes,
                ..CollisionRow::new(
                    b.contender,
                    prep.model.len(),
                    collider.body.mesh.triangles.len(),
                    note(b.contender),
                )
            },
        });
    }
    let most = runners.iter().map(|r| r.repeats).max().unwrap_or(0);
    for s in samples {
        println!("  sample at frame {}", s.frame);
        let first = &s.steps[..1];
        let thickness = s.params.bodies[0].thickness;
        let truth = match deformed {
            true => {
                let mesh = deforming::mesh_at(exact, &first[0], dt);
                deforming::truth(&deforming::exact(&mesh)?, &s.pre.positions, thickness)
            }
            false => {
                let x = exact_alone.solver();
                x.set_params(&s.params);
                x.set_state(&s.pre);
                x.advance(first)?;
                moved(&s.pre, &x.state()?)
            }
        };
        // The fastest stage and (GPU) the fastest empty batch, each the least disturbed.
        let mut fastest = vec![(f64::INFINITY, f64::INFINITY); runners.len()];
        for round in 0..most {
            for (r, best) in runners.iter_mut().zip(&mut fastest) {
                if round >= r.repeats {
                    continue;
                }
                let (stage, empty) = stage_seconds(r, s)?;
                *best = (best.0.min(stage), best.1.min(empty));
            }
        }
        for (r, best) in runners.iter_mut().zip(fastest) {
            // The contacts, and what the stage leaves inside the body.
            let alone = r.alone.solver();
            alone.set_state(&s.pre);
            alone.advance(first)?;
            let after = alone.state()?;
            let found = moved(&s.pre, &after);
            let (d, e) = deepest(exact, &first[0], dt, &after.positions, &edges)?;
            let row = &mut r.row;
            row.collision_us += 1e6 * (best.0 - best.1) / samples.len() as f64;
            row.contacts += found.iter().filter(|&&m| m).count();
            row.exact_contacts += truth.iter().filter(|&&m| m).count();
            row.missed += truth.iter().zip(&found).filter(|(&t, &f)| t && !f).count();
            row.extra += truth.iter().zip(&found).filter(|(&t, &f)| f && !t).count();
            row.max_penetration = row.max_penetration.max(d);
            row.max_edge_penetration = row.max_edge_penetration.max(e);
        }
        // The plan without the stage is timed before each contender's window, in turns with
        // them, and its fastest run counts: the least disturbed figure, as for everything else.
        let steps = &s.steps[..window];
        let (mut bare_cpu, mut bare_gpu) = (f64::INFINITY, f64::INFINITY);
        let mut with = Vec::new();
        for r in runners.iter_mut() {
            match (r.row.contender, without_gpu.as_mut()) {
                (Contender::GpuSdf, Some(g)) => {
                    bare_gpu = bare_gpu.min(window_seconds(g, s, steps, false)?)
                }
                _ => bare_cpu = bare_cpu.min(window_seconds(&mut without_cpu, s, steps, false)?),
            }
            let steps = &s.steps[..r.window];
            with.push(window_seconds(&mut r.whole, s, steps, true)?);
            let end = r.whole.solver().state()?;
            let last = &steps[steps.len() - 1];
            let (d, e) = deepest(exact, last, dt, &end.positions, &edges)?;
            let row = &mut r.row;
            row.max_penetration = row.max_penetration.max(d);
            row.max_edge_penetration = row.max_edge_penetration.max(e);
        }
        for (r, seconds) in runners.iter_mut().zip(with) {
            let bare = match r.row.contender {
                Contender::GpuSdf => bare_gpu,
                _ => bare_cpu,
            };
            let row = &mut r.row;
            row.substep_us += 1e6 * seconds / samples.len() as f64;
            row.in_run_us += 1e6 * (seconds - bare) / samples.len() as f64;
        }
        if !rebuilt.is_empty() {
            if bare_cpu.is_infinite() {
                bare_cpu = window_seconds(&mut without_cpu, s, steps, false)?;
            }
            let mesh = deforming::mesh_at(exact, &first[0], dt);
            for row in rebuilt.iter_mut() {
                rebuilt_sample(row, &mesh, s, &truth, bare_cpu, samples.len())?;
            }
        }
    }
    let mut rows: Vec<CollisionRow> = runners.into_iter().map(|r| r.row).collect();
    rows.extend(rebuilt);
    Ok(rows)
}

/// A rebuilt contender's figures on one sample: the fastest of its repeats (the structure's
/// build time from the same run), its contacts against `truth`, and a substep as the plan
/// less collision (`bare`, s) plus its stage.
fn rebuilt_sample(
    row: &mut CollisionRow,
    mesh: &crate::mesh::TriMesh,
    s: &Sample,
    truth: &[bool],
    bare: f64,
    samples: usize,
) -> Result<(), Error> {
    let thickness = s.params.bodies[0].thickness;
    let mut best: Option<(f64, f64, usize, Vec<bool>)> = None;
    for _ in 0..row.repeats.max(1) {
        let run = deforming::rebuilt_stage(row.contender, mesh, &s.pre.positions, thickness)?;
        if best.as_ref().is_none_or(|b| run.0 < b.0) {
            best = Some(run);
        }
    }
    let (stage, build, bytes, found) = best.expect("at least one repeat");
    let n = samples as f64;
    row.collision_us += 1e6 * stage / n;
    row.in_run_us += 1e6 * stage / n;
    row.substep_us += 1e6 * (bare + stage) / n;
    row.build_s += build / n;
    row.memory_bytes = row.memory_bytes.max(bytes);
    row.contacts += found.iter().filter(|&&m| m).count();
    row.exact_contacts += truth.iter().filter(|&&m| m).count();
    row.missed += truth.iter().zip(&found).filter(|(&t, &f)| t && !f).count();
    row.extra += truth.iter().zip(&found).filter(|(&t, &f)| f && !t).count();
    Ok(())
}

/// One timed collision stage on the sample's state and the fixed cost to take off it, in s.
/// On the CPU an untimed stage on the same state runs first, so that the structures the other
/// contenders pushed out of the caches are back; the GPU runs a batch of the same substep,
/// and an empty plan's batch measures the fixed cost of a submission.
fn stage_seconds(r: &mut Runner, s: &Sample) -> Result<(f64, f64), Error> {
    let first = &s.steps[..1];
    let Some(empty) = r.empty.as_mut() else {
        let alone = r.alone.solver();
        alone.set_params(&s.params);
        // Brute force takes a second a stage: its caches are not what limits it.
        if r.row.contender != Contender::Cpu(Strategy::Brute) {
            alone.set_state(&s.pre);
            alone.advance(first)?;
        }
        alone.set_state(&s.pre);
        let start = Instant::now();
        alone.advance(first)?;
        return Ok((start.elapsed().as_secs_f64(), 0.0));
    };
    let batch = vec![s.steps[0]; GPU_STAGE_BATCH];
    let time = |solver: &mut dyn Solver| -> Result<f64, Error> {
        solver.set_params(&s.params);
        solver.set_state(&s.pre);
        let start = Instant::now();
        solver.advance(&batch)?;
        solver.finish()?;
        Ok(start.elapsed().as_secs_f64() / batch.len() as f64)
    };
    Ok((time(r.alone.solver())?, time(empty.solver())?))
}

/// What to know about a contender's figures.
fn note(c: Contender) -> String {
    match c {
        Contender::GpuSdf => "alone: a batch of the same substep less an empty batch".into(),
        Contender::Cpu(Strategy::Brute) => {
            "first size only; at most two timed stages and two substeps".into()
        }
        Contender::Cpu(Strategy::Exact) => "the reference for contacts".into(),
        _ => String::new(),
    }
}
