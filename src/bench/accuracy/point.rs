//! Running one point of the sweep: the scene with the point's settings, simulated for the sweep's
//! frames (settle rule off), measured frame by frame against the exact original body.

use super::compare::{Material, Snapshot};
use super::ladder::{Setting, Step};
use crate::body::exact::ExactBody;
use crate::body::sdf::Sdf;
use crate::body::simplify::{simplify, to_obj};
use crate::body::Body;
use crate::cpu::CpuSolver;
use crate::error::Error;
use crate::gpu::{GpuContext, GpuSolver};
use crate::scene::{BodySource, ClothSource, Scene};
use crate::sim::{prepare, simulate_from, Prepared, RunStats};
use crate::solver::Solver;
use std::collections::HashMap;
use std::path::PathBuf;
use std::time::Instant;

/// How a point ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// It ran every frame.
    Ok,
    /// The solver stopped it (`Error::Unstable`): non-finite, exploded, too fast or gaining
    /// energy.
    Diverged,
    /// It could not run (refused by the scene's checks, or a simplified body that is not closed).
    Failed,
}

impl Status {
    /// The name in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Diverged => "diverged",
            Status::Failed => "failed",
        }
    }
}

/// What one point measured. Figures it could not measure are NaN (written as empty cells).
#[derive(Clone, Debug)]
pub struct Outcome {
    /// How it ended.
    pub status: Status,
    /// Why it diverged or failed.
    pub error: Option<String>,
    /// Substeps per output frame.
    pub substeps: u32,
    /// Particles.
    pub particles: usize,
    /// Particle distance in m (pattern) or grid spacing along the width (grid); NaN for meshes.
    pub particle_distance_m: f64,
    /// SDF node spacing in m (NaN without a body).
    pub sdf_resolution_m: f64,
    /// Body triangles after simplification (0 without a body).
    pub body_triangles: usize,
    /// The simplifier's bound on the body's deviation, in m (0 for the body as given).
    pub body_error_m: f64,
    /// Seconds to bake the SDF from scratch (measured even when the cache had it).
    pub bake_s: f64,
    /// Frames run.
    pub frames: u32,
    /// Wall seconds of stepping and readback.
    pub wall_s: f64,
    /// Simulated seconds.
    pub simulated_s: f64,
    /// Deepest particle inside the exact original body at any frame, in m.
    pub max_penetration_m: f64,
    /// Largest seam gap at the last frame, in m.
    pub max_seam_gap_m: f64,
    /// Largest spring strain at any frame.
    pub max_strain: f64,
    /// Largest spring strain at the last frame.
    pub final_strain: f64,
    /// Kinetic energy per free particle at the last frame, in J.
    pub final_ke_per_particle_j: f64,
    /// The mechanical energy the monitor sums (kinetic, gravitational, spring) at the frame from
    /// which nothing does work on the cloth, and at the last frame, with the largest kinetic
    /// plus elastic part in between, in J; `None` where the monitor's sum is incomplete or
    /// something does work (see `Prepared::energy_check_from`).
    pub energy: Option<(f64, f64, f64)>,
    /// The last frame's state, for the position error.
    pub snapshot: Option<Snapshot>,
}

impl Outcome {
    fn failed(error: String) -> Outcome {
        Outcome {
            status: Status::Failed,
            error: Some(error),
            substeps: 0,
            particles: 0,
            particle_distance_m: f64::NAN,
            sdf_resolution_m: f64::NAN,
            body_triangles: 0,
            body_error_m: f64::NAN,
            bake_s: f64::NAN,
            frames: 0,
            wall_s: f64::NAN,
            simulated_s: f64::NAN,
            max_penetration_m: f64::NAN,
            max_seam_gap_m: f64::NAN,
            max_strain: f64::NAN,
            final_strain: f64::NAN,
            final_ke_per_particle_j: f64::NAN,
            energy: None,
            snapshot: None,
        }
    }

    /// Wall seconds per simulated second.
    pub fn wall_per_simulated_s(&self) -> f64 {
        self.wall_s / self.simulated_s
    }

    /// Particles × substeps / wall seconds.
    pub fn particle_substeps_per_s(&self) -> f64 {
        self.particles as f64 * self.substeps as f64 * self.frames as f64 / self.wall_s
    }
}

/// Which path runs the points.
pub enum Backend {
    /// The CPU twin.
    Cpu,
    /// The wgpu path on this device.
    Gpu(Box<GpuContext>),
}

/// What every point shares: the scene, the run length, the backend, the exact original body and
/// what was already simplified or baked.
pub struct Sweep {
    /// The scene as given.
    pub scene: Scene,
    /// Output frames per point.
    pub frames: u32,
    /// The most substeps per frame the stability bound may ask for.
    pub max_substeps: u32,
    /// The backend.
    pub backend: Backend,
    /// Where simplified bodies are written (as OBJ, to load like any body).
    pub bodies_dir: PathBuf,
    /// The body as given, and its exact queries (penetration is measured against it).
    pub body: Option<(Body, ExactBody)>,
    simplified: HashMap<u32, Result<(PathBuf, usize, f64), String>>,
    bakes: HashMap<(u64, u32), f64>,
}

impl Sweep {
    /// A sweep over `scene` (its body, if any, is built here once).
    pub fn new(
        scene: Scene,
        frames: u32,
        max_substeps: u32,
        backend: Backend,
        bodies_dir: PathBuf,
    ) -> Result<Sweep, Error> {
        let body = match scene.bodies.first() {
            Some(b) => {
                let body = crate::model::build_body(b, &scene.checker(), "body")?;
                let exact = ExactBody::new(&body.mesh).map_err(|e| {
                    Error::Input(scene.error(
                        "body",
                        "",
                        format!("cannot build the BVH: {e}"),
                        "check the body mesh",
                    ))
                })?;
                Some((body, exact))
            }
            None => None,
        };
        Ok(Sweep {
            scene,
            frames,
            max_substeps,
            backend,
            bodies_dir,
            body,
            simplified: HashMap::new(),
            bakes: HashMap::new(),
        })
    }

    /// The scene with `s`'s settings (substeps still "auto" for `Step::Auto`), and the body's
    /// triangle count and simplification error.
    fn scene_for(&mut self, s: &Setting) -> Result<(Scene, usize, f64), String> {
        let mut scene = self.scene.clone();
        scene.solver.integrator = s.integrator;
        scene.solver.iterations = Some(s.iterations);
        scene.solver.frames = self.frames;
        scene.solver.max_substeps_per_frame = self.max_substeps;
        // Every point runs the same frames, so that all are compared at the same time.
        scene.solver.settle_speed = None;
        scene.solver.substeps = match s.step {
            Step::Fixed(n) => Some(n),
            Step::Auto(_) => None,
        };
        match &mut scene.cloth {
            ClothSource::Pattern { options, .. } => options.particle_distance *= s.spacing as f64,
            ClothSource::Grid { columns, rows, .. } => {
                let scale = |n: &mut u32| {
                    *n = (((*n - 1) as f32 / s.spacing).round() as u32).max(1) + 1;
                };
                scale(columns);
                scale(rows);
            }
            ClothSource::Mesh { .. } => {}
        }
        let mut triangles = 0;
        let mut body_error = 0.0;
        if let (Some(b), Some((body, _))) = (scene.bodies.first_mut(), &self.body) {
            let old = b.sdf_resolution;
            b.sdf_resolution *= s.sdf;
            // An unset margin follows the resolution, as the scene parser sets it.
            if b.sdf_margin == (2.0 * b.thickness).max(3.0 * old) {
                b.sdf_margin = (2.0 * b.thickness).max(3.0 * b.sdf_resolution);
            }
            triangles = body.mesh.triangles.len();
            if s.body < 1.0 {
                let key = s.body.to_bits();
                if !self.simplified.contains_key(&key) {
                    let made = self.write_simplified(body, s.body);
                    self.simplified.insert(key, made);
                }
                let (path, n, e) = self.simplified[&key].clone()?;
                b.source = BodySource::Mesh {
                    path,
                    scale: 1.0,
                    offset: glam::Vec3::ZERO,
                };
                triangles = n;
                body_error = e;
            }
        }
        Ok((scene, triangles, body_error))
    }

    fn write_simplified(&self, body: &Body, keep: f32) -> Result<(PathBuf, usize, f64), String> {
        let target = ((body.mesh.triangles.len() as f32 * keep).round() as usize).max(4);
        let s = simplify(body, target)?;
        let n = s.body.mesh.triangles.len();
        let path = self.bodies_dir.join(format!("body_{n}_triangles.obj"));
        std::fs::create_dir_all(&self.bodies_dir).map_err(|e| e.to_string())?;
        crate::atomic_file::write_atomic(&path, to_obj(&s.body.mesh).as_bytes())
            .map_err(|e| e.to_string())?;
        Ok((path, n, s.error_m as f64))
    }

    /// Seconds a fresh bake of the prepared body's SDF takes: the bake `prepare` just did, or,
    /// when the cache held the grid, one timed here (once per body and resolution).
    fn bake_seconds(&mut self, prep: &Prepared, margin: f32) -> f64 {
        let Some(c) = prep.model.colliders.first() else {
            return f64::NAN;
        };
        let key = (c.body.hash(), c.sdf.cell.to_bits());
        if !c.bake.from_cache {
            self.bakes.insert(key, c.bake.bake_seconds);
        }
        if let Some(&s) = self.bakes.get(&key) {
            return s;
        }
        let start = Instant::now();
        let seconds = match Sdf::bake(&c.body, c.sdf.cell, margin) {
            Ok(_) => start.elapsed().as_secs_f64(),
            Err(_) => f64::NAN,
        };
        self.bakes.insert(key, seconds);
        seconds
    }

    /// Runs one point; `nudge` (m) moves every free particle's start by up to that much along
    /// each axis (deterministically), to see how far a tiny change carries.
    pub fn run(&mut self, s: &Setting, nudge: f32) -> Outcome {
        let (mut scene, body_triangles, body_error_m) = match self.scene_for(s) {
            Ok(x) => x,
            Err(e) => return Outcome::failed(e),
        };
        let prep = match self.prepare(&mut scene, s.step) {
            Ok(p) => p,
            Err(e) => return Outcome::failed(e.to_string()),
        };
        let margin = scene.bodies.first().map_or(0.0, |b| b.sdf_margin);
        let bake_s = self.bake_seconds(&prep, margin);
        let mut solver: Box<dyn Solver> = match &self.backend {
            Backend::Cpu => {
                let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
                if prep.cpu_point_triangle {
                    cpu.use_point_triangle_reference();
                }
                Box::new(cpu)
            }
            Backend::Gpu(ctx) => match GpuSolver::new(
                ctx,
                &prep.model,
                prep.params,
                &prep.plan,
                prep.substeps as usize,
            ) {
                Ok(g) => Box::new(g),
                Err(e) => return Outcome::failed(e.to_string()),
            },
        };
        if nudge > 0.0 {
            match solver.state() {
                Ok(mut state) => {
                    nudged(&mut state.positions, nudge);
                    solver.set_state(&state);
                }
                Err(e) => return Outcome::failed(e.to_string()),
            }
        }
        let exact = self.body.as_ref().map(|(_, e)| e);
        let mut stats = RunStats::default();
        let mut last = Vec::new();
        let mut max_penetration = 0.0f64;
        let (mut e_from, mut e_last, mut active_max) = (None, 0.0, 0.0f64);
        let result = simulate_from(
            &prep,
            solver.as_mut(),
            &mut stats,
            None,
            |frame, state, st| {
                if let Some(exact) = exact {
                    let body = prep.body_state(0, frame as f32 * prep.frame_dt);
                    let inverse = body.rotation.inverse();
                    for p in &state.positions {
                        let d = exact.query(inverse * (p.truncate() - body.translation)).0;
                        max_penetration = max_penetration.max(-d as f64);
                    }
                }
                if let (Some(from), Some((e, active))) = (prep.energy_check_from, st.energy) {
                    if frame >= from {
                        e_from.get_or_insert(e);
                        e_last = e;
                        active_max = active_max.max(active);
                    }
                }
                last = state.positions.iter().map(|p| p.truncate()).collect();
                Ok(())
            },
        );
        let (status, error) = match result {
            Ok(()) => (Status::Ok, None),
            Err(e @ Error::Unstable(_)) => (Status::Diverged, Some(e.to_string())),
            Err(e) => (Status::Failed, Some(e.to_string())),
        };
        let free = prep.model.pinned.iter().filter(|p| !**p).count().max(1) as f64;
        let nan_without = |has: bool, v: f64| if has { v } else { f64::NAN };
        Outcome {
            status,
            error,
            substeps: prep.substeps,
            particles: prep.model.len(),
            particle_distance_m: particle_distance(&scene),
            sdf_resolution_m: (scene.bodies.first()).map_or(f64::NAN, |b| b.sdf_resolution as f64),
            body_triangles,
            body_error_m,
            bake_s,
            frames: stats.frames_run,
            wall_s: stats.wall_seconds,
            simulated_s: stats.frames_run as f64 * prep.frame_dt as f64,
            max_penetration_m: nan_without(exact.is_some(), max_penetration),
            max_seam_gap_m: (stats.seam_gaps.iter().copied())
                .fold(None, |m: Option<f32>, g| Some(m.map_or(g, |m| m.max(g))))
                .map_or(f64::NAN, |g| g as f64),
            max_strain: stats.max_edge_strain as f64,
            final_strain: stats.last_edge_strain as f64,
            final_ke_per_particle_j: stats.kinetic_energy_j / free,
            energy: e_from.map(|from| (from, e_last, active_max)),
            snapshot: (status == Status::Ok).then(|| Snapshot {
                positions: last,
                spacing: s.spacing,
                material: Material::of(&scene, &prep),
            }),
        }
    }

    /// Prepares `scene`; for `Step::Auto(f)` with f ≠ 1, first asks the stability bound for its
    /// count and then fixes f times that.
    fn prepare(&mut self, scene: &mut Scene, step: Step) -> Result<Prepared, Error> {
        let prep = prepare(scene)?;
        match step {
            Step::Auto(f) if f != 1.0 => {
                scene.solver.substeps = Some(((prep.substeps as f32 * f).ceil() as u32).max(1));
                prepare(scene)
            }
            _ => Ok(prep),
        }
    }
}

/// Moves every free particle (inverse mass w > 0) by up to `by` m along each axis, with a
/// fixed xorshift sequence so that every run nudges alike.
fn nudged(positions: &mut [glam::Vec4], by: f32) {
    let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut unit = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 40) as f32 / (1u64 << 23) as f32 - 1.0
    };
    for p in positions.iter_mut().filter(|p| p.w > 0.0) {
        let d = glam::Vec3::new(unit(), unit(), unit()) * by;
        *p += d.extend(0.0);
    }
}

/// The particle distance of a pattern, or the grid's spacing along its width, in m.
fn particle_distance(scene: &Scene) -> f64 {
    match &scene.cloth {
        ClothSource::Pattern { options, .. } => options.particle_distance,
        ClothSource::Grid { width, columns, .. } => *width as f64 / (*columns - 1) as f64,
        ClothSource::Mesh { .. } => f64::NAN,
    }
}
