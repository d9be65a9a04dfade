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
    #[arg(long, value_delimiter = ',', default_value = "64,128,256", value_parser = grid_size())]
    sizes: Vec<u32>,
    /// Substeps per timed batch (one submission on the GPU).
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=MAX_SUBSTEPS as i64))]
    substeps: u32,
    /// Timed batches per size and backend; the median is reported.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=MAX_REPEATS as i64))]
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
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_FRAMES as i64))]
    frames: Option<u32>,
}

/// A benchmark grid's side in particles: an N×N grid from 2×2 (one cell) to 4096×4096 (16.8
/// million particles, more than a GPU benchmark here has run).
fn grid_size() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(*GRID_SIDES.start() as i64..=*GRID_SIDES.end() as i64)
}

/// The grid sides `grid_size` takes.
const GRID_SIDES: std::ops::RangeInclusive<u32> = 2..=4096;

/// The most substeps (or sweeps) a benchmark option may ask for at once: each substep's
/// parameters are made ahead, and 10⁸ of them asked for 11 TB and aborted.
const MAX_SUBSTEPS: u32 = 100_000;
/// The most frames a benchmark point may run.
const MAX_FRAMES: u32 = 1_000_000;
/// The most repeats or samples of a timing (each is kept for the median).
const MAX_REPEATS: u32 = 1_000;
/// The most Newton steps or sweeps per substep.
const MAX_ITERATIONS: u32 = 10_000;

/// `grid_size`, or 0 for no grid (`bench profile` of a scene alone).
fn grid_size_or_none(text: &str) -> Result<u32, String> {
    match text.trim().parse::<u32>() {
        Ok(n) if n == 0 || GRID_SIDES.contains(&n) => Ok(n),
        Ok(n) => Err(format!(
            "{n} is not 0 (no grid) or a grid side from {} to {}",
            GRID_SIDES.start(),
            GRID_SIDES.end()
        )),
        Err(e) => Err(format!("{text:?} is not a whole number ({e})")),
    }
}

/// The benchmark subcommands.
#[derive(Subcommand)]
enum BenchCommand {
    /// drapekit beside NVIDIA Warp's own cloth benchmark and Newton's cloth solvers (on CUDA
    /// when Warp finds it, else the CPU), on Warp's benchmark cloth, in one run; writes peer.csv and peer.md.
    #[command(
        after_help = "The peers run from a Python environment (default target/peer-venv) \
        that the first run creates with pinned warp-lang and newton (--no-venv: the Python's \
        own). They run on Warp's first CUDA device when there is one (--peer-device).\n\n\
        Examples:\n  \
        drapekit bench peer --sizes 64,128,256 --out out/peer\n  \
        drapekit bench peer --quick --out out/peer-quick\n  \
        drapekit bench peer --systems drapekit --quick --sizes 16 --newton-sizes 16"
    )]
    Peer(PeerArgs),
    /// What accuracy costs in time: one knob at a time (integrator and step, particle distance,
    /// SDF resolution, body simplification) against the finest setting of every knob; writes
    /// accuracy.csv, accuracy.md and accuracy.svg.
    Accuracy(AccuracyArgs),
    /// What each optional effect (bending, wind, seams, body collision, self-collision, strain
    /// limit) costs per substep, added and removed, on the CPU and GPU paths; writes effects.csv
    /// and effects.md.
    Effects(EffectsArgs),
    /// Every fabric preset in the Cusick drape test and the cantilever bending test, against
    /// published drape coefficients and the preset's bending rigidity; writes fabric.csv and
    /// fabric.md (and each specimen's scene under specimens/).
    Fabric(FabricArgs),
    /// Every way drapekit finds contacts with a body (the GPU's SDF pass, the CPU's SDF, BVHs
    /// with AABB, OBB and sphere volumes, exact point–triangle with and without edge–edge,
    /// brute force) on a skirt on a turning body at three sizes; writes collision.csv,
    /// collision.md and collision.svg.
    Collision(CollisionArgs),
    /// Implicit Euler's force residual against cost on one substep, plain Vertex Block Descent
    /// sweeps against Newton steps with multigrid-preconditioned conjugate gradients, at the
    /// scene's particle spacing and twice and four times finer; writes convergence.csv,
    /// convergence.md and convergence.svg.
    Convergence(ConvergenceArgs),
    /// Where the GPU's time goes in a substep, stage by stage (kernel by kernel and level by
    /// level in the implicit solve), from GPU timestamps: the benchmark cloth at several sizes
    /// and optionally a scene; writes profile.csv and profile.md.
    Profile(ProfileArgs),
}

/// `drapekit bench profile --out DIR`.
#[derive(Args)]
#[command(after_help = "Examples:\n  \
    drapekit bench profile --sizes 256,512,1024 --out out/profile\n  \
    drapekit bench profile --sizes 64 --scene fixtures/scenes/tshirt_drape_cotton.toml --out out/profile-shirt")]
struct ProfileArgs {
    /// Output folder for profile.csv and profile.md.
    #[arg(long)]
    out: PathBuf,
    /// Benchmark-cloth sizes (N: an N×N grid, springs and bending, symplectic Euler; 0: none,
    /// for a scene alone).
    #[arg(long, value_delimiter = ',', default_value = "128,256,512,1024", value_parser = grid_size_or_none)]
    sizes: Vec<u32>,
    /// Substeps profiled per size (and timed without timestamps beside them).
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=MAX_SUBSTEPS as i64))]
    substeps: u32,
    /// Also profile this scene on the GPU, with its own integrator and step.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// With --scene: frames run unprofiled, then again profiled.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=MAX_FRAMES as i64))]
    frames: u32,
    /// auto (honours WGPU_ADAPTER_NAME), fallback (software), or part of an adapter name.
    #[arg(long, default_value = "auto")]
    adapter: AdapterChoice,
}

/// `drapekit bench convergence SCENE --out DIR`.
#[derive(Args)]
#[command(after_help = "Examples:\n  \
    drapekit bench convergence fixtures/scenes/tshirt_drape_cotton.toml --out out/convergence\n  \
    drapekit bench convergence fixtures/scenes/hanging_cloth.toml --quick --out out/convergence-quick")]
struct ConvergenceArgs {
    /// The scene file (TOML): implicit Euler, a pattern or grid cloth.
    scene: PathBuf,
    /// Output folder for convergence.csv, convergence.md and convergence.svg.
    #[arg(long)]
    out: PathBuf,
    /// Frames to run before the measured substep: 0 measures the scene's first substep from its
    /// initial state (default: until the scene settles, at most its frames; 12 with --quick).
    #[arg(long)]
    frames: Option<u32>,
    /// Spacing divisors (default 1,2,4; 1,2 with --quick).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=8))]
    refinements: Vec<u32>,
    /// The most plain sweeps (default 1024; 64 with --quick).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SUBSTEPS as i64))]
    max_sweeps: Option<u32>,
    /// Frames a finer mesh runs from the carried state before its measured substep.
    #[arg(long, default_value_t = 2)]
    relax_frames: u32,
    /// The most Newton steps, and FAS cycles (default 12; 3 with --quick).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_ITERATIONS as i64))]
    max_newton: Option<u32>,
    /// Conjugate-gradient iterations in each measured multigrid Newton step (the run before the
    /// measured substep solves as the scene does). Up to 1024: a Newton step of more than a
    /// thousand V-cycles measures nothing a shorter one does not.
    #[arg(long, default_value_t = drapekit::plan::LINEAR_ITERATIONS,
          value_parser = clap::value_parser!(u32).range(1..=1024))]
    linear_iterations: u32,
    /// The nonlinear multigrid (FAS) V-cycle's coarsening: each level the cloth meshed this many
    /// times coarser than the one above, down to 150 particles (0 or 1: no FAS curve). Where
    /// the cloth coarsens no further (a grid's rows or columns less one that it does not
    /// divide), the V-cycle stops there, with a warning.
    #[arg(long, default_value_t = drapekit::bench::fas::FAS_COARSENING,
          value_parser = clap::value_parser!(u32).range(0..=8))]
    fas_coarsening: u32,
    /// Vertex Block Descent sweeps on the FAS V-cycle's coarsest level in each cycle.
    #[arg(long, default_value_t = drapekit::bench::fas::FAS_COARSE_SWEEPS,
          value_parser = clap::value_parser!(u32).range(1..=4096))]
    fas_sweeps: u32,
    /// Fewer frames, two spacings and short curves (a smoke test).
    #[arg(long)]
    quick: bool,
}

/// `drapekit bench collision --out DIR`.
#[derive(Args)]
#[command(after_help = "Examples:\n  \
    drapekit bench collision --out out/collision\n  \
    drapekit bench collision --quick --out out/collision-quick\n  \
    drapekit bench collision --strategies sdf,bvh-aabb,exact --scales 1,4 --out out/collision-some")]
struct CollisionArgs {
    /// Output folder for collision.csv, collision.md and collision.svg.
    #[arg(long)]
    out: PathBuf,
    /// The scene: a pattern or grid cloth and a moving body.
    #[arg(long, default_value = "fixtures/scenes/skirt_collision.toml")]
    scene: PathBuf,
    /// Particle-count multiples of the scene's cloth (default 1,4,16; 1 with --quick).
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=64))]
    scales: Vec<u32>,
    /// The strategies (default: all): gpu-sdf, sdf, bvh-aabb, bvh-obb, bvh-sphere, exact,
    /// exact+edges, brute (brute runs at the first scale only).
    #[arg(long, value_delimiter = ',')]
    strategies: Vec<String>,
    /// One sample, two timed stages and ten substeps per strategy, at the scene's size.
    #[arg(long)]
    quick: bool,
    /// Frames sampled over the body's motion (default 4; 1 with --quick).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_REPEATS as i64))]
    samples: Option<u32>,
    /// Whole substeps timed per sample and strategy (default 50; 10 with --quick).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SUBSTEPS as i64))]
    window: Option<u32>,
    /// Timed collision stages per sample and strategy (default 5; 2 with --quick).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_REPEATS as i64))]
    repeats: Option<u32>,
    /// The GPU strategy's adapter: auto (honours WGPU_ADAPTER_NAME), fallback (software), or
    /// part of an adapter name.
    #[arg(long, default_value = "auto")]
    adapter: AdapterChoice,
}

/// `drapekit bench fabric --out DIR`.
#[derive(Args)]
#[command(after_help = "Examples:\n  \
    drapekit bench fabric --out out/fabric\n  \
    drapekit bench fabric --quick --presets cotton,silk --out out/fabric-quick")]
struct FabricArgs {
    /// Output folder for fabric.csv, fabric.md and the specimens' scenes.
    #[arg(long)]
    out: PathBuf,
    /// Coarser specimens (1.5 cm Cusick spacing, 12 particles along the overhang), two
    /// cantilever runs and at most 96 frames each.
    #[arg(long)]
    quick: bool,
    /// The presets to test (default: all).
    #[arg(long, value_delimiter = ',')]
    presets: Vec<String>,
    /// The specimens' integrator: symplectic (converges to the resting shape at its stable step)
    /// or implicit (Newton steps at large steps; see docs/src/benchmarks/fabric.md).
    #[arg(long, default_value = "symplectic", value_parser = ["symplectic", "implicit"])]
    integrator: String,
    /// Substeps per frame (default: the stability estimate for symplectic, 4 for implicit).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SUBSTEPS as i64))]
    substeps: Option<u32>,
    /// Implicit iterations per substep: Newton steps where the specimen has coarse levels,
    /// sweeps where it has none (default: the scene's default, 1 Newton step or 10 sweeps).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_ITERATIONS as i64))]
    iterations: Option<u32>,
    /// Implicit only: end a step's solve once its RMS force residual is at most this fraction
    /// of the weight (0.01 = 1%), with --iterations the most Newton steps (default 8 with a
    /// tolerance).
    #[arg(long, value_parser = fraction_of_weight)]
    tolerance: Option<f32>,
    /// The most frames a specimen may take to settle (default 480; 96 with --quick).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_FRAMES as i64))]
    max_frames: Option<u32>,
    /// The fabric model: isotropic edge springs, or the orthotropic membrane (the preset's
    /// warp, weft and shear; cantilevers cut along the warp, the weft and the bias).
    #[arg(long, default_value = "springs", value_parser = ["springs", "membrane"])]
    fabric_model: String,
    /// The Cusick specimen's particle spacing in mm (default 7.5; 15 with --quick): run it at
    /// several to see how the drape coefficient converges with the mesh.
    #[arg(long, value_parser = positive_mm)]
    cusick_spacing_mm: Option<f64>,
    /// The tests to run (default both).
    #[arg(long, value_delimiter = ',', value_parser = ["cusick", "cantilever"])]
    tests: Vec<String>,
    /// Multiply every preset's bending rigidity by this (0.01 to 100; default 1), to see how
    /// the drape coefficient follows bending (the cantilevers measure the scaled rigidity).
    #[arg(long, value_parser = bending_scale)]
    bending_scale: Option<f64>,
    /// How the cloth takes compression: linearly, or buckling at its strip's Euler load
    /// (`[fabric] compression`).
    #[arg(long, default_value = "linear", value_parser = ["linear", "buckling"])]
    compression: String,
    /// cpu: the CPU twin (the book's figures); gpu: the GPU path on --adapter; auto: a hardware
    /// GPU if there is one (a software adapter only when --adapter names it), else the CPU.
    #[arg(long, default_value = "cpu")]
    backend: BackendChoice,
    /// The GPU path's adapter: auto (honours WGPU_ADAPTER_NAME), fallback (software), or part
    /// of an adapter name.
    #[arg(long, default_value = "auto")]
    adapter: AdapterChoice,
}

/// The command line as a reader would type it: `drapekit` and its arguments, whatever path
/// the binary was run from.
fn command_line() -> String {
    std::iter::once("drapekit".to_string())
        .chain(std::env::args().skip(1))
        .collect::<Vec<_>>()
        .join(" ")
}

/// A force-residual tolerance: as `[solver] tolerance` takes it.
fn fraction_of_weight(text: &str) -> Result<f32, String> {
    // Checked in f64, as the scene's key is.
    let (low, high) = drapekit::scene::TOLERANCE_RANGE;
    match text.parse::<f64>() {
        Ok(t) if (low..=high).contains(&t) => Ok(t as f32),
        Ok(t) => Err(format!(
            "{t} is outside {low:e} to {high:e} (a fraction of the weight)"
        )),
        Err(e) => Err(format!("{text:?} is not a number ({e})")),
    }
}

/// The bending scale's range: a hundredth to a hundred times the preset's rigidity spans the
/// bending lengths of real fabrics (0.7 to 3.9 cm in Feng et al. 2022's 618) from any preset.
fn bending_scale(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(f) if (0.01..=100.0).contains(&f) => Ok(f),
        Ok(f) => Err(format!("{f} is outside 0.01 to 100")),
        Err(e) => Err(format!("{text:?} is not a number ({e})")),
    }
}

/// A spacing in mm between 1 and 50: finer meshes a 30 cm disc into millions of particles,
/// coarser leaves a handful across the 6 cm annulus that drapes.
fn positive_mm(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(mm) if (1.0..=50.0).contains(&mm) => Ok(mm),
        Ok(mm) => Err(format!("{mm} mm is outside 1 to 50 mm")),
        Err(e) => Err(format!("{text:?} is not a number of mm ({e})")),
    }
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
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_FRAMES as i64))]
    frames: Option<u32>,
    /// The most substeps per frame a point may take; points whose stability bound asks for
    /// more are reported as failed with the count they need (default: the scene's
    /// max_substeps_per_frame; with --quick at most 2000).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SUBSTEPS as i64))]
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

/// `drapekit bench peer`.
#[derive(Args)]
struct PeerArgs {
    /// Grid sizes of the Warp comparison: N means Warp's N×N benchmark cloth.
    #[arg(long, value_delimiter = ',', default_value = "64,128,256", value_parser = grid_size())]
    sizes: Vec<u32>,
    /// Grid sizes of the Newton comparison (Newton's two solvers and drapekit's two
    /// integrators).
    #[arg(long, value_delimiter = ',', default_value = "64", value_parser = grid_size())]
    newton_sizes: Vec<u32>,
    /// Timed frames per point (default 60, one simulated second as in Warp's benchmark;
    /// 6 with --quick).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_FRAMES as i64))]
    frames: Option<u32>,
    /// A short run: 6 frames per point.
    #[arg(long)]
    quick: bool,
    /// Which systems to time: drapekit, warp, newton.
    #[arg(long, value_delimiter = ',', default_value = "drapekit,warp,newton")]
    systems: Vec<drapekit::bench::peer::System>,
    /// Substeps per frame of the implicit points (Newton's VBD, drapekit's implicit Euler).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=MAX_SUBSTEPS as i64))]
    implicit_substeps: u32,
    /// Sweeps per implicit substep.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=MAX_ITERATIONS as i64))]
    iterations: u32,
    /// Output folder for peer.csv and peer.md.
    #[arg(long, default_value = "out/peer")]
    out: PathBuf,
    /// auto (honours WGPU_ADAPTER_NAME), fallback (software), or part of an adapter name.
    #[arg(long, default_value = "auto")]
    adapter: AdapterChoice,
    /// The Python that creates the environment (3.10 or newer).
    #[arg(long, default_value = "python3")]
    python: String,
    /// The Python environment's folder (created on first use).
    #[arg(long, default_value = "target/peer-venv")]
    venv: PathBuf,
    /// Run the peers with --python itself, with the warp and newton it imports (any version,
    /// recorded in the report; e.g. from PYTHONPATH on a machine without the network); --venv
    /// then only holds the driver script.
    #[arg(long)]
    no_venv: bool,
    /// Warp's device for Warp and Newton: auto (the first CUDA device when Warp finds one,
    /// else the CPU), cpu or cuda.
    #[arg(long, default_value = "auto", value_parser = ["auto", "cpu", "cuda"])]
    peer_device: String,
}

impl BenchCommand {
    /// The subcommand's output folder.
    fn out(&self) -> &std::path::Path {
        match self {
            BenchCommand::Peer(p) => &p.out,
            BenchCommand::Accuracy(a) => &a.out,
            BenchCommand::Effects(e) => &e.out,
            BenchCommand::Fabric(f) => &f.out,
            BenchCommand::Collision(c) => &c.out,
            BenchCommand::Convergence(c) => &c.out,
            BenchCommand::Profile(p) => &p.out,
        }
    }
}

/// Runs `drapekit bench …`. An output folder that names a file is refused before anything
/// runs (the reports are written at the end, minutes later).
pub fn execute(b: BenchCli) -> Result<(), Error> {
    let out = b.command.as_ref().map_or(b.out.as_path(), |c| c.out());
    if out.exists() && !out.is_dir() {
        return Err(Error::Input(drapekit::error::InputError::new(
            out,
            "--out",
            "is a file, not a folder: the benchmark writes its reports into a folder",
            "give a folder (it is made if it does not exist)",
        )));
    }
    match (b.command, b.scene) {
        (Some(BenchCommand::Peer(p)), _) => run_peer(p),
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
        (Some(BenchCommand::Fabric(f)), _) => {
            drapekit::bench::fabric::run_cli(&drapekit::bench::fabric::FabricOptions {
                out: f.out,
                quick: f.quick,
                presets: f.presets,
                stepping: drapekit::bench::fabric::Stepping {
                    substeps: f.substeps.or((f.integrator == "implicit").then_some(4)),
                    integrator: f.integrator,
                    iterations: f.iterations.or(f.tolerance.map(|_| 8)),
                    tolerance: f.tolerance,
                    max_frames: f.max_frames.unwrap_or(if f.quick { 96 } else { 480 }),
                    fabric_model: f.fabric_model,
                    bending_scale: f.bending_scale,
                    buckling: f.compression == "buckling",
                },
                cusick_spacing: f.cusick_spacing_mm.map(|mm| mm * 1e-3),
                tests: drapekit::bench::fabric::Tests {
                    cusick: f.tests.is_empty() || f.tests.iter().any(|t| t == "cusick"),
                    cantilever: f.tests.is_empty() || f.tests.iter().any(|t| t == "cantilever"),
                },
                backend: f.backend,
                adapter: f.adapter,
                command: command_line(),
            })
            .map(|_| ())
        }
        (Some(BenchCommand::Profile(p)), _) => {
            let sizes: Vec<u32> = p.sizes.into_iter().filter(|&n| n > 0).collect();
            if sizes.is_empty() && p.scene.is_none() {
                return Err(Error::Input(drapekit::error::InputError::new(
                    std::path::Path::new("drapekit bench profile"),
                    "--sizes",
                    "no grid size and no --scene: nothing to profile".to_string(),
                    "give grid sizes (e.g. --sizes 128,256) or a scene with --scene",
                )));
            }
            drapekit::bench::profile::run_cli(&drapekit::bench::profile::ProfileOptions {
                sizes,
                substeps: p.substeps,
                scene: p.scene,
                frames: p.frames,
                adapter: p.adapter,
                out: p.out,
                command: command_line(),
            })
            .map(|_| ())
        }
        (Some(BenchCommand::Convergence(c)), _) => {
            let quick = |normal, quick| if c.quick { quick } else { normal };
            drapekit::bench::convergence::run_cli(
                &drapekit::bench::convergence::ConvergenceOptions {
                    frames: c.frames.or(c.quick.then_some(12)),
                    refinements: match (c.refinements.is_empty(), c.quick) {
                        (false, _) => c.refinements.clone(),
                        (true, true) => vec![1, 2],
                        (true, false) => vec![1, 2, 4],
                    },
                    max_sweeps: c.max_sweeps.unwrap_or(quick(1024, 64)),
                    max_newton: c.max_newton.unwrap_or(quick(12, 3)),
                    relax_frames: c.relax_frames,
                    linear_iterations: c.linear_iterations,
                    fas_coarsening: c.fas_coarsening,
                    fas_sweeps: c.fas_sweeps,
                    scene: c.scene,
                    out: c.out,
                },
            )
            .map(|_| ())
        }
        (Some(BenchCommand::Collision(c)), _) => {
            let pick = |v: Option<u32>, normal: u32, quick: u32| {
                v.unwrap_or(if c.quick { quick } else { normal }) as usize
            };
            drapekit::bench::collision::run_cli(&drapekit::bench::collision::CollisionOptions {
                scales: match (c.scales.is_empty(), c.quick) {
                    (false, _) => c.scales.clone(),
                    (true, true) => vec![1],
                    (true, false) => vec![1, 4, 16],
                },
                samples: pick(c.samples, 4, 1),
                repeats: pick(c.repeats, 5, 2),
                window: pick(c.window, 50, 10),
                scene: c.scene,
                out: c.out,
                contenders: c.strategies,
                adapter: c.adapter,
                command: command_line(),
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

fn run_peer(p: PeerArgs) -> Result<(), Error> {
    use drapekit::bench::peer::{run_cli, PeerOptions};
    let positive = |sizes: &[u32], key: &str| {
        if sizes.iter().any(|&n| n < 3) {
            return Err(Error::Input(drapekit::error::InputError::new(
                std::path::Path::new("drapekit bench peer"),
                key,
                format!("{sizes:?} has a size below 3"),
                "use grid sizes of 3 or more (Warp's cloth has bend springs two apart)",
            )));
        }
        Ok(())
    };
    positive(&p.sizes, "--sizes")?;
    positive(&p.newton_sizes, "--newton-sizes")?;
    let command = command_line();
    run_cli(&PeerOptions {
        sizes: p.sizes,
        newton_sizes: p.newton_sizes,
        frames: p.frames.unwrap_or(if p.quick { 6 } else { 60 }),
        systems: p.systems,
        implicit_substeps: p.implicit_substeps,
        iterations: p.iterations,
        out: p.out,
        adapter: p.adapter,
        python: p.python,
        venv: p.venv,
        no_venv: p.no_venv,
        peer_device: p.peer_device,
        command,
    })
    .map(|_| ())
}
