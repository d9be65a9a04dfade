//! Self-collision: the spatial hash stages and particle repulsion, GPU vs CPU, and a strip
//! folded onto itself that must not pass through itself.

mod common;

use common::{fixture, gpu, max_abs_diff, perturbed};
use drapekit::cpu::CpuSolver;
use drapekit::gpu::GpuSolver;
use drapekit::plan::Pass;
use drapekit::scene::Scene;
use drapekit::sim::{prepare, simulate, substep_params, Prepared, RunStats};
use drapekit::solver::Solver;

const COLS: usize = 21;

/// Smallest height of the top layer above the bottom layer point it lies over (the strip's
/// rows are mirrored: top row r sits over bottom row 20 − r).
fn min_gap(positions: &[glam::Vec4]) -> f32 {
    let mut gap = f32::MAX;
    for r in 0..21 {
        for c in 0..COLS {
            let top = positions[(24 + r) * COLS + c].y;
            let bottom = positions[(20 - r) * COLS + c].y;
            gap = gap.min(top - bottom);
        }
    }
    gap
}

fn fold_scene(self_collision: bool) -> Prepared {
    let mut scene = Scene::load(&fixture("scenes/self_fold.toml")).unwrap();
    if !self_collision {
        scene.self_collision = None;
    }
    prepare(&scene).unwrap()
}

fn smallest_gap_over_run(prep: &Prepared, solver: &mut dyn Solver) -> (f32, f32) {
    let mut smallest = f32::MAX;
    let mut last = 0.0;
    simulate(prep, solver, &mut RunStats::default(), |_, s| {
        last = min_gap(&s.positions);
        smallest = smallest.min(last);
        Ok(())
    })
    .unwrap();
    (smallest, last)
}

#[test]
fn a_folded_strip_does_not_pass_through_itself() {
    let prep = fold_scene(true);
    let h = prep.params.self_thickness;
    assert!(prep.plan.contains(Pass::SelfCollide));
    let mut backends: Vec<Box<dyn Solver>> = vec![Box::new(CpuSolver::new(
        &prep.model,
        prep.params,
        &prep.plan,
    ))];
    if let Some(ctx) = gpu() {
        backends.push(Box::new(
            GpuSolver::new(
                ctx,
                &prep.model,
                prep.params,
                &prep.plan,
                prep.substeps as usize,
            )
            .unwrap(),
        ));
    }
    for mut solver in backends {
        let (smallest, last) = smallest_gap_over_run(&prep, solver.as_mut());
        let name = solver.backend_name();
        eprintln!("{name}: smallest gap {smallest} m, final {last} m, thickness {h} m");
        // Repulsion keeps the layers about one thickness apart; half of it is a clear margin
        // above zero (where a layer that passed through would be).
        assert!(
            smallest > 0.5 * h,
            "{name}: the layers came within {smallest} m"
        );
    }
    // The control: without self-collision the top layer falls onto the floor through the
    // bottom one, so the criterion above would fail.
    let prep = fold_scene(false);
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let (smallest, _) = smallest_gap_over_run(&prep, &mut cpu);
    assert!(
        smallest < 0.5 * h,
        "control: gap {smallest} m without self-collision"
    );
}

#[test]
fn parity_spatial_hash_and_self_collide() {
    let Some(ctx) = gpu() else { return };
    let prep = fold_scene(true);
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, 1).unwrap();
    // Squash the layers together (y jitter of 1 cm) so that many pairs are in contact.
    let mut state = perturbed(&cpu.state().unwrap(), 4, 1e-2, 0.3);
    for p in &mut state.positions {
        p.y *= 0.3;
    }
    cpu.set_state(&state);
    gpu.set_state(&state);
    let step = substep_params(&prep, 1)[0];
    let hash_passes = [
        Pass::HashClear,
        Pass::HashCount,
        Pass::HashScan,
        Pass::HashFill,
    ];
    for pass in hash_passes {
        cpu.run_pass(pass, &step);
    }
    gpu.run_passes(&hash_passes, &[step]).unwrap();
    let (counts, starts, sorted) = gpu.hash_tables().unwrap();
    let h = cpu.hash.as_ref().unwrap();
    let buckets = h.counts.len();
    // Counts and starts are integers: exactly equal.
    assert_eq!(&counts[..buckets], &h.counts[..]);
    assert_eq!(&starts[..=buckets], &h.starts[..]);
    // Within a bucket the GPU's order depends on its atomics: compare as sets.
    for b in 0..buckets {
        let range = h.starts[b] as usize..h.starts[b + 1] as usize;
        let mut g = sorted[range.clone()].to_vec();
        let mut c = h.sorted[range].to_vec();
        g.sort_unstable();
        c.sort_unstable();
        assert_eq!(g, c, "bucket {b}");
    }
    // self_collide alone, from the CPU's table on both sides.
    let (starts, sorted) = (h.starts.clone(), h.sorted.clone());
    gpu.set_hash(&starts, &sorted);
    cpu.run_pass(Pass::SelfCollide, &step);
    gpu.run_passes(&[Pass::SelfCollide], &[step]).unwrap();
    let g = gpu.state().unwrap();
    let moved = (0..state.positions.len())
        .filter(|&i| cpu.pos[i] != state.positions[i])
        .count();
    assert!(moved > 100, "only {moved} particles were pushed");
    // Positions O(0.4 m), sums of up to ~10 corrections of O(1 cm): a few f32 roundings of
    // 3e-8 m each; 1e-6 m leaves a wide margin below the centimetre corrections.
    let dx = max_abs_diff(&g.positions, &cpu.pos);
    let dv = max_abs_diff(&g.velocities, &cpu.vel);
    assert!(dx <= 1e-6, "positions differ by {dx} m");
    assert!(dv <= 1e-5, "velocities differ by {dv} m/s");
}

#[test]
fn point_triangle_reference_conserves_momentum_and_keeps_the_layers_apart() {
    let prep = fold_scene(true);
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    cpu.use_point_triangle_reference();
    // One application on a squashed, jittered state: many impulses, zero net momentum change.
    let mut state = perturbed(&cpu.state().unwrap(), 8, 1e-2, 0.3);
    for p in &mut state.positions {
        p.y *= 0.3;
    }
    cpu.set_state(&state);
    let momentum = |vel: &[glam::Vec4]| {
        (0..vel.len())
            .map(|i| prep.model.masses[i] as f64 * vel[i].truncate().as_dvec3())
            .sum::<glam::DVec3>()
    };
    let before = momentum(&state.velocities);
    cpu.run_pass(Pass::SelfCollide, &substep_params(&prep, 1)[0]);
    let after = momentum(&cpu.vel);
    let changed = (0..state.velocities.len())
        .filter(|&i| cpu.vel[i] != state.velocities[i])
        .count();
    assert!(changed > 100, "only {changed} velocities changed");
    // Impulses are computed in f64 and stored in f32: each velocity rounds once to ~1e-7 of
    // O(1 m/s) times O(1e-4 kg) masses, summed over ~1000 particles: ~1e-8 kg·m/s.
    assert!(
        (after - before).length() < 1e-7,
        "momentum changed by {}",
        (after - before).length()
    );
    // Half a second (the top layer lands at ~0.1 s): it must not pass through the bottom one.
    let mut prep = prep;
    prep.frames = 12;
    let mut cpu = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    cpu.use_point_triangle_reference();
    let (smallest, last) = smallest_gap_over_run(&prep, &mut cpu);
    eprintln!("point-triangle: smallest gap {smallest} m, final {last} m");
    assert!(
        smallest > 0.5 * prep.params.self_thickness,
        "layers came within {smallest} m"
    );
}

#[test]
fn a_self_collision_thickness_of_many_edges_is_warned() {
    // The fold's mean edge is 2.1 cm (the default thickness 0.75 of it); half a metre makes
    // particles a few triangles apart repel, which the run should say before it blows up.
    let warned = |thickness: Option<f32>| {
        let mut scene = Scene::load(&fixture("scenes/self_fold.toml")).unwrap();
        scene.self_collision.as_mut().unwrap().thickness = thickness;
        let prep = prepare(&scene).unwrap();
        prep.warnings
            .iter()
            .any(|w| w.contains("times the cloth's mean edge"))
    };
    assert!(warned(Some(0.5)));
    assert!(!warned(None) && !warned(Some(0.02)));
}
