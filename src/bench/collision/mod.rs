//! `drapekit bench collision --out DIR`: every way drapekit finds contacts with a body, on one
//! skirt on a turning body, at the scene's particle count and at about 4× and 16× it.
//!
//! The contenders are the GPU's SDF pass, its CPU twin, our BVHs with axis-aligned boxes,
//! oriented boxes and spheres, parry's exact point queries (point–triangle only, against the
//! body enlarged by the thickness), the same plus cloth-edge against body-edge contacts, and
//! every particle against every triangle (`brute`, at the first size only). Every contender
//! sees the same states: one warm-up run per size (CPU, SDF) records the state at frames spread
//! over the body's motion; from each, one substep's passes before the collision stage give the
//! state the stage receives. On that state each contender's collision stage alone is timed and
//! its contacts (the particles it moves) are compared with `exact`'s; from the frame's state a
//! window of whole substeps is timed, and the deepest any particle or edge midpoint then lies
//! inside the exact body is measured. Writes `collision.csv`, `collision.md` and
//! `collision.svg`.

mod deforming;
mod measure;
mod report;

use super::cpu_threads_description;
use crate::atomic_file::write_atomic;
use crate::body::Strategy;
use crate::error::{Error, InputError};
use crate::gpu::{AdapterChoice, GpuContext};
use crate::scene::{ClothSource, Scene};
use std::path::PathBuf;

pub use measure::Sample;

/// The options of `drapekit bench collision`.
#[derive(Clone, Debug)]
pub struct CollisionOptions {
    /// The scene: a pattern or grid cloth and a moving body.
    pub scene: PathBuf,
    /// Output folder.
    pub out: PathBuf,
    /// Particle-count multiples of the scene's cloth (1, 4, 16: spacing ÷1, ÷2, ÷4).
    pub scales: Vec<u32>,
    /// The contenders to run (empty: all).
    pub contenders: Vec<String>,
    /// Frames sampled over the body's motion.
    pub samples: usize,
    /// Timed collision stages per sample and contender (the fastest counts).
    pub repeats: usize,
    /// Whole substeps timed per sample and contender.
    pub window: usize,
    /// The adapter of the GPU contender.
    pub adapter: AdapterChoice,
    /// The command line, for the report.
    pub command: String,
}

/// A way of finding contacts with the body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contender {
    /// `kernels/collide_body.wgsl` on the GPU.
    GpuSdf,
    /// A CPU strategy, point–triangle (or SDF) contacts only.
    Cpu(Strategy),
    /// `exact` plus cloth-edge against body-edge contacts.
    ExactEdges,
}

impl Contender {
    /// Every contender, in table order.
    pub const ALL: [Contender; 8] = [
        Contender::GpuSdf,
        Contender::Cpu(Strategy::Sdf),
        Contender::Cpu(Strategy::BvhAabb),
        Contender::Cpu(Strategy::BvhObb),
        Contender::Cpu(Strategy::BvhSphere),
        Contender::Cpu(Strategy::Exact),
        Contender::ExactEdges,
        Contender::Cpu(Strategy::Brute),
    ];

    /// The name in the tables and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Contender::GpuSdf => "gpu-sdf",
            Contender::Cpu(s) => s.name(),
            Contender::ExactEdges => "exact+edges",
        }
    }

    /// "gpu" or "cpu".
    pub fn backend(self) -> &'static str {
        match self {
            Contender::GpuSdf => "gpu",
            _ => "cpu",
        }
    }
}

/// The CSV's columns, in order (documented in docs/src/benchmarks/collision.md).
pub const CSV_COLUMNS: [&str; 24] = [
    "scale",
    "particles",
    "body_triangles",
    "strategy",
    "backend",
    "device",
    "samples",
    "repeats",
    "window_substeps",
    "collision_us_per_substep",
    "collision_in_run_us",
    "substep_us",
    "collision_share_percent",
    "contacts",
    "exact_contacts",
    "missed",
    "extra",
    "missed_percent",
    "extra_percent",
    "max_penetration_mm",
    "max_edge_penetration_mm",
    "build_ms",
    "memory_bytes",
    "note",
];

/// One contender at one size. Times are µs per substep: per sample the fastest of the
/// repeats (collision) or the window's mean (substep), averaged over the samples.
#[derive(Clone, Debug)]
pub struct CollisionRow {
    /// Particle-count multiple of the scene's cloth.
    pub scale: u32,
    /// Particles.
    pub particles: usize,
    /// Body triangles.
    pub body_triangles: usize,
    /// The contender.
    pub contender: Contender,
    /// The device.
    pub device: String,
    /// Frames sampled.
    pub samples: usize,
    /// Timed collision stages per sample.
    pub repeats: usize,
    /// Whole substeps timed per sample.
    pub window_substeps: usize,
    /// The collision stage alone, on the state every contender receives.
    pub collision_us: f64,
    /// The collision stage in the contender's own run: a whole substep less the plan without
    /// the stage, over the same window.
    pub in_run_us: f64,
    /// A whole substep with this contender.
    pub substep_us: f64,
    /// Particles the stage moved, summed over the samples.
    pub contacts: usize,
    /// Particles `exact` moved.
    pub exact_contacts: usize,
    /// Particles `exact` moved and this contender did not.
    pub missed: usize,
    /// Particles this contender moved and `exact` did not.
    pub extra: usize,
    /// Deepest particle inside the exact body, after the stage and after each window, in m.
    pub max_penetration: f32,
    /// Deepest cloth-edge midpoint inside the exact body, likewise, in m.
    pub max_edge_penetration: f32,
    /// Building the contender's structure (the body is rigid: built once, never refitted), s.
    pub build_s: f64,
    /// The structure's bytes.
    pub memory_bytes: usize,
    /// What to know.
    pub note: String,
}

impl CollisionRow {
    /// A row at scale 1 with nothing measured yet (the measurements add up over the samples).
    pub fn new(
        contender: Contender,
        particles: usize,
        body_triangles: usize,
        note: String,
    ) -> Self {
        CollisionRow {
            scale: 1,
            particles,
            body_triangles,
            contender,
            device: String::new(),
            samples: 0,
            repeats: 0,
            window_substeps: 0,
            collision_us: 0.0,
            in_run_us: 0.0,
            substep_us: 0.0,
            contacts: 0,
            exact_contacts: 0,
            missed: 0,
            extra: 0,
            max_penetration: 0.0,
            max_edge_penetration: 0.0,
            build_s: 0.0,
            memory_bytes: 0,
            note,
        }
    }

    /// The collision stage's share of a whole substep in the contender's own run, in %.
    pub fn share_percent(&self) -> f64 {
        100.0 * self.in_run_us / self.substep_us
    }
}

fn bad(opts: &CollisionOptions, key: &str, problem: String, fix: &str) -> Error {
    Error::Input(InputError::new(&opts.scene, key, problem, fix))
}

/// The contenders `opts` asks for, in table order.
fn chosen(opts: &CollisionOptions) -> Result<Vec<Contender>, Error> {
    let names: Vec<&str> = Contender::ALL.iter().map(|c| c.name()).collect();
    for name in &opts.contenders {
        if !names.contains(&name.as_str()) {
            return Err(Error::Input(InputError::new(
                std::path::Path::new("drapekit bench collision"),
                "--strategies",
                format!("unknown strategy {name:?}"),
                format!("use some of: {}", names.join(", ")),
            )));
        }
    }
    Ok(Contender::ALL
        .into_iter()
        .filter(|c| opts.contenders.is_empty() || opts.contenders.iter().any(|n| n == c.name()))
        .collect())
}

/// The scene at `scale` times its particle count: the particle spacing divided by √scale.
fn scaled(scene: &Scene, scale: u32) -> Scene {
    let mut s = scene.clone();
    let shrink = (scale as f64).sqrt();
    match &mut s.cloth {
        ClothSource::Pattern { options, .. } => options.particle_distance /= shrink,
        ClothSource::Grid { columns, rows, .. } => {
            let more = |n: &mut u32| *n = (((*n - 1) as f64 * shrink).round() as u32).max(1) + 1;
            more(columns);
            more(rows);
        }
        ClothSource::Mesh { .. } => {}
    }
    // Every size runs to the same frames, and the warm-up state is the only CPU strategy's.
    s.solver.settle_speed = None;
    if let Some(b) = s.bodies.first_mut() {
        b.strategy = Strategy::Sdf;
        b.edge_contacts = false;
    }
    s
}

/// Runs the benchmark and writes `collision.csv`, `collision.md` and `collision.svg`.
pub fn run_cli(opts: &CollisionOptions) -> Result<Vec<CollisionRow>, Error> {
    let contenders = chosen(opts)?;
    let scene = Scene::load(&opts.scene)?;
    if scene.bodies.is_empty() {
        return Err(bad(
            opts,
            "body",
            "the scene has no body to collide with".into(),
            "use a scene with a [body] section, e.g. fixtures/scenes/skirt_collision.toml",
        ));
    }
    if scene.bodies.len() > 1 {
        return Err(bad(
            opts,
            "body[1]",
            format!(
                "the scene has {} bodies, and the bench compares strategies on one",
                scene.bodies.len()
            ),
            "use a scene with a single [body] table, e.g. fixtures/scenes/skirt_collision.toml",
        ));
    }
    if matches!(scene.cloth, ClothSource::Mesh { .. }) && opts.scales.iter().any(|&s| s != 1) {
        return Err(bad(
            opts,
            "cloth.mesh",
            "a cloth loaded from a mesh cannot be refined to more particles".into(),
            "use --scales 1, or a pattern or grid cloth",
        ));
    }
    if let Some(&s) = opts.scales.iter().find(|&&s| s == 0) {
        return Err(Error::Input(InputError::new(
            std::path::Path::new("drapekit bench collision"),
            "--scales",
            format!("scale {s} has no particles"),
            "use scales of 1 or more, e.g. 1,4,16",
        )));
    }
    let ctx = match contenders.contains(&Contender::GpuSdf) {
        true => match GpuContext::new(&opts.adapter) {
            Ok(ctx) => Some(ctx),
            Err(e) => {
                eprintln!("drapekit: {e}; benchmarking the CPU strategies only");
                None
            }
        },
        false => None,
    };
    // A deforming body: only the contenders that can follow it (see `deforming`).
    let deformed = scene.bodies.first().is_some_and(|b| b.deform.is_some());
    let contenders: Vec<Contender> = match deformed {
        true => {
            let (kept, dropped): (Vec<_>, Vec<_>) =
                contenders.into_iter().partition(|&c| deforming::applies(c));
            if !dropped.is_empty() {
                let names: Vec<_> = dropped.iter().map(|c| c.name()).collect();
                println!(
                    "the body deforms: {} do not apply to it (rigid-body structures)",
                    names.join(", ")
                );
            }
            kept
        }
        false => contenders,
    };
    let cpu_device = format!("CPU ({})", cpu_threads_description());
    let gpu_device = ctx.as_ref().map(|c| c.report().describe());
    let mut rows = Vec::new();
    let mut built = None;
    for (k, &scale) in opts.scales.iter().enumerate() {
        let prep = crate::sim::prepare(&scaled(&scene, scale))?;
        // The body does not change with the cloth: its structures are built once.
        if built.is_none() {
            let settings = scene.bodies.first().expect("checked above");
            built = Some(measure::build_all(&prep, settings, &contenders)?);
        }
        let built = built.as_ref().expect("built above");
        println!(
            "scale {scale}: {} particles, {} substeps per frame; warming up",
            prep.model.len(),
            prep.substeps
        );
        let samples = measure::warm_up(&prep, opts.samples)?;
        // Every particle against every triangle is quadratic: only the first size.
        let here: Vec<_> = (built.iter())
            .filter(|b| k == 0 || b.contender != Contender::Cpu(Strategy::Brute))
            .filter(|b| b.contender != Contender::GpuSdf || ctx.is_some())
            .collect();
        let measured = measure::measure(&prep, &samples, &here, ctx.as_ref(), opts)?;
        for mut row in measured {
            row.scale = scale;
            row.device = match row.contender {
                Contender::GpuSdf => gpu_device.clone().unwrap_or_default(),
                _ => cpu_device.clone(),
            };
            println!(
                "  {:<12} collision {:>10.1} µs/substep ({:>5.1}% of {:>10.1})  contacts {:>6}  missed {:>5}  extra {:>5}  deepest {:.2} mm",
                row.contender.name(),
                row.collision_us,
                row.share_percent(),
                row.substep_us,
                row.contacts,
                row.missed,
                row.extra,
                1e3 * row.max_penetration
            );
            rows.push(row);
        }
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let csv = opts.out.join("collision.csv");
    let md = opts.out.join("collision.md");
    let svg = opts.out.join("collision.svg");
    write_atomic(&csv, report::csv_text(&rows).as_bytes())?;
    let devices = (cpu_device.as_str(), gpu_device.as_deref());
    write_atomic(
        &md,
        report::md_text(&rows, opts, devices, deformed).as_bytes(),
    )?;
    report::plot(&rows, deformed, &svg)?;
    println!(
        "wrote {}, {} and {}",
        csv.display(),
        md.display(),
        svg.display()
    );
    Ok(rows)
}
