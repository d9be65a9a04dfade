//! Shared by the criterion benches: one GPU context per bench binary, shipped scenes loaded
//! and prepared as `drapekit run` prepares them, and solvers on both backends.
#![allow(dead_code)] // each bench binary uses a different subset

use drapekit::cpu::CpuSolver;
use drapekit::gpu::{AdapterChoice, GpuContext, GpuSolver};
use drapekit::model::layout::SubstepParams;
use drapekit::scene::Scene;
use drapekit::sim::{prepare, substep_params, Prepared};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// `WGPU_ADAPTER_NAME` picks the adapter (default: wgpu's choice, e.g. lavapipe on CI
/// machines); without one, only the CPU path is benchmarked.
pub fn gpu_context() -> Option<GpuContext> {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // Silences the Vulkan loader's harmless XDG_RUNTIME_DIR warnings.
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    eprintln!("CPU: {}", drapekit::bench::cpu_threads_description());
    match GpuContext::new(&AdapterChoice::Auto) {
        Ok(ctx) => {
            let a = ctx.report();
            eprintln!(
                "GPU adapter: {} (driver {}, {}, {})",
                a.name, a.driver, a.backend, a.device_type
            );
            Some(ctx)
        }
        Err(e) => {
            eprintln!("no GPU adapter ({e}); benchmarking the CPU path only");
            None
        }
    }
}

/// A shipped scene, by file name.
pub fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/scenes")
        .join(name)
}

/// Loads a shipped scene, lets `edit` change it, and prepares it. Panics with the scene's
/// error: a shipped scene that does not load is a bug.
pub fn prepared(name: &str, edit: impl FnOnce(&mut Scene)) -> Prepared {
    let mut scene = Scene::load(&scene_path(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    edit(&mut scene);
    prepare(&scene).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The CPU solver `drapekit run --backend cpu` builds for `prep`.
pub fn cpu_solver(prep: &Prepared) -> CpuSolver {
    let mut solver = CpuSolver::new(&prep.model, prep.params, &prep.plan);
    if prep.cpu_point_triangle {
        solver.use_point_triangle_reference();
    }
    solver
}

/// The GPU solver for `prep`, holding `batch` substeps per submission.
pub fn gpu_solver(ctx: &GpuContext, prep: &Prepared, batch: usize) -> GpuSolver {
    GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, batch).expect("GPU solver")
}

/// `count` substeps of the scene's first output frame (time, wind, body pose), repeated if
/// the frame has fewer.
pub fn first_substeps(prep: &Prepared, count: usize) -> Vec<SubstepParams> {
    let frame = substep_params(prep, 1);
    frame.iter().cycle().take(count).copied().collect()
}

/// Times `iters` runs of `run`, each followed by waiting for the device (GPU work is timed
/// to completion, as wgpu's own benches do with `iter_custom`).
pub fn timed(iters: u64, mut run: impl FnMut()) -> Duration {
    let start = Instant::now();
    for _ in 0..iters {
        run();
    }
    start.elapsed()
}
