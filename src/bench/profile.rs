//! `drapekit bench profile`: where the GPU's time goes in a substep, stage by stage (and
//! kernel by kernel, level by level, in the implicit solve), from GPU timestamps: the benchmark
//! cloth at several sizes, and optionally a scene as it runs. Beside it, each case's wall time
//! per substep unprofiled, so launch overhead shows as the difference.

use crate::atomic_file::write_atomic;
use crate::error::Error;
use crate::gpu::profile::StageTime;
use crate::gpu::{AdapterChoice, GpuContext, GpuSolver};
use crate::scene::Scene;
use crate::sim::{prepare, simulate, RunStats};
use crate::solver::Solver;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What `bench profile` runs.
pub struct ProfileOptions {
    /// Benchmark-cloth sizes (N: an N×N grid, symplectic Euler).
    pub sizes: Vec<u32>,
    /// Substeps profiled (and timed unprofiled) per size.
    pub substeps: u32,
    /// A scene run on the GPU with its own integrator, profiled over `frames` frames.
    pub scene: Option<PathBuf>,
    /// Output frames of the scene.
    pub frames: u32,
    /// The adapter.
    pub adapter: AdapterChoice,
    /// Output folder for profile.csv and profile.md.
    pub out: PathBuf,
    /// The command line, for the report's header.
    pub command: String,
}

/// One profiled case: a grid size or the scene.
pub struct ProfileCase {
    /// "grid 256²" or the scene's file name.
    pub name: String,
    /// Particles.
    pub particles: usize,
    /// Substeps profiled.
    pub substeps: u64,
    /// Wall seconds per substep without timestamps (substeps batched as the solver does).
    pub wall_per_substep: f64,
    /// GPU time per label, summed over the profiled substeps.
    pub stages: Vec<StageTime>,
    /// Dispatch groups left untimed.
    pub dropped: u64,
}

impl ProfileCase {
    /// GPU seconds, all labels and substeps together.
    pub fn gpu_seconds(&self) -> f64 {
        self.stages.iter().map(|s| s.seconds).sum()
    }

    /// GPU seconds per substep, all labels together.
    pub fn gpu_per_substep(&self) -> f64 {
        self.gpu_seconds() / self.substeps.max(1) as f64
    }
}

/// Runs every case and writes profile.csv and profile.md.
pub fn run_cli(o: &ProfileOptions) -> Result<Vec<ProfileCase>, Error> {
    let ctx = GpuContext::open_with_timestamps(&o.adapter)?;
    let mut cases = Vec::new();
    for &n in &o.sizes {
        let case = grid_case(&ctx, n, o.substeps)?;
        print_case(&case);
        cases.push(case);
    }
    if let Some(path) = &o.scene {
        let case = scene_case(&ctx, path, o.frames)?;
        print_case(&case);
        cases.push(case);
    }
    write_report(o, &ctx, &cases)?;
    Ok(cases)
}

/// The benchmark cloth at `n`×`n`: `substeps` substeps timed in one submission (the median of
/// three, after `grid::warm_up`), then the same count profiled one substep a submission.
fn grid_case(ctx: &GpuContext, n: u32, substeps: u32) -> Result<ProfileCase, Error> {
    let n = n.max(2);
    let (model, params, plan) = super::bench_model(n);
    let steps = super::bench_steps(substeps.max(1), params.dt);
    let mut gpu = GpuSolver::new(ctx, &model, params, &plan, steps.len())?;
    let wall_per_substep = super::grid::median_batch(&mut gpu, &steps, 3)? / steps.len() as f64;
    gpu.start_profile()?;
    gpu.advance(&steps)?;
    gpu.finish()?;
    let profile = gpu.profile().expect("started above");
    Ok(ProfileCase {
        name: format!("grid {n}²"),
        particles: model.len(),
        substeps: profile.substeps(),
        wall_per_substep,
        stages: profile.totals().to_vec(),
        dropped: profile.dropped(),
    })
}

/// The scene on the GPU with its own integrator and step: `frames` frames unprofiled, then
/// `frames` more profiled (the settle rule off, so both run every frame).
fn scene_case(ctx: &GpuContext, path: &Path, frames: u32) -> Result<ProfileCase, Error> {
    let mut scene = Scene::load(path)?;
    scene.solver.frames = frames.max(1);
    scene.solver.settle_speed = None;
    let prep = prepare(&scene)?;
    let mut gpu = GpuSolver::new(
        ctx,
        &prep.model,
        prep.params,
        &prep.plan,
        prep.substeps as usize,
    )?;
    let mut stats = RunStats::default();
    simulate(&prep, &mut gpu, &mut stats, |_, _| Ok(()))?;
    let substeps = stats.frames_run as f64 * prep.substeps as f64;
    let wall_per_substep = stats.wall_seconds / substeps.max(1.0);
    gpu.start_profile()?;
    let mut profiled = RunStats::default();
    simulate(&prep, &mut gpu, &mut profiled, |_, _| Ok(()))?;
    let profile = gpu.profile().expect("started above");
    let name = path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    );
    Ok(ProfileCase {
        name,
        particles: prep.model.len(),
        substeps: profile.substeps(),
        wall_per_substep,
        stages: profile.totals().to_vec(),
        dropped: profile.dropped(),
    })
}

fn print_case(c: &ProfileCase) {
    println!(
        "{}: {} particles, {:.1} µs GPU and {:.1} µs wall per substep",
        c.name,
        c.particles,
        c.gpu_per_substep() * 1e6,
        c.wall_per_substep * 1e6
    );
    for s in &c.stages {
        println!(
            "  {:<28} {:>10.2} µs/substep  {:>5.1}%",
            s.label,
            s.seconds / c.substeps.max(1) as f64 * 1e6,
            share(s, c)
        );
    }
}

/// A stage's percentage of its case's GPU time.
fn share(s: &StageTime, c: &ProfileCase) -> f64 {
    100.0 * s.seconds / c.gpu_seconds().max(f64::MIN_POSITIVE)
}

fn write_report(o: &ProfileOptions, ctx: &GpuContext, cases: &[ProfileCase]) -> Result<(), Error> {
    let a = ctx.report();
    let device = format!(
        "{} ({}, {}, {})",
        a.name,
        a.backend,
        a.device_type,
        ctx.layout.name()
    );
    let mut csv = String::from(
        "case,particles,substeps,wall_us_per_substep,gpu_us_per_substep,stage,\
         dispatches_per_substep,stage_us_per_substep,share,device\n",
    );
    let mut md = format!(
        "`{}`\n\nGPU time per substep from timestamps after every stage (one substep a \
         submission; a scene's once-a-frame health check, `monitor`, spread over the frame's \
         substeps), and wall time per substep without them; device: {device}.\n",
        o.command
    );
    for c in cases {
        let per = |x: f64| x / c.substeps.max(1) as f64;
        let _ = write!(
            md,
            "\n### {} ({} particles)\n\nGPU {:.1} µs, wall {:.1} µs per substep ({} substeps \
             profiled{}).\n\n| stage | dispatches/substep | µs/substep | share |\n|---|---|---|---|\n",
            c.name,
            c.particles,
            c.gpu_per_substep() * 1e6,
            c.wall_per_substep * 1e6,
            c.substeps,
            match c.dropped {
                0 => String::new(),
                d => format!(", {d} dispatch groups untimed"),
            }
        );
        for s in &c.stages {
            let _ = writeln!(
                csv,
                "\"{}\",{},{},{:.3},{:.3},\"{}\",{:.2},{:.3},{:.2},\"{device}\"",
                c.name,
                c.particles,
                c.substeps,
                c.wall_per_substep * 1e6,
                c.gpu_per_substep() * 1e6,
                s.label,
                per(s.dispatches as f64),
                per(s.seconds) * 1e6,
                share(s, c)
            );
            let _ = writeln!(
                md,
                "| {} | {:.1} | {:.2} | {:.1}% |",
                s.label,
                per(s.dispatches as f64),
                per(s.seconds) * 1e6,
                share(s, c)
            );
        }
    }
    std::fs::create_dir_all(&o.out).map_err(|e| Error::io(&o.out, e))?;
    write_atomic(&o.out.join("profile.csv"), csv.as_bytes())?;
    write_atomic(&o.out.join("profile.md"), md.as_bytes())?;
    println!(
        "wrote {} and {}",
        o.out.join("profile.csv").display(),
        o.out.join("profile.md").display()
    );
    Ok(())
}
