//! Device loss: a GPU that goes away mid-run ends the run with a clear error, never a panic or
//! a hang, and what was written survives. Its own device: destroying the shared one would take
//! the other tests' adapter with it.

mod common;

use drapekit::error::Error;
use drapekit::gpu::{GpuContext, GpuSolver};
use drapekit::scene::Scene;
use drapekit::sim::{prepare, simulate, RunStats};
use drapekit::solver::Solver;

#[test]
fn a_lost_device_ends_the_run_with_a_clear_error() {
    // Only to learn whether an adapter exists (and to fail under CI=true when none does).
    if common::gpu().is_none() {
        return;
    }
    let ctx = GpuContext::new(&common::test_adapter()).unwrap();
    let mut scene = Scene::load(&common::fixture("scenes/hanging_cloth.toml")).unwrap();
    scene.solver.frames = 6;
    let prep = prepare(&scene).unwrap();
    let mut solver = GpuSolver::new(&ctx, &prep.model, prep.params, &prep.plan, 64).unwrap();
    let mut handed_out = Vec::new();
    let result = simulate(&prep, &mut solver, &mut RunStats::default(), |frame, _| {
        handed_out.push(frame);
        if frame == 2 {
            ctx.device.destroy();
        }
        Ok(())
    });
    let msg = match result {
        Err(Error::Gpu(msg)) => msg,
        other => panic!("expected a GPU error, got {other:?}"),
    };
    assert!(
        msg.contains("device was lost") && msg.contains("resume"),
        "{msg}"
    );
    assert_eq!(
        handed_out,
        vec![0, 1, 2],
        "no frame after the loss is handed out"
    );
    // Later calls keep failing the same way rather than panicking.
    match solver.state() {
        Err(Error::Gpu(later)) => assert!(later.contains("device was lost"), "{later}"),
        other => panic!("expected a GPU error, got {other:?}"),
    }
}
