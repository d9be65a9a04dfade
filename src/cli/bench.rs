//! `drapekit bench …`: the benchmark commands. With no subcommand it times whole substeps of
//! the benchmark cloth at several sizes (or, with `--scene`, one scene under two integrators).

use clap::{Args, Subcommand};
use drapekit::gpu::AdapterChoice;
use drapekit::run::BackendChoice;
use drapekit::Error;
use std::path::PathBuf;

/// `drapekit bench [--sizes …]`, `drapekit bench --scene SCENE`, or `drapekit bench <what> …`.
#[derive(Args)]
#[command(args_conflicts_with_subcommands = true)]
#[command(after_help = "Examples:\n  \
    drapekit bench --sizes 64,128 --repeats 3 --out out/bench\n  \
    drapekit bench --scene fixtures/scenes/hanging_cloth.toml --frames 24 --out out/integrators")]
pub struct BenchCli {
    #[command(subcommand)]
    command: Option<BenchCommand>,
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
}

/// The benchmark subcommands.
#[derive(Subcommand)]
enum BenchCommand {
    /// What accuracy costs in time: one knob at a time (integrator and step, particle distance,
    /// SDF resolution, body simplification) against the finest setting of every knob; writes
    /// accuracy.csv, accuracy.md and accuracy.svg.
    Accuracy(AccuracyArgs),
    /// What each optional effect (bending, wind, seams, body collision, self-collision, strain
    /// limit) costs per substep, added and removed, on the CPU and GPU paths; writes effects.csv
    /// and effects.md.
    Effects(EffectsArgs),
}

/// `drapekit bench accuracy SCENE --out DIR`.
#[derive(Args)]
#[command(after_help = "Examples:\n  \
    drapekit bench accuracy fixtures/scenes/drape_sphere.toml --out out/accuracy/sphere\n  \
    drapekit bench accuracy fixtures/scenes/tshirt_drape_cotton.toml --frames 168 --max-substeps 2000 --out out/accuracy/tshirt\n  \
    drapekit bench accuracy fixtures/scenes/drape_sphere.toml --quick --out out/accuracy/quick")]
struct AccuracyArgs {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Output folder for accuracy.csv, accuracy.md, accuracy.svg (and the simplified bodies).
    #[arg(long)]
    out: PathBuf,
    /// Shorter ladders and at most 12 frames per point (unless --frames is given).
    #[arg(long)]
    quick: bool,
    /// Output frames per point (default: the scene's; every point runs them all).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    frames: Option<u32>,
    /// The most substeps per frame a point may take; points whose stability bound asks for
    /// more are reported as failed with the count they need (default: the scene's
    /// max_substeps_per_frame; with --quick at most 2000).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    max_substeps: Option<u32>,
    /// auto: a hardware GPU if there is one, else the CPU; cpu; gpu.
    #[arg(long, default_value = "auto")]
    backend: BackendChoice,
    /// auto (honours WGPU_ADAPTER_NAME), fallback (software), or part of an adapter name.
    #[arg(long, default_value = "auto")]
    adapter: AdapterChoice,
}

/// `drapekit bench effects SCENE --out DIR`.
#[derive(Args)]
#[command(after_help = "Examples:\n  \
    drapekit bench effects fixtures/scenes/tshirt_drape_cotton.toml --out out/effects/tshirt\n  \
    drapekit bench effects fixtures/scenes/drape_sphere.toml --quick --adapter fallback --out out/effects/quick")]
struct EffectsArgs {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Output folder for effects.csv and effects.md.
    #[arg(long)]
    out: PathBuf,
    /// Three timed batches per plan of about 0.05 s instead of fifteen of about 0.1 s.
    #[arg(long)]
    quick: bool,
    /// The GPU path's adapter: auto (honours WGPU_ADAPTER_NAME), fallback (software), or part
    /// of an adapter name.
    #[arg(long, default_value = "auto")]
    adapter: AdapterChoice,
}

/// Runs `drapekit bench …`.
pub fn execute(b: BenchCli) -> Result<(), Error> {
    match (b.command, b.scene) {
        (Some(BenchCommand::Accuracy(a)), _) => {
            drapekit::bench::accuracy::run_cli(&drapekit::bench::accuracy::AccuracyOptions {
                scene: a.scene,
                out: a.out,
                quick: a.quick,
                frames: a.frames,
                max_substeps: a.max_substeps,
                backend: a.backend,
                adapter: a.adapter,
            })
            .map(|_| ())
        }
        (Some(BenchCommand::Effects(e)), _) => {
            drapekit::bench::effects::run_cli(&drapekit::bench::effects::EffectsOptions {
                scene: e.scene,
                out: e.out,
                quick: e.quick,
                adapter: e.adapter,
            })
            .map(|_| ())
        }
        (None, Some(scene)) => {
            drapekit::bench::integrators::run_cli(&scene, b.frames, &b.out, &b.adapter).map(|_| ())
        }
        (None, None) => {
            drapekit::bench::grid::run_cli(&b.sizes, b.substeps, b.repeats, &b.out, &b.adapter)
        }
    }
}
