//! `drapekit bench --sizes …`: whole-substep throughput on both backends, as CSV and Markdown tables and
//! an SVG plot.
//! The criterion benches in `benches/` use the same model builder, so the two agree on what
//! "a substep at 256²" means.

use super::cpu_threads_description;
use crate::atomic_file::write_atomic;
use crate::cpu::CpuSolver;
use crate::error::Error;
use crate::gpu::{AdapterChoice, GpuContext, GpuSolver};
use crate::mesh::{GridPlane, TriMesh};
use crate::model::layout::{SimParams, SubstepParams, INTEGRATOR_SYMPLECTIC};
use crate::model::ClothModel;
use crate::plan::{Effects, PassPlan};
use crate::plot::Series;
use crate::scene::Fabric;
use crate::solver::Solver;
use glam::Vec3;
use std::path::Path;
use std::time::Instant;

/// The benchmark cloth: an `n × n` grid, 1 m square, hanging from its two top corners, with
/// springs and bending (no wind), and its plan and parameters.
pub fn bench_model(n: u32) -> (ClothModel, SimParams, PassPlan) {
    let mesh = TriMesh::grid(1.0, 1.0, n, n, Vec3::new(0.0, 1.0, 0.0), GridPlane::Xy);
    let fabric = Fabric::linear(500.0);
    let model = ClothModel::from_mesh(&mesh, &fabric, &[(n - 1) * n, n * n - 1]);
    let plan = PassPlan::new(
        &model,
        Effects {
            bending: true,
            wind: false,
            body: false,
            self_collision: false,
            implicit: false,
            strain_limit: false,
        },
    );
    let dt = 0.5 * model.stable_dt(INTEGRATOR_SYMPLECTIC, 0.0).unwrap_or(1e-4);
    let params = SimParams {
        gravity: [0.0, -9.81, 0.0, 0.0],
        num_particles: model.len() as u32,
        integrator: INTEGRATOR_SYMPLECTIC,
        dt,
        ..Default::default()
    };
    (model, params, plan)
}

/// `count` substeps' parameters starting at time 0.
pub fn bench_steps(count: u32, dt: f32) -> Vec<SubstepParams> {
    (0..count)
        .map(|s| SubstepParams {
            time: s as f32 * dt,
            substep: s,
            ..Default::default()
        })
        .collect()
}

/// One row of the benchmark table.
#[derive(Clone, Debug)]
pub struct BenchRow {
    /// Grid side.
    pub size: u32,
    /// Particles.
    pub particles: usize,
    /// "cpu" or "gpu".
    pub backend: String,
    /// Adapter or CPU description.
    pub device: String,
    /// Median seconds per batch.
    pub median_seconds: f64,
    /// Particle-substeps per second at the median.
    pub particle_substeps_per_second: f64,
}

/// Untimed work before a size is timed: a GPU left idle while the CPU twin ran (seconds at the
/// larger sizes) lowers its clocks and raises them again only under sustained load.
pub const WARM_UP_SECONDS: f64 = 0.5;

/// Untimed batches of `steps` for `WARM_UP_SECONDS` (at least one): caches, pipeline state
/// and the clocks warm.
pub fn warm_up(solver: &mut dyn Solver, steps: &[SubstepParams]) -> Result<(), Error> {
    let start = Instant::now();
    loop {
        solver.advance(steps)?;
        solver.finish()?;
        if start.elapsed().as_secs_f64() >= WARM_UP_SECONDS {
            return Ok(());
        }
    }
}

/// Seconds of the median of `repeats` batches of `steps`, after `warm_up`.
pub(super) fn median_batch(
    solver: &mut dyn Solver,
    steps: &[SubstepParams],
    repeats: u32,
) -> Result<f64, Error> {
    warm_up(solver, steps)?;
    let mut times = Vec::new();
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        solver.advance(steps)?;
        solver.finish()?;
        times.push(start.elapsed().as_secs_f64());
    }
    times.sort_by(|a, b| a.total_cmp(b));
    Ok(times[times.len() / 2])
}

/// Times whole substeps for each size on the CPU twin and the GPU path.
pub fn run_cli(
    sizes: &[u32],
    substeps: u32,
    repeats: u32,
    out: &Path,
    adapter: &AdapterChoice,
) -> Result<(), Error> {
    let ctx = match GpuContext::new(adapter) {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            eprintln!("drapekit: {e}; benchmarking the CPU path only");
            None
        }
    };
    let cpu_name = format!("CPU twin ({})", cpu_threads_description());
    let mut rows = Vec::new();
    for &n in sizes {
        let (model, params, plan) = bench_model(n.max(2));
        let steps = bench_steps(substeps, params.dt);
        let work = model.len() as f64 * substeps as f64;
        let mut cpu = CpuSolver::new(&model, params, &plan);
        let t = median_batch(&mut cpu, &steps, repeats)?;
        rows.push(BenchRow {
            size: n,
            particles: model.len(),
            backend: "cpu".into(),
            device: cpu_name.clone(),
            median_seconds: t,
            particle_substeps_per_second: work / t,
        });
        if let Some(ctx) = &ctx {
            let mut gpu = GpuSolver::new(ctx, &model, params, &plan, substeps as usize)?;
            let t = median_batch(&mut gpu, &steps, repeats)?;
            let a = ctx.report();
            rows.push(BenchRow {
                size: n,
                particles: model.len(),
                backend: "gpu".into(),
                device: format!("{} ({}, {})", a.name, a.backend, a.device_type),
                median_seconds: t,
                particle_substeps_per_second: work / t,
            });
        }
        for r in rows
            .iter()
            .rev()
            .take(if ctx.is_some() { 2 } else { 1 })
            .rev()
        {
            println!("{:>4}² {:>3}  {:>12.3e} particle-substeps/s  ({:.4} s per {substeps} substeps)  {}", r.size, r.backend, r.particle_substeps_per_second, r.median_seconds, r.device);
        }
    }
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let mut csv = String::from("size,particles,backend,device,substeps_per_batch,median_seconds,particle_substeps_per_second\n");
    let mut md = format!(
        "Whole substep (CPU: {}; GPU: {}), {substeps} substeps per batch \
         (one submission on the GPU), median of {repeats} batches after {WARM_UP_SECONDS} s of \
         untimed ones.\n\n\
         | grid | particles | backend | particle-substeps/s | s per batch | device |\n|---|---|---|---|---|---|\n",
        stages(CpuSolver::HINGES),
        stages(GpuSolver::HINGES),
    );
    for r in &rows {
        csv.push_str(&format!(
            "{},{},{},\"{}\",{},{:.6},{:.1}\n",
            r.size,
            r.particles,
            r.backend,
            r.device,
            substeps,
            r.median_seconds,
            r.particle_substeps_per_second
        ));
        md.push_str(&format!(
            "| {}² | {} | {} | {:.3e} | {:.4} | {} |\n",
            r.size,
            r.particles,
            r.backend,
            r.particle_substeps_per_second,
            r.median_seconds,
            r.device
        ));
    }
    write_atomic(&out.join("bench.csv"), csv.as_bytes())?;
    write_atomic(&out.join("bench.md"), md.as_bytes())?;
    let title = format!("Whole substep, {substeps} substeps per batch");
    crate::plot::log_log_svg(
        &throughput_series(&rows),
        &title,
        "particles",
        "particle-substeps / s",
        &out.join("bench.svg"),
    )?;
    println!(
        "wrote {}, {} and {}",
        out.join("bench.csv").display(),
        out.join("bench.md").display(),
        out.join("bench.svg").display()
    );
    Ok(())
}

/// The bench cloth's stages with hinges evaluated `how` (each backend's own way).
fn stages(how: crate::plan::HingeEvaluation) -> String {
    bench_model(2).2.with_hinges(how).names().join(", ")
}

/// One line per backend and device: throughput against particle count.
fn throughput_series(rows: &[BenchRow]) -> Vec<Series> {
    let mut series: Vec<Series> = Vec::new();
    for r in rows {
        let name = format!("{}: {}", r.backend, r.device);
        let point = (r.particles as f64, r.particle_substeps_per_second);
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push(point),
            None => series.push(Series {
                name,
                points: vec![point],
            }),
        }
    }
    series
}
