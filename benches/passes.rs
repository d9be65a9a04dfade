//! Criterion benches: each pass and a whole substep, CPU twin vs GPU, at 64², 128² and 256².
//! Both ways of evaluating hinges are measured on both backends (`HingeEvaluation`).
//! Throughput is in particle-substeps. GPU batches are one submission, timed to completion.
//! `WGPU_ADAPTER_NAME` picks the adapter (default: wgpu's choice, e.g. lavapipe on CI machines).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use drapekit::bench::{bench_model, bench_steps, cpu_description};
use drapekit::cpu::CpuSolver;
use drapekit::gpu::{AdapterChoice, GpuContext, GpuSolver};
use drapekit::plan::{HingeEvaluation, Pass};
use drapekit::solver::Solver;
use std::time::{Duration, Instant};

const SIZES: [u32; 3] = [64, 128, 256];
/// Substeps per timed batch for single passes, and for whole substeps (the README's figure).
const PASS_BATCH: u32 = 10;
const SUBSTEP_BATCH: u32 = 100;

fn gpu_context() -> Option<GpuContext> {
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
            eprintln!("no GPU adapter ({e}); benchmarking the CPU twin only");
            None
        }
    }
}

/// Each pass of the bench cloth alone (the passes of both ways of evaluating hinges: per vertex,
/// `bending_forces`, and once per hinge, `hinge_forces` with `integrate` gathering), on both
/// backends, so that each way is measured on each.
fn per_pass(c: &mut Criterion) {
    eprintln!("CPU: {}", cpu_description());
    let ctx = gpu_context();
    let passes = [
        (Pass::HingeForces, HingeEvaluation::Once),
        (Pass::SpringForces, HingeEvaluation::Once),
        (Pass::BendingForces, HingeEvaluation::PerVertex),
        (Pass::Integrate, HingeEvaluation::Once),
    ];
    for (pass, hinges) in passes {
        let mut group = c.benchmark_group(pass.name());
        group
            .sample_size(10)
            .measurement_time(Duration::from_secs(3));
        for n in SIZES {
            let (model, params, plan) = bench_model(n);
            let plan = plan.with_hinges(hinges);
            let steps = bench_steps(PASS_BATCH, params.dt);
            group.throughput(Throughput::Elements(model.len() as u64 * PASS_BATCH as u64));
            let mut cpu = CpuSolver::new(&model, params, &plan);
            group.bench_function(BenchmarkId::new("cpu", format!("{n}x{n}")), |b| {
                b.iter(|| {
                    for s in &steps {
                        cpu.run_pass(pass, s);
                    }
                })
            });
            if let Some(ctx) = &ctx {
                let mut gpu =
                    GpuSolver::new(ctx, &model, params, &plan, PASS_BATCH as usize).unwrap();
                group.bench_function(BenchmarkId::new("gpu", format!("{n}x{n}")), |b| {
                    b.iter_custom(|iters| {
                        let start = Instant::now();
                        for _ in 0..iters {
                            gpu.run_passes(&[pass], &steps).unwrap();
                            gpu.finish().unwrap();
                        }
                        start.elapsed()
                    })
                });
            }
        }
        group.finish();
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
            let mut cpu = CpuSolver::new(&model, params, &plan);
            let id = BenchmarkId::new(format!("cpu/{way}"), format!("{n}x{n}"));
            group.bench_function(id, |b| b.iter(|| cpu.advance(&steps).unwrap()));
            if let Some(ctx) = &ctx {
                let mut gpu =
                    GpuSolver::new(ctx, &model, params, &plan, SUBSTEP_BATCH as usize).unwrap();
                let id = BenchmarkId::new(format!("gpu/{way}"), format!("{n}x{n}"));
                group.bench_function(id, |b| {
                    b.iter_custom(|iters| {
                        let start = Instant::now();
                        for _ in 0..iters {
                            gpu.advance(&steps).unwrap();
                            gpu.finish().unwrap();
                        }
                        start.elapsed()
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
    let fabric = Fabric {
        density: 0.2,
        stretch_stiffness: 500.0,
        bending_stiffness: Some(1e-5),
        damping_ratio: 0.05,
    };
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
