//! The GPU path's two array layouts (textures, storage buffers) run the same arithmetic on the
//! same values: every stage of every shipped effect gives the same bits in both.

mod common;

use common::fixture;
use drapekit::gpu::{ArrayLayout, GpuContext, GpuSolver};
use drapekit::plan::{HingeEvaluation, Pass};
use drapekit::scene::Scene;
use drapekit::sim::{prepare, simulate, RunStats};
use drapekit::solver::{ParticleState, Solver};
use std::collections::BTreeSet;

/// A device on the test adapter (`DRAPEKIT_TEST_ADAPTER`, else the fallback adapter) with
/// `layout`; `None` (said) without an adapter, which under `CI=true` is a failure.
fn device(layout: ArrayLayout) -> Option<GpuContext> {
    match GpuContext::open(&common::test_adapter(), Some(layout)) {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
            assert!(!ci, "CI=true but no fallback adapter for {layout:?}: {e}");
            eprintln!("SKIPPED (no GPU adapter, not under CI): {e}");
            None
        }
    }
}

/// Every frame's state of `scene`'s first `frames` frames on `ctx` with hinges evaluated
/// `hinges`, and the passes it ran.
fn run(
    ctx: &GpuContext,
    scene: &Scene,
    frames: u32,
    hinges: HingeEvaluation,
) -> (Vec<ParticleState>, Vec<Pass>) {
    let mut scene = scene.clone();
    scene.solver.frames = frames;
    let mut prep = prepare(&scene).unwrap();
    prep.plan = prep.plan.with_hinges(hinges);
    let steps = prep.substeps as usize;
    let mut gpu = GpuSolver::new(ctx, &prep.model, prep.params, &prep.plan, steps).unwrap();
    let mut states = Vec::new();
    simulate(&prep, &mut gpu, &mut RunStats::default(), |_, s| {
        states.push(s.clone());
        Ok(())
    })
    .unwrap();
    assert_eq!(gpu.backend_name(), "gpu");
    (states, prep.plan.passes.clone())
}

/// A membrane whose grain is off the grid's axes, so that every coefficient is used.
const MEMBRANE: &str = "model = \"membrane\"\nwarp_stiffness_n_m = 300.0\n\
    weft_stiffness_n_m = 150.0\nshear_stiffness_n_m = 30.0\ngrain_deg = 30.0";

#[test]
fn textures_and_buffers_give_the_same_bits_for_every_stage() {
    let (Some(textures), Some(buffers)) =
        (device(ArrayLayout::Textures), device(ArrayLayout::Buffers))
    else {
        return;
    };
    assert_eq!(textures.report().array_layout.as_deref(), Some("textures"));
    assert_eq!(buffers.report().array_layout.as_deref(), Some("buffers"));
    // Between them these plans hold every stage (checked below): springs, bending, wind,
    // strain limit, symplectic and explicit integration; seams and self-collision; a body;
    // implicit Euler's Newton solve with contact; the membrane, explicit and implicit.
    let load = |path: &str| Scene::load(&fixture(path)).unwrap();
    let mut membrane = common::scene_with_fabric("scenes/hanging_cloth.toml", MEMBRANE);
    membrane.solver.integrator = 1; // symplectic: the explicit membrane stage
    let (per_vertex, once) = (HingeEvaluation::PerVertex, HingeEvaluation::Once);
    let cases = [
        ("flag_wind", load("scenes/flag_wind.toml"), 2, per_vertex),
        ("self_fold", load("scenes/self_fold.toml"), 4, once),
        (
            "drape_sphere",
            load("scenes/drape_sphere.toml"),
            3,
            per_vertex,
        ),
        ("skirt_sew", load("scenes/skirt_sew.toml"), 3, once),
        (
            "skirt_rotating_implicit",
            load("scenes/skirt_rotating_implicit.toml"),
            2,
            per_vertex,
        ),
        (
            "skirt_bias_cut",
            load("scenes/skirt_bias_cut.toml"),
            1,
            per_vertex,
        ),
        ("membrane sheet", membrane, 2, per_vertex),
    ];
    let mut covered = BTreeSet::from(["monitor"]); // the solver adds it to every plan
    for (path, scene, frames, hinges) in cases {
        let (a, passes) = run(&textures, &scene, frames, hinges);
        let (b, _) = run(&buffers, &scene, frames, hinges);
        covered.extend(passes.iter().map(|p| p.name()));
        // Same kernels, same arithmetic, same inputs: only where the bytes live differs, and
        // the compiler sees the same expressions once the loads are done (lavapipe, and the
        // NVIDIA H200's Vulkan driver, compile both to the same floating-point operations).
        // Any difference is a wrong index or a lost component in the rewrite, so the
        // comparison is exact.
        for (f, (a, b)) in a.iter().zip(&b).enumerate() {
            assert!(
                a.positions == b.positions && a.velocities == b.velocities,
                "{path}: frame {f} differs between the texture and the buffer layout"
            );
        }
    }
    let every: BTreeSet<_> = Pass::ALL.iter().map(|p| p.name()).collect();
    let missing: Vec<_> = every.difference(&covered).collect();
    assert!(missing.is_empty(), "no case runs {missing:?}");
}
