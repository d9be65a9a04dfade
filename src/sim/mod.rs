//! From a scene to a prepared run (model, plan, substeps), and the frame loop shared by both
//! backends: one `advance` per output frame, one readback per output frame.

use crate::body::motion::BodyState;
use crate::error::Error;
use crate::metrics;
use crate::model::layout::{
    BodyParams, BodyPose, SimParams, SubstepParams, INTEGRATOR_IMPLICIT, MAX_BODIES,
};

mod attach;
mod bodies;
mod coarse;
mod explosion;
mod settle;
mod stats;
mod substeps;

use crate::model::BuiltCloth;
use crate::model::ClothModel;
use crate::pattern::garment::Garment;
use crate::plan::PassPlan;
use crate::scene::{ClothSource, Scene, Wind};
use crate::solver::{ParticleState, Solver};
pub use attach::packed_at;
pub(crate) use attach::release;
pub use bodies::{body_pose, part_poses};
pub use coarse::{carried, map_state, CoarseStart};
use settle::frame_speed;
pub use settle::Settled;
pub use stats::{FrameRecord, RunStats};
use std::time::Instant;
use substeps::StepChoice;

/// Fraction of the estimated stable step that `substeps = "auto"` uses.
pub const AUTO_DT_SAFETY: f32 = 0.5;

/// Everything a backend needs, derived from a scene.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The cloth.
    pub model: ClothModel,
    /// Run-constant GPU parameters.
    pub params: SimParams,
    /// The stages to run.
    pub plan: PassPlan,
    /// Substeps per output frame.
    pub substeps: u32,
    /// Whether `substeps` came from the stability estimate.
    pub auto_substeps: bool,
    /// What set the substep: `"scene"`, `"stretch"`, `"seam"`, `"bending"`, `"damping"` or
    /// `"body speed"`.
    pub dt_limited_by: &'static str,
    /// Estimated largest stable substep in s (`None`: no stable step exists).
    pub stable_dt: Option<f32>,
    /// Output frame length in s.
    pub frame_dt: f32,
    /// Output frames.
    pub frames: u32,
    /// Wind, if any.
    pub wind: Option<Wind>,
    /// The largest spring strain a frame may have before it counts as exploded.
    pub max_strain: f32,
    /// The settle rule: the free particles' RMS speed below which the cloth is at rest, m/s.
    pub settle_speed: Option<f32>,
    /// With implicit Euler, the settle rule's force residual (RMS |f|/(m·g)) too.
    pub settle_force_residual: Option<f32>,
    /// The free (never pinned) particles' mass, in kg, for the RMS speed.
    pub free_mass: f64,
    /// Things the user should know (e.g. a substep above the stable estimate).
    pub warnings: Vec<String>,
    /// The sewn pattern, for `[cloth.pattern]` scenes.
    pub garment: Option<Garment>,
    /// A seam is closed when all its pair gaps are below this, in m.
    pub seam_closed_gap: f32,
    /// Particles held in place (labelled pattern edges) until `attach_frames` have run.
    pub attached: Vec<u32>,
    /// Output frames after which `attached` particles are released.
    pub attach_frames: u32,
    /// Particles the scene's `[[pins]]` hold for the whole run.
    pub scene_pins: Vec<u32>,
    /// Fastest speed of any body surface point, in m/s (0 without a moving body).
    pub body_surface_speed: f32,
    /// CPU self-collision by point–triangle impulses instead of particle repulsion.
    pub cpu_point_triangle: bool,
    /// Gravity, and the output frame after which it is switched on (0: from the start).
    pub gravity: (glam::Vec3, u32),
    /// Vertex colours of the implicit solve (`None` for the explicit integrators).
    pub colors: Option<usize>,
    /// The first frame from which the cloth's energy may not rise (nothing does work on it
    /// any more: gravity on, attachments released); `None` with wind, a moving body or
    /// self-collision, which may add energy, and with bending or seams, whose energy the
    /// monitor does not sum.
    pub energy_check_from: Option<u32>,
    /// The most the energy may rise between such frames, as a fraction of the kinetic plus
    /// elastic energy at the earlier one.
    pub max_energy_growth: f32,
    /// A frame with a particle faster than this has diverged, in m/s.
    pub max_speed: f32,
    /// A pattern's seam stiffness as a multiple of its fabric's stretch stiffness (`None`
    /// without seams): an explosion names it first when it is far above the default's 2.
    pub seam_stiffness_ratio: Option<f64>,
    /// The bodies' parameters with their own friction slip speeds, from the first frame after
    /// every seam is closed (until then, `SEWING_SLIP_SPEED`); `None` when nothing switches.
    pub friction_slip_speed_sewn: Option<[BodyParams; MAX_BODIES]>,
}

/// Friction's slip speed (`BodyParams::friction_slip_speed`) while a garment is being sewn, in
/// m/s: friction reaches its Coulomb bound μλ only at this slip relative to the body, so the
/// panels slide onto the body as the seams pull them. With the static value (0.01 m/s) from the
/// start, the seams' tension wrapping the body pressed the panels on so hard that friction held
/// them where they were placed: 4 of the cotton T-shirt's 12 seams closed. Once every seam is
/// closed, the run switches to the scene's `friction_slip_speed_m_s`.
pub const SEWING_SLIP_SPEED: f32 = 1.0;

impl Prepared {
    /// Body `b`'s pose and velocity at time `t` (at rest at the origin past the scene's bodies).
    pub fn body_state(&self, b: usize, t: f32) -> BodyState {
        self.model
            .colliders
            .get(b)
            .map_or(BodyState::REST, |c| c.motion.at(t))
    }

    /// "particle i (panel 'p', pattern point (u, v) m)" for error messages: where to look.
    pub fn describe_particle(&self, i: u32) -> String {
        match &self.garment {
            Some(g) if (i as usize) < g.uv.len() => {
                let uv = g.uv[i as usize];
                // A particle lies in one panel: the panel of any triangle that uses it.
                let panel = (g.mesh.triangles.iter().zip(&g.triangle_panel))
                    .find(|(t, _)| t.contains(&i))
                    .and_then(|(_, &p)| g.panel_names.get(p as usize));
                match panel {
                    Some(name) => format!(
                        "particle {i} (panel '{name}', pattern point ({:.3}, {:.3}) m)",
                        uv.x, uv.y
                    ),
                    None => format!("particle {i} (pattern point ({:.3}, {:.3}) m)", uv.x, uv.y),
                }
            }
            _ => {
                let p = self
                    .model
                    .positions
                    .get(i as usize)
                    .copied()
                    .unwrap_or_default();
                format!(
                    "particle {i} (starting at ({:.3}, {:.3}, {:.3}) m)",
                    p.x, p.y, p.z
                )
            }
        }
    }

    /// Hinges the plan actually simulates (0 when bending is off).
    pub fn hinges_in_use(&self) -> usize {
        use crate::plan::Pass;
        // Implicit steps evaluate the hinges inside vbd_solve.
        if self.plan.contains(Pass::BendingForces)
            || self.plan.contains(Pass::HingeForces)
            || self.plan.contains(Pass::VbdSolve)
        {
            self.model.hinges.len()
        } else {
            0
        }
    }
}

/// Builds the model and plan and chooses the substep count.
pub fn prepare(scene: &Scene) -> Result<Prepared, Error> {
    let BuiltCloth {
        model,
        garment,
        scene_pins,
        attached,
    } = scene.build_model()?;
    let (seam_closed_gap, sewing_time, attach_frames) = match &scene.cloth {
        ClothSource::Pattern {
            closed_gap,
            sewing_time,
            attach_frames,
            ..
        } => (*closed_gap, *sewing_time, *attach_frames),
        _ => (0.0, 0.0, 0),
    };
    let plan = PassPlan::new(&model, scene.effects());
    let s = &scene.solver;
    let frame_dt = 1.0 / s.fps;
    let implicit = s.integrator == INTEGRATOR_IMPLICIT;
    let mut warnings = Vec::new();
    warnings.extend(metrics::mesh_warnings(&model, garment.is_none()));
    let run_s = s.frames as f32 / s.fps;
    let wind = scene
        .wind
        .map_or((glam::Vec3::ZERO, 0.0), |w| (w.velocity, w.gust_amplitude));
    for (i, apart) in metrics::unreachable_bodies(&model, scene.gravity, wind, run_s) {
        let key = match scene.bodies[i].source {
            crate::scene::BodySource::Mesh { .. } => "offset_m",
            _ => "center_m",
        };
        let problem = format!(
            "the body is {apart:.2} m from the cloth and stays there: the cloth cannot reach it \
             in the run's {run_s:.2} s, so it touches nothing"
        );
        let fix = "place the body where the cloth is, or the cloth where the body is, or run \
                   more frames";
        let e = scene.error(&scene.body_table(i), key, problem, fix);
        warnings.push(e.one_line());
    }
    let StepChoice {
        substeps,
        auto: auto_substeps,
        stable_dt,
        mut limited_by,
    } = substeps::choose(scene, &model, frame_dt, &mut warnings)?;
    for (i, c) in model.colliders.iter().enumerate() {
        let r = &c.body.repairs;
        if r.flipped_faces > 0 || r.turned_outside_out {
            warnings.push(format!(
                "{}: repaired orientation ({} faces flipped to match their neighbours{})",
                scene.body_table(i),
                r.flipped_faces,
                if r.turned_outside_out {
                    "; the mesh was inside out and was turned"
                } else {
                    ""
                }
            ));
        }
    }
    let (substeps, body_surface_speed, body_limited) = bodies::body_speed_substeps(
        &model,
        scene,
        frame_dt,
        substeps,
        auto_substeps,
        &mut warnings,
    )?;
    if body_limited {
        limited_by = "body speed";
    }
    let dt = frame_dt / substeps as f32;
    let colors = implicit.then(|| model.vertex_coloring().colors());
    let wind = scene.wind;
    let body = scene.bodies.first();
    let (self_thickness, hash_buckets) = match &scene.self_collision {
        Some(sc) => {
            let mean_edge = model.springs.iter().map(|s| s.rest_length).sum::<f32>()
                / model.springs.len().max(1) as f32;
            if let Some(t) = sc.thickness.filter(|&t| t > 2.0 * mean_edge) {
                warnings.push(format!(
                    "self_collision.thickness_m = {t} m is {:.0} times the cloth's mean edge \
                     ({mean_edge:.3e} m): particles a few triangles apart push each other away, \
                     and the cloth inflates or blows up (the default is 0.75 times the edge)",
                    t / mean_edge
                ));
            }
            (
                sc.thickness.unwrap_or(0.75 * mean_edge),
                sc.buckets.unwrap_or(
                    ((2 * model.len()) as u32)
                        .next_power_of_two()
                        .clamp(1024, 1 << 22),
                ),
            )
        }
        None => (0.0, 1),
    };
    let [euler_onset, membrane_onset, buckled_fraction] = scene.fabric.compression_law();
    let params = SimParams {
        gravity: if scene.gravity_start > 0.0 {
            [0.0; 4]
        } else {
            scene.gravity.extend(0.0).to_array()
        },
        num_particles: model.len() as u32,
        integrator: s.integrator,
        dt,
        air_damping: scene.air_damping,
        air_density: wind.map_or(0.0, |w| w.air_density),
        drag_coefficient: wind.map_or(0.0, |w| w.drag_coefficient),
        sewing_rate: if sewing_time > 0.0 {
            1.0 / sewing_time
        } else {
            0.0
        },
        iterations: s.iterations_for(model.multigrid.is_some()),
        self_thickness,
        // Cells at least as large as the contact distance: all contacts lie in the 27 cells.
        hash_cell: self_thickness.max(1e-6),
        hash_buckets,
        strain_limit: s.strain_limit.unwrap_or(0.0),
        strain_iterations: if s.strain_limit.is_some() {
            s.strain_limit_iterations
        } else {
            0
        },
        tolerance: s.tolerance.unwrap_or(0.0),
        num_bodies: model.colliders.len() as u32,
        smoothing: s.smoothing_sweeps,
        euler_onset,
        membrane_onset,
        buckled_fraction,
        stiffening: scene.fabric.stiffening(),
        // Friction is soft while a garment is being sewn; the run switches to each body's
        // slip speed once every seam is closed (see `phase_params`).
        bodies: bodies::body_params(&model, &scene.bodies, garment.is_some()),
        ..Default::default()
    };
    let sewing = garment.is_some() && body.is_some();
    let friction_slip_speed_sewn =
        sewing.then(|| bodies::body_params(&model, &scene.bodies, false));
    let free_mass = (model.masses.iter().zip(&model.pinned))
        .filter(|(_, pinned)| !**pinned)
        .map(|(m, _)| *m as f64)
        .sum();
    // The monitor counts each spring's energy as ½k·s²: not a membrane's, nor a buckled
    // spring's (`compression = "buckling"`), which is far less.
    let energy_complete = model.seams.is_empty()
        && (model.hinges.is_empty() || !scene.effects().bending)
        && model.membranes.is_empty()
        && params.buckled_fraction == 0.0;
    Ok(Prepared {
        model,
        params,
        plan,
        substeps,
        auto_substeps,
        dt_limited_by: limited_by,
        stable_dt,
        frame_dt,
        frames: s.frames,
        wind,
        settle_speed: s.settle_speed,
        settle_force_residual: implicit.then_some(s.settle_force_residual),
        free_mass,
        max_strain: s.max_strain,
        warnings,
        garment,
        seam_closed_gap,
        scene_pins,
        attached,
        attach_frames,
        body_surface_speed,
        cpu_point_triangle: scene
            .self_collision
            .as_ref()
            .is_some_and(|s| s.cpu_point_triangle),
        gravity: (
            scene.gravity,
            (scene.gravity_start / frame_dt).ceil() as u32,
        ),
        colors,
        // The monitor sums kinetic, gravitational and spring energy; hinges, seams, membranes
        // and buckled springs store energy it does not count, so with them only the speed and
        // strain limits guard.
        energy_check_from: (wind.is_none()
            && body_surface_speed == 0.0
            && scene.self_collision.is_none()
            && energy_complete)
            .then(|| {
                let gravity_on = (scene.gravity_start / frame_dt).ceil() as u32;
                let sewn = (sewing_time / frame_dt).ceil() as u32;
                gravity_on.max(sewn).max(attach_frames) + 1
            }),
        max_energy_growth: s.max_energy_growth,
        max_speed: s.max_speed,
        seam_stiffness_ratio: crate::scene::limits::seam_stiffness_ratio(scene),
        friction_slip_speed_sewn,
    })
}

/// The per-substep values of output frame `frame` (1-based): its time and wind.
///
/// Panics at frame 0, the initial state, which no step leads to.
pub fn substep_params(prep: &Prepared, frame: u32) -> Vec<SubstepParams> {
    assert!(
        frame >= 1,
        "output frames count from 1: frame 0 is the initial state"
    );
    (0..prep.substeps)
        .map(|s| {
            let t = ((frame - 1) as f64 * prep.frame_dt as f64 + s as f64 * prep.params.dt as f64)
                as f32;
            let wind = prep.wind.map_or(glam::Vec3::ZERO, |w| w.at(t));
            // Each body's pose at the end of the substep, where collision is resolved.
            let mut bodies = [BodyPose::default(); MAX_BODIES];
            for (b, pose) in bodies.iter_mut().enumerate() {
                *pose = body_pose(&prep.body_state(b, t + prep.params.dt));
            }
            SubstepParams {
                wind: wind.extend(0.0).to_array(),
                time: t,
                substep: s,
                _pad0: 0,
                _pad1: 0,
                bodies,
                parts: bodies::part_poses(&prep.model, t + prep.params.dt),
            }
        })
        .collect()
}

/// A particle rests on the body when it is within the collision thickness plus this of the
/// exact surface, in m. Resting particles sit at the thickness give or take the SDF's error:
/// in tshirt_drape (1 cm cells, 3 mm thickness) they lie 1.5 to 3.5 mm from the exact mesh.
pub const CONTACT_SLACK: f32 = 1e-3;

/// Runs `prep.frames` output frames on `solver`, calling `on_frame` with each finite frame
/// (frame 0 is the initial state). A non-finite frame stops the run with an error naming the
/// frame and the first bad particle; `on_frame` never sees it.
///
/// ```
/// use drapekit::cpu::CpuSolver;
/// use drapekit::scene::Scene;
/// use drapekit::sim::{prepare, simulate, RunStats};
/// use std::path::Path;
///
/// let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
/// let mut scene = Scene::load(&dir.join("fixtures/scenes/hanging_cloth.toml"))?;
/// scene.solver.frames = 3;
/// let prep = prepare(&scene)?;
/// let mut solver = CpuSolver::new(&prep.model, prep.params, &prep.plan);
/// let mut lowest = Vec::new();
/// simulate(&prep, &mut solver, &mut RunStats::default(), |frame, state| {
///     lowest.push((frame, state.positions.iter().map(|p| p.y).fold(f32::MAX, f32::min)));
///     Ok(())
/// })?;
/// assert_eq!(lowest.len(), 4); // frame 0 (the start) and frames 1 to 3
/// assert!(lowest[3].1 < lowest[0].1); // the cloth sags
/// # Ok::<(), drapekit::Error>(())
/// ```
pub fn simulate(
    prep: &Prepared,
    solver: &mut dyn Solver,
    stats: &mut RunStats,
    mut on_frame: impl FnMut(u32, &ParticleState) -> Result<(), Error>,
) -> Result<(), Error> {
    simulate_from(prep, solver, stats, None, |f, s, _| on_frame(f, s))
}

/// Where a resumed run starts: the state at the end of output frame `frame`, as a checkpoint
/// holds it (the stats of the frames before it are restored by the caller).
#[derive(Clone, Debug)]
pub struct ResumeFrom {
    /// The last frame the checkpoint completed.
    pub frame: u32,
    /// The state at its end, before anything that happens after a frame (gravity, releases).
    pub state: ParticleState,
}

/// `simulate`, optionally continuing from a checkpoint, with the stats so far passed to
/// `on_frame` (to write checkpoints). A resumed CPU run repeats the uninterrupted one bit for bit.
pub fn simulate_from(
    prep: &Prepared,
    solver: &mut dyn Solver,
    stats: &mut RunStats,
    resume: Option<ResumeFrom>,
    mut on_frame: impl FnMut(u32, &ParticleState, &RunStats) -> Result<(), Error>,
) -> Result<(), Error> {
    let seam_gaps = |state: &ParticleState| match &prep.garment {
        Some(g) => metrics::seam_gaps(&g.seam_pairs, g.stitches, &state.positions),
        None => Vec::new(),
    };
    // Positions at the end of the last frame, for the settle rule's speed over a frame.
    let mut previous;
    let first = match resume {
        None => {
            let initial = solver.state()?;
            stats.finite = metrics::first_non_finite(&initial).is_none();
            stats.seam_gaps = seam_gaps(&initial);
            on_frame(0, &initial, stats)?;
            previous = initial.positions;
            1
        }
        Some(r) => {
            solver.set_state(&r.state);
            previous = r.state.positions.clone();
            let params = phase_params(prep, r.frame, stats);
            if params != prep.params {
                solver.set_params(&params);
            }
            // What the interrupted run did after this frame, it does now.
            if after_frame(prep, solver, stats, r.frame, r.state)? {
                return Ok(());
            }
            r.frame + 1
        }
    };
    let mut params = phase_params(prep, first - 1, stats);
    for frame in first..=prep.frames {
        let steps = substep_params(prep, frame);
        let start = Instant::now();
        solver.advance(&steps)?;
        // The monitor stage checks the frame on the device before anything is read back.
        let health = solver.health()?;
        let substeps = match ((frame - 1) * prep.substeps + 1, frame * prep.substeps) {
            (a, b) if a == b => format!("substep {a}"),
            (a, b) => format!("substeps {a}–{b}"),
        };
        if let Some(i) = health.first_non_finite {
            stats.finite = false;
            return Err(Error::Unstable(format!(
                "frame {frame} ({substeps}): {} particle(s) non-finite, the first {}; the frame \
                 was not written. The substep ({:.3e} s) is too large for the fabric's \
                 stiffness: use substeps = \"auto\" or more substeps",
                health.non_finite,
                prep.describe_particle(i),
                prep.params.dt
            )));
        }
        let strain = health.max_strain;
        if strain > prep.max_strain {
            let advice = explosion::cause(prep).unwrap_or_else(|| {
                if prep.colors.is_some() {
                    "the implicit solve did not hold the cloth together: use more substeps or \
                     solver.iterations, or a longer seam_sewing_time_s"
                } else {
                    "the substep is too large for the fabric's stiffness: use substeps = \
                     \"auto\", more substeps, or integrator = \"implicit\""
                }
                .to_string()
            });
            return Err(Error::Unstable(format!(
                "frame {frame} ({substeps}): a spring at {} is stretched by {:.0}%, past \
                 solver.max_strain = {:.0}%: the frame exploded and was not written. At a \
                 substep of {:.3e} s, {advice}",
                prep.describe_particle(health.worst),
                100.0 * strain,
                100.0 * prep.max_strain,
                prep.params.dt
            )));
        }
        if health.max_speed > prep.max_speed {
            let advice = explosion::cause(prep).unwrap_or_else(|| {
                "the step is too large for the fabric's stiffness: use substeps = \"auto\", \
                 more substeps or integrator = \"implicit\""
                    .to_string()
            });
            return Err(Error::Unstable(format!(
                "frame {frame} ({substeps}): a particle moves at {:.3e} m/s, past \
                 solver.max_speed_m_s = {} m/s: the run diverged and the frame was not written. \
                 At a substep of {:.3e} s, {advice}",
                health.max_speed, prep.max_speed, prep.params.dt
            )));
        }
        let energy = health.kinetic_energy + health.gravity_energy + health.elastic_energy;
        let active = health.kinetic_energy + health.elastic_energy;
        if let (Some((before, before_active)), Some(from)) = (stats.energy, prep.energy_check_from)
        {
            // f32 partial sums of energies whose largest part is ~|gravitational|: a relative
            // 1e-5 of the energies involved, plus 1 nJ per particle, is rounding, not growth.
            let rounding = 1e-5 * (health.gravity_energy.abs() + active + before_active.abs())
                + 1e-9 * prep.model.len() as f64;
            let allowed = before + prep.max_energy_growth as f64 * before_active + rounding;
            if frame > from && energy > allowed {
                return Err(Error::Unstable(format!(
                    "frame {frame} ({substeps}): the cloth's energy rose from {before:.4e} J to \
                     {energy:.4e} J although nothing did work on it (allowed: \
                     solver.max_energy_growth = {:.0}% of its kinetic and elastic energy, \
                     {:.3e} J); the frame was not written. The fastest particle is at {:.2} m/s: \
                     the substep ({:.3e} s) is too large for the fabric's stiffness, use \
                     substeps = \"auto\", more substeps or integrator = \"implicit\"",
                    100.0 * prep.max_energy_growth,
                    prep.max_energy_growth as f64 * before_active,
                    health.max_speed,
                    prep.params.dt
                )));
            }
        }
        stats.energy = Some((energy, active));
        let state = solver.state()?;
        stats.wall_seconds += start.elapsed().as_secs_f64();
        let speed = frame_speed(prep, &previous, &state.positions);
        stats.frame_speed_m_s = Some(speed);
        previous.clone_from(&state.positions);
        if let Some(p) = solver.residual()? {
            let r = p.relative_residual;
            stats.max_residual = Some(stats.max_residual.map_or(r, |m| m.max(r)));
            stats.iterations_run += p.iterations;
            stats.newton_steps_run += p.newton_steps;
            stats.force_residual = Some(p.force_residual);
        }
        stats.max_speed = stats.max_speed.max(health.max_speed);
        stats.max_edge_strain = stats.max_edge_strain.max(strain);
        stats.last_edge_strain = strain;
        stats.last_edge_strain_p99 =
            metrics::edge_strain_quantile(&state.positions, &prep.model.springs, 0.99);
        stats.last_thread_strain = metrics::thread_strain(&state.positions, &prep.model.membranes);
        if prep.plan.contains(crate::plan::Pass::StrainLimit) {
            let cap = 0.999 * prep.params.strain_limit;
            let springs = &prep.model.springs;
            let held = metrics::edges_stretched_past(&state.positions, springs, cap);
            stats.strain_limit_clamped_edges = Some(held);
        }
        stats.kinetic_energy_j = health.kinetic_energy;
        stats.seam_gaps = seam_gaps(&state);
        let mut touching = vec![false; state.positions.len()];
        let mut deformed_depth: Option<f32> = None;
        for (b, c) in prep.model.colliders.iter().enumerate() {
            let t = frame as f32 * prep.frame_dt;
            let distances = if c.deformed.is_some() {
                let d = metrics::deformed_distances(c, t, &state.positions).map_err(|e| {
                    Error::Unstable(format!("the deformed body mesh at {t} s: {e}"))
                })?;
                let depth = metrics::max_penetration(&d);
                deformed_depth = Some(deformed_depth.map_or(depth, |m| m.max(depth)));
                d
            } else {
                metrics::body_distances(c, &prep.body_state(b, t), &state.positions)
            };
            stats.max_penetration_m = stats
                .max_penetration_m
                .max(metrics::max_penetration(&distances));
            let reach = prep.params.bodies[b].thickness + CONTACT_SLACK;
            metrics::mark_contacts(&distances, reach, &mut touching);
        }
        stats.body_contacts = touching.iter().filter(|&&t| t).count();
        if let Some(depth) = deformed_depth {
            stats.deformed_penetration_m.push((frame, depth));
        }
        let all_closed = stats.seam_gaps.iter().all(|&g| g < prep.seam_closed_gap);
        if !stats.seam_gaps.is_empty() && all_closed && stats.seams_closed_frame.is_none() {
            stats.seams_closed_frame = Some(frame);
        }
        // The frame counts as run once every figure of it is in (the summary's `frames` and
        // frames.csv's rows agree).
        stats.frames_run = frame;
        stats.record_frame(frame, prep.model.len(), speed, strain);
        on_frame(frame, &state, stats)?;
        let next = phase_params(prep, frame, stats);
        if next != params {
            solver.set_params(&next);
            params = next;
        }
        if after_frame(prep, solver, stats, frame, state)? {
            break;
        }
    }
    Ok(())
}

/// The run-constant parameters after frame `frame`: gravity once its start frame is done, and
/// the body's static friction once every seam is closed.
pub fn phase_params(prep: &Prepared, frame: u32, stats: &RunStats) -> SimParams {
    let mut params = prep.params;
    if prep.gravity.1 > 0 && frame >= prep.gravity.1 {
        params.gravity = prep.gravity.0.extend(0.0).to_array();
    }
    if let (Some(sewn), Some(_)) = (prep.friction_slip_speed_sewn, stats.seams_closed_frame) {
        params.bodies = sewn;
    }
    params
}

/// What happens once frame `frame` is done: attachments let go, and the settle rule. Returns
/// whether the run has settled.
fn after_frame(
    prep: &Prepared,
    solver: &mut dyn Solver,
    stats: &mut RunStats,
    frame: u32,
    state: ParticleState,
) -> Result<bool, Error> {
    if frame == prep.attach_frames && !prep.attached.is_empty() {
        release(prep, solver, state);
        stats.released_after_frame = Some(frame);
    }
    stats.settled = settle::check(prep, stats, frame);
    Ok(stats.settled.is_some())
}
