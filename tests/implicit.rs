//! Implicit Euler (Vertex Block Descent): GPU/CPU parity of its stages and trajectories,
//! stability at frame-sized steps on stiff cloth, statics against symplectic Euler, convergence
//! in iterations, and contact on drape_sphere.

mod common;

use common::{fixture, gpu, max_abs_diff, perturbed};
use drapekit::cpu::CpuSolver;
use drapekit::gpu::GpuSolver;
use drapekit::model::layout::{INTEGRATOR_IMPLICIT, INTEGRATOR_SYMPLECTIC};
use drapekit::plan::{implicit_schedule, Pass, SolveShape};
use drapekit::scene::Scene;
use drapekit::sim::{prepare, simulate, substep_params, Prepared, RunStats};
use drapekit::solver::{ParticleState, Solver};

/// The shipped hanging cloth at 10,000 N/m (33× the shipped value), stepped by implicit Euler
/// with `substeps` per 1/24 s frame.
fn stiff_hanging(substeps: u32, bending: bool) -> Scene {
    let mut scene = Scene::load(&fixture("scenes/hanging_cloth.toml")).unwrap();
    scene.fabric.stretch_stiffness = 1e4;
    if !bending {
        scene.fabric.bending_stiffness = None;
    }
    scene.solver.integrator = INTEGRATOR_IMPLICIT;
    scene.solver.substeps = Some(substeps);
    scene
}

/// How far `energy` can be off because the state is stored in f32: each coordinate is within
/// half an ulp, 2^-24·|x|, of the exact value, so a spring's length is within 2·√3·2^-24·|x|max
/// and its energy within k·|stretch| times that; a particle's height within 2^-24·|x|max.
fn energy_rounding(prep: &Prepared, s: &ParticleState) -> f64 {
    let x_max = s
        .positions
        .iter()
        .map(|p| p.truncate().abs().max_element())
        .fold(0.0f32, f32::max) as f64;
    let ulp = 2f64.powi(-24) * x_max;
    let mut bound = 0.0;
    for sp in &prep.model.springs {
        let [a, b] = sp
            .ends
            .map(|i| s.positions[i as usize].truncate().as_dvec3());
        let stretch = (a.distance(b) - sp.rest_length as f64).abs();
        bound += sp.stiffness as f64 * stretch * 2.0 * 3f64.sqrt() * ulp;
    }
    let weight: f64 =
        prep.model.masses.iter().map(|&m| m as f64).sum::<f64>() * prep.gravity.0.length() as f64;
    bound + weight * ulp
}

/// Kinetic, gravitational and spring energy in J (the hanging cloth has no bending here, so
/// this is its whole mechanical energy).
fn energy(prep: &Prepared, s: &ParticleState) -> f64 {
    let g = prep.gravity.0.as_dvec3();
    let mut e = 0.0f64;
    for (i, p) in s.positions.iter().enumerate() {
        let m = prep.model.masses[i] as f64;
        let v = s.velocities[i].truncate().as_dvec3();
        e += 0.5 * m * v.length_squared() - m * g.dot(p.truncate().as_dvec3());
    }
    for sp in &prep.model.springs {
        let [a, b] = sp
            .ends
            .map(|i| s.positions[i as usize].truncate().as_dvec3());
        let stretch = a.distance(b) - sp.rest_length as f64;
        e += 0.5 * sp.stiffness as f64 * stretch * stretch;
    }
    e
}

fn run_frames(prep: &Prepared, solver: &mut dyn Solver, frames: u32) -> Vec<ParticleState> {
    let mut out = vec![solver.state().unwrap()];
    for frame in 1..=frames {
        solver.advance(&substep_params(prep, frame)).unwrap();
        out.push(solver.state().unwrap());
    }
    out
}

/// How far one substep's solve may leave the two backends' positions apart, in m. Each of its
/// sweeps adds at most one sweep's rounding difference (16ε·ℓ per colour, ε = 2^-24, ℓ the
/// longest spring in `states`: see tests/implicit_stages.rs), and so may each Newton step's
/// correction; sweeps and line-searched corrections pass earlier differences on without
/// amplifying them. Positions xₙ + D then round once more, by 2^-24 of the largest coordinate
/// on each backend.
fn solve_bound(prep: &Prepared, states: &[&ParticleState]) -> f32 {
    let eps = f32::EPSILON / 2.0;
    let schedule = implicit_schedule(SolveShape::for_run(&prep.model, &prep.params, &prep.plan));
    let count = |kind: &str| schedule.iter().filter(|op| op.kind() == kind).count() as f32;
    let steps = count("vbd_solve") + count("apply_correction");
    let colours = prep.model.vertex_coloring().colors() as f32;
    let mut longest = 0.0f32;
    let mut x_max = 0.0f32;
    for s in states {
        let p = |i: u32| s.positions[i as usize].truncate();
        for sp in &prep.model.springs {
            longest = longest.max(p(sp.ends[0]).distance(p(sp.ends[1])));
        }
        for q in &s.positions {
            x_max = x_max.max(q.truncate().abs().max_element());
        }
    }
    steps * 16.0 * eps * longest * colours + 2.0 * eps * x_max
}

#[test]
fn parity_vbd_stages() {
    // The T-shirt as placed, with the body: springs, hinges, seams and contact all in the solve.
    let Some(ctx) = gpu() else { return };
    let mut scene = Scene::load(&fixture("scenes/tshirt_drape_cotton.toml")).unwrap();
    scene.gravity_start = 0.0;
    let mut prep = prepare(&scene).unwrap();
    prep.params.gravity = [0.0, -9.81, 0.0, 0.0];
    for passes in [
        vec![Pass::VbdInit, Pass::VbdFinish],
        vec![Pass::VbdInit, Pass::VbdSolve, Pass::VbdFinish],
    ] {
        let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
        let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
        // 5 mm and 0.5 m/s perturbations give every element a non-trivial force.
        let state = perturbed(&cpu.state().unwrap(), 11, 5e-3, 0.5);
        cpu.set_state(&state);
        gpu.set_state(&state);
        let step = substep_params(&prep, 3)[0];
        for &p in &passes {
            cpu.run_pass(p, &step);
        }
        gpu.run_passes(&passes, &[step]).unwrap();
        let g = gpu.state().unwrap();
        let dx = max_abs_diff(&g.positions, &cpu.pos);
        let dv = max_abs_diff(&g.velocities, &cpu.vel);
        // Init and finish alone: positions are O(2 m), one f32 rounding is 2^-24 · 2 m ≈
        // 1.2e-7 m, and FMA contraction may make the two backends round one operation
        // differently: a few roundings, 4e-7 m, and velocities D/h, 1/h times that.
        let tx = if passes.len() == 2 {
            4e-7
        } else {
            solve_bound(&prep, &[&state, &cpu.state().unwrap()])
        };
        let tv = tx / prep.params.dt;
        eprintln!("{passes:?}: dx {dx:.2e} m, dv {dv:.2e} m/s");
        assert!(dx <= tx, "{passes:?}: positions differ by {dx} m");
        assert!(dv <= tv, "{passes:?}: velocities differ by {dv} m/s");
        assert!(
            max_abs_diff(&g.positions, &state.positions) > 1e-4,
            "the step moved nothing"
        );
    }
}

#[test]
fn parity_vbd_stages_with_two_bodies() {
    // The pinched cotton as shipped (implicit), its clamp closed: every vertex's Newton step
    // adds the table's and the clamp's contact, each sampled at its own SDF nodes.
    let Some(ctx) = gpu() else { return };
    let (mut prep, state, step) = common::pinched();
    assert!(prep.plan.contains(Pass::VbdSolve) && prep.model.colliders.len() == 2);
    // Ten Newton steps, not the scene's one: the state puts vertices at random depths around
    // both contact layers, and a correction or sweep step that would enter a layer lands on it
    // at the fraction gap/approach of its length, which for a step nearly parallel to the
    // layer turns the backends' 1e-9 m difference in the gap into micrometres (measured: 5e-6 m
    // after one Newton step's correction, 6e-4 m after the next sweep). Converged, both reach
    // the same minimum, which the rounding bound below covers; the per-stage parity of every
    // kernel from identical inputs is tests/implicit_stages.
    prep.params.iterations = 10;
    let passes = [Pass::VbdInit, Pass::VbdSolve, Pass::VbdFinish];
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
    cpu.set_state(&state);
    gpu.set_state(&state);
    for &p in &passes {
        cpu.run_pass(p, &step);
    }
    gpu.run_passes(&passes, &[step]).unwrap();
    let g = gpu.state().unwrap();
    let tx = solve_bound(&prep, &[&state, &cpu.state().unwrap()]);
    let dx = max_abs_diff(&g.positions, &cpu.pos);
    eprintln!("two bodies: dx {dx:.2e} m (bound {tx:.2e} m)");
    assert!(dx <= tx, "positions differ by {dx} m");
    assert!(
        max_abs_diff(&g.positions, &state.positions) > 1e-4,
        "the step moved nothing"
    );
}

#[test]
fn trajectory_parity_implicit() {
    let Some(ctx) = gpu() else { return };
    let prep = prepare(&stiff_hanging(1, true)).unwrap();
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
    let a = run_frames(&prep, &mut cpu, 48);
    let b = run_frames(&prep, &mut gpu, 48);
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| max_abs_diff(&x.positions, &y.positions))
        .fold(0.0f32, f32::max);
    // The stiff cloth settles (backward Euler damps), so differences of one rounding per
    // operation (≤ 1e-6 m per step, as in parity_vbd_stages) do not grow: 48 steps bound them
    // by 48e-6 m; 5e-5 m is that bound.
    eprintln!("implicit trajectory: worst {worst:.2e} m over 48 frames");
    assert!(worst <= 5e-5, "trajectories differ by {worst} m");
}

#[test]
fn stiff_cloth_at_one_step_per_frame_is_stable_and_only_loses_energy() {
    for backend in ["cpu", "gpu"] {
        let prep = prepare(&stiff_hanging(1, false)).unwrap();
        let mut solver: Box<dyn Solver> = match backend {
            "cpu" => Box::new(CpuSolver::new(&prep.model, prep.params, &prep.plan)),
            _ => match gpu() {
                Some(ctx) => {
                    Box::new(GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap())
                }
                None => continue,
            },
        };
        assert_eq!(prep.substeps, 1);
        let frames = run_frames(&prep, solver.as_mut(), 100);
        let mut max_strain = 0.0f32;
        let mut worst_rise = f64::MIN;
        let mut previous = energy(&prep, &frames[0]);
        for (k, s) in frames.iter().enumerate().skip(1) {
            assert!(
                drapekit::metrics::first_non_finite(s).is_none(),
                "{backend}: frame {k} not finite"
            );
            let e = energy(&prep, s);
            // Backward Euler with damping only dissipates. What the energy of an f32 state can
            // show beyond that is its rounding, in this frame and the last.
            let slack = energy_rounding(&prep, s) + energy_rounding(&prep, &frames[k - 1]);
            assert!(
                e <= previous + slack,
                "{backend}: energy rose from {previous} J to {e} J at frame {k} (rounding {slack:.2e} J)"
            );
            worst_rise = worst_rise.max(e - previous);
            previous = e;
            max_strain = max_strain.max(drapekit::metrics::max_edge_strain(
                &s.positions,
                &prep.model.springs,
            ));
        }
        // The cloth hangs from two corners: its weight (0.15 kg·9.81 ≈ 1.5 N) over the corner
        // springs of 10^4 N/m gives sub-percent strain; 5% bounds it with room for the corners'
        // stress concentration.
        eprintln!("{backend}: max strain {max_strain}, largest energy change {worst_rise:.2e} J");
        assert!(max_strain < 0.05, "{backend}: strain {max_strain}");
    }
}

#[test]
fn large_steps_settle_where_small_symplectic_steps_do() {
    // 1,000 N/m keeps the symplectic reference at a few hundred substeps per frame.
    let settle = |integrator: u32, substeps: Option<u32>| -> (ParticleState, f64) {
        let mut scene = Scene::load(&fixture("scenes/hanging_cloth.toml")).unwrap();
        scene.fabric.stretch_stiffness = 1e3;
        scene.solver.integrator = integrator;
        scene.solver.substeps = substeps;
        // Air damping of 6/s damps the slowest mode, the ~1 m cloth's pendulum swing at
        // ω ≈ √(g/L) ≈ 3 rad/s, critically (ζ = c/2ω = 1), so it settles fastest; every mode's
        // energy falls by e^-6 per second. 5 s takes both runs far below the bound below
        // (measured: 6.5e-12 J per particle symplectic, 4.9e-17 implicit at one Newton step a
        // frame).
        scene.air_damping = 6.0;
        scene.solver.frames = 120;
        let prep = prepare(&scene).unwrap();
        let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
        let mut stats = RunStats::default();
        simulate(&prep, &mut cpu, &mut stats, |_, _| Ok(())).unwrap();
        let free = prep.model.pinned.iter().filter(|p| !**p).count() as f64;
        (cpu.state().unwrap(), stats.kinetic_energy_j / free)
    };
    let (reference, ke_ref) = settle(INTEGRATOR_SYMPLECTIC, None);
    let (implicit, ke_imp) = settle(INTEGRATOR_IMPLICIT, Some(1));
    let d = max_abs_diff(&reference.positions, &implicit.positions);
    eprintln!("kinetic energy per particle: symplectic {ke_ref:.2e} J, implicit {ke_imp:.2e} J; rest shapes differ by {d:.2e} m");
    for ke in [ke_ref, ke_imp] {
        assert!(ke < 1e-10, "{ke} J per particle: not at rest");
    }
    // Both end below 1e-10 J per particle (m ≈ 0.15 kg / 1024 ≈ 1.5e-4 kg): speeds below
    // √(2e-10/1.5e-4) ≈ 1.2 mm/s. The slowest mode, a pendulum swing of the ~1 m cloth, has
    // ω ≈ √(g/L) ≈ 3 rad/s, so each run may end up to 1.2e-3/3 ≈ 0.4 mm from rest; the
    // static states agree within twice that, 1 mm.
    eprintln!("rest shapes differ by {d:.2e} m");
    assert!(d <= 1e-3, "rest shapes differ by {d} m");
}

/// One implicit step of the stiff hanging cloth from a perturbed state (2 mm of noise stretches
/// its springs by up to ~15% of their 3 cm, far from equilibrium), with `iterations` sweeps at
/// most and an optional tolerance; returns the solver after the step.
fn one_perturbed_step(
    solver: impl FnOnce(&Prepared) -> Box<dyn Solver>,
    iterations: u32,
    tolerance: Option<f32>,
) -> Box<dyn Solver> {
    let mut scene = stiff_hanging(1, true);
    scene.solver.iterations = Some(iterations);
    scene.solver.tolerance = tolerance;
    let prep = prepare(&scene).unwrap();
    let mut solver = solver(&prep);
    let state = perturbed(&solver.state().unwrap(), 5, 2e-3, 0.0);
    solver.set_state(&state);
    solver.advance(&substep_params(&prep, 1)).unwrap();
    solver
}

fn cpu_solver(prep: &Prepared) -> Box<dyn Solver> {
    Box::new(CpuSolver::new(&prep.model, prep.params, &prep.plan))
}

#[test]
fn residual_falls_as_newton_steps_rise() {
    // The sheet has coarse levels, so `iterations` counts Newton steps, each after `smoothing`
    // sweeps, and `smoothing` more sweeps end the substep. Without a tolerance every one runs,
    // and the force residual at the substep's end falls as more run.
    let smoothing = stiff_hanging(1, true).solver.smoothing_sweeps as u64;
    let residual = |newton: u32| {
        let mut cpu = one_perturbed_step(cpu_solver, newton, None);
        let p = cpu.residual().unwrap().unwrap();
        assert_eq!(
            p.newton_steps, newton as u64,
            "no tolerance: every step runs"
        );
        assert_eq!(p.iterations, smoothing * (newton as u64 + 1), "{p:?}");
        p.force_residual.1
    };
    let r: Vec<f32> = [1, 4, 16].into_iter().map(residual).collect();
    eprintln!("RMS force residual after 1, 4, 16 Newton steps: {r:?}");
    assert!(r[1] < r[0] && r[2] < r[1], "{r:?}");
}

#[test]
fn a_tolerance_stops_the_solve_once_the_force_residual_is_within_it() {
    // At most 64 Newton steps (the sheet has coarse levels), each after `smoothing` sweeps,
    // stopping once the RMS force residual |f|/(m·g) is within the tolerance: the solve stops
    // early, and where it stops the residual is within the tolerance by the rule itself.
    let tolerance = 0.1;
    let smoothing = stiff_hanging(1, true).solver.smoothing_sweeps as u64;
    let max_sweeps = smoothing * (64 + 1);
    let mut cpu = one_perturbed_step(cpu_solver, 64, Some(tolerance));
    let c = cpu.residual().unwrap().unwrap();
    eprintln!(
        "CPU: {} sweeps, force residual {:?}",
        c.iterations, c.force_residual
    );
    assert!(
        c.iterations > smoothing && c.iterations < max_sweeps,
        "{c:?}"
    );
    assert!(c.force_residual.1 <= tolerance, "{c:?}");
    // A stop comes at a Newton step's tolerance check, after its sweeps and before its
    // correction: one set of sweeps more than corrections.
    assert_eq!(c.iterations, smoothing * (c.newton_steps + 1), "{c:?}");
    // The GPU applies the same rule to its own residuals, which may differ from the CPU's by
    // rounding (parity_vbd_stages): where a residual sits at the tolerance that can move the
    // stop by one Newton step (its `smoothing` sweeps), no more.
    let Some(ctx) = gpu() else { return };
    let mut gpu = one_perturbed_step(
        |prep| Box::new(GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap()),
        64,
        Some(tolerance),
    );
    let g = gpu.residual().unwrap().unwrap();
    eprintln!(
        "GPU: {} sweeps, force residual {:?}",
        g.iterations, g.force_residual
    );
    assert!(
        g.iterations.abs_diff(c.iterations) <= smoothing,
        "{g:?} vs {c:?}"
    );
    assert!(g.force_residual.1 <= tolerance, "{g:?}");
    assert_eq!(g.iterations, smoothing * (g.newton_steps + 1), "{g:?}");
}

#[test]
fn implicit_drape_sphere_stays_within_a_millimetre() {
    let mut scene = Scene::load(&fixture("scenes/drape_sphere.toml")).unwrap();
    scene.solver.integrator = INTEGRATOR_IMPLICIT;
    scene.solver.substeps = Some(4);
    let prep = prepare(&scene).unwrap();
    let deepest = |solver: &mut dyn Solver| {
        let mut deepest = 0.0f32;
        let mut closest = f32::MAX;
        for frame in 1..=24 {
            for step in substep_params(&prep, frame) {
                solver.advance(&[step]).unwrap();
                for p in &solver.state().unwrap().positions {
                    let r = p.truncate().length();
                    deepest = deepest.max(0.3 - r);
                    closest = closest.min(r - 0.3);
                }
            }
        }
        (deepest, closest)
    };
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let (d, closest) = deepest(&mut cpu);
    assert!(d <= 1e-3, "cpu: {d} m inside");
    // The cloth did land on the sphere.
    assert!(
        closest < 0.005,
        "closest particle {closest} m from the sphere"
    );
    if let Some(ctx) = gpu() {
        let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
        let (d, _) = deepest(&mut gpu);
        assert!(d <= 1e-3, "gpu: {d} m inside");
    }
}
