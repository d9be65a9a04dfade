//! `drapekit bench effects SCENE --out DIR`: the cost per substep of the scene's plan with each
//! optional effect (bending, wind, seams, body collision, self-collision, strain limit, and the
//! orthotropic membrane in place of edge springs) added and removed, on the CPU twin and the GPU
//! path, and the check that an absent effect costs nothing:
//! the plan without an effect should cost what the plan with it costs minus its own passes run
//! by themselves. Writes `effects.csv` and `effects.md`.

mod report;

use super::cpu_threads_description;
use crate::atomic_file::write_atomic;
use crate::body::motion::Motion;
use crate::body::Strategy;
use crate::cpu::CpuSolver;
use crate::error::Error;
use crate::gpu::{AdapterChoice, GpuContext, GpuSolver};
use crate::model::layout::SubstepParams;
use crate::plan::{Pass, PassPlan};
use crate::scene::{BodySettings, BodySource, Orthotropic, Scene, SelfCollision, Wind};
use crate::sim::{prepare, substep_params, Prepared};
use crate::solver::Solver;
use glam::Vec3;
use std::path::PathBuf;
use std::time::Instant;

/// The options of `drapekit bench effects`.
#[derive(Clone, Debug)]
pub struct EffectsOptions {
    /// The scene file.
    pub scene: PathBuf,
    /// Output folder.
    pub out: PathBuf,
    /// Fewer and shorter timed batches.
    pub quick: bool,
    /// The adapter of the GPU path.
    pub adapter: AdapterChoice,
}

/// An optional effect.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Effect {
    /// Dihedral bending.
    Bending,
    /// Wind drag.
    Wind,
    /// Seam forces (patterns only).
    Seams,
    /// Collision with the body.
    Body,
    /// Cloth-cloth repulsion.
    SelfCollision,
    /// Edge strain limiting.
    StrainLimit,
    /// The orthotropic membrane in place of the edge springs (without it: springs).
    Membrane,
}

impl Effect {
    /// Every effect, in table order.
    pub const ALL: [Effect; 7] = [
        Effect::Bending,
        Effect::Wind,
        Effect::Seams,
        Effect::Body,
        Effect::SelfCollision,
        Effect::StrainLimit,
        Effect::Membrane,
    ];

    /// The name in the tables.
    pub fn name(self) -> &'static str {
        match self {
            Effect::Bending => "bending",
            Effect::Wind => "wind",
            Effect::Seams => "seams",
            Effect::Body => "body collision",
            Effect::SelfCollision => "self-collision",
            Effect::StrainLimit => "strain limit",
            Effect::Membrane => "membrane",
        }
    }
}

/// The CSV's columns, in order (documented in docs/src/benchmarks/effects.md).
pub const CSV_COLUMNS: [&str; 22] = [
    "effect",
    "in_scene",
    "backend",
    "device",
    "passes_added",
    "particles",
    "substeps_per_batch",
    "us_per_substep_with",
    "us_per_substep_without",
    "cost_us",
    "cost_percent",
    "us_per_substep_own_passes",
    "us_per_substep_empty_plan",
    "residue_us",
    "residue_percent",
    "spread_percent",
    "stages_with",
    "stages_without",
    "resources_with",
    "resources_without",
    "resources_added",
    "note",
];

/// One effect on one backend. Times are µs per substep, the fastest of the timed batches.
#[derive(Clone, Debug)]
pub struct EffectRow {
    /// The effect.
    pub effect: Effect,
    /// Whether the scene has it.
    pub in_scene: bool,
    /// "cpu" or "gpu".
    pub backend: &'static str,
    /// The device.
    pub device: String,
    /// The passes the effect adds to the plan (empty: it lives inside another pass).
    pub passes: Vec<&'static str>,
    /// Particles.
    pub particles: usize,
    /// Substeps per timed batch.
    pub batch: usize,
    /// The plan with the effect.
    pub with: f64,
    /// The plan without it.
    pub without: f64,
    /// The effect's own passes run by themselves, less the empty plan's time (NaN when it has
    /// no pass of its own).
    pub own: f64,
    /// A plan with no pass at all: what a batch costs per substep before any work (submission
    /// and waiting on the GPU).
    pub idle: f64,
    /// The largest spread (slowest − fastest over fastest) of the timed batches, in %.
    pub spread_percent: f64,
    /// Pipelines (GPU) or passes (CPU) with and without the effect, including the monitor.
    pub stages: (usize, usize),
    /// GPU buffers and textures with and without the effect (CPU: 0).
    pub resources: (usize, usize),
    /// The labels of the GPU buffers and textures only the plan with the effect creates.
    pub resources_added: Vec<&'static str>,
    /// Why figures are missing, or what to know.
    pub note: String,
}

impl EffectRow {
    /// What the effect costs: with − without.
    pub fn cost(&self) -> f64 {
        self.with - self.without
    }

    /// What removing the effect leaves behind: without − (with − own passes). Zero when the
    /// plan without the effect costs exactly the plan with it less its passes.
    pub fn residue(&self) -> f64 {
        self.without - (self.with - self.own)
    }
}

/// The scene with `effect` switched on (`Some`) or off, prepared; `None` when it cannot be
/// added (seams without a pattern).
fn variant(
    scene: &Scene,
    base: &Prepared,
    effect: Effect,
    on: bool,
) -> Result<Option<Prepared>, Error> {
    let mut s = scene.clone();
    match (effect, on) {
        // The fixtures' soft-cloth value, N·m.
        (Effect::Bending, true) => {
            s.fabric.bending_stiffness = s.fabric.bending_stiffness.or(Some(2e-5))
        }
        (Effect::Bending, false) => s.fabric.bending_stiffness = None,
        (Effect::Wind, true) => {
            s.wind = s.wind.or(Some(Wind {
                velocity: Vec3::new(3.0, 0.0, 1.0),
                air_density: 1.225,
                drag_coefficient: 1.0,
                gust_amplitude: 0.0,
                gust_frequency: 0.0,
            }))
        }
        (Effect::Wind, false) => s.wind = None,
        (Effect::Seams, true) => {
            return Ok((!base.model.seams.is_empty()).then(|| base.clone()));
        }
        (Effect::Seams, false) => {
            // Seams come from the pattern's stitches: drop them from the model, rebuild the
            // multigrid (its matrix pattern and colours followed the seams' couplings, which
            // the solver's vertex colouring no longer does), and re-plan.
            let mut p = base.clone();
            p.model.seams.clear();
            p.model.multigrid = scene
                .build_multigrid(&p.model, p.garment.as_ref())
                .map(std::sync::Arc::new);
            p.plan = PassPlan::new(&p.model, scene.effects());
            return Ok(Some(p));
        }
        (Effect::Body, true) => {
            if s.bodies.is_empty() {
                s.bodies = vec![sphere_under(&base.model.positions)];
            }
        }
        (Effect::Body, false) => s.bodies.clear(),
        (Effect::SelfCollision, true) => {
            s.self_collision = s.self_collision.or(Some(SelfCollision {
                thickness: None,
                buckets: None,
                cpu_point_triangle: false,
            }))
        }
        (Effect::SelfCollision, false) => s.self_collision = None,
        // The scene format's default limit, 10% over rest length.
        (Effect::StrainLimit, true) => s.solver.strain_limit = s.solver.strain_limit.or(Some(0.1)),
        (Effect::StrainLimit, false) => s.solver.strain_limit = None,
        (Effect::Membrane, true) => {
            s.fabric.membrane = Some(membrane_of(&s.fabric));
            // The springs' step for both plans: both time the same substep.
            s.solver.substeps = Some(base.substeps);
        }
        (Effect::Membrane, false) => s.fabric.membrane = None,
    }
    Ok(Some(prepare(&s)?))
}

/// The scene's membrane, else its preset's warp, weft and shear, else an isotropic membrane of
/// the springs' stiffness (shear a tenth of it, as wovens shear far more easily than they
/// stretch). The cost per substep does not depend on the values.
fn membrane_of(fabric: &crate::scene::Fabric) -> Orthotropic {
    let k = fabric.stretch_stiffness;
    let from_preset = (fabric.preset.and_then(crate::scene::preset)).map(|p| Orthotropic {
        warp: p.warp_stiffness_n_m as f32,
        weft: p.weft_stiffness_n_m as f32,
        shear: p.shear_stiffness_n_m as f32,
        bending: None,
        large_strain: None,
    });
    (fabric.membrane.or(from_preset)).unwrap_or(Orthotropic {
        warp: k,
        weft: k,
        shear: 0.1 * k,
        bending: None,
        large_strain: None,
    })
}

/// A sphere just below the cloth, 0.3 of its width across, for scenes without a body.
fn sphere_under(positions: &[Vec3]) -> BodySettings {
    let (lo, hi) = positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let radius = (0.3 * (hi.x - lo.x).max(hi.z - lo.z)).clamp(0.05, 1.0);
    let centre = Vec3::new(
        0.5 * (lo.x + hi.x),
        lo.y - radius - 0.01,
        0.5 * (lo.z + hi.z),
    );
    let resolution = 0.01;
    BodySettings {
        source: BodySource::Sphere {
            center: centre,
            radius,
        },
        sdf_resolution: resolution,
        sdf_margin: (2.0f32 * 0.003).max(3.0 * resolution),
        sdf_max_bytes: 1 << 30,
        sdf_cache: true,
        thickness: 0.003,
        friction: 0.3,
        // The scene's default ([body] friction_slip_speed_m_s).
        friction_slip_speed: 0.01,
        normal_loss: 0.0,
        tangential_loss: 0.0,
        strategy: Strategy::Sdf,
        edge_contacts: false,
        motion: Motion { keys: Vec::new() },
        deform: None,
    }
}

/// `count` substeps from the start of the run, frame after frame.
fn steps(prep: &Prepared, count: usize) -> Vec<SubstepParams> {
    let mut steps = Vec::new();
    let mut frame = 1;
    while steps.len() < count {
        steps.extend(substep_params(prep, frame));
        frame += 1;
    }
    steps.truncate(count);
    steps
}

/// Times `solvers` in turns, one batch each per round for `repeats` rounds after one untimed
/// round, so that a change in the machine's load falls on every plan alike. Returns, per
/// solver, the fastest batch (the one least disturbed by other work) in s per substep and the
/// spread (slowest − fastest)/fastest.
fn time_in_turns(
    solvers: &mut [(Box<dyn Solver>, &[SubstepParams])],
    repeats: usize,
) -> Result<Vec<(f64, f64)>, Error> {
    let mut times = vec![Vec::new(); solvers.len()];
    for round in 0..=repeats.max(1) {
        for (k, (solver, steps)) in solvers.iter_mut().enumerate() {
            let start = Instant::now();
            solver.advance(steps)?;
            solver.finish()?;
            if round > 0 {
                times[k].push(start.elapsed().as_secs_f64() / steps.len() as f64);
            }
        }
    }
    Ok(times
        .iter()
        .map(|t| {
            let fastest = t.iter().copied().fold(f64::INFINITY, f64::min);
            let slowest = t.iter().copied().fold(0.0, f64::max);
            let spread = if fastest > 0.0 {
                (slowest - fastest) / fastest
            } else {
                0.0
            };
            (fastest, spread)
        })
        .collect())
}

/// A solver, its stage count and its GPU resources' labels.
type Built = (Box<dyn Solver>, usize, Vec<&'static str>);

/// A solver for `plan` on the backend, with its stage and resource counts.
fn build(
    ctx: Option<&GpuContext>,
    prep: &Prepared,
    plan: &PassPlan,
    batch: usize,
) -> Result<Built, Error> {
    Ok(match ctx {
        None => {
            let solver = CpuSolver::new(&prep.model, prep.params, plan);
            (Box::new(solver), plan.passes.len() + 1, Vec::new())
        }
        Some(ctx) => {
            let solver = GpuSolver::new(ctx, &prep.model, prep.params, plan, batch)?;
            let stages = solver.pipeline_passes().len();
            let labels = solver.resource_labels().to_vec();
            (Box::new(solver), stages, labels)
        }
    })
}

/// Runs the comparison and writes `effects.csv` and `effects.md`.
pub fn run_cli(opts: &EffectsOptions) -> Result<Vec<EffectRow>, Error> {
    let scene = Scene::load(&opts.scene)?;
    let base = prepare(&scene)?;
    let ctx = match GpuContext::new(&opts.adapter) {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            eprintln!("drapekit: {e}; benchmarking the CPU path only");
            None
        }
    };
    let cpu_device = format!("CPU twin ({})", cpu_threads_description());
    let gpu_device = ctx.as_ref().map(|c| c.report().describe());
    let (repeats, target_s) = if opts.quick { (3, 0.05) } else { (15, 0.1) };
    let mut rows = Vec::new();
    for effect in Effect::ALL {
        let in_scene = match effect {
            Effect::Bending => scene.fabric.bending_stiffness.is_some(),
            Effect::Wind => scene.wind.is_some(),
            Effect::Seams => !base.model.seams.is_empty(),
            Effect::Body => !scene.bodies.is_empty(),
            Effect::SelfCollision => scene.self_collision.is_some(),
            Effect::StrainLimit => scene.solver.strain_limit.is_some(),
            Effect::Membrane => scene.fabric.membrane.is_some(),
        };
        let with = variant(&scene, &base, effect, true)?;
        let without = variant(&scene, &base, effect, false)?.expect("an effect can be removed");
        for (backend, device, gpu) in std::iter::once(("cpu", cpu_device.clone(), None))
            .chain(gpu_device.clone().map(|d| ("gpu", d, ctx.as_ref())))
        {
            let row = measure(
                effect,
                in_scene,
                with.as_ref(),
                &without,
                backend,
                device,
                gpu,
                repeats,
                target_s,
            )?;
            println!(
                "{:<15} {:<3} with {:>10.1} µs/substep  without {:>10.1}  own passes {:>10.1}  residue {:>+8.1}  {}",
                row.effect.name(),
                row.backend,
                row.with,
                row.without,
                row.own,
                row.residue(),
                row.note
            );
            rows.push(row);
        }
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let (csv, md) = (opts.out.join("effects.csv"), opts.out.join("effects.md"));
    write_atomic(&csv, report::csv_text(&rows).as_bytes())?;
    write_atomic(
        &md,
        report::md_text(&rows, opts, &base, &cpu_device, gpu_device.as_deref()).as_bytes(),
    )?;
    println!("wrote {} and {}", csv.display(), md.display());
    Ok(rows)
}

/// Times one effect on one backend: the plan with it, without it, and its own passes alone.
#[allow(clippy::too_many_arguments)]
fn measure(
    effect: Effect,
    in_scene: bool,
    with: Option<&Prepared>,
    without: &Prepared,
    backend: &'static str,
    device: String,
    ctx: Option<&GpuContext>,
    repeats: usize,
    target_s: f64,
) -> Result<EffectRow, Error> {
    let mut row = EffectRow {
        effect,
        in_scene,
        backend,
        device,
        passes: Vec::new(),
        particles: without.model.len(),
        batch: 0,
        with: f64::NAN,
        without: f64::NAN,
        own: f64::NAN,
        idle: f64::NAN,
        spread_percent: f64::NAN,
        stages: (0, 0),
        resources: (0, 0),
        resources_added: Vec::new(),
        note: String::new(),
    };
    let Some(with) = with else {
        row.note = "cannot be added: the scene has no pattern to sew".into();
        return Ok(row);
    };
    let own: Vec<Pass> = (with.plan.passes.iter())
        .filter(|p| !without.plan.contains(**p))
        .copied()
        .collect();
    row.passes = own.iter().map(|p| p.name()).collect();
    // Batches of about `target_s`: five substeps of the plan with the effect set the size.
    let probe = steps(with, 5);
    let solver = build(ctx, with, &with.plan, probe.len())?.0;
    let t = time_in_turns(&mut [(solver, &probe[..])], 1)?[0].0;
    row.batch = ((target_s / t).round() as usize).clamp(5, 400);
    let batch = row.batch;
    let (with_steps, without_steps) = (steps(with, batch), steps(without, batch));
    let (w, ws, wr) = build(ctx, with, &with.plan, batch)?;
    let (wo, wos, wor) = build(ctx, without, &without.plan, batch)?;
    row.stages = (ws, wos);
    row.resources = (wr.len(), wor.len());
    // Labels repeat (one per stage that owns such an array): compare them as multisets.
    let mut left = wor.clone();
    for label in wr {
        match left.iter().position(|l| *l == label) {
            Some(k) => {
                left.swap_remove(k);
            }
            None => row.resources_added.push(label),
        }
    }
    // The plan without the effect steps its own scene; the others step the scene with it.
    let mut solvers = vec![(w, &with_steps[..]), (wo, &without_steps[..])];
    let mut notes = Vec::new();
    if effect == Effect::Membrane {
        notes.push("against edge springs: \"without\" runs the springs the membrane replaces");
        if !own.is_empty() {
            notes.push("the residue is the springs' own cost");
        }
    }
    if own.is_empty() {
        notes.push("no pass of its own: it is evaluated inside vbd_solve");
    } else {
        // The own passes' batch carries the same fixed cost as any batch: the empty plan
        // measures that, to take it off.
        let alone = build(
            ctx,
            with,
            &PassPlan {
                passes: own,
                hinges: None,
            },
            batch,
        )?
        .0;
        let empty = build(
            ctx,
            with,
            &PassPlan {
                passes: Vec::new(),
                hinges: None,
            },
            batch,
        )?
        .0;
        solvers.push((alone, &with_steps[..]));
        solvers.push((empty, &with_steps[..]));
    }
    row.note = notes.join("; ");
    let timed = time_in_turns(&mut solvers, repeats)?;
    let spread = timed.iter().map(|t| t.1).fold(0.0, f64::max);
    (row.with, row.without) = (1e6 * timed[0].0, 1e6 * timed[1].0);
    if let [_, _, alone, empty] = timed[..] {
        row.idle = 1e6 * empty.0;
        row.own = 1e6 * (alone.0 - empty.0);
    }
    row.spread_percent = 100.0 * spread;
    Ok(row)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_garment_without_its_seams_steps_by_implicit_euler() {
        // The seams-off variant of a sewn garment solved by Newton steps with multigrid: its
        // multigrid must follow the model without seams, or the smoothing's colours (the
        // solver's vertex colouring, which no longer separates the seams' pairs) meet matrix
        // blocks that still join them.
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fixtures/scenes/skirt_rotating_implicit.toml");
        let scene = Scene::load(&path).unwrap();
        let base = prepare(&scene).unwrap();
        assert!(!base.model.seams.is_empty() && base.model.multigrid.is_some());
        let p = variant(&scene, &base, Effect::Seams, false)
            .unwrap()
            .unwrap();
        assert!(p.model.seams.is_empty() && p.model.multigrid.is_some());
        let mut solver = CpuSolver::new(&p.model, p.params, &p.plan);
        solver.advance(&steps(&p, 1)).unwrap();
        solver.finish().unwrap();
    }
}
