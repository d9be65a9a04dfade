//! Criterion benches: every pass, CPU path against GPU path, at three sizes, on shipped scenes
//! that have the pass (the benchmark cloth alone has no body, seams, wind or self-collision).
//! Both ways of evaluating hinges are measured on both backends (`HingeEvaluation`).
//! Throughput is in particle-substeps. GPU batches are one submission, timed to completion.
//! `WGPU_ADAPTER_NAME` picks the adapter (default: wgpu's choice, e.g. lavapipe on CI
//! machines). A filter runs a subset: `cargo bench --bench passes -- vbd_solve/cpu`.
//!
//! Bench ids are `<pass>/<backend>/<fixture>-<size>`, e.g. `collide_body/gpu/drape_sphere-128x128`.

mod common;

use common::{cpu_solver, first_substeps, gpu_context, gpu_solver, prepared, timed};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use drapekit::bench::{bench_model, bench_steps};
use drapekit::model::layout::INTEGRATOR_IMPLICIT;
use drapekit::plan::{HingeEvaluation, Pass};
use drapekit::scene::{ClothSource, Scene, SelfCollision};
use drapekit::sim::Prepared;
use drapekit::solver::Solver;
use std::time::{Duration, Instant};

/// Grid sides of the grid scenes.
const SIZES: [u32; 3] = [64, 128, 256];
/// Particle spacings in m of the pattern scene (its shipped 0.02 m, then finer).
const SPACINGS: [f64; 3] = [0.02, 0.01, 0.005];
/// Substeps per timed batch for single passes, and for whole substeps (the book's figure).
const PASS_BATCH: u32 = 10;
const SUBSTEP_BATCH: u32 = 100;

/// A scene at three sizes and the passes it is benchmarked for.
struct Fixture {
    /// The shipped scene.
    scene: &'static str,
    /// Short name in bench ids.
    label: &'static str,
    /// The passes timed on it (each in its plan).
    passes: &'static [Pass],
    /// How the scene takes its three sizes.
    resize: Resize,
    /// Further changes (integrator, self-collision).
    edit: fn(&mut Scene),
    /// How hinges are evaluated, where the fixture fixes it (`None`: as each backend prefers).
    hinges: Option<HingeEvaluation>,
}

/// How a fixture scene takes size index 0, 1 or 2.
#[derive(Clone, Copy, PartialEq)]
enum Resize {
    /// A grid scene: `SIZES[i]` particles along each side.
    Grid,
    /// A pattern scene: particles `SPACINGS[i]` apart.
    Spacing,
}

fn resize(scene: &mut Scene, how: Resize, size: usize) {
    match (&mut scene.cloth, how) {
        (ClothSource::Grid { columns, rows, .. }, Resize::Grid) => {
            (*columns, *rows) = (SIZES[size], SIZES[size]);
        }
        (ClothSource::Pattern { options, .. }, Resize::Spacing) => {
            options.particle_distance = SPACINGS[size];
        }
        _ => panic!("{}: cannot resize this cloth", scene.path.display()),
    }
}

fn unchanged(_: &mut Scene) {}

fn implicit(scene: &mut Scene) {
    scene.solver.integrator = INTEGRATOR_IMPLICIT;
    scene.solver.substeps = None;
}

fn self_collision(scene: &mut Scene) {
    scene.self_collision = Some(SelfCollision {
        thickness: None,
        buckets: None,
        cpu_point_triangle: false,
    });
}

const FIXTURES: [Fixture; 7] = [
    Fixture {
        scene: "hanging_cloth.toml",
        label: "hanging_cloth",
        passes: &[
            Pass::SpringForces,
            Pass::BendingForces,
            Pass::Integrate,
            Pass::StrainLimit,
            Pass::Monitor,
        ],
        resize: Resize::Grid,
        edit: unchanged,
        hinges: Some(HingeEvaluation::PerVertex),
    },
    Fixture {
        scene: "hanging_cloth.toml",
        label: "hanging_cloth_once",
        // `integrate` here also gathers the forces `hinge_forces` wrote.
        passes: &[Pass::HingeForces, Pass::Integrate],
        resize: Resize::Grid,
        edit: unchanged,
        hinges: Some(HingeEvaluation::Once),
    },
    Fixture {
        scene: "hanging_cloth.toml",
        label: "hanging_cloth_implicit",
        passes: &[Pass::VbdInit, Pass::VbdSolve, Pass::VbdFinish],
        resize: Resize::Grid,
        edit: implicit,
        hinges: None,
    },
    Fixture {
        scene: "flag_wind.toml",
        label: "flag_wind",
        passes: &[Pass::WindForces],
        resize: Resize::Grid,
        edit: unchanged,
        hinges: None,
    },
    Fixture {
        scene: "drape_sphere.toml",
        label: "drape_sphere",
        passes: &[Pass::CollideBody],
        resize: Resize::Grid,
        edit: unchanged,
        hinges: None,
    },
    Fixture {
        scene: "drape_sphere.toml",
        label: "drape_sphere_self",
        passes: &[
            Pass::HashClear,
            Pass::HashCount,
            Pass::HashScan,
            Pass::HashFill,
            Pass::SelfCollide,
        ],
        resize: Resize::Grid,
        edit: self_collision,
        hinges: None,
    },
    Fixture {
        scene: "skirt_sew.toml",
        label: "skirt_sew",
        passes: &[Pass::SeamForces],
        resize: Resize::Spacing,
        edit: unchanged,
        hinges: None,
    },
];

/// The fixture at size `size`. Its solvers are advanced by one output frame (the GPU's by
/// one batch) before timing, so that the passes see a moving cloth rather than the rest state.
fn fixture_at(f: &Fixture, size: usize) -> Prepared {
    let mut prep = prepared(f.scene, |s| {
        resize(s, f.resize, size);
        (f.edit)(s);
    });
    if let Some(how) = f.hinges {
        prep.plan = prep.plan.with_hinges(how);
    }
    prep
}

fn size_label(f: &Fixture, size: usize, particles: usize) -> String {
    if f.resize == Resize::Grid {
        format!("{}-{}x{}", f.label, SIZES[size], SIZES[size])
    } else {
        format!("{}-{}p", f.label, particles)
    }
}

/// The stages that must run before `pass`, every substep, for its input to be valid: the
/// spatial hash is rebuilt from cleared counts (a stage repeated on its own would overflow the
/// buckets it fills).
fn prerequisites(pass: Pass) -> &'static [Pass] {
    const CHAIN: [Pass; 4] = [
        Pass::HashClear,
        Pass::HashCount,
        Pass::HashScan,
        Pass::HashFill,
    ];
    match pass {
        Pass::HashCount => &CHAIN[..1],
        Pass::HashScan => &CHAIN[..2],
        Pass::HashFill => &CHAIN[..3],
        Pass::SelfCollide => &CHAIN[..4],
        _ => &[],
    }
}

/// Each pass of the bench cloth alone (the passes of both ways of evaluating hinges: per vertex,
/// `bending_forces`, and once per hinge, `hinge_forces` with `integrate` gathering), on both
/// backends, so that each way is measured on each.
fn per_pass(c: &mut Criterion) {
    let ctx = gpu_context();
    for f in &FIXTURES {
        for size in 0..3 {
            let prep = fixture_at(f, size);
            let n = prep.model.len();
            let id = size_label(f, size, n);
            for &pass in f.passes {
                assert!(
                    pass == Pass::Monitor || prep.plan.contains(pass),
                    "{id}: {} is not in the plan {:?}",
                    pass.name(),
                    prep.plan.names()
                );
            }
            let steps = first_substeps(&prep, PASS_BATCH as usize);
            // Solvers are built on first use, so that a filtered run builds only what it times.
            let mut cpu = None;
            let mut gpu = None;
            for &pass in f.passes {
                let mut group = c.benchmark_group(pass.name());
                group
                    .sample_size(10)
                    .measurement_time(Duration::from_secs(2))
                    .warm_up_time(Duration::from_millis(500));
                // The monitor runs once per output frame, not per substep: one per iteration.
                let batch = if pass == Pass::Monitor { 1 } else { PASS_BATCH };
                group.throughput(Throughput::Elements(n as u64 * batch as u64));
                let pre = prerequisites(pass);
                group.bench_function(BenchmarkId::new("cpu", &id), |b| {
                    let cpu = cpu.get_or_insert_with(|| {
                        let mut solver = cpu_solver(&prep);
                        solver
                            .advance(&first_substeps(&prep, prep.substeps as usize))
                            .unwrap();
                        solver
                    });
                    if pass == Pass::Monitor {
                        return b.iter(|| std::hint::black_box(cpu.health_partials()));
                    }
                    // Each substep runs the stage's prerequisites untimed, then the stage.
                    b.iter_custom(|iters| {
                        let mut total = Duration::ZERO;
                        for _ in 0..iters {
                            for s in &steps {
                                for &p in pre {
                                    cpu.run_pass(p, s);
                                }
                                let start = Instant::now();
                                cpu.run_pass(pass, s);
                                total += start.elapsed();
                            }
                        }
                        total
                    })
                });
                if let Some(ctx) = &ctx {
                    let steps = &steps[..batch as usize];
                    let chain: Vec<Pass> = pre.iter().copied().chain([pass]).collect();
                    group.bench_function(BenchmarkId::new("gpu", &id), |b| {
                        let gpu = gpu.get_or_insert_with(|| {
                            let mut solver = gpu_solver(ctx, &prep, PASS_BATCH as usize);
                            solver
                                .advance(&first_substeps(&prep, PASS_BATCH as usize))
                                .unwrap();
                            solver
                        });
                        // One submission per batch; with prerequisites, the chain with the
                        // stage minus the chain without it.
                        b.iter_custom(|iters| {
                            let mut run = |passes: &[Pass]| {
                                timed(iters, || {
                                    gpu.run_passes(passes, steps).unwrap();
                                    gpu.finish().unwrap();
                                })
                            };
                            let full = run(&chain);
                            if pre.is_empty() {
                                full
                            } else {
                                // Floored at 1 ns where noise exceeds the stage's cost.
                                full.saturating_sub(run(pre)).max(Duration::from_nanos(1))
                            }
                        })
                    });
                }
                group.finish();
            }
        }
    }
}

/// Whole substeps, each way of evaluating hinges on each backend (`cpu/once` and
/// `gpu/per_vertex` are what the backends run by default).
fn whole_substep(c: &mut Criterion) {
    let ctx = gpu_context();
    let mut group = c.benchmark_group("substep");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    for n in SIZES {
        let (model, params, plan) = bench_model(n);
        let steps = bench_steps(SUBSTEP_BATCH, params.dt);
        group.throughput(Throughput::Elements(
            model.len() as u64 * SUBSTEP_BATCH as u64,
        ));
        for (hinges, way) in [
            (HingeEvaluation::Once, "once"),
            (HingeEvaluation::PerVertex, "per_vertex"),
        ] {
            let plan = plan.with_hinges(hinges);
            let mut cpu = drapekit::cpu::CpuSolver::new(&model, params, &plan);
            let id = BenchmarkId::new(format!("cpu/{way}"), format!("{n}x{n}"));
            group.bench_function(id, |b| b.iter(|| cpu.advance(&steps).unwrap()));
            if let Some(ctx) = &ctx {
                let mut gpu = drapekit::gpu::GpuSolver::new(
                    ctx,
                    &model,
                    params,
                    &plan,
                    SUBSTEP_BATCH as usize,
                )
                .unwrap();
                let id = BenchmarkId::new(format!("gpu/{way}"), format!("{n}x{n}"));
                group.bench_function(id, |b| {
                    b.iter_custom(|iters| {
                        timed(iters, || {
                            gpu.advance(&steps).unwrap();
                            gpu.finish().unwrap();
                        })
                    })
                });
            }
        }
    }
    group.finish();
}

/// Model building (mesh edges, springs, hinges) per particle: linear in the particle count when
/// the time per element stays flat from 256² to 1024² (Throughput: particles).
fn model_build(c: &mut Criterion) {
    use drapekit::mesh::{GridPlane, TriMesh};
    use drapekit::model::ClothModel;
    use drapekit::scene::Fabric;
    let mut group = c.benchmark_group("model_build");
    group.sample_size(10);
    let fabric = Fabric::linear(500.0);
    for n in [256u32, 1024] {
        let origin = glam::Vec3::new(0.0, 1.0, 0.0);
        let mesh = TriMesh::grid(1.0, 1.0, n, n, origin, GridPlane::Xy);
        group.throughput(Throughput::Elements((n * n) as u64));
        group.bench_function(BenchmarkId::new("from_mesh", format!("{n}x{n}")), |b| {
            b.iter(|| ClothModel::from_mesh(&mesh, &fabric, &[]))
        });
    }
    group.finish();
}

criterion_group!(benches, per_pass, whole_substep, model_build);
criterion_main!(benches);
