//! The multi-threaded CPU path gives the same bits on any number of threads: every stage writes
//! each particle's result from reads of the previous arrays and sums its elements in a fixed
//! order, so the thread count may change only the speed. Equality here is exact (`to_bits`),
//! not within a tolerance: any difference means a stage's result depends on scheduling.

mod common;

use drapekit::cpu::{grain, CpuSolver};
use drapekit::scene::{ClothSource, Scene};
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
fn implicit_multigrid_past_every_grain_is_thread_count_independent() {
    // The T-shirt's 2,468 particles split its vertex loops and block rows into tasks but not
    // the element-wise vector updates (`vbd_init`, conjugate gradients' updates and dot
    // products): a 120 × 120 sheet does.
    let (columns, rows) = (120, 120);
    assert!(grain::splits(columns * rows, grain::ARRAY));
    let stats = same_on_any_thread_count("hanging_sheet_cotton", 1, |s| match &mut s.cloth {
        ClothSource::Grid {
            columns: c,
            rows: r,
            ..
        } => (*c, *r) = (columns as u32, rows as u32),
        other => panic!("the fixture is a grid, not {other:?}"),
    });
    assert!(stats.max_residual.is_some(), "the implicit solve ran");
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

#[test]
fn backend_auto_prefers_the_cpu_path_to_a_software_adapter() {
    let out = std::env::temp_dir().join(format!("drapekit-threads-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let r = std::process::Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args(["run", "--frames", "2", "--quiet", "--threads", "2", "--out"])
        .arg(&out)
        .arg(common::fixture("scenes/hanging_cloth.toml"))
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env_remove("WGPU_ADAPTER_NAME")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    // What `--adapter auto` finds decides what `--backend auto` must have run.
    let hardware = drapekit::gpu::adapters()
        .auto
        .is_some_and(|a| a.device_type != "cpu");
    if hardware {
        assert_eq!(summary["backend"], "gpu", "{summary}");
        assert!(summary["cpu_threads"].is_null());
    } else {
        assert_eq!(summary["backend"], "cpu", "{summary}");
        assert_eq!(summary["cpu_threads"], 2);
        assert!(stdout.contains("[CPU, 2 threads]"), "{stdout}");
        let note = summary["backend_note"].as_str().unwrap();
        assert!(note.contains("CPU path"), "{note}");
    }
}

#[test]
fn far_more_threads_than_cores_are_noted() {
    // 4096 threads on a 2-core machine took 11 s for what 2 do in 0.07 s: said, not refused
    // (results do not depend on it). Five times the cores, whatever the machine.
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let many = (5 * cores).min(4096).to_string();
    let r = std::process::Command::new(env!("CARGO_BIN_EXE_drapekit"))
        .args(["--threads", &many, "info"])
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(
        stderr.contains(&format!("--threads {many} on {cores} logical CPUs")),
        "{stderr}"
    );
}
