//! Checks against closed-form answers: discrete free fall, a hanging chain's static
//! extensions, a loaded column's buckled compressions, and the energy behaviour of both Euler integrators on an undamped spring.

mod common;

use common::{fixture, gpu};
use drapekit::cpu::CpuSolver;
use drapekit::gpu::GpuSolver;
use drapekit::model::layout::{
    SimParams, SubstepParams, INTEGRATOR_EXPLICIT, INTEGRATOR_IMPLICIT, INTEGRATOR_SYMPLECTIC,
};
use drapekit::model::{ClothModel, Spring};
use drapekit::plan::{Effects, Pass, PassPlan};
use drapekit::scene::Scene;
use drapekit::sim::{prepare, simulate, RunStats};
use drapekit::solver::Solver;
use glam::Vec3;

fn free_fall(solver_for: impl Fn(&drapekit::sim::Prepared) -> Box<dyn Solver>, integrator: u32) {
    let mut scene = Scene::load(&fixture("scenes/free_fall.toml")).unwrap();
    scene.solver.integrator = integrator;
    let prep = prepare(&scene).unwrap();
    let mut solver = solver_for(&prep);
    let (dt, g) = (prep.params.dt as f64, -9.81f64);
    let y0 = prep.model.positions[0].y as f64;
    let steps_per_frame = prep.substeps as f64;
    let mut worst = 0.0f64;
    let mut bound = 0.0f64;
    simulate(
        &prep,
        solver.as_mut(),
        &mut RunStats::default(),
        |frame, state| {
            let n = frame as f64 * steps_per_frame;
            // Symplectic: v_n = n·g·dt, y_n = y0 + g·dt²·n(n+1)/2. Explicit: y_n = y0 + g·dt²·n(n−1)/2.
            let k = if integrator == INTEGRATOR_SYMPLECTIC {
                n + 1.0
            } else {
                n - 1.0
            };
            let y_exact = y0 + g * dt * dt * n * k.max(0.0) / 2.0;
            let v_exact = n * g * dt;
            // f32 rounding: each position update rounds by ≤ ½ulp(|y| ≤ 4 m) = 2.4e-7 m, and each
            // velocity update by ≤ ½ulp(|v| ≤ 8 m/s) = 4.8e-7 m/s, which later position updates
            // integrate: n·2.4e-7 + dt·n²/2·4.8e-7 bounds the accumulated error.
            let tol = n * 2.4e-7 + dt * n * n / 2.0 * 4.8e-7 + 1e-9;
            bound = tol;
            for (i, (p, v)) in state.positions.iter().zip(&state.velocities).enumerate() {
                let dy = (p.y as f64 - y_exact).abs();
                let dv = (v.y as f64 - v_exact).abs();
                assert!(dy <= tol, "frame {frame}: y off by {dy} m (tol {tol})");
                assert!(dv <= n * 4.8e-7 + 1e-9, "frame {frame}: v off by {dv} m/s");
                // Rigid translation: springs stay exactly at rest length, so x and z never change.
                let p0 = prep.model.positions[i];
                assert_eq!(
                    (p.x, p.z),
                    (p0.x, p0.z),
                    "frame {frame}: particle {i} moved sideways"
                );
                worst = worst.max(dy);
            }
            Ok(())
        },
    )
    .unwrap();
    eprintln!("free fall (integrator {integrator}): worst |Δy| {worst:.3e} m, bound {bound:.3e} m");
}

#[test]
fn free_fall_matches_discrete_euler_cpu() {
    for integrator in [INTEGRATOR_SYMPLECTIC, INTEGRATOR_EXPLICIT] {
        free_fall(
            |p| Box::new(CpuSolver::new(&p.model, p.params, &p.plan)),
            integrator,
        );
    }
}

#[test]
fn free_fall_matches_discrete_euler_gpu() {
    let Some(ctx) = gpu() else { return };
    for integrator in [INTEGRATOR_SYMPLECTIC, INTEGRATOR_EXPLICIT] {
        free_fall(
            |p| {
                Box::new(
                    GpuSolver::new(ctx, &p.model, p.params, &p.plan, p.substeps as usize).unwrap(),
                )
            },
            integrator,
        );
    }
}

/// A vertical chain: particle 0 pinned at the top, `n` free particles of mass `m` below it,
/// joined by springs of stiffness `k` and rest length `l0`.
fn chain(n: usize, m: f32, k: f32, l0: f32, damping: f32) -> ClothModel {
    let count = n + 1;
    ClothModel {
        positions: (0..count)
            .map(|i| Vec3::new(0.0, 2.0 - i as f32 * l0, 0.0))
            .collect(),
        velocities: vec![Vec3::ZERO; count],
        masses: vec![m; count],
        pinned: (0..count).map(|i| i == 0).collect(),
        triangles: vec![],
        springs: (0..n)
            .map(|i| Spring {
                ends: [i as u32, i as u32 + 1],
                rest_length: l0,
                stiffness: k,
                damping,
            })
            .collect(),
        hinges: vec![],
        seams: vec![],
        membranes: vec![],
        colliders: Vec::new(),
        multigrid: None,
    }
}

/// Steps `solver` through 20 s at substeps of `dt`, a second at a time: under air damping
/// γ = 2/s the slowest mode decays at least as e^(−γt/2) = e^−20.
fn run_20_seconds(solver: &mut dyn Solver, dt: f32) {
    let per_second = (1.0 / dt).round() as u32;
    for _ in 0..20 {
        let steps: Vec<SubstepParams> = (0..per_second)
            .map(|s| SubstepParams {
                substep: s,
                ..Default::default()
            })
            .collect();
        solver.advance(&steps).unwrap();
    }
}

fn chain_settles(make: impl Fn(&ClothModel, SimParams, &PassPlan) -> Box<dyn Solver>) {
    let (n, m, k, l0) = (10usize, 0.01f32, 10.0f32, 0.05f32);
    let model = chain(n, m, k, l0, 0.05);
    let plan = PassPlan::new(&model, Effects::default());
    assert_eq!(plan.passes, vec![Pass::SpringForces, Pass::Integrate]);
    let params = SimParams {
        gravity: [0.0, -9.81, 0.0, 0.0],
        num_particles: model.len() as u32,
        integrator: INTEGRATOR_SYMPLECTIC,
        dt: 1e-3,
        air_damping: 2.0,
        ..Default::default()
    };
    let mut solver = make(&model, params, &plan);
    run_20_seconds(solver.as_mut(), params.dt);
    let state = solver.state().unwrap();
    let y: Vec<f32> = state.positions.iter().map(|p| p.y).collect();
    // Float dead zone: a position update dt·v smaller than ½ulp(y) (y in [1, 2) m: 5.96e-8 m)
    // rounds away, so each particle can rest with a residual force up to m·γ·(½ulp)/dt, kept
    // in balance by air damping on a velocity that no longer moves it. Spring i carries the
    // residuals of the n − i particles below it, plus one rounding of its own length (2.4e-7).
    let residual_extension = m * params.air_damping * 5.96e-8 / params.dt / k;
    for i in 0..n {
        let extension = (y[i] - y[i + 1]) - l0;
        let expected = m * 9.81 * (n - i) as f32 / k;
        let tol = (n - i) as f32 * residual_extension + 2.4e-7;
        assert!(
            (extension - expected).abs() <= tol,
            "spring {i}: extension {extension} m, expected {expected} m (tol {tol} m)"
        );
    }
}

#[test]
fn hanging_chain_settles_to_static_extensions_cpu() {
    chain_settles(|m, p, plan| Box::new(CpuSolver::new(m, p, plan)));
}

#[test]
fn hanging_chain_settles_to_static_extensions_gpu() {
    let Some(ctx) = gpu() else { return };
    chain_settles(|m, p, plan| Box::new(GpuSolver::new(ctx, m, p, plan, 1000).unwrap()));
}

/// A column under load: the chain of `chain_settles` with gravity turned upward and stiffer
/// springs (k = 1000 N/m), so spring i carries the compressive load F = m·g·(n − i) of the
/// particles below it (0.098–0.98 N); the chain stays on its axis, every force being along it.
/// Its springs buckle (`compression = "buckling"`): onset o = 0.5 mm (β = o·L), so those
/// loaded below k·o = 0.5 N compress by F/k and those above by o + (F − k·o)/(r·k), r the
/// buckled fraction. Both branches are checked.
fn column_settles(
    integrator: u32,
    dt: f32,
    make: impl Fn(&ClothModel, SimParams, &PassPlan) -> Box<dyn Solver>,
) {
    let (n, m, k, l0, r) = (10usize, 0.01f32, 1000.0f32, 0.05f32, 0.03f32);
    let onset = 5e-4f32;
    let model = chain(n, m, k, l0, 0.05);
    let implicit = integrator == INTEGRATOR_IMPLICIT;
    let plan = PassPlan::new(
        &model,
        Effects {
            implicit,
            ..Effects::default()
        },
    );
    let params = SimParams {
        gravity: [0.0, 9.81, 0.0, 0.0],
        num_particles: model.len() as u32,
        integrator,
        dt,
        air_damping: 2.0,
        iterations: 10,
        euler_onset: onset * l0,
        buckled_fraction: r,
        ..Default::default()
    };
    let mut solver = make(&model, params, &plan);
    run_20_seconds(solver.as_mut(), dt);
    let state = solver.state().unwrap();
    let y: Vec<f32> = state.positions.iter().map(|p| p.y).collect();
    // Float dead zone (see `chain_settles`): a step's change smaller than ½ulp(y) = 5.96e-8 m
    // rounds away, so a particle can rest with a residual force up to what moves it that far
    // in one step: m·γ·ulp/dt for symplectic Euler (damping holds the velocity), and
    // (m/dt² + 2k)·ulp for implicit Euler (its step's stiffness). Spring i carries the
    // residuals of the n − i particles below it over its own stiffness (k, or r·k buckled),
    // plus one rounding of its length (2.4e-7 m).
    let half_ulp = 5.96e-8;
    let residual = if implicit {
        (m / (dt * dt) + 2.0 * k) * half_ulp
    } else {
        m * params.air_damping * half_ulp / dt
    };
    let mut buckled = 0;
    for i in 0..n {
        let compression = l0 - (y[i] - y[i + 1]);
        let load = m * 9.81 * (n - i) as f32;
        let (expected, stiffness) = if load <= k * onset {
            (load / k, k)
        } else {
            buckled += 1;
            (onset + (load - k * onset) / (r * k), r * k)
        };
        let tol = (n - i) as f32 * residual / stiffness + 2.4e-7;
        assert!(
            (compression - expected).abs() <= tol,
            "spring {i}: compression {compression} m, expected {expected} m (tol {tol} m)"
        );
    }
    assert!(
        buckled > 0 && buckled < n,
        "{buckled} of {n} springs buckled"
    );
}

#[test]
fn loaded_column_buckles_at_the_euler_load_cpu() {
    for (integrator, dt) in [(INTEGRATOR_SYMPLECTIC, 1e-3), (INTEGRATOR_IMPLICIT, 1e-2)] {
        column_settles(integrator, dt, |m, p, plan| {
            Box::new(CpuSolver::new(m, p, plan))
        });
    }
}

#[test]
fn loaded_column_buckles_at_the_euler_load_gpu() {
    let Some(ctx) = gpu() else { return };
    for (integrator, dt) in [(INTEGRATOR_SYMPLECTIC, 1e-3), (INTEGRATOR_IMPLICIT, 1e-2)] {
        column_settles(integrator, dt, |m, p, plan| {
            Box::new(GpuSolver::new(ctx, m, p, plan, 1000).unwrap())
        });
    }
}

/// Energy ½kx² + ½mv² of one undamped spring (one end pinned) over 10⁵ steps.
fn spring_energies(integrator: u32) -> Vec<f64> {
    let (m, k, l0) = (1.0f32, 100.0f32, 1.0f32);
    let mut model = chain(1, m, k, l0, 0.0);
    model.positions[1].y -= 0.1; // stretched by 0.1 m
    let plan = PassPlan::new(&model, Effects::default());
    let dt = 5e-4; // ω·dt = 10 rad/s · 5e-4 s = 0.005
    let params = SimParams {
        num_particles: 2,
        integrator,
        dt,
        ..Default::default()
    };
    let mut cpu = CpuSolver::new(&model, params, &plan);
    let step = [SubstepParams::default()];
    let energy = |s: &CpuSolver| {
        let x = (s.pos[0].truncate().distance(s.pos[1].truncate()) - l0) as f64;
        let v = s.vel[1].truncate().length() as f64;
        0.5 * k as f64 * x * x + 0.5 * m as f64 * v * v
    };
    let mut out = vec![energy(&cpu)];
    for _ in 0..100_000 {
        cpu.advance(&step).unwrap();
        out.push(energy(&cpu));
    }
    out
}

#[test]
fn symplectic_energy_stays_bounded() {
    let e = spring_energies(INTEGRATOR_SYMPLECTIC);
    let e0 = e[0];
    let max_dev = e.iter().map(|x| (x - e0).abs() / e0).fold(0.0, f64::max);
    // Symplectic Euler conserves a modified energy; the true energy oscillates with relative
    // amplitude about ω·dt/2 = 0.0025 and does not drift. Allow ω·dt = 0.005.
    assert!(max_dev <= 0.005, "energy deviated by {max_dev}");
    // No secular drift: the last 1000 steps look like the first 1000.
    let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
    let drift = (mean(&e[e.len() - 1000..]) - mean(&e[..1000])).abs() / e0;
    assert!(drift <= 0.005, "energy drifted by {drift}");
}

#[test]
fn explicit_energy_grows_as_predicted() {
    let e = spring_energies(INTEGRATOR_EXPLICIT);
    // Explicit Euler multiplies ½kx² + ½mv² by exactly (1 + ω²dt²) per step on this
    // oscillator: (1 + 2.5e-5)^1e5 ≈ e^2.5 ≈ 12.2 after 10⁵ steps.
    let predicted = (1.0f64 + 2.5e-5).powi(100_000);
    let ratio = e[e.len() - 1] / e[0];
    // Each step rounds the state by ~2^-24 relative; 10⁵ steps accumulate at most ~6e-3.
    assert!(ratio > 10.0, "explicit Euler energy did not grow: ×{ratio}");
    assert!(
        (ratio / predicted - 1.0).abs() <= 6e-3,
        "×{ratio} vs predicted ×{predicted}"
    );
}

/// One strain-limiting iteration on a single edge stretched to twice its rest length: the edge
/// comes back to exactly (1 + limit)·L, each end moving by its inverse-mass share, and each
/// velocity changes by its displacement over the step. The spring has zero stiffness and there
/// is no gravity, so `integrate` moves nothing and the step is the strain limit alone.
fn strain_limit_single_edge(make: impl Fn(&ClothModel, SimParams, &PassPlan) -> Box<dyn Solver>) {
    let (l0, limit, dt) = (0.05f32, 0.1f32, 1e-3f32);
    for pinned_top in [true, false] {
        let mut model = chain(1, 0.01, 0.0, l0, 0.0);
        model.pinned[0] = pinned_top;
        model.positions[1].y = 2.0 - 2.0 * l0;
        let plan = PassPlan::new(
            &model,
            Effects {
                strain_limit: true,
                ..Effects::default()
            },
        );
        assert_eq!(
            plan.passes,
            vec![Pass::SpringForces, Pass::Integrate, Pass::StrainLimit]
        );
        let params = SimParams {
            num_particles: 2,
            integrator: INTEGRATOR_SYMPLECTIC,
            dt,
            strain_limit: limit,
            strain_iterations: 1,
            ..Default::default()
        };
        let mut solver = make(&model, params, &plan);
        solver.advance(&[SubstepParams::default()]).unwrap();
        let s = solver.state().unwrap();
        // The top end takes all of the 0.9·L correction when pinned, half of it otherwise.
        let top_share = if pinned_top { 0.0 } else { 0.5 };
        let fix = (2.0 - (1.0 + limit)) * l0;
        let expect_y = [
            2.0 - top_share * fix,
            2.0 - 2.0 * l0 + (1.0 - top_share) * fix,
        ];
        let expect_v = [-top_share * fix / dt, (1.0 - top_share) * fix / dt];
        for i in 0..2 {
            // Positions near 2 m: the correction (a few f32 operations on 5 cm lengths, ~1e-8 m)
            // plus the rounding of storing y + Δ (½ulp(2 m) = 1.2e-7 m), and the setup's own
            // rounding of 2 − 2L: 3e-7 m covers them. Velocities are Δ/dt ≈ 45 m/s, and Δ
            // inherits the rounding of the two stored input positions (½ulp of 1.9 and 2 m,
            // 1.2e-7 m together), which dt = 1e-3 s turns into 1.2e-4 m/s; plus a few ulp of
            // 45 m/s (2e-5): 1.4e-4 m/s.
            assert!(
                (s.positions[i].y - expect_y[i]).abs() <= 3e-7,
                "pinned_top {pinned_top}: particle {i} at y = {} m, expected {} m",
                s.positions[i].y,
                expect_y[i]
            );
            assert!(
                (s.velocities[i].y - expect_v[i]).abs() <= 1.4e-4,
                "pinned_top {pinned_top}: particle {i} at v = {} m/s, expected {} m/s",
                s.velocities[i].y,
                expect_v[i]
            );
        }
        let length = s.positions[0].y - s.positions[1].y;
        assert!(
            (length - (1.0 + limit) * l0).abs() <= 5e-7,
            "edge length {length} m"
        );
    }
}

#[test]
fn strain_limit_single_edge_cpu() {
    strain_limit_single_edge(|m, p, plan| Box::new(CpuSolver::new(m, p, plan)));
}

#[test]
fn strain_limit_single_edge_gpu() {
    let Some(ctx) = gpu() else { return };
    strain_limit_single_edge(|m, p, plan| Box::new(GpuSolver::new(ctx, m, p, plan, 1).unwrap()));
}
