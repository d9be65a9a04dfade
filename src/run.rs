//! `drapekit run`: scene → prepared run → backend → frames and summary on disk.

use crate::atomic_file::write_atomic;
use crate::checkpoint::{Checkpoint, CheckpointHeader};
use crate::cpu::CpuSolver;
use crate::error::Error;
use crate::export::Exporter;
use crate::gpu::{AdapterChoice, GpuContext, GpuSolver};
use crate::model::layout::{INTEGRATOR_EXPLICIT, INTEGRATOR_IMPLICIT};
use crate::output::Summary;
use crate::preview::RunPreviews;
use crate::scene::Scene;
use crate::sim::{
    map_state, prepare, simulate, simulate_from, CoarseStart, Prepared, ResumeFrom, RunStats,
};
use crate::solver::Solver;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set by the CLI's Ctrl-C handler: the run stops after the current frame, writes a checkpoint
/// and returns `Error::Interrupted`.
pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Which path runs the simulation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BackendChoice {
    /// A hardware GPU when there is one; else (no adapter, or only a software rasteriser such
    /// as llvmpipe) the multi-threaded CPU path, and the summary says why.
    Auto,
    /// The CPU reference path.
    Cpu,
    /// The GPU path; fails if no adapter exists.
    Gpu,
}

impl FromStr for BackendChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(BackendChoice::Auto),
            "cpu" => Ok(BackendChoice::Cpu),
            "gpu" => Ok(BackendChoice::Gpu),
            _ => Err(format!("unknown backend {s:?}; use auto, cpu or gpu")),
        }
    }
}

impl BackendChoice {
    /// The text `from_str` reads back.
    pub fn name(self) -> &'static str {
        match self {
            BackendChoice::Auto => "auto",
            BackendChoice::Cpu => "cpu",
            BackendChoice::Gpu => "gpu",
        }
    }
}

/// Options of `drapekit run` beyond the scene.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Backend.
    pub backend: BackendChoice,
    /// Adapter, for the GPU backend.
    pub adapter: AdapterChoice,
    /// Overrides `[output] dir`.
    pub out_dir: Option<PathBuf>,
    /// Overrides `[solver] frames`.
    pub frames: Option<u32>,
    /// Show a progress bar on stderr (drawn only when stderr is a terminal).
    pub progress: bool,
    /// Write `checkpoint.bin` every this many frames (and always when interrupted).
    pub checkpoint_every: Option<u32>,
    /// Replace the results of another run in the output folder (a rerun of the same scene
    /// replaces its own without it).
    pub overwrite: bool,
}

/// Creates the chosen backend; with `Auto`, falls back to the CPU and returns a note saying why.
/// `Auto` with `--adapter auto` skips software adapters (`DeviceType::Cpu`): the multi-threaded
/// CPU path measured faster than lavapipe (docs/src/benchmarks/throughput.md). Naming an adapter, or
/// `--backend gpu`, still runs it.
pub fn make_solver(
    prep: &Prepared,
    choice: BackendChoice,
    adapter: &AdapterChoice,
) -> Result<(Box<dyn Solver>, Option<String>), Error> {
    let (device, note) = choose_device(choice, adapter)?;
    Ok((build_solver(prep, device.as_ref())?, note))
}

/// The GPU device a run will use (`None`: the CPU path), and a note when `Auto` fell back to
/// the CPU. Opened before the model is built, so that its limits can refuse a scene early.
pub fn choose_device(
    choice: BackendChoice,
    adapter: &AdapterChoice,
) -> Result<(Option<GpuContext>, Option<String>), Error> {
    match choice {
        BackendChoice::Cpu => Ok((None, None)),
        BackendChoice::Gpu => Ok((Some(GpuContext::new(adapter)?), None)),
        BackendChoice::Auto => match GpuContext::new(adapter) {
            Ok(ctx) if ctx.is_software() && !adapter_named(adapter) => Ok((
                None,
                Some(format!(
                    "only a software adapter ({}), ran on the CPU path with {} threads",
                    ctx.info.name,
                    rayon::current_num_threads()
                )),
            )),
            Ok(ctx) => Ok((Some(ctx), None)),
            Err(e) => Ok((
                None,
                Some(format!("no GPU adapter, ran on the CPU path ({e})")),
            )),
        },
    }
}

/// The solver for a prepared run: the GPU path on `device`, else the CPU path.
pub fn build_solver(
    prep: &Prepared,
    device: Option<&GpuContext>,
) -> Result<Box<dyn Solver>, Error> {
    Ok(match device {
        Some(ctx) => Box::new(GpuSolver::new(
            ctx,
            &prep.model,
            prep.params,
            &prep.plan,
            prep.substeps as usize,
        )?),
        None => {
            let mut solver = CpuSolver::new(&prep.model, prep.params, &prep.plan);
            if prep.cpu_point_triangle {
                solver.use_point_triangle_reference();
            }
            Box::new(solver)
        }
    })
}

/// Whether the user picked the adapter (`--adapter` other than auto, or `WGPU_ADAPTER_NAME`).
pub fn adapter_named(adapter: &AdapterChoice) -> bool {
    *adapter != AdapterChoice::Auto
        || std::env::var("WGPU_ADAPTER_NAME").is_ok_and(|name| !name.is_empty())
}

/// Runs a scene and writes its frames and `summary.json`. Bad input fails before anything is
/// written. A run that goes non-finite still writes its summary (with `finite: false` and the
/// error) before returning the error.
///
/// ```
/// use drapekit::gpu::AdapterChoice;
/// use drapekit::run::{run_scene, BackendChoice, RunOptions};
/// use drapekit::scene::Scene;
/// use std::path::Path;
///
/// let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
/// let scene = Scene::load(&dir.join("fixtures/scenes/drape_sphere.toml"))?;
/// let out = std::env::temp_dir().join(format!("drapekit-doc-{}", std::process::id()));
/// let options = RunOptions {
///     backend: BackendChoice::Cpu,
///     adapter: AdapterChoice::Auto,
///     out_dir: Some(out.clone()),
///     frames: Some(2),
///     progress: false,
///     checkpoint_every: None,
///     overwrite: false,
/// };
/// let summary = run_scene(&scene, &options)?;
/// assert!(summary.finite);
/// assert!(out.join("summary.json").exists() && out.join("frame_0002.obj").exists());
/// # std::fs::remove_dir_all(&out).ok();
/// # Ok::<(), drapekit::Error>(())
/// ```
pub fn run_scene(scene: &Scene, opts: &RunOptions) -> Result<Summary, Error> {
    run_scene_from(scene, opts, None)
}

/// `drapekit resume DIR`: continues the run whose checkpoint is in `dir`, with its scene,
/// backend and adapter (`frames` may extend it). The scene must not have changed.
pub fn resume_run(
    dir: &std::path::Path,
    frames: Option<u32>,
    progress: bool,
) -> Result<Summary, Error> {
    let checkpoint = Checkpoint::read(dir)?;
    let h = &checkpoint.header;
    let scene = Scene::load(&h.scene_path)?;
    if scene.source != h.scene_text {
        return Err(Error::Input(crate::error::InputError::new(
            &h.scene_path,
            "scene",
            format!(
                "the scene changed since the checkpoint in {} was written",
                dir.display()
            ),
            "restore the scene as it was, or rerun it from the start with drapekit run",
        )));
    }
    let opts = RunOptions {
        backend: h.backend.parse().map_err(|e: String| {
            Error::Input(crate::error::InputError::new(
                &dir.join(crate::checkpoint::CHECKPOINT_FILE),
                "backend",
                e,
                "rerun the scene",
            ))
        })?,
        adapter: h.adapter.parse().expect("infallible"),
        out_dir: Some(dir.to_path_buf()),
        frames: frames.or(h.frames),
        progress,
        checkpoint_every: h.checkpoint_every,
        overwrite: false,
    };
    run_scene_from(&scene, &opts, Some(checkpoint))
}

fn run_scene_from(
    scene: &Scene,
    opts: &RunOptions,
    resume: Option<Checkpoint>,
) -> Result<Summary, Error> {
    let mut scene = scene.clone();
    if let Some(frames) = opts.frames {
        scene.solver.frames = crate::health::inputs::check_frames(&scene, frames)?;
    }
    let out_dir = opts
        .out_dir
        .clone()
        .unwrap_or_else(|| scene.output.dir.clone());
    // A resumed run continues in its own folder; a new one must not mix with another's.
    let stale = match resume {
        None => crate::run_folder::check(&out_dir, &scene, opts.overwrite)?,
        Some(_) => Vec::new(),
    };
    // Before the distance field is baked (a body in the wrong unit is named before its SDF's
    // size is refused) and before the long part of the run.
    let input_warnings = crate::health::scene_warnings(&scene)?;
    for w in &input_warnings {
        eprintln!("drapekit: warning: {w}");
    }
    // Values that compute but no real scene has: said before anything slow starts.
    let load_warnings = crate::model::budget::load_warnings(&scene);
    for w in &load_warnings {
        eprintln!("drapekit: warning: {w}");
    }
    let (device, backend_note) = choose_device(opts.backend, &opts.adapter)?;
    if let Some(ctx) = &device {
        // Refused from the scene alone, before anything is built or baked.
        crate::model::budget::check_gpu_textures(&scene, ctx.max_texels())?;
        crate::model::budget::check_sdf_textures(&scene, ctx.max_texels())?;
    }
    let prep = prepare(&scene)?;
    if let Some(ctx) = &device {
        // The estimate cannot see an OBJ cloth's size; the built model can.
        crate::model::budget::check_model_textures(&scene, &prep.model, ctx.max_texels())?;
    }
    // Refused before anything is simulated or written: the files must fit the disk.
    let from_frame = resume.as_ref().map_or(0, |c| c.header.frame);
    crate::export::disk::check_space(&scene, &prep, &out_dir, from_frame)?;
    let mut solver = build_solver(&prep, device.as_ref())?;
    if let Some(note) = &backend_note {
        eprintln!("drapekit: {note}");
    }
    let mut warnings = prep.warnings.clone();
    let wants_edges = (prep.model.colliders.iter()).any(|c| c.edges.is_some());
    if wants_edges && solver.backend_name() == "gpu" {
        warnings.push(
            "edge_contacts is CPU only: the GPU backend tests particles against the SDF \
             (use --backend cpu for cloth-edge against body-edge contacts)"
                .into(),
        );
    }
    for w in &warnings {
        eprintln!("drapekit: warning: {w}");
    }
    warnings.splice(0..0, input_warnings.into_iter().chain(load_warnings));
    // Before the output folder exists: a coarse start that cannot settle is bad input. A
    // resumed run continues from its checkpoint, past any coarse start.
    let coarse = match (&scene.cloth, &resume) {
        (
            crate::scene::ClothSource::Pattern {
                coarse_start: Some(distance),
                ..
            },
            None,
        ) => Some(coarse_start(&scene, *distance, device.as_ref(), &prep)?),
        _ => None,
    };
    crate::run_folder::clear(&out_dir, &stale)?;
    let temporaries = crate::atomic_file::remove_stale_temporaries(&out_dir);
    if !temporaries.is_empty() {
        eprintln!(
            "drapekit: removed {} temporary file(s) a stopped run left in {}: {}",
            temporaries.len(),
            out_dir.display(),
            temporaries.join(", ")
        );
    }

    let mut outputs = Vec::new();
    if resume.is_none() {
        outputs.push(crate::run_folder::write_scene_copy(&out_dir, &scene)?);
    }
    let scene_path = crate::run_folder::absolute(&scene.path);
    let mut stats = RunStats::default();
    let mut exporter = Exporter::new(&prep, &scene, &out_dir);
    let coarse_started = coarse.is_some();
    let resume = match resume {
        None => coarse.map(|(from, coarse_stats)| {
            stats = coarse_stats;
            from
        }),
        Some(c) => {
            if c.header.particles != prep.model.len() {
                return Err(Error::Input(crate::error::InputError::new(
                    &scene.path,
                    "scene",
                    format!(
                        "the scene now builds {} particles, the checkpoint holds {}: a file it \
                         uses (pattern or mesh) changed",
                        prep.model.len(),
                        c.header.particles
                    ),
                    "restore the files, or rerun the scene from the start with drapekit run",
                )));
            }
            stats = c.header.stats;
            outputs = c.header.outputs;
            exporter.restore(c.header.kept_frames, c.kept, c.header.exported_frames);
            Some(ResumeFrom {
                frame: c.header.frame,
                state: c.state,
            })
        }
    };
    let checkpoint = |frame: u32,
                      state: &crate::solver::ParticleState,
                      stats: &RunStats,
                      outputs: &[String],
                      exporter: &Exporter|
     -> Result<(), Error> {
        let (kept_frames, kept, exported_frames) = exporter.progress();
        Checkpoint {
            header: CheckpointHeader {
                drapekit_version: env!("CARGO_PKG_VERSION").to_string(),
                scene_path: scene_path.clone(),
                scene_text: scene.source.clone(),
                backend: opts.backend.name().to_string(),
                adapter: opts.adapter.to_string(),
                frames: opts.frames,
                checkpoint_every: opts.checkpoint_every,
                frame,
                particles: state.positions.len(),
                stats: stats.clone(),
                outputs: outputs.to_vec(),
                kept_frames: kept_frames.to_vec(),
                exported_frames,
            },
            state: state.clone(),
            kept: kept.to_vec(),
        }
        .write(&out_dir)
    };
    if coarse_started {
        // The full mesh's flat panels as frame 0, as every run has it: the strain preview's
        // rest shape. OBJ only: the caches hold the simulated frames, evenly spaced.
        outputs.extend(exporter.rest_frame(&prep.model.positions)?);
    }
    let mut previews = RunPreviews::new(&scene, &opts.adapter, &out_dir);
    let bar = crate::progress::frames(opts.progress, prep.frames);
    let particle_substeps = prep.model.len() as f64 * prep.substeps as f64;
    let started = std::time::Instant::now();
    // Frames this call simulates start after a checkpoint's or a coarse start's frame.
    let start_frame = resume.as_ref().map_or(0, |r| r.frame);
    let result = simulate_from(
        &prep,
        solver.as_mut(),
        &mut stats,
        resume,
        |frame, state, stats| {
            if exporter.wants_frames() && exporter.on_schedule(frame) {
                outputs.extend(exporter.frame(frame, &state.positions)?);
                bar.suspend(|| previews.frame_written(frame));
            }
            let interrupted = INTERRUPTED.load(Ordering::SeqCst);
            let due = opts
                .checkpoint_every
                .is_some_and(|n| frame > 0 && frame % n == 0);
            if due || interrupted {
                checkpoint(frame, state, stats, &outputs, &exporter)?;
            }
            if interrupted {
                return Err(Error::Interrupted {
                    frame,
                    dir: out_dir.clone(),
                });
            }
            if frame > 0 {
                let rate = particle_substeps * (frame - start_frame) as f64
                    / started.elapsed().as_secs_f64();
                bar.set_message(format!(
                    "{:.2} s simulated, {rate:.2e} particle-substeps/s",
                    frame as f32 * prep.frame_dt
                ));
                bar.set_position(frame as u64);
            }
            Ok(())
        },
    );
    bar.finish_and_clear();
    // The last frame is the result: it is written also when the run ended between `every`
    // frames (the settle rule, or a frame count that is not a multiple). The solver still
    // holds its positions.
    let last = stats.frames_run;
    let last_state = if result.is_ok() {
        Some(solver.state()?)
    } else {
        None
    };
    if let Some(state) = last_state.as_ref() {
        if exporter.wants_frames() && !exporter.on_schedule(last) {
            outputs.extend(exporter.frame(last, &state.positions)?);
            previews.frame_written(last);
        }
    }
    let positions = last_state.as_ref().map(|state| &state.positions[..]);
    let (show_through, found) = crate::health::last_frame(&prep, &stats, positions, last);
    warnings.extend(found);
    let checkpoint_name = crate::checkpoint::CHECKPOINT_FILE.to_string();
    if out_dir.join(&checkpoint_name).is_file() && !outputs.contains(&checkpoint_name) {
        outputs.push(checkpoint_name);
    }
    // The caches hold the frames written so far, also when the run stopped early.
    outputs.extend(exporter.finish()?);
    for w in &exporter.warnings {
        eprintln!("drapekit: warning: {w}");
    }
    warnings.append(&mut exporter.warnings);
    if result.is_ok() && previews.wanted() {
        let (names, missing) = previews.finish();
        outputs.extend(names);
        warnings.extend(missing);
    } else {
        warnings.extend(previews.warnings);
        outputs.extend(previews.names);
    }
    outputs.push(crate::run_folder::FRAMES_CSV.to_string());
    outputs.push("summary.json".to_string());
    let substeps_run = stats.frames_run as f64 * prep.substeps as f64;
    let first_body = prep.model.colliders.first();
    let summary = Summary {
        scene: scene_path.display().to_string(),
        inputs: crate::run_folder::inputs(&scene),
        backend: solver.backend_name().to_string(),
        backend_note,
        adapter: solver.adapter(),
        cpu_threads: (solver.backend_name() == "cpu").then(rayon::current_num_threads),
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
            .for_backend(match solver.backend_name() {
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
            if solver.backend_name() == "gpu" {
                "sdf"
            } else if all.iter().all(|c| c.strategy == first.strategy) {
                first.strategy.name()
            } else {
                "mixed"
            }
        }),
        edge_contacts: first_body.map(|_| {
            let any = prep.model.colliders.iter().any(|c| c.edges.is_some());
            any && solver.backend_name() == "cpu"
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
        error: result.as_ref().err().map(|e| e.to_string()),
        outputs,
    };
    finish_summary(summary, result, &out_dir, &stats.frames_csv())
}

/// Writes `frames.csv` (`frames`) and `summary.json` and returns the run's result: its own
/// error first (a frame that could not be written is the cause, a file that then could not be
/// written the consequence), and a summary number that is not finite (JSON would show it as
/// `null`) as an unstable run. A `frames.csv` that could not be written leaves the summary's
/// outputs.
fn finish_summary(
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
            eprintln!("drapekit: also: {w}");
            Err(e)
        }
        (Err(e), Ok(())) | (Ok(()), Err(e)) => Err(e),
        (Ok(()), Ok(())) => Ok(()),
    }
}

/// Sews and drapes `scene`'s garment at `distance` spacing until it settles (or its frames
/// end) and maps the result onto `fine`'s mesh: where the full-resolution run continues from,
/// and its stats so far (what the coarse start did, the seams' state, its time).
fn coarse_start(
    scene: &Scene,
    distance: f64,
    device: Option<&GpuContext>,
    fine: &Prepared,
) -> Result<(ResumeFrom, RunStats), Error> {
    let started = std::time::Instant::now();
    let mut coarse = scene.clone();
    if let crate::scene::ClothSource::Pattern {
        options,
        coarse_start,
        ..
    } = &mut coarse.cloth
    {
        options.particle_distance = distance;
        *coarse_start = None;
    }
    let prep = prepare(&coarse)?;
    eprintln!(
        "drapekit: coarse start: sewing and draping {} particles at {distance:.3} m until they \
         settle (a second Ctrl-C stops it at once)",
        prep.model.len()
    );
    let mut solver = build_solver(&prep, device)?;
    let mut stats = RunStats::default();
    simulate(&prep, solver.as_mut(), &mut stats, |_, _| Ok(())).map_err(|e| match e {
        Error::Unstable(m) => Error::Unstable(format!(
            "the coarse start (coarse_start_distance_m = {distance:.3}): {m}"
        )),
        e => e,
    })?;
    let frame = stats.frames_run;
    if stats.settled.is_none() || frame >= fine.frames {
        return Err(scene
            .error(
                "cloth.pattern",
                "coarse_start_distance_m",
                format!(
                    "the coarse start ({} particles at {distance:.3} m) {} within the run's {} \
                     frames (its speed at frame {frame}: {:.2e} m/s, against settle_speed_m_s), \
                     so no frame is left for the full mesh",
                    prep.model.len(),
                    if stats.settled.is_none() {
                        "did not settle"
                    } else {
                        "settled only at the last frame"
                    },
                    fine.frames,
                    stats.frame_speed_m_s.unwrap_or(f64::NAN),
                ),
                "raise solver.frames (or --frames), use a finer coarse_start_distance_m, or \
                 remove it",
            )
            .into());
    }
    let (state, gap) = map_state(&prep, &solver.state()?, fine, frame).ok_or_else(|| {
        scene.error(
            "cloth.pattern",
            "coarse_start_distance_m",
            "a coarse start needs a sewing pattern",
            "remove coarse_start_distance_m",
        )
    })?;
    let wall_seconds = started.elapsed().as_secs_f64();
    let record = CoarseStart {
        particle_distance_m: distance as f32,
        particles: prep.model.len(),
        frame,
        settled_frame: stats.settled.as_ref().map(|s| s.frame),
        seams_closed_frame: stats.seams_closed_frame,
        max_edge_strain: stats.max_edge_strain,
        wall_seconds,
        max_pattern_gap_m: gap,
    };
    let continued = RunStats {
        frames: stats.frames,
        frames_run: frame,
        wall_seconds,
        finite: true,
        seams_closed_frame: stats.seams_closed_frame,
        released_after_frame: stats.released_after_frame,
        coarse_start: Some(record),
        ..RunStats::default()
    };
    Ok((ResumeFrom { frame, state }, continued))
}
