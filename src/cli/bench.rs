//! `drapekit bench …`: the benchmark commands. With no subcommand it times whole substeps of
//! the benchmark cloth at several sizes (or, with `--scene`, one scene under two integrators).

use clap::{Args, Subcommand};
use drapekit::gpu::AdapterChoice;
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
enum BenchCommand {}

/// Runs `drapekit bench …`.
pub fn execute(b: BenchCli) -> Result<(), Error> {
    match (b.command, b.scene) {
        (Some(command), _) => match command {},
        (None, Some(scene)) => {
            drapekit::bench::integrators::run_cli(&scene, b.frames, &b.out, &b.adapter).map(|_| ())
        }
        (None, None) => {
            drapekit::bench::grid::run_cli(&b.sizes, b.substeps, b.repeats, &b.out, &b.adapter)
        }
    }
}
