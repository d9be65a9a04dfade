//! Refusing scenes too large for the machine before building anything: the particle count is
//! estimated from the scene alone (grid size, or pattern area over the particle spacing), and
//! its memory checked against `[solver] max_memory_mb`.

use crate::check::Checker;
use crate::error::InputError;
use crate::pattern::Pattern;
use crate::scene::{ClothSource, Scene};
use std::path::Path;

/// Peak memory per particle of a run, in bytes: 1,115 measured (peak resident set of an
/// implicit CPU run of a 1000 × 1000 grid writing one frame: 1,089,508 KiB), rounded up. The GPU
/// path holds a similar copy on the device.
pub const BYTES_PER_PARTICLE: u64 = 1200;

/// Particles per m² of a mesh at spacing s: equilateral triangles of side s hold one particle
/// per √3/2·s² of area.
fn particles_per_m2(spacing: f64) -> f64 {
    2.0 / (3f64.sqrt() * spacing * spacing)
}

/// Half the machine's memory (from /proc/meminfo), or 8 GiB where that cannot be read.
pub fn default_memory_cap() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("MemTotal:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kib| kib.parse::<u64>().ok())
        })
        .map_or(8 << 30, |kib| kib * 1024 / 2)
}

/// The particle count the scene will build, estimated without building it (`None` for OBJ
/// cloth, whose count is known only once read).
pub fn estimated_particles(scene: &Scene) -> Result<Option<u64>, InputError> {
    Ok(match &scene.cloth {
        ClothSource::Grid { columns, rows, .. } => Some(*columns as u64 * *rows as u64),
        ClothSource::Pattern { path, options, .. } => {
            let (by_area, by_outline, _) = pattern_estimate(path, options.particle_distance)?;
            // `as` saturates: an infinite estimate becomes u64::MAX, which the cap refuses.
            Some(by_area.max(by_outline).ceil() as u64)
        }
        ClothSource::Mesh { .. } => None,
    })
}

/// A pattern's particles by panel area and by outline length at `spacing`, and the outline
/// length in m. Outlines count too: a long thin panel (or a stray control point) has little
/// area but a long edge, every sample of which is a particle.
fn pattern_estimate(path: &Path, spacing: f64) -> Result<(f64, f64, f64), InputError> {
    let pattern = Pattern::load(path)?;
    let unit = pattern.units_in_meter;
    let area: f64 = (pattern.panels.iter())
        .map(|p| 0.5 * p.signed_area2().abs() / (unit * unit))
        .sum();
    let outline: f64 = (pattern.panels.iter())
        .flat_map(|p| &p.edges)
        .map(|e| e.curve.length() / unit)
        .sum();
    Ok((area * particles_per_m2(spacing), outline / spacing, outline))
}

/// Refuses (bad input, naming the key to change and a value that fits) a scene whose estimated
/// particles need more memory than the cap.
pub fn check_budget(scene: &Scene) -> Result<(), InputError> {
    let Some(particles) = estimated_particles(scene)? else {
        return Ok(());
    };
    let cap = scene
        .solver
        .max_memory_bytes
        .unwrap_or_else(default_memory_cap);
    let need = particles.saturating_mul(BYTES_PER_PARTICLE);
    if need <= cap {
        return Ok(());
    }
    let fits = cap / BYTES_PER_PARTICLE;
    let mib = |b: u64| b as f64 / 1048576.0;
    let mut problem = format!(
        "about {particles} particles need about {:.0} MiB, above the memory cap of {:.0} MiB \
         ([solver] max_memory_mb, default half the machine's memory)",
        mib(need),
        mib(cap)
    );
    if let ClothSource::Pattern { path, options, .. } = &scene.cloth {
        let (by_area, by_outline, outline) = pattern_estimate(path, options.particle_distance)?;
        if by_outline >= by_area {
            problem.push_str(&format!(
                "; the panel outlines alone are {outline:.3e} m long: check {}'s edges and \
                 units_in_meter",
                path.display()
            ));
        }
    }
    Err(too_many(
        scene,
        particles,
        fits,
        problem,
        "or raise solver.max_memory_mb",
    ))
}

/// Elements per particle in the largest array the GPU path uploads: the hinge incidence list
/// holds four entries per hinge, and a triangle mesh has at most about three interior edges per
/// vertex (Euler's formula, E ≈ 3V), so 12 (measured: 11.0 on a 32² grid, 11.7 on the 5 mm
/// T-shirt).
pub const GPU_ELEMENTS_PER_PARTICLE: u64 = 12;

/// Refuses, before anything is built, a scene whose arrays would not fit the GPU's largest
/// texture (`max_texels` elements per array, see `gpu/texels.rs`).
pub fn check_gpu_textures(scene: &Scene, max_texels: u64) -> Result<(), InputError> {
    let Some(particles) = estimated_particles(scene)? else {
        return Ok(());
    };
    let fits = max_texels / GPU_ELEMENTS_PER_PARTICLE;
    if particles <= fits {
        return Ok(());
    }
    let problem = format!(
        "about {particles} particles need arrays of about {} elements on the GPU, above this \
         adapter's {max_texels} (its largest 2D texture)",
        particles.saturating_mul(GPU_ELEMENTS_PER_PARTICLE)
    );
    Err(too_many(
        scene,
        particles,
        fits,
        problem,
        "or run with --backend cpu",
    ))
}

/// Refuses, before any SDF is baked, bodies whose SDF nodes together would not fit the GPU's
/// largest texture (the kernels read every body's nodes from one texture), naming the body
/// with the most nodes and a spacing that fits (nodes fall with the cube of the spacing).
pub fn check_sdf_textures(scene: &Scene, max_texels: u64) -> Result<(), InputError> {
    let c = scene.checker();
    let mut nodes = Vec::new();
    for (i, b) in scene.bodies.iter().enumerate() {
        let body = super::build_body(b, &c, &scene.body_table(i))?;
        let (_, dims) = crate::body::sdf::grid_for(&body, b.sdf_resolution, b.sdf_margin);
        nodes.push(dims.iter().map(|&d| d as u64).product::<u64>());
    }
    let total: u64 = nodes.iter().sum();
    if total <= max_texels {
        return Ok(());
    }
    let (i, _) = (nodes.iter().enumerate())
        .max_by_key(|(_, &n)| n)
        .expect("a body has nodes");
    let b = &scene.bodies[i];
    let suggested = b.sdf_resolution * (total as f32 / max_texels as f32).cbrt() * 1.05;
    Err(c.err(
        &scene.body_table(i),
        "sdf_resolution_m",
        format!(
            "the bodies' SDFs have {total} nodes together, above this adapter's {max_texels} \
             (its largest 2D texture holds them all)"
        ),
        format!(
            "{}use sdf_resolution_m = {suggested:.4} or coarser, or run with --backend cpu",
            super::collider::unit_hint(&super::build_body(b, &c, &scene.body_table(i))?, b)
        ),
    ))
}

/// The same check on a built model (an OBJ cloth has no estimate): its largest array.
pub fn check_model_textures(
    scene: &Scene,
    model: &super::ClothModel,
    max_texels: u64,
) -> Result<(), InputError> {
    let largest = model.largest_array() as u64;
    if largest <= max_texels {
        return Ok(());
    }
    let particles = model.len() as u64;
    let fits = (particles as f64 * max_texels as f64 / largest as f64) as u64;
    let problem = format!(
        "the cloth's {particles} particles need an array of {largest} elements on the GPU, \
         above this adapter's {max_texels} (its largest 2D texture)"
    );
    Err(too_many(
        scene,
        particles,
        fits,
        problem,
        "or run with --backend cpu",
    ))
}

/// Bad input naming the key that sets the particle count, and a value that makes `particles`
/// come down to `fits`.
fn too_many(scene: &Scene, particles: u64, fits: u64, problem: String, or: &str) -> InputError {
    let ratio = (fits as f64 / particles as f64).sqrt();
    let c = Checker {
        path: &scene.path,
        src: &scene.source,
    };
    match &scene.cloth {
        ClothSource::Grid { columns, rows, .. } => c.err(
            "cloth.grid",
            "columns",
            problem,
            format!(
                "use at most about {} × {} particles, {or}",
                (*columns as f64 * ratio).floor(),
                (*rows as f64 * ratio).floor()
            ),
        ),
        ClothSource::Pattern { options, .. } => c.err(
            "cloth.pattern",
            "particle_distance_m",
            problem,
            format!(
                "use particle_distance_m = {:.4} or more, {or}",
                options.particle_distance / ratio
            ),
        ),
        ClothSource::Mesh { .. } => c.err(
            "cloth",
            "mesh",
            problem,
            format!("use a mesh of at most about {fits} vertices, {or}"),
        ),
    }
}
