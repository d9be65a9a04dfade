//! GPU timestamps per stage (`GpuSolver::start_profile`, `drapekit bench profile`): every
//! dispatch of a substep is timed exactly once, under the stage or solve kernel that issued it,
//! and profiling changes no result.

mod common;

use common::{drapekit, fixture, out_dir};
use drapekit::gpu::{GpuContext, GpuSolver};
use drapekit::model::layout::INTEGRATOR_IMPLICIT;
use drapekit::plan::Pass;
use drapekit::scene::Scene;
use drapekit::sim::{prepare, substep_params, Prepared};
use drapekit::solver::Solver;

/// A device with timestamps on the test adapter; `None` (said) without one, which under
/// `CI=true` is a failure.
fn device() -> Option<GpuContext> {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // Silences the Vulkan loader's harmless XDG_RUNTIME_DIR warnings.
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    match GpuContext::open_with_timestamps(&common::test_adapter()) {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
            assert!(!ci, "CI=true but no adapter with timestamps: {e}");
            eprintln!("SKIPPED (no GPU adapter with timestamps, not under CI): {e}");
            None
        }
    }
}

/// The hanging cloth under implicit Euler: plan stages and the solve's kernels.
fn implicit_cloth() -> Prepared {
    let mut scene = Scene::load(&fixture("scenes/hanging_cloth.toml")).unwrap();
    scene.solver.integrator = INTEGRATOR_IMPLICIT;
    prepare(&scene).unwrap()
}

#[test]
fn every_dispatch_is_timed_once_under_its_stage() {
    let Some(ctx) = device() else { return };
    let prep = implicit_cloth();
    // Two frames' substeps in one call: a batch of more than one substep.
    let steps = [substep_params(&prep, 1), substep_params(&prep, 2)].concat();
    let mut gpu = GpuSolver::new(&ctx, &prep.model, prep.params, &prep.plan, steps.len()).unwrap();
    gpu.start_profile().unwrap();
    gpu.advance(&steps).unwrap();
    gpu.finish().unwrap();
    let profile = gpu.profile().unwrap();
    assert_eq!(profile.dropped(), 0);
    let timed: u64 = profile.totals().iter().map(|t| t.dispatches).sum();
    // Every substep but the batch's last leaves out the final force residual's two
    // dispatches (force_residual, reduce_residual): only the last one's is read back.
    let n = steps.len() as u64;
    assert!(
        n > 1,
        "the frame has {n} substep: the rule above goes unchecked"
    );
    assert_eq!(timed, n * gpu.dispatches_per_substep() as u64 - (n - 1) * 2);
    let labels: Vec<&str> = profile.totals().iter().map(|t| t.label.as_str()).collect();
    for pass in &prep.plan.passes {
        match pass {
            Pass::VbdSolve => assert!(labels.iter().any(|l| l.starts_with("solve/"))),
            p => assert!(labels.contains(&p.name()), "{} not in {labels:?}", p.name()),
        }
    }
    // The frame's health check runs apart from the substeps (as on the CPU).
    assert!(!labels.contains(&"monitor"), "{labels:?}");
    for t in profile.totals() {
        assert!(t.seconds.is_finite() && t.seconds >= 0.0, "{t:?}");
    }
    assert!(profile.totals().iter().map(|t| t.seconds).sum::<f64>() > 0.0);
}

#[test]
fn profiling_changes_no_result() {
    let Some(ctx) = device() else { return };
    let prep = implicit_cloth();
    let steps = substep_params(&prep, 1);
    let state = |profiled: bool| {
        let mut gpu =
            GpuSolver::new(&ctx, &prep.model, prep.params, &prep.plan, steps.len()).unwrap();
        if profiled {
            gpu.start_profile().unwrap();
        }
        gpu.advance(&steps).unwrap();
        gpu.state().unwrap()
    };
    let (plain, profiled) = (state(false), state(true));
    assert_eq!(plain.positions, profiled.positions);
    assert_eq!(plain.velocities, profiled.velocities);
}

#[test]
fn bench_profile_writes_each_stage_of_the_grid_and_the_scene() {
    let dir = out_dir("gpu_profile", "bench");
    let scene = fixture("scenes/hanging_cloth.toml");
    let adapter = common::test_adapter().to_string();
    let r = drapekit(&[
        "bench",
        "profile",
        "--sizes",
        "8",
        "--substeps",
        "3",
        "--scene",
        scene.to_str().unwrap(),
        "--frames",
        "1",
        "--adapter",
        &adapter,
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let csv = std::fs::read_to_string(dir.join("profile.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let stages_of = |case: &str| -> Vec<&str> {
        (rows.iter().filter(|r| r[0] == format!("\"{case}\"")))
            .map(|r| r[5].trim_matches('"'))
            .collect()
    };
    assert_eq!(
        stages_of("grid 8²"),
        ["spring_forces", "bending_forces", "integrate"],
        "{csv}"
    );
    assert!(
        stages_of("hanging_cloth.toml").contains(&"integrate"),
        "{csv}"
    );
    // The frame's substeps were profiled; its health check is timed but is no substep.
    let frame = prepare(&Scene::load(&scene).unwrap()).unwrap().substeps;
    let integrate = (rows.iter())
        .find(|r| r[0] == "\"hanging_cloth.toml\"" && r[5] == "\"integrate\"")
        .unwrap();
    assert_eq!(integrate[2], frame.to_string(), "{csv}");
    assert_eq!(integrate[6], "1.00", "{csv}");
    // Shares of a case add up to 100% (each printed to 0.01).
    let share: f64 = (rows.iter().filter(|r| r[0] == "\"grid 8²\""))
        .map(|r| r[8].parse::<f64>().unwrap())
        .sum();
    assert!((share - 100.0).abs() < 0.02, "{share}");
    assert!(std::fs::read_to_string(dir.join("profile.md"))
        .unwrap()
        .contains("### grid 8²"));
}

#[test]
fn bench_profile_with_nothing_to_profile_is_bad_input() {
    let dir = out_dir("gpu_profile", "nothing");
    let r = drapekit(&[
        "bench",
        "profile",
        "--sizes",
        "0",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(stderr.contains("nothing to profile"), "{stderr}");
    assert!(!dir.exists(), "nothing may be written");
}

#[test]
fn a_bench_output_folder_that_is_a_file_is_refused_before_anything_runs() {
    let dir = out_dir("gpu_profile", "out-file");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("report");
    std::fs::write(&file, "kept").unwrap();
    let out = file.to_str().unwrap();
    for args in [
        &["bench", "--sizes", "8", "--out", out][..],
        &["bench", "profile", "--sizes", "8", "--out", out],
        &["bench", "fabric", "--tests", "cusick", "--out", out],
    ] {
        let r = drapekit(args);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("is a file, not a folder"),
            "{args:?}: {stderr}"
        );
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "kept");
    }
}
