//! Derived quantities, computed in f64 from a parsed scene and range-checked before anything
//! is built in f32: the cloth's extent and edge length, each particle's mass, the springs'
//! stiffness and damping, the fastest oscillation (the stable step), the frame and substep,
//! gravity, and the wind's drag. A value outside its range is bad input naming the key to
//! change; `warnings` lists values that compute but make no physical sense.

use super::{ClothSource, Scene, Wind, INTEGRATOR_IMPLICIT};
use crate::check::Checker;
use crate::error::InputError;

/// The magnitudes (in SI units) a derived quantity may take. The solver multiplies up to three
/// of them (½·m·v², k·Δx·h) and its monitor sums 64 such products in f32: 64·(10¹²)³ =
/// 6.4·10³⁷ stays below f32's largest value, 3.4·10³⁸, and (10⁻¹²)³ = 10⁻³⁶ above its smallest
/// normal value, 1.2·10⁻³⁸.
pub const SAFE_MAGNITUDE: (f64, f64) = (1e-12, 1e12);

/// The shortest edge, as a fraction of the largest coordinate, whose strain f32 positions
/// resolve to 1%: a coordinate is rounded to 2⁻²⁴ of its size, so an edge of length L at
/// coordinate X carries a strain error of about 1.2·10⁻⁷·X/L.
pub const MIN_EDGE_PER_COORDINATE: f64 = 1.2e-5;

/// Springs meeting at a particle, at most, for the stable-step estimate (a grid's interior
/// particle has 4 axis and 2 or 4 diagonal springs; a pattern mesh about 6).
const SPRINGS_PER_PARTICLE: f64 = 8.0;

/// What `check` needs to know of the cloth: the extent of its coordinates, its shortest edge,
/// its lightest particle, and its stiffest spring.
struct ClothScale {
    /// The key the numbers come from, to name in errors.
    table: &'static str,
    key: &'static str,
    /// Largest |coordinate| in m (`None`: not known before the file is read).
    coordinate: Option<f64>,
    /// Shortest edge in m.
    edge: f64,
    /// Lightest particle in kg.
    mass: f64,
    /// Stiffest spring in N/m.
    stiffness: f64,
}

/// The cloth's scale, from the scene alone (`None` for an OBJ mesh, checked once built).
fn cloth_scale(scene: &Scene) -> Option<ClothScale> {
    let density = scene.fabric.density as f64;
    let stretch = scene.fabric.stiffest_stretch() as f64;
    match &scene.cloth {
        ClothSource::Grid {
            width,
            height,
            columns,
            rows,
            center,
            ..
        } => {
            let (w, h) = (*width as f64, *height as f64);
            let (dx, dy) = (w / (*columns as f64 - 1.0), h / (*rows as f64 - 1.0));
            let offset = center.abs().max_element() as f64;
            let reach = 0.5 * w.max(h) + offset;
            // The key most likely at fault: the centre if it dominates, else the longer side.
            let key = match (offset > w.max(h), w >= h) {
                (true, _) => "center_m",
                (false, true) => "width_m",
                (false, false) => "height_m",
            };
            Some(ClothScale {
                table: "cloth.grid",
                key,
                coordinate: Some(reach),
                edge: dx.min(dy),
                // A corner particle holds a quarter of a cell.
                mass: 0.25 * density * dx * dy,
                // k = Y·ΣA/L² on an axis edge of a cell dx × dy: Y·dy/dx (or dx/dy).
                stiffness: stretch * (dx / dy).max(dy / dx),
            })
        }
        ClothSource::Pattern {
            options,
            seam_stiffness,
            ..
        } => {
            let s = options.particle_distance;
            Some(ClothScale {
                table: "cloth.pattern",
                key: "particle_distance_m",
                coordinate: None,
                edge: s,
                // An outline corner may hold a sixth of an equilateral particle's √3/2·s².
                mass: density * 3f64.sqrt() / 12.0 * s * s,
                stiffness: stretch.max(*seam_stiffness as f64),
            })
        }
        ClothSource::Mesh { .. } => None,
    }
}

/// An error unless `v` lies in `SAFE_MAGNITUDE`; `what` says what it is and how it is made.
fn safe(
    c: &Checker,
    (table, key): (&str, &str),
    what: &str,
    v: f64,
    unit: &str,
    fix: &str,
) -> Result<(), InputError> {
    let (lo, hi) = SAFE_MAGNITUDE;
    if v.is_finite() && (lo..=hi).contains(&v.abs()) {
        return Ok(());
    }
    Err(c.err(
        table,
        key,
        format!(
            "{what} would be {v:.3e} {unit}, outside {lo:e} to {hi:e} {unit}, the range the \
             solver's 32-bit arithmetic holds"
        ),
        fix,
    ))
}

/// Refuses a scene whose derived quantities the solver cannot represent or integrate.
pub(super) fn check(c: &Checker, scene: &Scene) -> Result<(), InputError> {
    let fabric_fix = "check the fabric's density_kg_m2 and stretch_stiffness_n_m and the \
                      cloth's size and particle count (SI units: kg/m², N/m, m)";
    if let Some(cloth) = cloth_scale(scene) {
        let at = (cloth.table, cloth.key);
        let size_fix = format!(
            "check {}.{} and the cloth's size and particle count (in m)",
            cloth.table, cloth.key
        );
        safe(c, at, "the shortest edge", cloth.edge, "m", &size_fix)?;
        if let Some(reach) = cloth.coordinate {
            safe(c, at, "the largest coordinate", reach, "m", &size_fix)?;
            if cloth.edge < MIN_EDGE_PER_COORDINATE * reach {
                return Err(c.err(
                    cloth.table,
                    cloth.key,
                    format!(
                        "edges of {:.3e} m at coordinates up to {reach:.3e} m: 32-bit positions \
                         there are too coarse to resolve a 1% strain of such an edge",
                        cloth.edge
                    ),
                    format!(
                        "edges must be at least {MIN_EDGE_PER_COORDINATE:e} of the largest \
                         coordinate: move the cloth nearer the origin or use fewer particles"
                    ),
                ));
            }
        }
        // A density far from any fabric's (0.02 to 1 kg/m²) is the likelier slip.
        let density = scene.fabric.density as f64;
        let mass_at = if (1e-3..=10.0).contains(&density) {
            at
        } else {
            ("fabric", "density_kg_m2")
        };
        safe(
            c,
            mass_at,
            "the lightest particle's mass",
            cloth.mass,
            "kg",
            fabric_fix,
        )?;
        let stretch = ("fabric", "stretch_stiffness_n_m");
        safe(
            c,
            stretch,
            "the stiffest spring",
            cloth.stiffness,
            "N/m",
            fabric_fix,
        )?;
        // ω² ≤ 2·Σk/m (Gershgorin); its inverse is the scale of the stable step.
        let omega = (2.0 * SPRINGS_PER_PARTICLE * cloth.stiffness / cloth.mass).sqrt();
        safe(
            c,
            stretch,
            "the fastest oscillation",
            omega,
            "rad/s",
            fabric_fix,
        )?;
        let zeta = scene.fabric.damping_ratio as f64;
        if zeta > 0.0 {
            let damping = 2.0 * zeta * (cloth.stiffness * cloth.mass).sqrt();
            let fix = "use a damping_ratio from 0 to about 1 (a fraction of critical damping)";
            safe(
                c,
                ("fabric", "damping_ratio"),
                "the springs' damping",
                damping,
                "N·s/m",
                fix,
            )?;
            safe(
                c,
                ("fabric", "damping_ratio"),
                "the damping rate",
                damping / cloth.mass,
                "1/s",
                fix,
            )?;
        }
    }
    let s = &scene.solver;
    let frame = 1.0 / s.fps as f64;
    safe(
        c,
        ("solver", "fps"),
        "the frame length",
        frame,
        "s",
        "use a frame rate such as 24 or 30",
    )?;
    if let Some(n) = s.substeps {
        let fix = "use fewer substeps per frame";
        safe(
            c,
            ("solver", "substeps"),
            "the substep",
            frame / n as f64,
            "s",
            fix,
        )?;
    }
    let g = scene.gravity.as_dvec3().length();
    if g != 0.0 {
        let fix = "give gravity in m/s² (Earth: [0, -9.81, 0])";
        safe(c, ("world", "gravity_m_s2"), "gravity", g, "m/s²", fix)?;
    }
    check_wind(c, scene, frame)
}

/// The rate γ = ρ·C_d·|v|·(1 + gust)/σ, per s, at which the wind's drag pulls the cloth's speed
/// toward the wind's at its strongest gust (0 without wind).
pub fn wind_drag_rate(scene: &Scene) -> f64 {
    let Some(w) = &scene.wind else {
        return 0.0;
    };
    w.air_density as f64 * w.drag_coefficient as f64 * gust_speed(w) / scene.fabric.density as f64
}

/// The wind's speed at its strongest gust, in m/s.
fn gust_speed(w: &Wind) -> f64 {
    w.velocity.as_dvec3().length() * (1.0 + w.gust_amplitude as f64)
}

/// Wind drag relaxes the cloth's speed toward the wind's at the rate γ = ρ·C_d·|v|/σ (the
/// drag force's derivative in speed over the mass per area σ); the explicit drag update is
/// stable only for γ·h < 2, so a drag that no allowed substep can follow is bad input.
fn check_wind(c: &Checker, scene: &Scene, frame: f64) -> Result<(), InputError> {
    let Some(w) = &scene.wind else {
        return Ok(());
    };
    let speed = gust_speed(w);
    if speed != 0.0 {
        let fix = "give the wind in m/s (a gale is about 20 m/s)";
        safe(
            c,
            ("wind", "velocity_m_s"),
            "the wind speed",
            speed,
            "m/s",
            fix,
        )?;
    }
    let rate = wind_drag_rate(scene);
    let s = &scene.solver;
    // The shortest substep the scene allows: its own, or the most `auto` may choose.
    let (step, steps_key) = match s.substeps {
        Some(n) => (frame / n as f64, "substeps"),
        None if s.integrator == INTEGRATOR_IMPLICIT => (frame, "substeps"),
        None => (
            frame / s.max_substeps_per_frame as f64,
            "max_substeps_per_frame",
        ),
    };
    if rate * step < 2.0 {
        return Ok(());
    }
    let needed = (rate * frame / 2.0).ceil();
    Err(c.err(
        "wind",
        "drag_coefficient",
        format!(
            "the wind's drag (air density × drag coefficient × wind speed / fabric density = \
             {rate:.3e} per s) changes the cloth's speed faster than a substep of {step:.3e} s \
             can follow (it needs rate × substep < 2)"
        ),
        format!(
            "use a drag coefficient near 1 (cloth and flat plates: 1 to 2), or at least \
             {needed:.0} substeps per frame (solver.{steps_key})"
        ),
    ))
}

/// Values that the solver can compute with but that no real scene has.
pub fn warnings(scene: &Scene) -> Vec<String> {
    let mut out = Vec::new();
    // As the fabric's warnings read: file, line and key, what is odd, and the fix.
    let mut warn = |table: &str, key: &str, problem: String, fix: &str| {
        out.push(scene.error(table, key, problem, fix).one_line());
    };
    if let Some(w) = &scene.wind {
        let speed = gust_speed(w);
        if speed > MAX_WIND_SPEED {
            warn(
                "wind",
                "velocity_m_s",
                format!(
                    "its gusts reach {speed:.0} m/s, faster than any storm's (the strongest \
                     gust measured, 113 m/s): the cloth will tear"
                ),
                "a breeze is about 3 m/s, a gale 20 m/s",
            );
        }
        if w.gust_amplitude > 0.0 && w.gust_frequency > MAX_GUST_FREQUENCY {
            warn(
                "wind",
                "gust_frequency_hz",
                format!(
                    "{} Hz is a vibration, not a gust: wind gusts come seconds apart",
                    w.gust_frequency
                ),
                "gusts are about 0.1 to 2 Hz",
            );
        }
        if w.air_density > 5.0 {
            warn(
                "wind",
                "air_density_kg_m3",
                format!("{} kg/m³ is denser than any air", w.air_density),
                "air at sea level is 1.2 kg/m³",
            );
        }
        if w.drag_coefficient > 3.0 {
            warn(
                "wind",
                "drag_coefficient",
                format!(
                    "{} is above any cloth's or flat plate's",
                    w.drag_coefficient
                ),
                "cloth and flat plates: 1 to 2",
            );
        }
    }
    if scene.fabric.damping_ratio > 10.0 {
        warn(
            "fabric",
            "damping_ratio",
            format!(
                "{} is ten times critical damping: the cloth will creep, not swing",
                scene.fabric.damping_ratio
            ),
            "fabrics damp at about 0.01 to 1",
        );
    }
    let g = scene.gravity.length();
    if g > 3.0 * 9.81 {
        warn(
            "world",
            "gravity_m_s2",
            format!("{g} m/s² is {:.0} times Earth's", g / 9.81),
            "Earth's gravity is [0, -9.81, 0]",
        );
    }
    if scene.air_damping > 100.0 {
        warn(
            "world",
            "air_damping_per_s",
            format!(
                "{} /s stops any motion within {:.0} ms: the cloth will crawl instead of falling",
                scene.air_damping,
                1e3 / scene.air_damping
            ),
            "still air is about 0.1 to 5 /s",
        );
    }
    let run_s = scene.solver.frames as f64 / scene.solver.fps as f64;
    if g > 0.0 && scene.gravity_start as f64 >= run_s {
        warn(
            "world",
            "gravity_start_s",
            format!(
                "{} s is at or after the run's end ({run_s:.3} s): gravity never comes on",
                scene.gravity_start
            ),
            "start gravity within the run, or run more frames",
        );
    }
    if let Some(ratio) = seam_stiffness_ratio(scene).filter(|&r| r < MIN_SEAM_STIFFNESS_RATIO) {
        warn(
            "cloth.pattern",
            "seam_stiffness_n_m",
            format!(
                "{ratio:.1e} times the fabric's stretch stiffness: seams that weak never pull \
                 the panels shut"
            ),
            "leave it out (twice the fabric's stretch stiffness), or use at least a hundredth \
             of the fabric's",
        );
    }
    if let Some(ratio) = seam_stiffness_ratio(scene).filter(|&r| r > MAX_SEAM_STIFFNESS_RATIO) {
        warn(
            "cloth.pattern",
            "seam_stiffness_n_m",
            format!(
                "{ratio:.0} times the fabric's stretch stiffness: seams that stiff snap the \
                 panels shut in a substep, and the run can explode"
            ),
            "leave it out (twice the fabric's stretch stiffness), or use at most \
             100 times the fabric's",
        );
    }
    if let ClothSource::Pattern {
        attach_labels,
        attach_frames,
        ..
    } = &scene.cloth
    {
        if *attach_frames > 0 && attach_labels.is_empty() {
            warn(
                "cloth.pattern",
                "attach_frames",
                format!("{attach_frames} frames of holding, but no attach_labels: nothing is held"),
                "name the edges to hold with attach_labels, or leave attach_frames out",
            );
        } else if !attach_labels.is_empty() && *attach_frames >= scene.solver.frames {
            warn(
                "cloth.pattern",
                "attach_frames",
                format!(
                    "{attach_frames} frames is the whole run ({} frames): the labelled edges are \
                     never let go",
                    scene.solver.frames
                ),
                "hold them for fewer frames than the run, or pin them with [[pins]]",
            );
        }
    }
    if let ClothSource::Pattern { sewing_time, .. } = &scene.cloth {
        if *sewing_time as f64 > run_s {
            warn(
                "cloth.pattern",
                "seam_sewing_time_s",
                format!(
                    "{sewing_time} s is longer than the run ({run_s:.3} s): the seams are still \
                     being drawn shut when it ends"
                ),
                "sew within the run, or run more frames",
            );
        }
    }
    for (i, b) in scene.bodies.iter().enumerate() {
        if b.friction > 2.0 {
            warn(
                &scene.body_table(i),
                "friction",
                format!("{} is above any fabric's on skin or plastic", b.friction),
                "cloth on skin or plastic: about 0.2 to 1",
            );
        }
    }
    out
}

/// The wind speed past which, at its strongest gust, a scene is warned, in m/s: above the
/// strongest gust measured on Earth (113 m/s, Barrow Island, 1996).
pub const MAX_WIND_SPEED: f64 = 113.0;

/// The seam stiffness past which, as a multiple of the fabric's stretch stiffness, a scene
/// is warned: the default is 2; seams a hundred times stiffer than the cloth they join hold
/// nothing better and pull the panels shut in a single substep.
pub const MAX_SEAM_STIFFNESS_RATIO: f64 = 100.0;

/// The seam stiffness below which, as a multiple of the fabric's stretch stiffness, a scene is
/// warned: seams a hundred times softer than the cloth stretch open under its own weight.
pub const MIN_SEAM_STIFFNESS_RATIO: f64 = 0.01;

/// The gust frequency past which a scene is warned, in Hz: gusts come seconds apart; tens of
/// cycles a second shake the cloth instead.
pub const MAX_GUST_FREQUENCY: f32 = 10.0;

/// A pattern's seam stiffness as a multiple of its fabric's stiffest stretch stiffness
/// (`None` for grids and meshes, which have no seams).
pub fn seam_stiffness_ratio(scene: &Scene) -> Option<f64> {
    let ClothSource::Pattern { seam_stiffness, .. } = &scene.cloth else {
        return None;
    };
    Some(*seam_stiffness as f64 / scene.fabric.stiffest_stretch() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// The warnings of a small hanging cloth with `world` as its [world] table.
    fn world_warned(world: &str) -> Vec<String> {
        let text = format!(
            "[cloth.grid]\nwidth_m = 1.0\nheight_m = 1.0\ncolumns = 8\nrows = 8\n\
             center_m = [0.0, 1.5, 0.0]\n\n[fabric]\npreset = \"cotton\"\n\n[world]\n{world}\n\n\
             [solver]\nfps = 24\nframes = 24\n"
        );
        warnings(&Scene::parse(&text, Path::new("scene.toml")).unwrap())
    }

    #[test]
    fn gravity_and_air_no_room_has_and_gravity_after_the_end_are_warned() {
        assert!(world_warned("gravity_m_s2 = [0.0, -9.81, 0.0]").is_empty());
        let strong = world_warned("gravity_m_s2 = [0.0, -1000.0, 0.0]");
        assert!(strong[0].contains("102 times Earth's"), "{strong:?}");
        // Located and with a fix, as the fabric's warnings are.
        assert!(strong[0].starts_with("scene.toml:"), "{strong:?}");
        assert!(strong[0].contains("world.gravity_m_s2") && strong[0].contains("(fix: "));
        let thick = world_warned("air_damping_per_s = 1e4");
        assert!(thick[0].contains("the cloth will crawl"), "{thick:?}");
        // 24 frames at 24 fps: the run ends at 1 s.
        assert!(world_warned("gravity_start_s = 0.99").is_empty());
        let late = world_warned("gravity_start_s = 1.0");
        assert!(late[0].contains("gravity never comes on"), "{late:?}");
        assert!(world_warned("gravity_start_s = 5.0\ngravity_m_s2 = [0.0, 0.0, 0.0]").is_empty());
    }

    #[test]
    fn seams_still_being_drawn_shut_at_the_end_are_warned() {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/scenes/tshirt_drape_cotton.toml");
        let text = std::fs::read_to_string(&path).unwrap();
        let sewing = |frames: &str| {
            let text = text.replace("frames = 240", frames);
            let scene = Scene::parse(&text, &path).unwrap();
            let w = warnings(&scene);
            w.iter().any(|w| w.contains("still being drawn shut"))
        };
        // seam_sewing_time_s = 0.6 at 24 fps: 14 frames end at 0.583 s, 15 at 0.625 s.
        assert!(sewing("frames = 14"));
        assert!(!sewing("frames = 15"));
    }

    #[test]
    fn holding_nothing_or_holding_for_the_whole_run_is_warned() {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/scenes/tshirt_drape_cotton.toml");
        let text = std::fs::read_to_string(&path).unwrap();
        let warned = |keys: &str| {
            let with = format!("seam_sewing_time_s = 0.6\n{keys}");
            let text = text.replace("seam_sewing_time_s = 0.6", &with);
            let w = warnings(&Scene::parse(&text, &path).unwrap());
            (w.iter()).find(|w| w.contains("attach_frames")).cloned()
        };
        assert_eq!(
            warned("attach_labels = [\"collar\"]\nattach_frames = 10"),
            None
        );
        let nothing = warned("attach_frames = 10").unwrap();
        assert!(nothing.contains("nothing is held"), "{nothing}");
        // The scene runs 240 frames.
        let always = warned("attach_labels = [\"collar\"]\nattach_frames = 240").unwrap();
        assert!(always.contains("never let go"), "{always}");
    }

    #[test]
    fn seams_far_weaker_or_stiffer_than_the_fabric_are_warned() {
        // Cotton's stiffest stretch is 4,050 N/m: the default seam (twice that), 1% and 100
        // times pass; below and above do not.
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/scenes/tshirt_drape_cotton.toml");
        let text = std::fs::read_to_string(&path).unwrap();
        let warned = |stiffness: &str| {
            let with = format!("seam_sewing_time_s = 0.6\nseam_stiffness_n_m = {stiffness}");
            let text = text.replace("seam_sewing_time_s = 0.6", &with);
            let scene = Scene::parse(&text, &path).unwrap();
            let w = warnings(&scene);
            (w.iter())
                .find(|w| w.contains("seam_stiffness_n_m"))
                .cloned()
        };
        for fine in ["8100", "40.5", "405000"] {
            assert_eq!(warned(fine), None, "{fine}");
        }
        assert!(warned("40").unwrap().contains("never pull the panels shut"));
        assert!(warned("406000").unwrap().contains("snap the panels shut"));
    }

    #[test]
    fn a_wind_past_any_storm_or_gusting_like_a_vibration_is_warned() {
        let warned = |wind: &str| {
            let text = format!(
                "[cloth.grid]\nwidth_m = 1.0\nheight_m = 1.0\ncolumns = 8\nrows = 8\n\
                 [fabric]\npreset = \"cotton\"\n[wind]\n{wind}\n[solver]\nframes = 24\n"
            );
            warnings(&Scene::parse(&text, Path::new("scene.toml")).unwrap())
        };
        assert!(warned("velocity_m_s = [20.0, 0.0, 0.0]\ngust_amplitude = 0.5").is_empty());
        // 80 m/s with 50% gusts reaches 120 m/s.
        let storm = warned("velocity_m_s = [80.0, 0.0, 0.0]\ngust_amplitude = 0.5");
        assert!(storm[0].contains("gusts reach 120 m/s"), "{storm:?}");
        let shaking =
            warned("velocity_m_s = [5.0, 0.0, 0.0]\ngust_amplitude = 0.3\ngust_frequency_hz = 1e6");
        assert!(
            shaking[0].contains("a vibration, not a gust"),
            "{shaking:?}"
        );
    }
}
