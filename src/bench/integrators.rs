//! `drapekit bench --scene SCENE`: the same scene under symplectic Euler (at its stable step)
//! and implicit Euler (at the scene's step), on both backends, in one run: wall time per
//! simulated second, particle-substeps/s and the largest strain, as CSV and Markdown.

use super::cpu_threads_description;
use crate::atomic_file::write_atomic;
use crate::cpu::CpuSolver;
use crate::error::Error;
use crate::gpu::{AdapterChoice, GpuContext, GpuSolver};
use crate::model::layout::{INTEGRATOR_IMPLICIT, INTEGRATOR_SYMPLECTIC};
use crate::scene::Scene;
use crate::sim::{prepare, simulate, RunStats};
use crate::solver::Solver;
use std::fmt::Write as _;
use std::path::Path;

/// One integrator on one backend.
#[derive(Clone, Debug)]
pub struct IntegratorRow {
    /// "symplectic" or "implicit".
    pub integrator: &'static str,
    /// "cpu" or "gpu".
    pub backend: &'static str,
    /// The device.
    pub device: String,
    /// Substeps per output frame.
    pub substeps: u32,
    /// Frames simulated.
    pub frames: u32,
    /// Wall seconds of stepping and readback per simulated second.
    pub wall_per_simulated_second: f64,
    /// Particles × substeps / wall seconds.
    pub particle_substeps_per_second: f64,
    /// Largest spring strain at any output frame.
    pub max_edge_strain: f32,
    /// Why the point has no figures (refused or stopped), if so.
    pub error: Option<String>,
}

/// Runs the comparison for `frames` output frames (default: the scene's) and writes
/// `integrators.csv` and `integrators.md` to `out`.
pub fn run_cli(
    scene_path: &Path,
    frames: Option<u32>,
    out: &Path,
    adapter: &AdapterChoice,
) -> Result<Vec<IntegratorRow>, Error> {
    let base = Scene::load(scene_path)?;
    let ctx = match GpuContext::new(adapter) {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            eprintln!("drapekit: {e}; benchmarking the CPU path only");
            None
        }
    };
    let mut rows = Vec::new();
    for (name, integrator) in [
        ("symplectic", INTEGRATOR_SYMPLECTIC),
        ("implicit", INTEGRATOR_IMPLICIT),
    ] {
        let mut scene = base.clone();
        scene.solver.integrator = integrator;
        if integrator == INTEGRATOR_SYMPLECTIC {
            // The explicit integrators run at their stable step.
            scene.solver.substeps = None;
        }
        if let Some(f) = frames {
            scene.solver.frames = f;
        }
        // Every point runs the same frames.
        scene.solver.settle_speed = None;
        let failed = |backend, error: String| IntegratorRow {
            integrator: name,
            backend,
            device: String::new(),
            substeps: 0,
            frames: 0,
            wall_per_simulated_second: f64::NAN,
            particle_substeps_per_second: f64::NAN,
            max_edge_strain: f32::NAN,
            error: Some(error),
        };
        let prep = match prepare(&scene) {
            Ok(p) => p,
            Err(e) => {
                rows.push(failed("cpu", e.to_string()));
                continue;
            }
        };
        let mut backends: Vec<(&'static str, String, Box<dyn Solver>)> = vec![(
            "cpu",
            format!("CPU twin ({})", cpu_threads_description()),
            Box::new(CpuSolver::new(&prep.model, prep.params, &prep.plan)),
        )];
        if let Some(ctx) = &ctx {
            let a = ctx.report();
            let solver = GpuSolver::new(
                ctx,
                &prep.model,
                prep.params,
                &prep.plan,
                prep.substeps as usize,
            )?;
            backends.push((
                "gpu",
                format!("{} ({}, {})", a.name, a.backend, a.device_type),
                Box::new(solver),
            ));
        }
        for (backend, device, mut solver) in backends {
            let mut stats = RunStats::default();
            let result = simulate(&prep, solver.as_mut(), &mut stats, |_, _| Ok(()));
            let simulated = stats.frames_run as f64 * prep.frame_dt as f64;
            let substeps_run = stats.frames_run as f64 * prep.substeps as f64;
            let row = IntegratorRow {
                integrator: name,
                backend,
                device,
                substeps: prep.substeps,
                frames: stats.frames_run,
                wall_per_simulated_second: stats.wall_seconds / simulated,
                particle_substeps_per_second: prep.model.len() as f64 * substeps_run
                    / stats.wall_seconds,
                max_edge_strain: stats.max_edge_strain,
                error: result.err().map(|e| e.to_string()),
            };
            println!(
                "{:<10} {:<3} {:>6} substeps/frame  {:>9.3} s per simulated s  {:>10.3e} particle-substeps/s  strain {:.3}  {}",
                row.integrator,
                row.backend,
                row.substeps,
                row.wall_per_simulated_second,
                row.particle_substeps_per_second,
                row.max_edge_strain,
                row.error.as_deref().unwrap_or(&row.device)
            );
            rows.push(row);
        }
    }
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let mut csv = String::from(
        "integrator,backend,device,substeps_per_frame,frames,wall_s_per_simulated_s,\
         particle_substeps_per_second,max_edge_strain,error\n",
    );
    let mut md = format!(
        "`{}`: the same scene under each integrator, {} frames each (settle rule off).\n\n\
         | integrator | backend | substeps/frame | wall s per simulated s | particle-substeps/s | largest strain | device or error |\n\
         |---|---|---|---|---|---|---|\n",
        scene_path.display(),
        frames.unwrap_or(base.solver.frames)
    );
    for r in &rows {
        let _ = writeln!(
            csv,
            "{},{},\"{}\",{},{},{},{},{},\"{}\"",
            r.integrator,
            r.backend,
            r.device,
            r.substeps,
            r.frames,
            r.wall_per_simulated_second,
            r.particle_substeps_per_second,
            r.max_edge_strain,
            r.error.as_deref().unwrap_or("").replace('"', "'")
        );
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.3} | {:.3e} | {:.3} | {} |",
            r.integrator,
            r.backend,
            r.substeps,
            r.wall_per_simulated_second,
            r.particle_substeps_per_second,
            r.max_edge_strain,
            r.error.as_deref().unwrap_or(&r.device).replace('\n', " ")
        );
    }
    write_atomic(&out.join("integrators.csv"), csv.as_bytes())?;
    write_atomic(&out.join("integrators.md"), md.as_bytes())?;
    Ok(rows)
}
