//! The `drapekit` command line: parses arguments, calls the library, reports.

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
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene and write OBJ frames and summary.json.
    Run {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output folder (default: [output] dir, else out/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// auto: the GPU if an adapter exists, else the CPU; cpu; gpu.
        #[arg(long, default_value = "auto")]
        backend: BackendChoice,
        /// auto (honours WGPU_ADAPTER_NAME), fallback (software), or part of an adapter name.
        #[arg(long, default_value = "auto")]
        adapter: AdapterChoice,
        /// Override the number of output frames.
        #[arg(long)]
        frames: Option<u32>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// List the GPU adapters, the one `--adapter auto` picks, and the CPU.
    Info,
    /// Render one frame of a finished run (the garment and the body) to a PNG.
    Preview {
        /// The run's output folder (frame_NNNN.obj and summary.json).
        run: PathBuf,
        /// The frame (default: the last one written).
        #[arg(long)]
        frame: Option<u32>,
        /// front, back, side or three-quarter.
        #[arg(long, default_value = "three-quarter")]
        camera: drapekit::preview::CameraPreset,
        /// fabric, or strain (each triangle's stretch against frame 0, blue 0% to red 20%).
        #[arg(long, default_value = "fabric")]
        mode: drapekit::preview::ColorMode,
        /// Image size, WIDTHxHEIGHT in pixels.
        #[arg(long, default_value = "1280x960", value_parser = parse_size)]
        size: (u32, u32),
        /// auto (honours WGPU_ADAPTER_NAME), fallback (software), or part of an adapter name.
        #[arg(long, default_value = "auto")]
        adapter: AdapterChoice,
        /// The PNG to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Print the pass plan a scene compiles to.
    Plan {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Print JSON: {"passes": [...], ...}.
        #[arg(long)]
        json: bool,
    },
    /// Run a manifest of scenes (JSON Lines), or one shard of it; `batch report DIR` tabulates.
    Batch(BatchCli),
    /// Time whole substeps on both backends and write CSV and Markdown tables.
    Bench {
        /// Grid sizes: N means an N×N particle grid.
        #[arg(long, value_delimiter = ',', default_value = "64,128,256")]
        sizes: Vec<u32>,
        /// Substeps per timed batch (one submission on the GPU).
        #[arg(long, default_value_t = 100)]
        substeps: u32,
        /// Timed batches per size and backend; the median is reported.
        #[arg(long, default_value_t = 5)]
        repeats: u32,
        /// Output folder for bench.csv and bench.md.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// auto (honours WGPU_ADAPTER_NAME), fallback (software), or part of an adapter name.
        #[arg(long, default_value = "auto")]
        adapter: AdapterChoice,
        /// Instead of the grid sizes: run this scene under symplectic and implicit Euler on both
        /// backends and write integrators.csv and integrators.md.
        #[arg(long)]
        scene: Option<PathBuf>,
        /// With --scene: output frames per point (default: the scene's).
        #[arg(long)]
        frames: Option<u32>,
    },
}

/// `drapekit batch MANIFEST --out DIR [...]`, or `drapekit batch report DIR`.
#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
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
    /// auto: the GPU if an adapter exists, else the CPU; cpu; gpu.
    #[arg(long, default_value = "auto")]
    backend: BackendChoice,
    /// auto (honours WGPU_ADAPTER_NAME), fallback (software), or part of an adapter name.
    #[arg(long, default_value = "auto")]
    adapter: AdapterChoice,
    /// Override every scene's number of output frames.
    #[arg(long)]
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    match execute(cli.command) {
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
        } => {
            let scene = Scene::load(&scene)?;
            let opts = RunOptions {
                backend,
                adapter,
                out_dir: out.clone(),
                frames,
                progress: !quiet,
            };
            let out_dir = out.unwrap_or_else(|| scene.output.dir.clone());
            let summary = run_scene(&scene, &opts)?;
            let device = summary
                .adapter
                .as_ref()
                .map_or("single-threaded CPU".to_string(), |a| {
                    format!("{} ({}, {})", a.name, a.backend, a.device_type)
                });
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
            if let Some(s) = &summary.settled {
                println!("settled at frame {} ({})", s.frame, s.rule);
            }
            println!(
                "wrote {} files to {}",
                summary.outputs.len(),
                out_dir.display()
            );
            Ok(())
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
            println!("cpu: {}", drapekit::bench::cpu_description());
            Ok(())
        }
        Command::Plan { scene, json } => {
            let scene = Scene::load(&scene)?;
            let prep = drapekit::sim::prepare(&scene)?;
            let plan = serde_json::json!({
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
                for (k, pass) in prep.plan.passes.iter().enumerate() {
                    println!(
                        "  {}. {:<15} kernels/{}.wgsl  ↔  src/cpu/{}.rs",
                        k + 1,
                        pass.name(),
                        pass.name(),
                        pass.name()
                    );
                }
            }
            Ok(())
        }
        Command::Preview {
            run,
            frame,
            camera,
            mode,
            size,
            adapter,
            out,
        } => {
            let options = drapekit::preview::PreviewOptions {
                frame,
                camera,
                mode,
                size,
                adapter,
            };
            drapekit::preview::preview_run(&run, &options, &out)?;
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
        Command::Bench {
            scene: Some(scene),
            frames,
            out,
            adapter,
            ..
        } => drapekit::bench_integrators::run_cli(&scene, frames, &out, &adapter).map(|_| ()),
        Command::Bench {
            sizes,
            substeps,
            repeats,
            out,
            adapter,
            ..
        } => drapekit::bench::run_cli(&sizes, substeps, repeats, &out, &adapter),
    }
}
