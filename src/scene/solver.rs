//! The `[solver]` and `[output]` tables: frame rate, steps, integrator, and what is written.

use super::raw::{RawOutput, RawSolver, RawStrainLimit, RawSubsteps};
use crate::check::Checker;
use crate::error::InputError;
use std::path::{Path, PathBuf};

/// The `[solver] tolerance` values accepted: an RMS force residual of a millionth to a
/// thousand times the weight.
pub const TOLERANCE_RANGE: (f64, f64) = (1e-6, 1e3);

/// Forward (explicit) Euler. The integrator codes are mirrored in `kernels/common.wgsl`.
pub const INTEGRATOR_EXPLICIT: u32 = 0;
/// Semi-implicit (symplectic) Euler.
pub const INTEGRATOR_SYMPLECTIC: u32 = 1;
/// Backward (implicit) Euler, solved by Vertex Block Descent.
pub const INTEGRATOR_IMPLICIT: u32 = 2;

/// Newton steps per implicit substep by default, where the cloth has coarse levels: with two
/// smoothing sweeps before and after, one step sews and settles the cotton T-shirt with its
/// force residual under 2% of the weight (docs/src/implicit.md).
pub const DEFAULT_NEWTON_STEPS: u32 = 1;
/// Vertex Block Descent sweeps per implicit substep by default, where the cloth has no coarse
/// levels (an OBJ mesh, a grid too small to coarsen).
pub const DEFAULT_SWEEPS: u32 = 10;

impl SolverSettings {
    /// The implicit solve's outer iterations for a cloth with (`levels`) or without coarse
    /// levels: the scene's `iterations`, or the default of each.
    pub fn iterations_for(&self, levels: bool) -> u32 {
        self.iterations.unwrap_or(if levels {
            DEFAULT_NEWTON_STEPS
        } else {
            DEFAULT_SWEEPS
        })
    }
}

/// Solver settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverSettings {
    /// Output frames per simulated second.
    pub fps: f32,
    /// Number of output frames.
    pub frames: u32,
    /// Substeps per frame, or `None` for automatic from the stability bound.
    pub substeps: Option<u32>,
    /// `INTEGRATOR_EXPLICIT`, `INTEGRATOR_SYMPLECTIC` or `INTEGRATOR_IMPLICIT`.
    pub integrator: u32,
    /// `[solver] iterations` (implicit only; with a tolerance, the most): Newton steps per
    /// substep where the cloth has coarse levels, Vertex Block Descent sweeps where it has
    /// none; `None` for the default of each (`iterations_for`).
    pub iterations: Option<u32>,
    /// Implicit Euler stops a substep's solve once the RMS force residual |f|/(m·g) of the
    /// free particles is at most this (`None`: always `iterations`).
    pub tolerance: Option<f32>,
    /// Implicit Euler solves with coarse levels (a multigrid cycle) where the cloth has them
    /// (grids and sewing patterns).
    pub multigrid: bool,
    /// With coarse levels, fine sweeps before each coarse correction and after the last one.
    pub smoothing_sweeps: u32,
    /// Stop once the free particles' RMS speed, √(2·kinetic energy / their mass), falls
    /// below this (m/s): the same rule at every particle spacing.
    pub settle_speed: Option<f32>,
    /// With implicit Euler, the settle rule also needs the RMS force residual |f|/(m·g) of the
    /// free particles at the end of the frame at most this.
    pub settle_force_residual: f32,
    /// The most substeps per frame `auto` may choose before the scene is refused.
    pub max_substeps_per_frame: u32,
    /// A frame with any spring strain above this is exploded: the run stops before writing it.
    pub max_strain: f32,
    /// The most memory a run may plan for, in bytes (`None`: half the machine's memory).
    pub max_memory_bytes: Option<u64>,
    /// The largest edge stretch the strain-limiting stage lets through (0.1 = 10% over rest),
    /// or `None` when strain limiting is off.
    pub strain_limit: Option<f32>,
    /// Jacobi iterations of the strain-limiting stage per substep.
    pub strain_limit_iterations: u32,
    /// Between frames with no work done on the cloth, the most its energy may rise, as a
    /// fraction of its kinetic plus elastic energy at the earlier frame.
    pub max_energy_growth: f32,
    /// A frame with a particle faster than this (m/s) has diverged.
    pub max_speed: f32,
}

/// The settle rule's force residual with implicit Euler: the free particles' forces balance to
/// 5% of their weight (RMS) at the end of the frame.
pub const DEFAULT_SETTLE_FORCE_RESIDUAL: f32 = 0.05;

/// Fine sweeps around each coarse correction of implicit Euler's multigrid cycle.
pub const DEFAULT_SMOOTHING_SWEEPS: u32 = 2;

/// The default of `[solver] strain_limit`: 10% over rest length. Woven fabrics reach about 5%
/// only at the 500 gf/cm load of the KES tensile test (docs/src/stability.md, "Strain limiting").
pub const DEFAULT_STRAIN_LIMIT: f32 = 0.1;

/// Output settings.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputSettings {
    /// Output folder.
    pub dir: PathBuf,
    /// Write one OBJ per output frame.
    pub obj: bool,
    /// Write every n-th frame.
    pub every: u32,
    /// Write the written frames as a PC2 point cache, `cloth.pc2`, beside `rest.obj`.
    pub pc2: bool,
    /// Write the written frames as an animated glTF binary, `garment.glb`.
    pub gltf: bool,
    /// Weld each seam's vertex pairs into one vertex in the glTF binary, so that a sewn
    /// garment is one connected mesh.
    pub weld_seams: bool,
}

/// Validates `[solver]`.
pub(super) fn parse_solver(c: &Checker, s: &RawSolver) -> Result<SolverSettings, InputError> {
    let substeps = match &s.substeps {
        None => None,
        Some(RawSubsteps::Word(w)) if w == "auto" => None,
        Some(RawSubsteps::Word(w)) => {
            return Err(c.err(
                "solver",
                "substeps",
                format!("{w:?} is not a substep count"),
                "write \"auto\" or a whole number ≥ 1",
            ))
        }
        Some(RawSubsteps::Count(n)) => Some(c.count("solver", "substeps", *n, 1)?),
    };
    // Each substep of a frame is prepared before the frame runs: a count past the limit is a
    // typo, not a run (and the limit says so as it does for "auto").
    let most = c.count(
        "solver",
        "max_substeps_per_frame",
        s.max_substeps_per_frame,
        1,
    )?;
    if let Some(n) = substeps.filter(|&n| n > most) {
        return Err(c.err(
            "solver",
            "substeps",
            format!("{n} substeps a frame is above solver.max_substeps_per_frame = {most}"),
            "use fewer substeps (or \"auto\"), or raise solver.max_substeps_per_frame",
        ));
    }
    let integrator = match s.integrator.as_str() {
        "explicit" => INTEGRATOR_EXPLICIT,
        "symplectic" | "semi-implicit" => INTEGRATOR_SYMPLECTIC,
        "implicit" | "backward" => INTEGRATOR_IMPLICIT,
        other => {
            return Err(c.err(
                "solver",
                "integrator",
                format!("unknown integrator {other:?}"),
                "use \"explicit\", \"symplectic\" or \"implicit\"",
            ))
        }
    };
    let settings =
        SolverSettings {
            fps: c.positive("solver", "fps", s.fps, "frames per second")?,
            frames: c.count("solver", "frames", s.frames, 1)?,
            substeps,
            integrator,
            iterations: match s.iterations {
                Some(n) => Some(c.count("solver", "iterations", n, 1)?),
                None => None,
            },
            tolerance: match s.tolerance {
                None => None,
                Some(_) if integrator != INTEGRATOR_IMPLICIT => return Err(c.err(
                    "solver",
                    "tolerance",
                    "a tolerance stops the implicit solve's sweeps; this scene's integrator has \
                     none",
                    "remove tolerance, or use integrator = \"implicit\"",
                )),
                Some(v) => Some(c.within(
                    "solver",
                    "tolerance",
                    v,
                    TOLERANCE_RANGE,
                    "(the RMS force residual |f|/(m·g) of the free particles: 0.01 = 1% of each \
                 particle's weight)",
                )?),
            },
            multigrid: match s.multigrid {
                Some(true) if integrator != INTEGRATOR_IMPLICIT => return Err(c.err(
                    "solver",
                    "multigrid",
                    "multigrid solves implicit Euler's equations; this scene's integrator has none",
                    "remove multigrid, or use integrator = \"implicit\"",
                )),
                other => other.unwrap_or(true),
            },
            smoothing_sweeps: match s.smoothing_sweeps {
                None => DEFAULT_SMOOTHING_SWEEPS,
                Some(v) => c.count("solver", "smoothing_sweeps", v, 1)?,
            },
            settle_speed: match (s.settle_speed_m_s, s.settle_ke_per_particle_j) {
                (_, Some(_)) => return Err(c.err(
                    "solver",
                    "settle_ke_per_particle_j",
                    "the settle rule is now a speed: energy per particle meant a different \
                     speed at every particle spacing",
                    "write settle_speed_m_s = v, the RMS speed below which the cloth counts as \
                     at rest (1e-9 J per particle of mass m is v = √(2e-9 / m))",
                )),
                (None, None) => None,
                (Some(v), None) => {
                    Some(c.within("solver", "settle_speed_m_s", v, (1e-6, 10.0), "m/s")?)
                }
            },
            settle_force_residual: match s.settle_force_residual {
                None => DEFAULT_SETTLE_FORCE_RESIDUAL,
                Some(_) if integrator != INTEGRATOR_IMPLICIT => {
                    return Err(c.err(
                        "solver",
                        "settle_force_residual",
                        "the force residual is what the implicit solve leaves unbalanced; this \
                     scene's integrator solves no equations",
                        "remove settle_force_residual, or use integrator = \"implicit\"",
                    ))
                }
                Some(v) => c.within(
                    "solver",
                    "settle_force_residual",
                    v,
                    (1e-6, 1e3),
                    "(the RMS force residual |f|/(m·g): 0.05 = 5% of each particle's weight)",
                )?,
            },
            max_substeps_per_frame: most,
            // Below 10%, a garment's first frames would read as exploded; above 100 (10,000%),
            // the guard never fires.
            max_strain: c.within(
                "solver",
                "max_strain",
                s.max_strain,
                (0.1, 100.0),
                "(a strain: 1 = 100%)",
            )?,
            max_memory_bytes: match s.max_memory_mb {
                Some(mb) => Some(
                    (c.positive("solver", "max_memory_mb", mb, "MiB")? as f64 * 1048576.0) as u64,
                ),
                None => None,
            },
            strain_limit: match s.strain_limit {
                // The implicit solve holds the cloth at its physical strain; a cap would hide
                // where it does not.
                None if integrator == INTEGRATOR_IMPLICIT => None,
                None | Some(RawStrainLimit::Switch(true)) => Some(DEFAULT_STRAIN_LIMIT),
                Some(RawStrainLimit::Switch(false)) => None,
                Some(RawStrainLimit::Limit(v)) => Some(c.within(
                    "solver",
                    "strain_limit",
                    v,
                    (1e-3, 10.0),
                    "(as a fraction: 0.1 = 10%)",
                )?),
            },
            max_energy_growth: c.within(
                "solver",
                "max_energy_growth",
                s.max_energy_growth,
                (1e-3, 1e6),
                "(as a fraction: 0.5 = 50%)",
            )?,
            max_speed: c.within(
                "solver",
                "max_speed_m_s",
                s.max_speed_m_s,
                (0.1, 1e6),
                "m/s",
            )?,
            strain_limit_iterations: c.count(
                "solver",
                "strain_limit_iterations",
                s.strain_limit_iterations,
                1,
            )?,
        };
    // The cap holds every spring at or below strain_limit: an explosion guard below it would
    // stop the first frame that reaches the cap.
    if let Some(limit) = settings.strain_limit.filter(|&l| settings.max_strain <= l) {
        return Err(c.err(
            "solver",
            "max_strain",
            format!(
                "{} is at or below strain_limit = {limit}: every frame the cap holds would read \
                 as exploded",
                settings.max_strain
            ),
            "give max_strain above strain_limit (default 5 = 500%)",
        ));
    }
    Ok(settings)
}

/// Validates `[output]`; the folder defaults to `out/<scene file stem>`.
pub(super) fn parse_output(
    c: &Checker,
    path: &Path,
    raw: &RawOutput,
) -> Result<OutputSettings, InputError> {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
    let (obj, pc2, gltf) = formats(c, raw)?;
    Ok(OutputSettings {
        dir: raw
            .dir
            .as_ref()
            .map(PathBuf::from)
            .unwrap_or_else(|| Path::new("out").join(stem)),
        every: c.count("output", "every", raw.every, 1)?,
        obj,
        pc2,
        gltf,
        weld_seams: raw.weld_seams.unwrap_or(true),
    })
}

/// The export formats: `formats = ["obj", "glb", "pc2"]`, or the older switches `obj` (default
/// on), `pc2` and `gltf`. Giving both spellings is refused, so that neither silently wins.
fn formats(c: &Checker, raw: &RawOutput) -> Result<(bool, bool, bool), InputError> {
    let Some(list) = &raw.formats else {
        return Ok((
            raw.obj.unwrap_or(true),
            raw.pc2.unwrap_or(false),
            raw.gltf.unwrap_or(false),
        ));
    };
    for (key, given) in [("obj", raw.obj), ("pc2", raw.pc2), ("gltf", raw.gltf)] {
        if given.is_some() {
            return Err(c.err(
                "output",
                key,
                format!("both formats and {key} choose the exports"),
                format!("remove {key} and list the exports in formats only"),
            ));
        }
    }
    let mut chosen = (false, false, false);
    for f in list {
        match f.as_str() {
            "obj" => chosen.0 = true,
            "pc2" => chosen.1 = true,
            "glb" | "gltf" => chosen.2 = true,
            other => {
                return Err(c.err(
                    "output",
                    "formats",
                    format!("unknown export format {other:?}"),
                    "use any of \"obj\", \"glb\", \"pc2\" (or [] for summary.json only)",
                ))
            }
        }
    }
    Ok(chosen)
}
