//! The `drapekit` command line: parses arguments, calls the library, reports.

mod cli;

use clap::{Parser, Subcommand};
use drapekit::gpu::AdapterChoice;
use drapekit::run::{run_scene, BackendChoice, RunOptions};
use drapekit::scene::Scene;
use drapekit::Error;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "drapekit",
    version,
    about = "Cloth and garment simulation on wgpu, with a CPU twin of every pass"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Threads of the CPU backend (default: all cores; at most 4096). Results do not depend on
    /// it.
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=4096))]
    threads: Option<u32>,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene and write OBJ frames, frames.csv and summary.json.
    #[command(after_help = "Examples:\n  \
        drapekit run fixtures/scenes/tshirt_drape_cotton.toml\n  \
        drapekit run fixtures/scenes/drape_sphere.toml --backend cpu --frames 12 --out out/sphere --quiet")]
    Run {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output folder (default: [output] dir, else out/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// auto: a hardware GPU if there is one, else the CPU (also instead of a software
        /// adapter such as llvmpipe); cpu; gpu.
        #[arg(long, default_value = "auto")]
        backend: BackendChoice,
        /// auto (honours WGPU_ADAPTER_NAME), fallback (software), or part of an adapter name.
        #[arg(long, default_value = "auto")]
        adapter: AdapterChoice,
        /// Override the number of output frames (1 or more).
        #[arg(long, value_parser = parse_frames)]
        frames: Option<u32>,
        /// No progress bars.
        #[arg(long)]
        quiet: bool,
        /// Write checkpoint.bin every N frames (Ctrl-C always writes one); continue with
        /// `drapekit resume OUT`.
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
        checkpoint_every: Option<u32>,
        /// Treat warnings as errors: exit 5 before the run when an input is implausible, and
        /// after it (with every file written) when the result has warnings.
        #[arg(long)]
        strict: bool,
        /// Replace another run's results in the output folder (a rerun of the same scene
        /// replaces its own without it). Only drapekit's own files are removed.
        #[arg(long)]
        overwrite: bool,
    },
    /// Continue a run from the checkpoint in its output folder (same scene, backend, adapter).
    #[command(after_help = "Examples:\n  \
        drapekit run fixtures/scenes/hanging_cloth.toml --checkpoint-every 12 --out out/hang\n  \
        drapekit resume out/hang --frames 96   # continue, and run to frame 96")]
    Resume {
        /// The run's output folder (holding checkpoint.bin).
        dir: PathBuf,
        /// Run to this many output frames instead of the original count.
        #[arg(long, value_parser = parse_frames)]
        frames: Option<u32>,
        /// No progress bars.
        #[arg(long)]
        quiet: bool,
        /// Exit 5 (with every file written) when the result has warnings.
        #[arg(long)]
        strict: bool,
    },
    /// List the GPU adapters, the one `--adapter auto` picks, and the CPU.
    #[command(after_help = "Example:\n  \
        drapekit info\n  \
        WGPU_ADAPTER_NAME=llvmpipe drapekit info   # what --adapter auto picks when told a name")]
    Info,
    /// Render one frame of a finished run (the garment and the body) to a PNG, or all of them
    /// to a GIF.
    #[command(
        after_help = "Defaults come from the run's scene ([preview] table), then the options.\n\n\
        Examples:\n  \
        drapekit preview out/tshirt_drape_cotton --out shirt.png\n  \
        drapekit preview out/tshirt_drape_cotton --mode strain --strain-max 0.1 --seams --out strain.png\n  \
        drapekit preview out/tshirt_drape_cotton --checker 0.05 --out grain.png\n  \
        drapekit preview out/tshirt_drape_cotton --turntable --out turntable.gif\n  \
        drapekit preview out/skirt_rotating_implicit --camera front --out skirt.gif\n  \
        drapekit preview out/drape_sphere --frame 0 --camera front --size 3840x2160 --out big.png"
    )]
    Preview {
        /// The run's output folder (frame_NNNN.obj and summary.json).
        run: PathBuf,
        /// The frame (default: the last one written).
        #[arg(long)]
        frame: Option<u32>,
        /// front, back, side or three-quarter (default: the scene's [preview] camera, else
        /// three-quarter).
        #[arg(long)]
        camera: Option<drapekit::preview::CameraPreset>,
        /// fabric (the fabric's colour or image, folds darkened by ambient occlusion); strain
        /// (each triangle's stretch against frame 0, blue 0% to red at --strain-max); or
        /// penetration (distance to the body: red inside, yellow within the contact thickness,
        /// green beyond).
        #[arg(long, default_value = "fabric")]
        mode: drapekit::preview::ColorMode,
        /// The strain shown in full red, as a fraction: 0.2 = 20% (default: the scene's
        /// [preview] strain_max, else the fabric preset's range: 5% for wovens, 20% for the
        /// knit, 15% for leather; 20% without a preset).
        #[arg(long, value_parser = parse_strain_max)]
        strain_max: Option<f32>,
        /// Draw the garment's seams as dark lines (also on with [preview] seams = true).
        #[arg(long)]
        seams: bool,
        /// Leave out the colour legend of the strain and penetration modes.
        #[arg(long)]
        no_legend: bool,
        /// A checker over the pattern coordinates with squares this many metres wide, to see
        /// grain and distortion (default: the scene's [preview] checker_m, else none).
        #[arg(long)]
        checker: Option<f32>,
        /// Image size, WIDTHxHEIGHT in pixels (default: the scene's [preview] size, else
        /// 1280x960).
        #[arg(long, value_parser = parse_size)]
        size: Option<(u32, u32)>,
        /// auto (honours WGPU_ADAPTER_NAME), fallback (software), or part of an adapter name.
        #[arg(long, default_value = "auto")]
        adapter: AdapterChoice,
        /// Spin the frame (--frame, default the last) a full turn around the body: a looping
        /// GIF of 36 views, 3.6 s a turn (--out must end in .gif).
        #[arg(long)]
        turntable: bool,
        /// The PNG to write; a name ending in .gif writes every frame of the run as a looping
        /// animation instead (default size: the scene's [preview] animation_size, else 480x360).
        #[arg(long)]
        out: PathBuf,
    },
    /// Print the pass plan a scene compiles to.
    #[command(after_help = "Examples:\n  \
        drapekit plan fixtures/scenes/tshirt_drape_cotton.toml\n  \
        drapekit plan fixtures/scenes/flag_wind.toml --json")]
    Plan {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Print JSON: {"passes": [...], ...}.
        #[arg(long)]
        json: bool,
    },
    /// Run a manifest of scenes (JSON Lines), or one shard of it; `batch report DIR` tabulates.
    Batch(BatchCli),
    /// Benchmarks: whole substeps at several grid sizes (default), one scene under two
    /// integrators (--scene), or a subcommand.
    Bench(cli::bench::BenchCli),
}

/// `drapekit batch MANIFEST --out DIR [...]`, or `drapekit batch report DIR`.
#[derive(clap::Args)]
#[command(
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    after_help = "Examples:\n  \
        drapekit batch fixtures/datasets/skirts_small.jsonl --out out/skirts_small --backend cpu\n  \
        drapekit batch fixtures/datasets/skirts_small.jsonl --out out/skirts_small --shard 0/4\n  \
        drapekit batch report out/skirts_small"
)]
struct BatchCli {
    #[command(subcommand)]
    report: Option<BatchCommand>,
    /// The manifest: one JSON object a line, {"id": "…", "scene": "path.toml", "overrides": {…}}.
    #[arg(required = true)]
    manifest: Option<PathBuf>,
    /// The batch's output folder; each item writes DIR/<id>/ (the scenes' [output] dir is ignored).
    #[arg(long, required = true)]
    out: Option<PathBuf>,
    /// Run shard i of n (items k with k mod n = i). Default: from SLURM_ARRAY_TASK_ID/COUNT or
    /// JOB_COMPLETION_INDEX, else the whole manifest.
    #[arg(long)]
    shard: Option<drapekit::batch::Shard>,
    /// The shard count: with JOB_COMPLETION_INDEX (the Kubernetes Job's completions), or with
    /// a Slurm array whose task ids are shard indices (resubmitting some shards).
    #[arg(long)]
    shards: Option<u32>,
    /// Items at once (default: one per core with --backend cpu, else 1: GPU items run in turn).
    #[arg(long)]
    jobs: Option<usize>,
    /// Extra attempts for an item after a transient failure (GPU error, device lost, I/O).
    #[arg(long, default_value_t = 0)]
    retries: u32,
    /// auto: a hardware GPU if there is one, else the CPU (also instead of a software adapter
    /// such as llvmpipe); cpu; gpu.
    #[arg(long, default_value = "auto")]
    backend: BackendChoice,
    /// auto (honours WGPU_ADAPTER_NAME), fallback (software), or part of an adapter name.
    #[arg(long, default_value = "auto")]
    adapter: AdapterChoice,
    /// Override every scene's number of output frames (1 or more).
    #[arg(long, value_parser = parse_frames)]
    frames: Option<u32>,
}

#[derive(Subcommand)]
enum BatchCommand {
    /// Merge every item's summary into DIR/batch.csv and DIR/batch.md.
    Report {
        /// The batch's output folder.
        dir: PathBuf,
    },
}

/// "1280x960" → (1280, 960); each side from 16 to 3840 px (4K UHD is 3840×2160).
fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("{s:?} is not WIDTHxHEIGHT, e.g. 1280x960"))?;
    let side = |v: &str| -> Result<u32, String> {
        let n: u32 = v
            .parse()
            .map_err(|_| format!("{v:?} is not a whole number"))?;
        if (16..=3840).contains(&n) {
            Ok(n)
        } else {
            Err(format!("{n} px is outside 16 to 3840"))
        }
    };
    Ok((side(w)?, side(h)?))
}

/// `--frames`: a whole number of output frames, at least 1 (frame 0 is the starting state).
fn parse_frames(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(0) => {
            Err("0 frames simulate nothing (frame 0 is the starting state): give 1 or more".into())
        }
        Ok(n) => Ok(n),
        Err(_) => Err(format!("{s:?} is not a whole number of frames, e.g. 48")),
    }
}

/// A strain as a fraction, from 0.001 to 5 (0.1% to 500%).
fn parse_strain_max(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .parse()
        .map_err(|_| format!("{s:?} is not a number; give a fraction, e.g. 0.2 for 20%"))?;
    if (0.001..=5.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "{v} is outside 0.001 to 5; give a fraction, e.g. 0.2 for 20%"
        ))
    }
}

fn main() -> ExitCode {
    #[cfg(unix)]
    // SAFETY: restoring the default action of a signal, before any thread starts. Rust ignores
    // SIGPIPE, which turns `drapekit … | head` into a panic at the first println after the
    // reader left; the default ends the process quietly, as other command-line tools do.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // Mesa's Vulkan loader prints a harmless error per adapter without it; set before any
        // thread starts.
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    let cli = Cli::parse();
    // The CPU stages run on rayon's global pool, sized once, before any of them runs (without
    // --threads: RAYON_NUM_THREADS, else one thread per logical CPU). The command itself runs
    // on a thread of the pool: a parallel loop started there queues its tasks where the pool's
    // other threads take them and the thread takes part, where one started from outside wakes
    // a thread and sleeps until it ends, a hand-over the implicit solve pays thousands of times
    // a frame (the cotton T-shirt: about 5% faster). Not `batch`: its jobs are threads of their
    // own whose loops need the pool, and a pool thread waiting for them would leave them one
    // thread fewer (on a one-thread pool, none). The pool's threads get 8 MiB stacks, as a
    // main thread usually has.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(cli.threads.unwrap_or(0) as usize)
        .stack_size(8 << 20)
        .build_global();
    if let Err(e) = pool {
        // Built only here, so the only failure is the system's: too many threads for it.
        eprintln!(
            "drapekit: cannot start the CPU backend's {} threads ({e})\n  fix: use fewer \
             (--threads N, or RAYON_NUM_THREADS)",
            cli.threads
                .map_or_else(|| "default number of".to_string(), |n| n.to_string())
        );
        return ExitCode::from(2);
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if let Some(n) = cli.threads.filter(|&n| n as usize > 4 * cores) {
        // Results do not depend on it, but threads past the cores only take turns.
        eprintln!(
            "drapekit: note: --threads {n} on {cores} logical CPUs: the threads take turns, and \
             the CPU backend runs slower than with --threads {cores}"
        );
    }
    let result = match cli.command {
        command @ Command::Batch(_) => execute(command),
        command => rayon::scope(|_| execute(command)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("drapekit: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

fn execute(command: Command) -> Result<(), Error> {
    match command {
        Command::Run {
            scene,
            out,
            backend,
            adapter,
            frames,
            quiet,
            checkpoint_every,
            strict,
            overwrite,
        } => {
            let scene = Scene::load(&scene)?;
            drapekit::progress::enable(!quiet);
            if strict {
                // Implausible inputs stop a strict run before its long part.
                let mut found = drapekit::health::scene_warnings(&scene)?;
                found.extend(drapekit::model::budget::load_warnings(&scene));
                if !found.is_empty() {
                    for w in &found {
                        drapekit::notice::warn(w);
                    }
                    return Err(Error::Warnings(format!(
                        "--strict: {} warning(s) about the scene's inputs (above); nothing was run",
                        found.len()
                    )));
                }
            }
            let opts = RunOptions {
                backend,
                adapter,
                out_dir: out.clone(),
                frames,
                progress: !quiet,
                checkpoint_every,
                overwrite,
            };
            let out_dir = out.unwrap_or_else(|| scene.output.dir.clone());
            cli::signals::stop_on_ctrl_c();
            let summary = run_scene(&scene, &opts)?;
            report(&summary, &out_dir);
            strict_check(strict, &summary)
        }
        Command::Resume {
            dir,
            frames,
            quiet,
            strict,
        } => {
            cli::signals::stop_on_ctrl_c();
            drapekit::progress::enable(!quiet);
            let summary = drapekit::run::resume_run(&dir, frames, !quiet)?;
            report(&summary, &dir);
            strict_check(strict, &summary)
        }
        Command::Info => {
            let info = drapekit::gpu::adapters();
            if info.adapters.is_empty() {
                println!(
                    "no GPU adapter (on Debian/Ubuntu, apt-get install -y mesa-vulkan-drivers \
                     libvulkan1 gives the software one)"
                );
            }
            for a in &info.adapters {
                println!(
                    "adapter: {} ({}, {}), driver {}",
                    a.name, a.backend, a.device_type, a.driver
                );
            }
            match &info.auto {
                Some(a) => println!("--adapter auto picks: {} ({})", a.name, info.auto_reason),
                None => println!("--adapter auto finds none: {}", info.auto_reason),
            }
            if let Some(l) = &info.auto_limits {
                println!(
                    "its limits: 2D textures up to {} px, so arrays of up to {} elements (about \
                     {} particles on the GPU path); {} workgroups per dispatch dimension, {} \
                     invocations per workgroup; {} sampled and {} storage textures per stage; \
                     buffers up to {} MiB",
                    l.max_texture_dimension_2d,
                    l.max_array_elements,
                    l.max_particles,
                    l.max_compute_workgroups_per_dimension,
                    l.max_compute_invocations_per_workgroup,
                    l.max_sampled_textures_per_shader_stage,
                    l.max_storage_textures_per_shader_stage,
                    l.max_buffer_size >> 20
                );
            }
            if info.auto.as_ref().is_none_or(|a| a.device_type == "cpu") {
                println!("--backend auto runs the CPU path (no hardware GPU)");
            }
            println!("cpu: {}", drapekit::bench::cpu_description());
            let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
            println!(
                "cpu threads: {threads} available (the CPU backend uses {}; --threads N)",
                rayon::current_num_threads()
            );
            Ok(())
        }
        Command::Plan { scene, json } => {
            let scene = Scene::load(&scene)?;
            // The bake's bar is on stderr and drawn only on a terminal: `--json` output to a
            // pipe stays clean, and a first bake of a fine field is not seconds of silence.
            drapekit::progress::enable(true);
            for w in drapekit::model::budget::load_warnings(&scene) {
                drapekit::notice::warn(&w);
            }
            let prep = drapekit::sim::prepare(&scene)?;
            // What `drapekit run` would write into the scene's output folder, and whether it fits.
            let output = drapekit::export::disk::check_space(&scene, &prep, &scene.output.dir, 0)?;
            let coarse_start = match &scene.cloth {
                drapekit::scene::ClothSource::Pattern { coarse_start, .. } => *coarse_start,
                _ => None,
            };
            let plan = serde_json::json!({
                // As the scene gave it (the f32 the scene keeps, printed shortest).
                "coarse_start_distance_m": coarse_start.map(|d| (d as f32).to_string().parse::<f64>().unwrap_or(d)),
                "passes": prep.plan.names(),
                "particles": prep.model.len(),
                "triangles": prep.model.triangles.len(),
                "springs": prep.model.springs.len(),
                "hinges": prep.hinges_in_use(),
                "pinned": prep.model.pinned.iter().filter(|p| **p).count(),
                "substeps_per_frame": prep.substeps,
                "substeps_source": if prep.auto_substeps { "auto" } else { "scene" },
                "dt": prep.params.dt,
                "stable_dt_estimate_s": prep.stable_dt,
                "dt_limited_by": prep.dt_limited_by,
                "implicit_solve": prep.plan.contains(drapekit::plan::Pass::VbdSolve).then(|| {
                    let shape = drapekit::plan::SolveShape::for_run(&prep.model, &prep.params, &prep.plan);
                    serde_json::json!({
                        "shape": shape,
                        "level_particles": prep.model.multigrid.as_ref().map(|m| m.sizes()),
                        "operations_per_substep": drapekit::plan::implicit_schedule(shape).len(),
                    })
                }),
                "buckling_onset_strain": buckling_onset_strain(&prep),
                "output_frames": output.frames,
                "output_bytes_estimate": output.bytes(),
            });
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&plan).expect("plan serialises")
                );
            } else {
                println!(
                    "{}: {} particles, {} substeps/frame (dt = {:.3e} s, {})",
                    scene.path.display(),
                    prep.model.len(),
                    prep.substeps,
                    prep.params.dt,
                    if prep.auto_substeps {
                        "auto"
                    } else {
                        "from the scene"
                    }
                );
                println!(
                    "  writes about {} ({} frames) into {}",
                    drapekit::export::disk::size(output.bytes()),
                    output.frames,
                    scene.output.dir.display()
                );
                if let Some(d) = coarse_start {
                    println!(
                        "  starts from the garment meshed at {d:.3} m, sewn and draped until it \
                         settles (coarse start)"
                    );
                }
                if let Some(strain) = buckling_onset_strain(&prep) {
                    println!(
                        "  cloth buckles in compression (compression = \"buckling\"): at {:.3}% \
                         strain on average, keeping {:.0}% of its stiffness beyond",
                        100.0 * strain,
                        100.0 * prep.params.buckled_fraction
                    );
                }
                for (k, pass) in prep.plan.passes.iter().enumerate() {
                    println!(
                        "  {}. {:<15} kernels/{}.wgsl  ↔  src/cpu/{}.rs",
                        k + 1,
                        pass.name(),
                        pass.name(),
                        pass.name()
                    );
                }
                if prep.plan.contains(drapekit::plan::Pass::VbdSolve) {
                    println!("  {}", describe_solve(&prep));
                }
            }
            Ok(())
        }
        Command::Preview {
            run,
            frame,
            camera,
            mode,
            strain_max,
            seams,
            no_legend,
            checker,
            size,
            adapter,
            turntable,
            out,
        } => {
            if let Some(c) = checker.filter(|c| !(c.is_finite() && (1e-3..=10.0).contains(c))) {
                return Err(Error::Input(drapekit::error::InputError::new(
                    std::path::Path::new("--checker"),
                    "",
                    format!("{c} m is not a square size"),
                    "give the checker's square size in m, from 0.001 to 10, e.g. 0.05",
                )));
            }
            let adjust = |look: &mut drapekit::preview::Look| {
                if let Some(c) = camera {
                    look.camera = drapekit::preview::CameraChoice::Preset(c);
                }
                if let Some(m) = strain_max {
                    look.strain_max = m;
                }
                if let Some(s) = size {
                    look.size = s;
                }
                look.seams |= seams;
                if let Some(c) = checker {
                    look.checker = c;
                }
                look.legend = !no_legend;
            };
            drapekit::preview::preview_run(&run, frame, mode, &adapter, adjust, turntable, &out)?;
            println!("wrote {}", out.display());
            Ok(())
        }
        Command::Batch(BatchCli {
            report: Some(BatchCommand::Report { dir }),
            ..
        }) => {
            let report = drapekit::batch::report::write(&dir)?;
            println!(
                "{} items; wrote {} and {}",
                report.rows.len(),
                dir.join("batch.csv").display(),
                dir.join("batch.md").display()
            );
            Ok(())
        }
        Command::Batch(b) => drapekit::batch::run_cli(&drapekit::batch::BatchOptions {
            manifest: b.manifest.expect("clap requires it"),
            out: b.out.expect("clap requires it"),
            shard: b.shard,
            shards: b.shards,
            jobs: b.jobs,
            item: drapekit::batch::ItemOptions {
                backend: b.backend,
                adapter: b.adapter,
                frames: b.frames,
                retries: b.retries,
            },
        }),
        Command::Bench(b) => cli::bench::execute(b),
    }
}

/// The lines `run` and `resume` print when they finish.
fn report(summary: &drapekit::output::Summary, out_dir: &std::path::Path) {
    let device = match (&summary.adapter, summary.cpu_threads) {
        (Some(a), _) => format!("{} ({}, {})", a.name, a.backend, a.device_type),
        (None, Some(1)) => "CPU, 1 thread".to_string(),
        (None, n) => format!("CPU, {} threads", n.unwrap_or(1)),
    };
    println!(
        "simulated {:.2} s ({} frames × {} substeps, {}) on the {} backend [{}] in {:.2} s: {:.3e} particle-substeps/s",
        summary.simulated_seconds,
        summary.frames,
        summary.substeps_per_frame,
        summary.integrator,
        summary.backend,
        device,
        summary.wall_seconds,
        summary.particle_substeps_per_second
    );
    if let Some(c) = &summary.coarse_start {
        println!(
            "coarse start: {} particles at {:.3} m spacing, {} at frame {} in {:.2} s; the full \
             mesh went on from there",
            c.particles,
            c.particle_distance_m,
            if c.settled_frame.is_some() {
                "settled"
            } else {
                "not settled"
            },
            c.frame,
            c.wall_seconds
        );
    }
    println!("{}", drapekit::health::block(summary));
    println!(
        "wrote {} files to {}",
        summary.outputs.len(),
        out_dir.display()
    );
}

/// `--strict`: a run with warnings is an error (exit 5), after its results were written.
fn strict_check(strict: bool, summary: &drapekit::output::Summary) -> Result<(), Error> {
    if strict && !summary.warnings.is_empty() {
        return Err(Error::Warnings(format!(
            "--strict: the run has {} warning(s) (listed above); its files are written",
            summary.warnings.len()
        )));
    }
    Ok(())
}

/// How implicit Euler solves each substep, in one line for `drapekit plan`.
/// With `compression = "buckling"`: the mean compressive strain at which the cloth's elements
/// buckle (the membrane's warp conditions, else the springs: `cpu::stretch_law`).
fn buckling_onset_strain(prep: &drapekit::sim::Prepared) -> Option<f64> {
    let (p, m) = (&prep.params, &prep.model);
    if p.buckled_fraction <= 0.0 {
        return None;
    }
    use drapekit::cpu::stretch_law::StretchLaw;
    let strains: Vec<f64> = if m.membranes.is_empty() {
        let strain = |l: f32| (StretchLaw::spring(p, l).onset / l) as f64;
        m.springs.iter().map(|s| strain(s.rest_length)).collect()
    } else {
        let strain = |k: f32| StretchLaw::membrane(p, k, 0).onset as f64;
        m.membranes.iter().map(|t| strain(t.stiffness[0])).collect()
    };
    Some(strains.iter().sum::<f64>() / strains.len().max(1) as f64)
}

fn describe_solve(prep: &drapekit::sim::Prepared) -> String {
    let shape = drapekit::plan::SolveShape::for_run(&prep.model, &prep.params, &prep.plan);
    match &prep.model.multigrid {
        None => format!(
            "implicit solve: {} Vertex Block Descent sweeps per substep",
            shape.iterations
        ),
        Some(m) => {
            let levels: Vec<String> = m.sizes().iter().map(|n| n.to_string()).collect();
            format!(
                "implicit solve: {} Newton step(s) per substep, each after {} sweeps: conjugate \
                 gradients ({} iterations) preconditioned by a multigrid V-cycle over {} \
                 particles, then a line search; {} final sweeps",
                shape.iterations,
                shape.smoothing,
                shape.linear_iterations,
                levels.join(" → "),
                shape.smoothing
            )
        }
    }
}
