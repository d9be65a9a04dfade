//! `drapekit run`: scene → prepared run → backend → frames and summary on disk.

mod coarse_start;
mod summary;

use crate::checkpoint::{Checkpoint, CheckpointHeader};
use crate::cpu::CpuSolver;
use crate::error::Error;
use crate::export::Exporter;
use crate::gpu::{AdapterChoice, GpuContext, GpuSolver};
use crate::notice::{note, warn};
use crate::output::Summary;
use crate::preview::RunPreviews;
use crate::scene::Scene;
use crate::sim::{prepare, simulate_from, Prepared, ResumeFrom, RunStats};
use crate::solver::Solver;
use coarse_start::coarse_start;
use std::path::Path;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::atomic::{AtomicBool, Ordering};
use summary::Backend;

/// Set by the CLI's Ctrl-C handler: the run stops after the current frame, writes a checkpoint
/// and returns `Error::Interrupted`.
pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Output past which a run says, before it starts, how much it will write: 1 GiB.
const LARGE_OUTPUT_BYTES: u64 = 1 << 30;

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
    // The run may have gone on past its checkpoint: its summary says how far. Ending sooner
    // would leave its later frames beside a shorter run's summary.
    let written = std::fs::read(dir.join("summary.json"))
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .and_then(|s| s["frames"].as_u64())
        .map_or(0, |f| f.min(u32::MAX as u64) as u32);
    let (reached, least) = (h.frame.max(written), (h.frame + 1).max(written));
    if let Some(f) = frames.filter(|&f| f < least) {
        return Err(Error::Input(crate::error::InputError::new(
            &dir.join(crate::checkpoint::CHECKPOINT_FILE),
            "--frames",
            if f >= reached {
                format!("the run has reached frame {reached}: there is nothing to continue")
            } else {
                format!(
                    "the run has reached frame {reached}: resuming it to {f} frames would end \
                     it sooner and leave its later frames beside a shorter run's summary"
                )
            },
            format!(
                "give --frames {least} or more, or rerun the scene with drapekit run --frames {f}"
            ),
        )));
    }
    // A scene file moved or deleted since: its text is in the checkpoint, and its relative
    // paths resolve from where it stood.
    let scene = if h.scene_path.exists() {
        Scene::load(&h.scene_path)?
    } else {
        note(&format!(
            "{} is gone; resuming with the scene as the checkpoint keeps it",
            h.scene_path.display()
        ));
        Scene::parse(&h.scene_text, &h.scene_path)?
    };
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
    let now = crate::checkpoint::input_files(&scene);
    if let Some(path) = h.changed_input(&now) {
        let gone = !now.iter().any(|(p, s)| p == path && s != "missing");
        return Err(Error::Input(crate::error::InputError::new(
            Path::new(path),
            "contents",
            format!(
                "the file {} since the checkpoint in {} was written",
                if gone {
                    "cannot be read (moved or deleted?)"
                } else {
                    "changed"
                },
                dir.display()
            ),
            "restore the file as it was, or rerun the scene from the start with drapekit run",
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
    let from_frame = resume.as_ref().map_or(0, |c| c.header.frame);
    let SetUp {
        device,
        backend_note,
        prep,
        mut solver,
        mut warnings,
    } = set_up(&scene, opts, &out_dir, from_frame)?;
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
        note(&format!(
            "removed {} temporary file(s) a stopped run left in {}: {}",
            temporaries.len(),
            out_dir.display(),
            temporaries.join(", ")
        ));
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
    let input_files = crate::checkpoint::input_files(&scene);
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
                input_files: input_files.clone(),
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
        warn(w);
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
    let backend = Backend {
        name: solver.backend_name(),
        adapter: solver.adapter(),
        note: backend_note,
    };
    let error = result.as_ref().err().map(|e| e.to_string());
    let summary = summary::summary(
        &scene,
        &prep,
        &stats,
        backend,
        show_through,
        (warnings, error),
        outputs,
    );
    summary::finish_summary(summary, result, &out_dir, &stats.frames_csv())
}

/// What a run needs before its first frame, each input checked on the way.
struct SetUp {
    device: Option<GpuContext>,
    backend_note: Option<String>,
    prep: Prepared,
    solver: Box<dyn Solver>,
    /// Every warning so far (also said on stderr).
    warnings: Vec<String>,
}

/// Checks `scene` and builds its run: the warnings on its inputs, the backend, the prepared
/// model and the solver, refusing what the adapter's textures or the disk under `out_dir`
/// (from frame `from_frame` on) cannot hold before anything slow starts.
fn set_up(
    scene: &Scene,
    opts: &RunOptions,
    out_dir: &std::path::Path,
    from_frame: u32,
) -> Result<SetUp, Error> {
    // Before the distance field is baked (a body in the wrong unit is named before its SDF's
    // size is refused) and before the long part of the run.
    let input_warnings = crate::health::scene_warnings(scene)?;
    for w in &input_warnings {
        warn(w);
    }
    // Values that compute but no real scene has: said before anything slow starts.
    let load_warnings = crate::model::budget::load_warnings(scene);
    for w in &load_warnings {
        warn(w);
    }
    let (device, backend_note) = choose_device(opts.backend, &opts.adapter)?;
    if let Some(ctx) = &device {
        // Refused from the scene alone, before anything is built or baked.
        crate::model::budget::check_gpu_textures(scene, ctx.max_texels())?;
        crate::model::budget::check_sdf_textures(scene, ctx.max_texels())?;
    }
    let prep = prepare(scene)?;
    if let Some(ctx) = &device {
        // The estimate cannot see an OBJ cloth's size; the built model can.
        crate::model::budget::check_model_textures(scene, &prep.model, ctx.max_texels())?;
    }
    // Refused before anything is simulated or written: the files must fit the disk. A run
    // that fits but writes gigabytes says so before it starts.
    let output = crate::export::disk::check_space(scene, &prep, out_dir, from_frame)?;
    if output.bytes() > LARGE_OUTPUT_BYTES {
        note(&format!(
            "this run writes about {} ({} frames) into {}",
            crate::export::disk::size(output.bytes()),
            output.frames,
            out_dir.display()
        ));
    }
    let solver = build_solver(&prep, device.as_ref())?;
    if let Some(n) = &backend_note {
        note(n);
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
        warn(w);
    }
    warnings.splice(0..0, input_warnings.into_iter().chain(load_warnings));
    Ok(SetUp {
        device,
        backend_note,
        prep,
        solver,
        warnings,
    })
}
