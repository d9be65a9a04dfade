//! A test specimen: one flat pattern panel of a fabric preset, held where a test rig holds it,
//! settled under gravity. Each specimen is written out as a scene (`scene.toml` beside its
//! `specimen.json`), so that `drapekit run` repeats it.

use crate::atomic_file::write_atomic;
use crate::error::Error;
use crate::gpu::GpuContext;
use crate::scene::Scene;
use crate::sim::{prepare, simulate, RunStats};
use glam::Vec3;
use std::collections::VecDeque;
use std::path::Path;
use std::time::Instant;

/// The panel's outline, flat in the horizontal plane y = [`HEIGHT_M`], in metres.
#[derive(Clone, Copy, Debug)]
pub enum Outline {
    /// A disc about the origin.
    Circle {
        /// Radius, m.
        radius: f64,
    },
    /// A strip along x, centred on z = 0.
    Strip {
        /// Where it starts, m.
        x0: f64,
        /// Where it ends, m.
        x1: f64,
        /// Its width in z, m.
        width: f64,
    },
}

/// Where the rig sits: the specimen starts flat at this height (m), high enough to hang freely.
pub const HEIGHT_M: f64 = 0.5;

/// How a specimen is stepped.
#[derive(Clone, Debug)]
pub struct Stepping {
    /// `"implicit"` or `"symplectic"`.
    pub integrator: String,
    /// Substeps per frame (`None`: the scene's "auto").
    pub substeps: Option<u32>,
    /// Implicit iterations per substep (`None`: the scene's default); with a tolerance, the
    /// most.
    pub iterations: Option<u32>,
    /// Implicit Euler ends a substep's solve once its RMS force residual is at most this
    /// fraction of the weight (`None`: always `iterations`).
    pub tolerance: Option<f32>,
    /// The most frames to wait for the settle rule.
    pub max_frames: u32,
    /// `"springs"` or `"membrane"` (the preset's warp, weft and shear).
    pub fabric_model: String,
    /// The preset's bending rigidity times this (`None`: as the preset has it).
    pub bending_scale: Option<f64>,
    /// The springs buckle in compression (`compression = "buckling"`).
    pub buckling: bool,
}

/// The bending rigidity a specimen of `preset` is given, N·m: the preset's, times
/// `--bending-scale`. The one place the scale is applied, for the scene and the report alike.
pub fn bending_rigidity(preset: &crate::scene::FabricPreset, step: &Stepping) -> f64 {
    preset.bending_stiffness_n_m * step.bending_scale.unwrap_or(1.0)
}

/// The bending rigidity a strip of `preset` cut `grain_deg` from the warp is given, N·m, where
/// `preset.bending_stiffness_n_m` is already the specimens' (`bending_rigidity`): with the
/// membrane, the preset's rigidity for strips of that direction (warp, bias or weft: the
/// membrane bends by direction, `model::bending`) times `--bending-scale`; else that one value.
pub fn strip_rigidity(preset: &crate::scene::FabricPreset, step: &Stepping, grain_deg: f64) -> f64 {
    let [warp, bias, weft] = preset.strip_bending_n_m;
    let scale = step.bending_scale.unwrap_or(1.0);
    match step.fabric_model.as_str() {
        "membrane" if grain_deg == 0.0 => warp * scale,
        "membrane" if grain_deg == 45.0 => bias * scale,
        "membrane" if grain_deg == 90.0 => weft * scale,
        _ => preset.bending_stiffness_n_m,
    }
}

/// A settled specimen.
#[derive(Clone, Debug)]
pub struct Settled {
    /// Rest positions (the flat panel), m.
    pub rest: Vec<Vec3>,
    /// Positions at the last frame, m.
    pub positions: Vec<Vec3>,
    /// The mesh's triangles.
    pub triangles: Vec<[u32; 3]>,
    /// The frame the settle rule fired at (`None`: it ran `max_frames` without settling).
    pub settled_frame: Option<u32>,
    /// Frames simulated.
    pub frames: u32,
    /// Substeps per frame.
    pub substeps: u32,
    /// Particles.
    pub particles: usize,
    /// Seconds spent simulating.
    pub wall_seconds: f64,
    /// Implicit Euler's RMS force residual over the free particles at the last substep, as a
    /// fraction of their weight (`None` for explicit integrators).
    pub force_residual_rms: Option<f32>,
    /// Implicit Euler's Newton steps and fine sweeps, summed over the substeps run.
    pub solve_work: SolveWork,
}

/// The work of implicit Euler's solves over a run: what a substep costs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveWork {
    /// Substeps run.
    pub substeps: u64,
    /// Newton steps run.
    pub newton_steps: u64,
    /// Fine Vertex Block Descent sweeps run.
    pub sweeps: u64,
}

impl SolveWork {
    /// Newton steps and sweeps per substep (`None` before any substep).
    pub fn per_substep(&self) -> Option<(f64, f64)> {
        let n = self.substeps as f64;
        (self.substeps > 0).then(|| (self.newton_steps as f64 / n, self.sweeps as f64 / n))
    }

    /// Adds another run's work.
    pub fn add(&mut self, other: SolveWork) {
        self.substeps += other.substeps;
        self.newton_steps += other.newton_steps;
        self.sweeps += other.sweeps;
    }
}

/// The panel's GarmentCode JSON (centimetres; the panel is rotated flat onto the xz plane).
fn pattern_json(outline: Outline) -> String {
    let cm = |m: f64| m * 100.0;
    let (vertices, edges) = match outline {
        Outline::Circle { radius } => {
            // Three arcs of 120°, counter-clockwise, each bulging outward (to its right).
            let r = cm(radius);
            let corner = |k: f64| {
                let a = k * std::f64::consts::TAU / 3.0;
                format!("[{}, {}]", r * a.cos(), r * a.sin())
            };
            let arc = |a: u32, b: u32| {
                format!(
                    r#"{{"endpoints": [{a}, {b}], "curvature": {{"type": "circle", "params": [{r}, 0, 1]}}}}"#
                )
            };
            (
                format!("[{}, {}, {}]", corner(0.0), corner(1.0), corner(2.0)),
                format!("[{}, {}, {}]", arc(0, 1), arc(1, 2), arc(2, 0)),
            )
        }
        Outline::Strip { x0, x1, width } => {
            let (a, b, h) = (cm(x0), cm(x1), cm(width) / 2.0);
            (
                format!("[[{a}, {}], [{b}, {}], [{b}, {h}], [{a}, {h}]]", -h, -h),
                r#"[{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]"#
                    .to_string(),
            )
        }
    };
    // Rotation −90° about x maps the panel's (x, y) to (x, 0, −y).
    format!(
        r#"{{"pattern": {{"panels": {{"specimen": {{"translation": [0, {}, 0], "rotation": [-90, 0, 0], "vertices": {vertices}, "edges": {edges}}}}}, "stitches": []}}, "properties": {{"curvature_coords": "relative", "units_in_meter": 100}}}}"#,
        cm(HEIGHT_M)
    )
}

/// The `[fabric]` lines after the preset: the scaled bending, the compression, the model, the
/// grain and, for a strip whose stretch is capped at `stretch`, the capped values.
fn fabric_lines(preset: &str, stretch: Option<f64>, grain_deg: f64, step: &Stepping) -> String {
    let mut s = String::new();
    if let (Some(f), Some(p)) = (step.bending_scale, crate::scene::preset(preset)) {
        // The key is the hinge stiffness, HINGE_PER_RIGIDITY·B.
        s += &format!(
            "# The preset's bending rigidity times {f} (--bending-scale).\n\
             bending_stiffness_n_m = {}\n",
            crate::scene::HINGE_PER_RIGIDITY * bending_rigidity(p, step)
        );
    }
    if let Some(k) = stretch {
        s += &format!(
            "# Softer than the preset: see docs/src/benchmarks/fabric.md.\n\
             stretch_stiffness_n_m = {k}\n"
        );
    }
    if step.buckling {
        s += "compression = \"buckling\"\n";
    }
    if step.fabric_model == "membrane" {
        s += &format!("model = \"membrane\"\ngrain_deg = {grain_deg}\n");
        if let (Some(f), Some(p)) = (step.bending_scale, crate::scene::preset(preset)) {
            // The membrane bends by direction: its warp and weft strips scaled alike.
            let [warp, _, weft] = p.strip_bending_n_m;
            for (key, b) in [("warp", warp), ("weft", weft)] {
                let k = crate::scene::HINGE_PER_RIGIDITY * b * f;
                s += &format!("{key}_bending_n_m = {k}\n");
            }
        }
        if let (Some(k), Some(p)) = (stretch, crate::scene::preset(preset)) {
            for (key, v) in [
                ("warp", p.warp_stiffness_n_m),
                ("weft", p.weft_stiffness_n_m),
                ("shear", p.shear_stiffness_n_m),
            ] {
                s += &format!("{key}_stiffness_n_m = {}\n", v.min(k));
            }
        }
    }
    s
}

fn scene_toml(
    preset: &str,
    stretch: Option<f64>,
    grain_deg: f64,
    spacing: f64,
    step: &Stepping,
) -> String {
    let substeps = match step.substeps {
        Some(n) => n.to_string(),
        None => "\"auto\"".to_string(),
    };
    let mut s = format!(
        "# Written by `drapekit bench fabric`: rerun with `drapekit run` on this file.\n\
         [cloth.pattern]\npath = \"specimen.json\"\nparticle_distance_m = {spacing}\n\n\
         [fabric]\npreset = \"{preset}\"\n{}\n\
         [world]\ngravity_m_s2 = [0.0, -9.81, 0.0]\n\
         # Air damping (a = -10 v, about critical for the slowest sway of a hanging drape)\n\
         # settles the specimen in a second or two; at rest it has no force, so it does not\n\
         # move the resting shape.\n\
         air_damping_per_s = 10.0\n\n\
         [solver]\nfps = 24\nframes = {}\nsubsteps = {substeps}\nintegrator = \"{}\"\n",
        fabric_lines(preset, stretch, grain_deg, step),
        step.max_frames,
        step.integrator
    );
    if let (true, Some(n)) = (step.integrator == "implicit", step.iterations) {
        s += &format!("iterations = {n}\n");
    }
    if let (true, Some(t)) = (step.integrator == "implicit", step.tolerance) {
        s += &format!("tolerance = {t}\n");
    }
    s
}

/// Frames over which a specimen must have stopped moving: 0.25 s at 24 fps.
pub const SETTLE_WINDOW: usize = 6;

/// Settles `preset` (with its stretch stiffness replaced by `stretch`, N/m, where given) cut to
/// `outline` with its warp `grain_deg` degrees from x (a membrane fabric) at `spacing` (m), with
/// every particle whose rest position `held` accepts pinned, in `dir` (created), on the GPU
/// path on `gpu` or else the CPU twin. The specimen has settled once no particle moved more
/// than `tolerance` (m) over the last [`SETTLE_WINDOW`] frames. (A kinetic-energy rule does
/// not serve here: the stiff wovens keep a jitter of about 1 mm/s in their in-plane springs
/// long after their shape has stopped changing.)
#[allow(clippy::too_many_arguments)] // one specimen's whole description
pub fn settle(
    dir: &Path,
    preset: &str,
    stretch: Option<f64>,
    grain_deg: f64,
    outline: Outline,
    spacing: f64,
    step: &Stepping,
    gpu: Option<&GpuContext>,
    tolerance: f32,
    held: impl Fn(Vec3) -> bool,
) -> Result<Settled, Error> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    write_atomic(&dir.join("specimen.json"), pattern_json(outline).as_bytes())?;
    let path = dir.join("scene.toml");
    let mut toml = scene_toml(preset, stretch, grain_deg, spacing, step);
    // A first build finds the particles the rig holds.
    let free = Scene::parse(&toml, &path)?;
    let model = prepare(&free)?.model;
    let pins: Vec<String> = (0..model.positions.len())
        .filter(|&i| held(model.positions[i]))
        .map(|i| i.to_string())
        .collect();
    toml += &format!(
        "\n# The particles the rig holds.\n[[pins]]\nindices = [{}]\n",
        pins.join(", ")
    );
    write_atomic(&path, toml.as_bytes())?;
    let scene = Scene::parse(&toml, &path)?;
    let prep = prepare(&scene)?;
    let mut solver = crate::run::build_solver(&prep, gpu)?;
    let mut stats = RunStats::default();
    let mut recent: VecDeque<Vec<Vec3>> = VecDeque::new();
    let mut settled_frame = None;
    let start = Instant::now();
    let run = simulate(&prep, solver.as_mut(), &mut stats, |frame, s| {
        recent.push_back(s.positions.iter().map(|p| p.truncate()).collect());
        if recent.len() > SETTLE_WINDOW + 1 {
            recent.pop_front();
        }
        if recent.len() == SETTLE_WINDOW + 1 {
            let (old, new) = (&recent[0], &recent[SETTLE_WINDOW]);
            let moved = old
                .iter()
                .zip(new)
                .map(|(a, b)| a.distance(*b))
                .fold(0.0, f32::max);
            if moved <= tolerance {
                settled_frame = Some(frame);
                // Stops the run here: the shape is what the test measures.
                return Err(Error::Interrupted {
                    frame,
                    dir: dir.to_path_buf(),
                });
            }
        }
        Ok(())
    });
    match run {
        Err(Error::Interrupted { .. }) if settled_frame.is_some() => {}
        other => other?,
    }
    Ok(Settled {
        rest: prep.model.positions.clone(),
        positions: recent.pop_back().unwrap_or_default(),
        triangles: prep.model.triangles.clone(),
        settled_frame,
        frames: settled_frame.unwrap_or(stats.frames_run),
        substeps: prep.substeps,
        particles: prep.model.positions.len(),
        wall_seconds: start.elapsed().as_secs_f64(),
        force_residual_rms: stats.force_residual.map(|(_, rms)| rms),
        solve_work: SolveWork {
            substeps: if stats.force_residual.is_some() {
                // The frame the rule fired at, when it did: the run stops there.
                u64::from(stats.frames_run) * u64::from(prep.substeps)
            } else {
                0
            },
            newton_steps: stats.newton_steps_run,
            sweeps: stats.iterations_run,
        },
    })
}
