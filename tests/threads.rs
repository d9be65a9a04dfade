//! The multi-threaded CPU path gives the same bits on any number of threads: every stage writes
//! each particle's result from reads of the previous arrays and sums its elements in a fixed
//! order, so the thread count may change only the speed. Equality here is exact (`to_bits`),
//! not within a tolerance: any difference means a stage's result depends on scheduling.

mod common;

use drapekit::cpu::CpuSolver;
use drapekit::scene::Scene;
use drapekit::sim::{prepare, simulate, RunStats};
use drapekit::solver::Solver;

/// The bits of the final positions and velocities, and the run's stats, of `scene` on the CPU
/// path inside a rayon pool of `threads`.
fn run_on(threads: usize, scene: &Scene) -> (Vec<u32>, RunStats) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    assert_eq!(pool.current_num_threads(), threads);
    pool.install(|| {
        let prep = prepare(scene).unwrap();
        let mut solver = CpuSolver::new(&prep.model, prep.params, &prep.plan);
        if prep.cpu_point_triangle {
            solver.use_point_triangle_reference();
        }
        let mut stats = RunStats::default();
        simulate(&prep, &mut solver, &mut stats, |_, _| Ok(())).unwrap();
        stats.wall_seconds = 0.0;
        let state = solver.state().unwrap();
        let bits = (state.positions.iter())
            .chain(&state.velocities)
            .flat_map(|v| v.to_array())
            .map(f32::to_bits)
            .collect();
        (bits, stats)
    })
}

/// Runs `scene` for `frames` on 1, 2 and 3 threads (3 splits the particles unevenly) and
/// requires identical states and stats; returns the stats.
fn same_on_any_thread_count(name: &str, frames: u32, edit: impl Fn(&mut Scene)) -> RunStats {
    let mut scene = Scene::load(&common::fixture(&format!("scenes/{name}.toml"))).unwrap();
    scene.solver.frames = frames;
    edit(&mut scene);
    let (one, one_stats) = run_on(1, &scene);
    assert!(one_stats.finite, "{name}: the run went non-finite");
    assert_eq!(one_stats.frames_run, frames, "{name}: frames run");
    for threads in [2, 3] {
        let (many, many_stats) = run_on(threads, &scene);
        let first = (one.iter().zip(&many)).position(|(a, b)| a != b);
        assert!(
            first.is_none() && one.len() == many.len(),
            "{name}: 1 and {threads} threads differ first at float {first:?}"
        );
        assert_eq!(one_stats, many_stats, "{name}: stats on {threads} threads");
    }
    one_stats
}

#[test]
fn hanging_cloth_with_bending_and_strain_limit_is_thread_count_independent() {
    let stats = same_on_any_thread_count("hanging_cloth", 12, |s| {
        assert!(s.fabric.bending_stiffness.is_some(), "the fixture bends");
        s.solver.strain_limit = Some(0.05);
    });
    assert!(stats.max_edge_strain > 0.0);
}

#[test]
fn implicit_cotton_tshirt_is_thread_count_independent() {
    // Seams, the body's SDF contact and VBD's colour sweeps (parallel within a colour).
    let stats = same_on_any_thread_count("tshirt_drape_cotton", 10, |_| {});
    assert!(stats.max_residual.is_some(), "the implicit solve ran");
    assert!(!stats.seam_gaps.is_empty(), "the shirt has seams");
}

#[test]
fn self_collision_wind_and_exact_contact_are_thread_count_independent() {
    // Particle repulsion through the spatial hash.
    same_on_any_thread_count("self_fold", 6, |s| assert!(s.effects().self_collision));
    // Wind drag on triangles.
    same_on_any_thread_count("flag_wind", 6, |_| {});
    // Exact point-to-mesh queries and edge contacts against the body.
    same_on_any_thread_count("drape_bar", 6, |_| {});
}
