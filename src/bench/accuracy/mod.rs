//! `drapekit bench accuracy SCENE --out DIR`: what accuracy costs in time. One knob at a time is
//! moved along a ladder from the scene's own settings (integrator and step, particle distance,
//! SDF resolution, body simplification), then every knob at its finest rung (the reference),
//! at its most accurate rung (combined best) and at its cheapest (combined cheapest). Each point
//! runs the same frames with the settle rule off and is compared with the reference at the last
//! frame. Writes `accuracy.csv`, `accuracy.md` and `accuracy.svg`.

pub mod compare;
pub mod ladder;
pub mod point;
pub mod report;

use crate::error::Error;
use crate::gpu::AdapterChoice;
use crate::run::BackendChoice;
use crate::scene::Scene;
use ladder::{Knob, Point, Setting};
use point::{Backend, Outcome, Status, Sweep};
use std::path::PathBuf;

/// The options of `drapekit bench accuracy`.
#[derive(Clone, Debug)]
pub struct AccuracyOptions {
    /// The scene file.
    pub scene: PathBuf,
    /// Output folder.
    pub out: PathBuf,
    /// Shorter ladders and (unless `frames` is given) at most `QUICK_FRAMES` frames.
    pub quick: bool,
    /// Output frames per point (default: the scene's).
    pub frames: Option<u32>,
    /// Which path runs the points.
    pub backend: BackendChoice,
    /// The adapter, for the GPU path.
    pub adapter: AdapterChoice,
    /// The most substeps per frame a point may take (default: the scene's
    /// `max_substeps_per_frame`, and at most `QUICK_MAX_SUBSTEPS` with `quick`); a point whose
    /// stability bound asks for more is reported as failed, with the count it needs.
    pub max_substeps: Option<u32>,
}

/// How far the nudged scene's particles start from the scene's, in m along each axis.
pub const NUDGE_M: f32 = 1e-6;

/// Frames per point of a `--quick` sweep when `--frames` is not given.
pub const QUICK_FRAMES: u32 = 12;

/// The most substeps per frame a `--quick` point may take when `--max-substeps` is not given.
pub const QUICK_MAX_SUBSTEPS: u32 = 2000;

/// One row of the table: a point, what it measured, and how it compares with the reference.
#[derive(Clone, Debug)]
pub struct Row {
    /// The point.
    pub point: Point,
    /// What it measured.
    pub outcome: Outcome,
    /// Position error against the reference (NaN where not comparable).
    pub error_m: compare::PositionError,
    /// Why there is no position error, where there is none.
    pub error_note: Option<String>,
    /// See `energy_drift`; NaN where it does not apply.
    pub energy_drift: f64,
    /// Whether no other row is both as fast and as accurate (and better in one).
    pub pareto: bool,
}

/// Runs the sweep and writes its files; returns the rows.
pub fn run_cli(opts: &AccuracyOptions) -> Result<Vec<Row>, Error> {
    let scene = Scene::load(&opts.scene)?;
    if scene.bodies.len() > 1 {
        // Its SDF and simplification knobs, and its penetration, are the one body's.
        return Err(Error::Input(crate::error::InputError::new(
            &opts.scene,
            "body[1]",
            format!(
                "the scene has {} bodies, and the accuracy sweep varies and measures one",
                scene.bodies.len()
            ),
            "use a scene with a single [body] table, e.g. fixtures/scenes/drape_sphere.toml",
        )));
    }
    let frames = opts.frames.unwrap_or(if opts.quick {
        scene.solver.frames.min(QUICK_FRAMES)
    } else {
        scene.solver.frames
    });
    let max_substeps = opts.max_substeps.unwrap_or(if opts.quick {
        scene.solver.max_substeps_per_frame.min(QUICK_MAX_SUBSTEPS)
    } else {
        scene.solver.max_substeps_per_frame
    });
    let (backend, device) = choose_backend(opts.backend, &opts.adapter)?;
    let (ladder, reference) = ladder::ladders(&scene, opts.quick);
    let base = Point {
        label: "scene".into(),
        knob: Knob::Scene,
        setting: Setting::of_scene(&scene),
    };
    let total = ladder.len() + 3;
    println!(
        "accuracy sweep of {}: {total} points and two combined ones, {frames} frames each, on {device}",
        opts.scene.display()
    );
    let mut sweep = Sweep::new(
        scene.clone(),
        frames,
        max_substeps,
        backend,
        opts.out.join("bodies"),
    )?;
    let mut rows: Vec<Row> = Vec::new();
    let nudged = Point {
        label: format!("scene nudged {:.0} µm", NUDGE_M * 1e6),
        knob: Knob::Nudged,
        setting: base.setting,
    };
    for (k, p) in std::iter::once(base)
        .chain([nudged])
        .chain(ladder)
        .chain([reference])
        .enumerate()
    {
        let outcome = match p.knob {
            Knob::Nudged => sweep.run(&p.setting, NUDGE_M),
            _ => run_once(&mut sweep, &rows, &p.setting),
        };
        print_point(k + 1, total, &p, &outcome);
        rows.push(Row::new(p, outcome));
    }
    let floor = noise_floor(&rows);
    if let Some(f) = floor {
        println!(
            "noise floor: a {:.0} µm nudge at the start moves the scene's last frame by {:.2} mm RMS ({:.2} mm at most, mean shift {:.2} mm)",
            NUDGE_M * 1e6,
            f.rms * 1e3,
            f.max * 1e3,
            f.shift * 1e3
        );
    }
    compare_all(&mut rows);
    for (knob, label) in [
        (Knob::Best, "combined best"),
        (Knob::Cheapest, "combined cheapest"),
    ] {
        let setting = combine(&rows, knob);
        let p = Point {
            label: label.into(),
            knob,
            setting,
        };
        let outcome = run_once(&mut sweep, &rows, &setting);
        print_point(rows.len() + 1, total + 2, &p, &outcome);
        rows.push(Row::new(p, outcome));
    }
    compare_all(&mut rows);
    mark_pareto(&mut rows);
    let env = report::Environment {
        floor,
        device,
        machine: super::cpu_threads_description(),
        frames,
        opts: opts.clone(),
        scene,
    };
    report::write(&rows, &env)?;
    Ok(rows)
}

/// The backend the points run on, and its description.
fn choose_backend(
    choice: BackendChoice,
    adapter: &AdapterChoice,
) -> Result<(Backend, String), Error> {
    let (gpu, device) = super::choose_device(choice, adapter)?;
    let backend = match gpu {
        Some(ctx) => Backend::Gpu(Box::new(ctx)),
        None => Backend::Cpu,
    };
    Ok((backend, device))
}

/// Runs `setting`, or reuses the outcome of a row that ran the same settings.
fn run_once(sweep: &mut Sweep, rows: &[Row], setting: &Setting) -> Outcome {
    match (rows.iter()).find(|r| r.point.setting == *setting && r.point.knob != Knob::Nudged) {
        Some(r) => r.outcome.clone(),
        None => sweep.run(setting, 0.0),
    }
}

/// How far the nudged scene's last frame lies from the scene's.
fn noise_floor(rows: &[Row]) -> Option<compare::PositionError> {
    let snapshot = |knob| {
        (rows.iter())
            .find(|r| r.point.knob == knob)
            .and_then(|r| r.outcome.snapshot.as_ref())
    };
    compare::position_error(snapshot(Knob::Nudged)?, snapshot(Knob::Scene)?).ok()
}

fn print_point(k: usize, total: usize, p: &Point, o: &Outcome) {
    println!(
        "[{k:>2}/{total}] {:<28} {:<8} {:>6} substeps/frame {:>7} particles {:>9.3} s per simulated s{}",
        p.label,
        o.status.name(),
        o.substeps,
        o.particles,
        o.wall_per_simulated_s(),
        o.error
            .as_deref()
            .map_or(String::new(), |e| format!("\n        {e}"))
    );
}

impl Row {
    fn new(point: Point, outcome: Outcome) -> Row {
        Row {
            point,
            outcome,
            error_m: compare::PositionError::NAN,
            error_note: None,
            energy_drift: f64::NAN,
            pareto: false,
        }
    }
}

/// Position errors and energy drift of every row against the reference row.
fn compare_all(rows: &mut [Row]) {
    let reference = rows
        .iter()
        .find(|r| r.point.knob == Knob::Reference)
        .map(|r| r.outcome.clone());
    for r in rows.iter_mut() {
        let Some(reference) = &reference else { break };
        match (&r.outcome.snapshot, &reference.snapshot) {
            (Some(s), Some(rs)) => match compare::position_error(s, rs) {
                Ok(e) => r.error_m = e,
                Err(e) => r.error_note = Some(e),
            },
            (Some(_), None) => {
                r.error_note = Some(format!(
                    "the reference {}: no position error",
                    reference.status.name()
                ))
            }
            (None, _) => {}
        }
        r.energy_drift = energy_drift(&r.outcome, reference);
    }
}

/// The mechanical energy a point gains (positive) or loses (negative) between the frame from
/// which nothing does work on the cloth and the last frame, minus what the reference gains or
/// loses, over the reference's largest kinetic plus elastic energy in that time. Zero: the
/// discretisation dissipates exactly as the reference does. NaN where the monitor's energy is
/// incomplete (bending, seams) or something does work (wind, a moving body, self-collision).
pub fn energy_drift(point: &Outcome, reference: &Outcome) -> f64 {
    match (point.energy, reference.energy) {
        (Some((from, last, _)), Some((rfrom, rlast, active))) if active > 0.0 => {
            ((last - from) - (rlast - rfrom)) / active
        }
        _ => f64::NAN,
    }
}

/// Every knob at the rung of its ladder (the scene's rung included) with the smallest RMS
/// error (`Knob::Best`) or the smallest wall plus bake time (`Knob::Cheapest`), among the rungs
/// that ran to the end.
fn combine(rows: &[Row], knob: Knob) -> Setting {
    let scene = rows[0].point.setting;
    let choose = |k: Knob| -> Setting {
        let candidates = rows
            .iter()
            .filter(|r| r.point.knob == k || r.point.knob == Knob::Scene)
            .filter(|r| r.outcome.status == Status::Ok);
        let key = |r: &Row| match knob {
            Knob::Best => r.error_m.rms,
            _ => r.outcome.wall_s + r.outcome.bake_s.max(0.0),
        };
        candidates
            .filter(|r| key(r).is_finite())
            .min_by(|a, b| key(a).total_cmp(&key(b)))
            .map_or(scene, |r| r.point.setting)
    };
    let step = choose(Knob::Step);
    Setting {
        integrator: step.integrator,
        step: step.step,
        iterations: step.iterations,
        spacing: choose(Knob::Spacing).spacing,
        sdf: choose(Knob::Sdf).sdf,
        body: choose(Knob::Body).body,
    }
}

/// Marks the rows that no other row dominates in (wall time per simulated second, RMS error).
fn mark_pareto(rows: &mut [Row]) {
    let figures: Vec<Option<(f64, f64)>> = rows
        .iter()
        .map(|r| {
            let f = (r.outcome.wall_per_simulated_s(), r.error_m.rms);
            (r.outcome.status == Status::Ok && f.0.is_finite() && f.1.is_finite()).then_some(f)
        })
        .collect();
    for (i, r) in rows.iter_mut().enumerate() {
        let Some((t, e)) = figures[i] else { continue };
        r.pareto = !figures
            .iter()
            .flatten()
            .any(|&(t2, e2)| t2 <= t && e2 <= e && (t2 < t || e2 < e));
    }
}
