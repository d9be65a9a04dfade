//! Refusing scenes too large for the machine before building anything: the particle count is
//! estimated from the scene alone (grid size, or pattern area over the particle spacing), and
//! its memory checked against `[solver] max_memory_mb`.

use crate::check::Checker;
use crate::error::InputError;
use crate::pattern::garment::GarmentOptions;
use crate::pattern::Pattern;
use crate::scene::limits::{MIN_EDGE_PER_COORDINATE, SAFE_MAGNITUDE};
use crate::scene::MAX_SDF_RESOLUTION_M;
use crate::scene::{ClothSource, Scene};
use glam::DVec3;
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

/// The machine's memory in bytes (`MemTotal` of /proc/meminfo), where it can be read.
pub fn machine_memory() -> Option<u64> {
    std::fs::read_to_string("/proc/meminfo").ok().and_then(|s| {
        s.lines()
            .find(|l| l.starts_with("MemTotal:"))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|kib| kib.parse::<u64>().ok())
            .map(|kib| kib.saturating_mul(1024))
    })
}

/// Half the machine's memory, or 8 GiB where that cannot be read.
pub fn default_memory_cap() -> u64 {
    machine_memory().map_or(8 << 30, |bytes| bytes / 2)
}

/// The memory a run may plan for, and how the cap came about (for messages): the scene's
/// `max_memory_mb`, never more than the machine has, or half the machine by default.
pub fn memory_cap(scene: &Scene) -> (u64, String) {
    let machine = machine_memory();
    let mib = |b: u64| b as f64 / 1048576.0;
    match (scene.solver.max_memory_bytes, machine) {
        (Some(given), Some(total)) if given > total => (
            total,
            format!(
                "this machine's {:.0} MiB (max_memory_mb = {:.0} is more than it has)",
                mib(total),
                mib(given)
            ),
        ),
        (Some(given), _) => (given, format!("max_memory_mb = {:.0}", mib(given))),
        (None, _) => (
            default_memory_cap(),
            format!(
                "{:.0} MiB ([solver] max_memory_mb, default half the machine's memory)",
                mib(default_memory_cap())
            ),
        ),
    }
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
        ClothSource::Mesh { path, .. } => obj_vertices(path),
    })
}

/// The vertex records (`v` lines) of an OBJ file: its particle count, read without parsing
/// the rest (`None` when it cannot be read: loading it reports why).
fn obj_vertices(path: &Path) -> Option<u64> {
    use std::io::BufRead;
    let file = std::io::BufReader::new(std::fs::File::open(path).ok()?);
    let lines = file.split(b'\n').map_while(Result::ok);
    Some(
        lines
            .filter(|l| l.starts_with(b"v ") || l.starts_with(b"v\t"))
            .count() as u64,
    )
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
/// particles and collision SDFs together need more memory than the cap (`memory_cap`).
/// Returns the particles the cap leaves room for beside the SDFs (the mesher stops there).
pub fn check_budget(scene: &Scene) -> Result<usize, InputError> {
    check_pattern_scale(scene)?;
    let (cap, cap_said) = memory_cap(scene);
    let sdfs = sdf_bytes(scene)?;
    let sdf_total = sdfs.iter().fold(0u64, |a, b| a.saturating_add(b.1));
    let particles = estimated_particles(scene)?.unwrap_or(0);
    let cloth = particles.saturating_mul(BYTES_PER_PARTICLE);
    let need = cloth.saturating_add(sdf_total);
    let mib = |b: u64| b as f64 / 1048576.0;
    // Each body's own cap, never above the run's.
    for &(i, bytes) in &sdfs {
        let own = scene.bodies[i].sdf_max_bytes.min(cap);
        if bytes > own {
            return Err(sdf_too_big(
                scene,
                i,
                bytes,
                own,
                &format!(
                    "above {}",
                    if own < scene.bodies[i].sdf_max_bytes {
                        format!("the memory cap, {cap_said}")
                    } else {
                        format!("sdf_max_mb = {:.0}", mib(own))
                    }
                ),
            ));
        }
    }
    let room = (cap.saturating_sub(sdf_total) / BYTES_PER_PARTICLE).min(usize::MAX as u64);
    if need <= cap {
        return Ok(room as usize);
    }
    if sdf_total > cloth {
        // The bodies' grids are the larger part: coarsen the largest.
        let &(i, bytes) = sdfs.iter().max_by_key(|s| s.1).expect("sdf_total > 0");
        let room = cap.saturating_sub(cloth).saturating_sub(sdf_total - bytes);
        return Err(sdf_too_big(scene, i, bytes, room, &format!(
            "which with the cloth ({:.0} MiB) and the other bodies is above the memory cap, {cap_said}",
            mib(cloth)
        )));
    }
    let fits = cap.saturating_sub(sdf_total) / BYTES_PER_PARTICLE;
    let mut problem = format!(
        "about {particles} particles need about {:.0} MiB{}, above the memory cap, {cap_said}",
        mib(cloth),
        if sdf_total > 0 {
            format!(" (with the bodies' SDFs, {:.0} MiB)", mib(need))
        } else {
            String::new()
        }
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

/// Each body's SDF size in bytes (body index, bytes), from its mesh's bounding box before
/// anything is baked.
fn sdf_bytes(scene: &Scene) -> Result<Vec<(usize, u64)>, InputError> {
    let c = scene.checker();
    let mut out = Vec::new();
    for (i, b) in scene.bodies.iter().enumerate() {
        let body = super::build_body(b, &c, &scene.body_table(i))?;
        let (_, dims) = crate::body::sdf::grid_for(&body, b.sdf_resolution, b.sdf_margin);
        out.push((i, crate::body::sdf::grid_bytes(dims)));
    }
    Ok(out)
}

/// Body `i`'s SDF of `bytes` is refused: it may have `room` bytes. Nodes fall with the cube of
/// the spacing, so the spacing that fits is the present one × ∛(bytes / room).
fn sdf_too_big(scene: &Scene, i: usize, bytes: u64, room: u64, why: &str) -> InputError {
    let b = &scene.bodies[i];
    let mib = |b: u64| b as f64 / 1048576.0;
    let ratio = bytes as f64 / room.max(1) as f64;
    let spacing = b.sdf_resolution as f64 * ratio.cbrt() * 1.05;
    // Nodes fall with the cube of the spacing: the field at the coarsest spacing allowed.
    let at_coarsest = bytes as f64 * (b.sdf_resolution as f64 / MAX_SDF_RESOLUTION_M).powi(3);
    let fix = if room < 4096 {
        "make room for the SDF: raise solver.max_memory_mb, or use fewer particles".to_string()
    } else if at_coarsest > room as f64 {
        // No spacing the scene may give fits: the body is far larger than any person.
        format!(
            "even sdf_resolution_m = {MAX_SDF_RESOLUTION_M} (the coarsest) is too fine for a \
             body this large: check its size and its units"
        )
    } else {
        let spacing = spacing.min(MAX_SDF_RESOLUTION_M);
        format!("use sdf_resolution_m = {spacing:.4} or coarser")
    };
    scene.error(
        &scene.body_table(i),
        "sdf_resolution_m",
        format!(
            "an SDF at {} m needs about {:.0} MiB, {why}",
            b.sdf_resolution,
            mib(bytes)
        ),
        fix,
    )
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
        let grid = dims.iter().map(|&d| d as u64).product::<u64>();
        // A deforming body's words follow its nodes (`body::deformed_sdf`): a nearest triangle
        // per node, then its rest mesh and weights (3 words per vertex, 3 per triangle, 5 per
        // vertex's weights; its parts' boxes are a few hundred words more).
        let deformed = match b.deform {
            Some(_) => {
                let mesh = &body.mesh;
                grid + 8 * mesh.positions.len() as u64 + 3 * mesh.triangles.len() as u64 + 512
            }
            None => 0,
        };
        nodes.push(grid + deformed);
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
        ClothSource::Pattern { options, path, .. } => {
            // Rounded up, so that the spacing given is one that fits.
            let spacing = (options.particle_distance / ratio * 1e4).ceil() / 1e4;
            let mut fix = format!("use particle_distance_m = {spacing:.4} or more, {or}");
            // A garment too large to be one is a unit slip: fix that first.
            let span = Pattern::load(path).ok().map(|p| garment_span(&p, options));
            if let Some(span) = span.filter(|s| !in_garment_range(*s)) {
                fix = format!(
                    "first check units_in_meter in {} (the garment spans {span:.3} m); \
                     if it is right, {fix}",
                    path.display()
                );
            }
            c.err("cloth.pattern", "particle_distance_m", problem, fix)
        }
        ClothSource::Mesh { .. } => c.err(
            "cloth",
            "mesh",
            problem,
            format!("use a mesh of at most about {fits} vertices, {or}"),
        ),
    }
}

/// The garment's size below which, or above which, a pattern's `units_in_meter` is probably a
/// unit slip (a sock is about 20 cm, a gown about 2 m): 5 cm and 5 m.
pub const GARMENT_SIZE_RANGE_M: (f64, f64) = (0.05, 5.0);

/// The fewest particle spacings across a pattern's garment below which it is warned: a sock
/// (20 cm) at the shipped 2 cm spacing is 10; a T-shirt at 0.5 m is under 3, a few dozen
/// particles that keep nothing of its cut.
pub const MIN_PARTICLES_ACROSS: f64 = 10.0;

/// The largest side of any one panel's own box (before placement), in m.
fn largest_panel_m(pattern: &Pattern) -> f64 {
    (pattern.panels.iter())
        .map(|panel| {
            let (lo, hi) = panel.outline_box();
            (hi - lo).max_element() / pattern.units_in_meter
        })
        .fold(0.0, f64::max)
}

/// The largest side of the box around the pattern's placed panels, in m.
fn garment_span(pattern: &Pattern, options: &GarmentOptions) -> f64 {
    let boxes = panel_reach(pattern, options);
    let lo = boxes.iter().fold(DVec3::INFINITY, |a, b| a.min(b.1[0]));
    let hi = boxes.iter().fold(DVec3::NEG_INFINITY, |a, b| a.max(b.1[1]));
    (hi - lo).max_element()
}

/// Whether a garment span is one a garment has (`GARMENT_SIZE_RANGE_M`); an infinite or NaN
/// span, refused elsewhere, counts as one.
fn in_garment_range(span: f64) -> bool {
    let (small, large) = GARMENT_SIZE_RANGE_M;
    !span.is_finite() || (small..=large).contains(&span)
}

/// Each panel's farthest reach from the origin once placed, in m, and its placed bounding box:
/// the box of its outline's curves (`Panel::outline_box`) carried into 3D.
fn panel_reach(pattern: &Pattern, options: &GarmentOptions) -> Vec<(f64, [DVec3; 2])> {
    let unit = pattern.units_in_meter;
    (pattern.panels.iter())
        .map(|panel| {
            let (rotation, translation) = match options.placement.get(&panel.name) {
                Some(p) => {
                    let mut placed = panel.clone();
                    placed.rotation_deg = p.rotation_deg;
                    (placed.rotation(), p.translation)
                }
                None => (panel.rotation(), panel.translation),
            };
            let (lo2, hi2) = panel.outline_box();
            let corners = [
                (lo2.x, lo2.y),
                (hi2.x, lo2.y),
                (lo2.x, hi2.y),
                (hi2.x, hi2.y),
            ]
            .map(|(x, y)| (rotation * DVec3::new(x, y, 0.0) + translation) / unit);
            let lo = corners.iter().fold(DVec3::INFINITY, |a, &b| a.min(b));
            let hi = corners.iter().fold(DVec3::NEG_INFINITY, |a, &b| a.max(b));
            (lo.abs().max(hi.abs()).max_element(), [lo, hi])
        })
        .collect()
}

/// Refuses a pattern whose placed panels reach farther than the solver's 32-bit positions can
/// hold, or so far that they cannot resolve the particle spacing (`scene::limits`).
fn check_pattern_scale(scene: &Scene) -> Result<(), InputError> {
    let ClothSource::Pattern { path, options, .. } = &scene.cloth else {
        return Ok(());
    };
    let pattern = Pattern::load(path)?;
    let mut placed: Vec<&String> = options.placement.keys().collect();
    placed.sort();
    if let Some(name) = placed
        .into_iter()
        .find(|name| !pattern.panels.iter().any(|p| &&p.name == name))
    {
        let names: Vec<&str> = pattern.panels.iter().map(|p| p.name.as_str()).collect();
        return Err(scene.error(
            &format!("cloth.pattern.placement.{name}"),
            "",
            format!("the pattern has no panel {name:?}: this placement would be ignored"),
            format!("use one of {names:?}"),
        ));
    }
    let (_, hi) = SAFE_MAGNITUDE;
    let spacing = options.particle_distance;
    let limit = hi.min(spacing / MIN_EDGE_PER_COORDINATE);
    for (panel, (reach, _)) in pattern.panels.iter().zip(panel_reach(&pattern, options)) {
        // NaN counts as too far.
        if reach.is_nan() || reach > limit {
            return Err(InputError::new(
                path,
                format!("panel '{}'", panel.name),
                format!(
                    "reaches {reach:.3e} m from the origin once placed (units_in_meter = {}): \
                     32-bit positions cannot resolve a {} m particle spacing beyond \
                     {limit:.3e} m",
                    pattern.units_in_meter, spacing as f32
                ),
                "check the panel's vertices, curvature control points and translation, and \
                 the pattern's units_in_meter",
            ));
        }
    }
    Ok(())
}

/// Warnings found before anything is built: values no real scene has (`scene::limits`), and a
/// pattern whose size, in its `units_in_meter`, makes no garment.
pub fn load_warnings(scene: &Scene) -> Vec<String> {
    let mut out = crate::scene::limits::warnings(scene);
    if let ClothSource::Pattern { path, options, .. } = &scene.cloth {
        // A pattern that does not load is refused later, with its own message.
        if let Ok(pattern) = Pattern::load(path) {
            let size = garment_span(&pattern, options);
            let (small, large) = GARMENT_SIZE_RANGE_M;
            let largest_panel = largest_panel_m(&pattern);
            if size > large && in_garment_range(largest_panel) {
                // Each panel is garment-sized: it is where they are placed that is not.
                out.push(format!(
                    "{}: the panels are placed across {size:.3} m, though the largest is \
                     {largest_panel:.3} m: check their translations (in the pattern, or \
                     [cloth.pattern.placement])",
                    path.display()
                ));
            } else if !in_garment_range(size) {
                out.push(format!(
                    "{}: with units_in_meter = {} the garment spans {size:.3} m, {} than any \
                     garment ({small} to {large} m): check properties.units_in_meter (100 for \
                     centimetres, 1000 for millimetres)",
                    path.display(),
                    pattern.units_in_meter,
                    if size > large { "larger" } else { "smaller" }
                ));
            }
            let across = size / options.particle_distance;
            if size.is_finite() && across < MIN_PARTICLES_ACROSS {
                // Rounded down, so that the spacing given is one that is not warned.
                let fix = format!(
                    "use particle_distance_m = {:.3} or less ({MIN_PARTICLES_ACROSS} spacings \
                     across; the shipped garments use 0.005 to 0.035)",
                    (size / MIN_PARTICLES_ACROSS * 1e3).floor() / 1e3
                );
                let problem = format!(
                    "{:.3} m is {across:.1} spacings across a garment {size:.3} m wide: \
                     too few particles to keep its cut",
                    options.particle_distance
                );
                let e = scene.error("cloth.pattern", "particle_distance_m", problem, &fix);
                out.push(e.one_line());
            }
        }
    }
    out
}

/// Refuses a built cloth mesh whose derived quantities, computed in f64, fall outside what the
/// solver's f32 arithmetic holds (`scene::limits`): its largest coordinate, its shortest edge
/// (also against that coordinate), its lightest particle, its stiffest spring and its fastest
/// oscillation. The scene's own check sees a grid or a pattern before it is built; an OBJ
/// cloth is seen here first, and every cloth passes here once more before it becomes f32.
pub fn check_mesh_scale(scene: &Scene, mesh: &crate::mesh::TriMesh) -> Result<(), InputError> {
    let p = |i: u32| mesh.positions[i as usize].as_dvec3();
    let reach = (mesh.positions.iter())
        .map(|v| v.as_dvec3().abs().max_element())
        .fold(0.0, f64::max);
    let mut area = vec![0.0f64; mesh.positions.len()];
    let (mut edge, mut stiffness) = (f64::INFINITY, 0.0f64);
    for t in &mesh.triangles {
        let a = 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length();
        for k in 0..3 {
            area[t[k] as usize] += a / 3.0;
            let l = p(t[k]).distance(p(t[(k + 1) % 3]));
            if l > 0.0 {
                edge = edge.min(l);
                // k = Y·ΣA/L², summed over the edge's one or two triangles.
                stiffness = stiffness.max(2.0 * a / (l * l));
            }
        }
    }
    let density = scene.fabric.density as f64;
    let mass = (area.iter().filter(|&&a| a > 0.0)).fold(f64::INFINITY, |m, &a| m.min(a * density));
    let stiffness = stiffness * scene.fabric.stiffest_stretch() as f64;
    let omega = (2.0 * 8.0 * stiffness / mass).sqrt();
    let (table, key) = match &scene.cloth {
        ClothSource::Grid { .. } => ("cloth.grid", "width_m"),
        ClothSource::Pattern { .. } => ("cloth.pattern", "particle_distance_m"),
        ClothSource::Mesh { .. } => ("cloth.mesh", "path"),
    };
    let (lo, hi) = SAFE_MAGNITUDE;
    let quantities = [
        ("largest coordinate", reach, "m"),
        ("shortest edge", edge, "m"),
        ("lightest particle's mass", mass, "kg"),
        ("stiffest spring", stiffness, "N/m"),
        ("fastest oscillation", omega, "rad/s"),
    ];
    for (what, v, unit) in quantities {
        // An empty or flat mesh has no edge or mass to check: other checks refuse it.
        if v.is_infinite() && (what == "shortest edge" || what.contains("mass")) {
            continue;
        }
        if !(v.is_finite() && (v == 0.0 || (lo..=hi).contains(&v))) {
            return Err(scene.error(
                table,
                key,
                format!(
                    "the cloth's {what} would be {v:.3e} {unit}, outside {lo:e} to {hi:e} \
                     {unit}, the range the solver's 32-bit arithmetic holds"
                ),
                "check the cloth's size and units (a mesh's units key), the fabric's \
                 density_kg_m2 and stretch_stiffness_n_m",
            ));
        }
    }
    if edge.is_finite() && edge < MIN_EDGE_PER_COORDINATE * reach {
        return Err(scene.error(
            table,
            key,
            format!(
                "edges of {edge:.3e} m at coordinates up to {reach:.3e} m: 32-bit positions \
                 there are too coarse to resolve a 1% strain of such an edge"
            ),
            "move the cloth nearer the origin, or use a mesh with longer edges",
        ));
    }
    Ok(())
}
