//! The run's last files: `frames.csv` and `summary.json`, and which error a run reports when
//! writing them fails too.

use crate::atomic_file::write_atomic;
use crate::cpu::CpuSolver;
use crate::error::Error;
use crate::gpu::GpuSolver;
use crate::metrics::ShowThrough;
use crate::model::layout::{INTEGRATOR_EXPLICIT, INTEGRATOR_IMPLICIT};
use crate::output::Summary;
use crate::scene::Scene;
use crate::sim::{Prepared, RunStats};
use crate::solver::AdapterReport;

/// The backend a run ran on, as the summary reports it.
pub(super) struct Backend {
    /// `cpu` or `gpu`.
    pub name: &'static str,
    /// The GPU adapter, if any.
    pub adapter: Option<AdapterReport>,
    /// Why the run is on this backend, when it was not the one asked for.
    pub note: Option<String>,
}

/// The summary of a run of `scene` that ran `stats.frames_run` frames: what was built, how
/// the solve went, the garment's and the bodies' state at the last frame, the run's warnings
/// and error, and the files it wrote.
pub(super) fn summary(
    scene: &Scene,
    prep: &Prepared,
    stats: &RunStats,
    backend: Backend,
    show_through: Option<ShowThrough>,
    (warnings, error): (Vec<String>, Option<String>),
    outputs: Vec<String>,
) -> Summary {
    let substeps_run = stats.frames_run as f64 * prep.substeps as f64;
    let first_body = prep.model.colliders.first();
    Summary {
        scene: crate::run_folder::absolute(&scene.path)
            .display()
            .to_string(),
        scene_sha256: crate::run_folder::sha256_hex(scene.source.as_bytes()),
        inputs: crate::run_folder::inputs(scene),
        backend: backend.name.to_string(),
        backend_note: backend.note,
        adapter: backend.adapter,
        cpu_threads: (backend.name == "cpu").then(rayon::current_num_threads),
        particles: prep.model.len(),
        triangles: prep.model.triangles.len(),
        springs: prep.model.springs.len(),
        hinges: prep.hinges_in_use(),
        frames: stats.frames_run,
        frames_requested: prep.frames,
        fps: scene.solver.fps,
        substeps_per_frame: prep.substeps,
        substeps_source: if prep.auto_substeps { "auto" } else { "scene" },
        stable_dt_estimate_s: prep.stable_dt,
        dt_limited_by: prep.dt_limited_by,
        dt: prep.params.dt,
        integrator: match prep.params.integrator {
            INTEGRATOR_EXPLICIT => "explicit",
            INTEGRATOR_IMPLICIT => "implicit",
            _ => "symplectic",
        },
        iterations: prep.colors.map(|_| prep.params.iterations),
        tolerance: prep.colors.and(scene.solver.tolerance),
        iterations_mean: prep.colors.map(|_| {
            let frames = stats.frames_run - stats.coarse_start.as_ref().map_or(0, |c| c.frame);
            stats.iterations_run as f64 / (frames as f64 * prep.substeps as f64).max(1.0)
        }),
        newton_steps_mean: prep.model.multigrid.as_ref().map(|_| {
            let frames = stats.frames_run - stats.coarse_start.as_ref().map_or(0, |c| c.frame);
            stats.newton_steps_run as f64 / (frames as f64 * prep.substeps as f64).max(1.0)
        }),
        multigrid_levels: prep.model.multigrid.as_ref().map(|m| m.sizes()),
        colors: prep.colors,
        max_residual: stats.max_residual,
        force_residual_max: stats.force_residual.map(|r| r.0),
        force_residual_rms: stats.force_residual.map(|r| r.1),
        simulated_seconds: substeps_run * prep.params.dt as f64,
        wall_seconds: stats.wall_seconds,
        particle_substeps_per_second: {
            // The full mesh's frames and time: the coarse start's are its own.
            let (frames, wall) = match &stats.coarse_start {
                Some(c) => (c.frame, c.wall_seconds),
                None => (0, 0.0),
            };
            let substeps = stats.frames_run.saturating_sub(frames) as f64 * prep.substeps as f64;
            let wall = stats.wall_seconds - wall;
            if wall > 0.0 {
                prep.model.len() as f64 * substeps / wall
            } else {
                0.0
            }
        },
        coarse_start: stats.coarse_start.clone(),
        // The stages the backend ran: each evaluates hinges its own way.
        passes: prep
            .plan
            .for_backend(match backend.name {
                "cpu" => CpuSolver::HINGES,
                _ => GpuSolver::HINGES,
            })
            .names(),
        max_edge_strain: stats.max_edge_strain,
        last_frame_max_edge_strain: stats.last_edge_strain,
        last_frame_edge_strain_p99: stats.last_edge_strain_p99,
        last_frame_thread_strain: stats.last_thread_strain,
        strain_limit: (prep.plan.contains(crate::plan::Pass::StrainLimit))
            .then_some(prep.params.strain_limit),
        strain_limit_clamped_edges: stats.strain_limit_clamped_edges,
        max_speed_m_s: stats.max_speed,
        kinetic_energy_j: stats.kinetic_energy_j,
        seams: stats.seam_gaps.len(),
        seams_closed: (stats.seam_gaps.iter())
            .filter(|&&g| g < prep.seam_closed_gap)
            .count(),
        max_seam_gap_m: stats.widest_seam_gap(),
        seam_gaps_m: stats.seam_gaps.clone(),
        seams_closed_frame: stats.seams_closed_frame,
        bodies: prep.model.colliders.len(),
        collision_strategy: first_body.map(|first| {
            let all = &prep.model.colliders;
            if backend.name == "gpu" {
                "sdf"
            } else if all.iter().all(|c| c.strategy == first.strategy) {
                first.strategy.name()
            } else {
                "mixed"
            }
        }),
        edge_contacts: first_body.map(|_| {
            let any = prep.model.colliders.iter().any(|c| c.edges.is_some());
            any && backend.name == "cpu"
        }),
        max_penetration_m: first_body.map(|_| stats.max_penetration_m),
        body_contacts: first_body.map(|_| stats.body_contacts),
        body_show_through: show_through,
        sdf: first_body.map(|c| c.bake.clone()),
        body_sdfs: (prep.model.colliders.iter())
            .map(|c| c.bake.clone())
            .collect(),
        body_surface_speed_m_s: first_body.map(|_| prep.body_surface_speed),
        body_surface_step_m: first_body.map(|_| prep.body_surface_speed * prep.params.dt),
        body_motion: (prep.model.colliders.iter())
            .find_map(|c| c.deformed.as_ref())
            .map(|d| d.deformation.report(stats.deformed_penetration_m.clone())),
        attached_particles: prep.attached.len(),
        released_after_frame: stats.released_after_frame,
        finite: stats.finite,
        settled: stats.settled.clone(),
        last_frame_rms_speed_m_s: stats.frame_speed_m_s,
        warnings,
        error,
        outputs,
    }
}

/// Writes `frames.csv` (`frames`) and `summary.json` and returns the run's result: its own
/// error first (a frame that could not be written is the cause, a file that then could not be
/// written the consequence), and a summary number that is not finite (JSON would show it as
/// `null`) as an unstable run. A `frames.csv` that could not be written leaves the summary's
/// outputs.
pub(super) fn finish_summary(
    mut summary: Summary,
    result: Result<(), Error>,
    out_dir: &std::path::Path,
    frames: &str,
) -> Result<Summary, Error> {
    let csv = crate::run_folder::FRAMES_CSV;
    let frames_written = write_atomic(&out_dir.join(csv), frames.as_bytes());
    if frames_written.is_err() {
        summary.outputs.retain(|o| o != csv);
    }
    let result = cause_first(result, frames_written);
    let non_finite = summary.non_finite_fields();
    let result = result.and_then(|()| match non_finite.is_empty() {
        true => Ok(()),
        false => Err(Error::Unstable(format!(
            "the run produced non-finite values in the summary ({}), written there as null",
            non_finite.join(", ")
        ))),
    });
    if let Err(e) = &result {
        summary.finite &= non_finite.is_empty();
        summary.error.get_or_insert_with(|| e.to_string());
    }
    let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
    let written = write_atomic(&out_dir.join("summary.json"), json.as_bytes());
    cause_first(result, written).map(|()| summary)
}

/// `result`'s error if it has one (the later failure only said on stderr), else `later`'s.
fn cause_first(result: Result<(), Error>, later: Result<(), Error>) -> Result<(), Error> {
    match (result, later) {
        (Err(e), Err(w)) => {
            crate::notice::note(&format!("also: {w}"));
            Err(e)
        }
        (Err(e), Ok(())) | (Ok(()), Err(e)) => Err(e),
        (Ok(()), Ok(())) => Ok(()),
    }
}
