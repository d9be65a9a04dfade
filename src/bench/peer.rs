//! `drapekit bench peer`: drapekit beside NVIDIA Warp's own cloth benchmark (Warp's classes,
//! from the installed wheel) and NVIDIA Newton's semi-implicit and VBD cloth solvers, on
//! Warp's first CUDA device when there is one and its CPU device otherwise, on the same cloth ([`super::warp_cloth`]), in one run.
//!
//! Every point times `frames` output frames from rest; a frame is the substeps of 1/60 s and
//! a read-back of the positions (Warp's benchmark returns them every frame). The median frame
//! is reported, kernel compilation excluded. Each point's final positions are compared with
//! Warp's at the same grid: for the symplectic rows that checks that the cloth and the
//! integrator are the same; for the implicit rows it is the implicit step's distance from the
//! small explicit step.

use super::python_peer::{ensure_env, run_driver, use_python, PeerRecord, PythonEnv};
use super::{cpu_threads_description, warp_cloth};
use crate::cpu::CpuSolver;
use crate::error::{Error, InputError};
use crate::gpu::{AdapterChoice, GpuContext, GpuSolver};
use crate::model::layout::{SubstepParams, INTEGRATOR_IMPLICIT, INTEGRATOR_SYMPLECTIC};
use crate::model::ClothModel;
use crate::solver::Solver;
use glam::Vec3;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Which systems a run times.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum System {
    /// drapekit's CPU and GPU paths.
    Drapekit,
    /// Warp's own benchmark (`WpIntegrator`) on Warp's device (CUDA or the CPU).
    Warp,
    /// Newton's `SolverSemiImplicit` and `SolverVBD` on Warp's device.
    Newton,
}

impl std::str::FromStr for System {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "drapekit" => Ok(System::Drapekit),
            "warp" => Ok(System::Warp),
            "newton" => Ok(System::Newton),
            _ => Err(format!(
                "unknown system {s:?}; use drapekit, warp or newton"
            )),
        }
    }
}

/// What `drapekit bench peer` runs.
#[derive(Clone, Debug)]
pub struct PeerOptions {
    /// Grid sides of the Warp comparison.
    pub sizes: Vec<u32>,
    /// Grid sides of the Newton comparison (both integrators).
    pub newton_sizes: Vec<u32>,
    /// Timed frames per point.
    pub frames: u32,
    /// Systems to time.
    pub systems: Vec<System>,
    /// Substeps per frame of the implicit points (Newton's VBD and drapekit's implicit Euler).
    pub implicit_substeps: u32,
    /// Sweeps per implicit substep.
    pub iterations: u32,
    /// Output folder.
    pub out: PathBuf,
    /// GPU adapter for drapekit's GPU path.
    pub adapter: AdapterChoice,
    /// Python to create the environment with.
    pub python: String,
    /// The environment's folder.
    pub venv: PathBuf,
    /// Run the driver with `python` itself (its own warp and newton, any version) instead of
    /// the pinned environment; `venv` then only holds the driver.
    pub no_venv: bool,
    /// Warp's device for the peers: "auto" (CUDA when Warp finds it, else the CPU), "cpu" or
    /// "cuda".
    pub peer_device: String,
    /// The command as typed, for the report.
    pub command: String,
}

/// One measured point.
#[derive(Clone, Debug)]
pub struct PeerRow {
    /// "drapekit", "warp" or "newton".
    pub system: String,
    /// "cpu" or "gpu".
    pub backend: &'static str,
    /// "symplectic" or "implicit".
    pub integrator: &'static str,
    /// Grid side.
    pub grid: u32,
    /// Particles.
    pub particles: usize,
    /// Springs (each evaluated once by the peers, once from each end by drapekit).
    pub springs: usize,
    /// Substeps per 1/60 s frame.
    pub substeps_per_frame: u32,
    /// Implicit sweeps per substep (0 for symplectic).
    pub iterations: u32,
    /// Timed frames.
    pub frames: u32,
    /// Median seconds per frame.
    pub median_frame_seconds: f64,
    /// Largest distance between this point's final positions and Warp's, in m.
    pub max_distance_to_warp_m: Option<f64>,
    /// The device and solver.
    pub device: String,
}

impl PeerRow {
    /// Particles × substeps per second at the median frame.
    pub fn particle_substeps_per_s(&self) -> f64 {
        self.particles as f64 * self.substeps_per_frame as f64 / self.median_frame_seconds
    }

    /// Wall seconds per simulated second at the median frame.
    pub fn wall_s_per_simulated_s(&self) -> f64 {
        self.median_frame_seconds * warp_cloth::FPS
    }
}

/// Everything one run measured, for the tables.
#[derive(Clone, Debug, Default)]
pub struct PeerReport {
    /// The points, in the order they ran.
    pub rows: Vec<PeerRow>,
    /// Peers that could not run, with their exact error.
    pub failures: Vec<String>,
    /// The Python environment's versions, if one was used.
    pub versions: Option<super::python_peer::Versions>,
    /// drapekit's CPU and thread count.
    pub machine: String,
    /// drapekit's GPU adapter, if any.
    pub adapter: Option<crate::solver::AdapterReport>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Times `frames` frames of `substeps` substeps on `solver` from its current (rest) state,
/// reading the positions back after each frame. Returns the median frame and the final
/// positions.
fn time_frames(
    solver: &mut dyn Solver,
    frames: u32,
    substeps: u32,
) -> Result<(f64, Vec<Vec3>), Error> {
    let mut times = Vec::with_capacity(frames as usize);
    let mut last = Vec::new();
    for f in 0..frames {
        let steps = frame_steps(f, substeps);
        let start = Instant::now();
        solver.advance(&steps)?;
        // The positions alone, as Warp's benchmark reads them back.
        let positions = solver.positions()?;
        times.push(start.elapsed().as_secs_f64());
        last = positions.iter().map(|p| p.truncate()).collect();
    }
    Ok((median(times), last))
}

/// Frame `f`'s substeps (from 0) of Warp's benchmark step.
fn frame_steps(f: u32, substeps: u32) -> Vec<SubstepParams> {
    let dt = warp_cloth::substep_dt(substeps);
    (0..substeps)
        .map(|s| SubstepParams {
            time: (f * substeps + s) as f32 * dt,
            substep: s,
            ..Default::default()
        })
        .collect()
}

/// Reads a peer's final positions (little-endian f32 xyz).
fn read_state(path: &Path) -> Result<Vec<Vec3>, Error> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    Ok(bytes
        .chunks_exact(12)
        .map(|c| {
            let f = |k: usize| f32::from_le_bytes([c[k], c[k + 1], c[k + 2], c[k + 3]]);
            Vec3::new(f(0), f(4), f(8))
        })
        .collect())
}

/// Largest distance between two position lists (NaN if any is non-finite or they differ in
/// length).
fn max_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    if a.len() != b.len() {
        return f64::NAN;
    }
    a.iter().zip(b).fold(0.0f64, |m, (p, q)| {
        let d = p.distance(*q) as f64;
        if d.is_nan() || m.is_nan() {
            f64::NAN
        } else {
            m.max(d)
        }
    })
}

/// Refuses a peer whose cloth is not drapekit's copy: the installed benchmark changed.
fn check_same_cloth(r: &PeerRecord, model: &ClothModel, env: &PythonEnv) -> Result<(), Error> {
    let ours: f64 = model.springs.iter().map(|s| s.rest_length as f64).sum();
    let mut differences = Vec::new();
    let mut differ = |what: &str, theirs: String, ours: String| {
        if theirs != ours {
            differences.push(format!("{what}: {theirs} (drapekit: {ours})"));
        }
    };
    differ(
        "particles",
        r.particles.to_string(),
        model.len().to_string(),
    );
    differ(
        "springs",
        r.springs.to_string(),
        model.springs.len().to_string(),
    );
    differ("pinned", r.pinned.to_string(), "2".into());
    differ(
        "mass",
        (r.mass as f32).to_string(),
        warp_cloth::MASS.to_string(),
    );
    differ(
        "spacing",
        r.spacing.to_string(),
        warp_cloth::SPACING.to_string(),
    );
    differ(
        "stiffness",
        format!("{:?}", r.stiffness),
        format!("{:?}", [warp_cloth::STIFFNESS as f64]),
    );
    differ(
        "damping",
        format!("{:?}", r.damping),
        format!("{:?}", [warp_cloth::DAMPING as f64]),
    );
    differ("fps", r.fps.to_string(), warp_cloth::FPS.to_string());
    differ(
        "substeps",
        r.benchmark_substeps.to_string(),
        warp_cloth::SUBSTEPS.to_string(),
    );
    // Both sum the same f32 rest lengths in f64, in different orders; recursive summation of
    // N terms errs by at most (N − 1)·ε·Σ|x| (Higham, Accuracy and Stability of Numerical
    // Algorithms, 2nd ed., §4.2), which bounds the difference.
    if (r.rest_length_sum - ours).abs() > r.springs as f64 * f64::EPSILON * ours {
        differences.push(format!(
            "sum of rest lengths: {} m (drapekit: {ours} m)",
            r.rest_length_sum
        ));
    }
    if differences.is_empty() {
        return Ok(());
    }
    Err(Error::Input(InputError::new(
        &env.venv,
        "bench peer",
        format!(
            "{}'s benchmark cloth at {}² is not drapekit's copy: {}",
            r.system,
            r.grid,
            differences.join("; ")
        ),
        format!(
            "the installed warp-lang {} differs from the pinned {}: remove {} to reinstall it",
            env.versions.warp,
            super::python_peer::PINNED[0].1,
            env.venv.display()
        ),
    )))
}

fn peer_row(r: &PeerRecord, warp_state: Option<&[Vec3]>) -> Result<PeerRow, Error> {
    let state = read_state(&r.state)?;
    Ok(PeerRow {
        system: r.system.clone(),
        backend: if r.on_cuda() { "gpu" } else { "cpu" },
        integrator: if r.integrator == "implicit" {
            "implicit"
        } else {
            "symplectic"
        },
        grid: r.grid,
        particles: r.particles,
        springs: r.springs,
        substeps_per_frame: r.substeps_per_frame(),
        iterations: r.iterations,
        frames: r.frames,
        median_frame_seconds: r.median_frame_seconds,
        max_distance_to_warp_m: warp_state.map(|w| max_distance(&state, w)),
        device: format!(
            "{} on {}",
            r.solver.as_deref().unwrap_or("WpIntegrator"),
            r.device_description()
        ),
    })
}

/// Times drapekit on the benchmark cloth at `dim` under `integrator`, on the CPU and (with a
/// context) the GPU.
#[allow(clippy::too_many_arguments)]
fn drapekit_rows(
    dim: u32,
    integrator: u32,
    substeps: u32,
    iterations: u32,
    frames: u32,
    ctx: Option<&GpuContext>,
    warp_state: Option<&[Vec3]>,
    machine: &str,
) -> Result<Vec<PeerRow>, Error> {
    let model = warp_cloth::model(dim);
    let params = warp_cloth::params(&model, integrator, substeps, iterations);
    let plan = warp_cloth::plan(&model, integrator);
    let implicit = integrator == INTEGRATOR_IMPLICIT;
    let mut backends: Vec<(&'static str, String, Box<dyn Solver>)> = vec![(
        "cpu",
        format!("CPU path ({machine})"),
        Box::new(CpuSolver::new(&model, params, &plan)),
    )];
    if let Some(ctx) = ctx {
        let a = ctx.report();
        let gpu = GpuSolver::new(ctx, &model, params, &plan, substeps as usize)?;
        backends.push((
            "gpu",
            format!("{} ({}, {})", a.name, a.backend, a.device_type),
            Box::new(gpu),
        ));
    }
    let mut rows = Vec::new();
    for (backend, device, mut solver) in backends {
        // Warm caches and clocks (an idle GPU runs at a fraction of its clock), then start
        // again from rest.
        let rest = solver.state()?;
        super::grid::warm_up(solver.as_mut(), &frame_steps(0, substeps))?;
        solver.set_state(&rest);
        let (median, state) = time_frames(solver.as_mut(), frames, substeps)?;
        rows.push(PeerRow {
            system: "drapekit".into(),
            backend,
            integrator: if implicit { "implicit" } else { "symplectic" },
            grid: dim,
            particles: model.len(),
            springs: model.springs.len(),
            substeps_per_frame: substeps,
            iterations: if implicit { iterations } else { 0 },
            frames,
            median_frame_seconds: median,
            max_distance_to_warp_m: warp_state.map(|w| max_distance(&state, w)),
            device,
        });
    }
    Ok(rows)
}

fn print_row(r: &PeerRow) {
    println!(
        "{:>4}² {:<8} {:<3} {:<10} {:>3} substeps{:<8} {:>10.3e} particle-substeps/s  {:>8.3} s per simulated s{}",
        r.grid,
        r.system,
        r.backend,
        r.integrator,
        r.substeps_per_frame,
        if r.iterations > 0 {
            format!(" ×{} it", r.iterations)
        } else {
            String::new()
        },
        r.particle_substeps_per_s(),
        r.wall_s_per_simulated_s(),
        r.max_distance_to_warp_m
            .map(|d| format!("  {d:.2e} m from Warp's state"))
            .unwrap_or_default()
    );
}

/// A peer's failure is reported, not fatal: the rest of the run goes on.
fn peer_or_note(
    result: Result<Vec<PeerRecord>, Error>,
    what: &str,
    report: &mut PeerReport,
) -> Vec<PeerRecord> {
    result.unwrap_or_else(|e| {
        eprintln!("drapekit: {what} did not run: {e}");
        report.failures.push(format!("{what}: {e}"));
        Vec::new()
    })
}

/// Runs the comparison and writes `peer.csv` and `peer.md` into `opts.out`.
pub fn run_cli(opts: &PeerOptions) -> Result<PeerReport, Error> {
    let wants = |s: System| opts.systems.contains(&s);
    let env = if wants(System::Warp) || wants(System::Newton) {
        Some(if opts.no_venv {
            use_python(&opts.python, &opts.venv)?
        } else {
            ensure_env(&opts.python, &opts.venv)?
        })
    } else {
        None
    };
    let ctx = if wants(System::Drapekit) {
        match GpuContext::new(&opts.adapter) {
            Ok(ctx) => Some(ctx),
            Err(e) => {
                eprintln!("drapekit: {e}; timing drapekit's CPU path only");
                None
            }
        }
    } else {
        None
    };
    let mut report = PeerReport {
        versions: env.as_ref().map(|e| e.versions.clone()),
        machine: cpu_threads_description(),
        adapter: ctx.as_ref().map(|c| c.report()),
        ..Default::default()
    };
    let states = std::env::temp_dir().join(format!("drapekit-peer-{}", std::process::id()));
    std::fs::create_dir_all(&states).map_err(|e| Error::io(&states, e))?;
    let result = measure(opts, env.as_ref(), ctx.as_ref(), &states, &mut report);
    let _ = std::fs::remove_dir_all(&states);
    result?;
    super::peer_report::write(opts, &report)?;
    Ok(report)
}

/// A peer driver's command line: its own arguments, then the frames, device and state folder
/// that every driver takes.
fn driver_args(own: &[&str], opts: &PeerOptions, states: &Path) -> Vec<String> {
    let mut args: Vec<String> = own.iter().map(|s| s.to_string()).collect();
    args.extend([
        "--frames".into(),
        opts.frames.to_string(),
        "--device".into(),
        opts.peer_device.clone(),
        "--state-dir".into(),
        states.display().to_string(),
    ]);
    args
}

fn measure(
    opts: &PeerOptions,
    env: Option<&PythonEnv>,
    ctx: Option<&GpuContext>,
    states: &Path,
    report: &mut PeerReport,
) -> Result<(), Error> {
    let wants = |s: System| opts.systems.contains(&s);
    let mut warp_states: Vec<(u32, Vec<Vec3>)> = Vec::new();
    let mut all_sizes: Vec<u32> = opts.sizes.clone();
    all_sizes.extend(opts.newton_sizes.iter().filter(|n| !opts.sizes.contains(n)));
    // Size by size, each system in turn, so that a change of load hits all of them alike.
    for &dim in &all_sizes {
        let model = warp_cloth::model(dim);
        if let (Some(env), true) = (env, wants(System::Warp)) {
            let args = driver_args(&["warp", "--sizes", &dim.to_string()], opts, states);
            let records = peer_or_note(run_driver(env, &args), "warp", report);
            for r in &records {
                check_same_cloth(r, &model, env)?;
                let row = peer_row(r, None)?;
                warp_states.push((dim, read_state(&r.state)?));
                print_row(&row);
                report.rows.push(row);
            }
        }
        let warp_state = warp_states
            .iter()
            .find(|(d, _)| *d == dim)
            .map(|(_, s)| s.clone());
        if wants(System::Drapekit) {
            for row in drapekit_rows(
                dim,
                INTEGRATOR_SYMPLECTIC,
                warp_cloth::SUBSTEPS,
                0,
                opts.frames,
                ctx,
                warp_state.as_deref(),
                &report.machine,
            )? {
                print_row(&row);
                report.rows.push(row);
            }
        }
        if !opts.newton_sizes.contains(&dim) {
            continue;
        }
        for (solver, substeps) in [
            ("semi_implicit", warp_cloth::SUBSTEPS),
            ("vbd", opts.implicit_substeps),
        ] {
            let Some(env) = env.filter(|_| wants(System::Newton)) else {
                continue;
            };
            let own = [
                "newton",
                "--solver",
                solver,
                "--sizes",
                &dim.to_string(),
                "--substeps",
                &substeps.to_string(),
                "--iterations",
                &opts.iterations.to_string(),
            ];
            let args = driver_args(&own, opts, states);
            let what = format!("newton --solver {solver} at {dim}²");
            for r in peer_or_note(run_driver(env, &args), &what, report) {
                check_same_cloth(&r, &model, env)?;
                let row = peer_row(&r, warp_state.as_deref())?;
                print_row(&row);
                report.rows.push(row);
            }
        }
        if wants(System::Drapekit) {
            for row in drapekit_rows(
                dim,
                INTEGRATOR_IMPLICIT,
                opts.implicit_substeps,
                opts.iterations,
                opts.frames,
                ctx,
                warp_state.as_deref(),
                &report.machine,
            )? {
                print_row(&row);
                report.rows.push(row);
            }
        }
    }
    for &dim in &opts.sizes {
        let find = |system: &str, backend: &str| {
            report.rows.iter().find(|r| {
                r.grid == dim
                    && r.system == system
                    && r.backend == backend
                    && r.integrator == "symplectic"
            })
        };
        if let Some(w) = find("warp", "cpu").or_else(|| find("warp", "gpu")) {
            let warp_on = if w.backend == "gpu" { "CUDA" } else { "CPU" };
            for backend in ["cpu", "gpu"] {
                if let Some(d) = find("drapekit", backend) {
                    println!(
                        "{dim:>4}²: drapekit {backend} / Warp {warp_on} = {:.2}×",
                        d.particle_substeps_per_s() / w.particle_substeps_per_s()
                    );
                }
            }
        }
    }
    Ok(())
}
