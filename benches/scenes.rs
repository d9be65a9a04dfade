//! Criterion benches: whole substeps of every shipped scene (`fixtures/scenes/*.toml`), as
//! `drapekit run` prepares it (its plan, substep and body), on the CPU path and the GPU path.
//! Each iteration runs a batch of the scene's first-frame substeps (at most `BATCH`; one
//! submission on the GPU, timed to completion). Throughput is in particle-substeps.
//! A filter runs a subset: `cargo bench --bench scenes -- drape_sphere`.

mod common;

use common::{cpu_solver, first_substeps, gpu_context, gpu_solver, prepared, timed};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use drapekit::solver::Solver;
use std::time::Duration;

/// Substeps per timed batch: a frame of most scenes, a part of a frame of the stiff ones.
const BATCH: usize = 10;

/// The shipped scenes, by file name, sorted.
fn scene_names() -> Vec<String> {
    let dir = common::scene_path("");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    names.sort();
    names
}

fn scenes(c: &mut Criterion) {
    let ctx = gpu_context();
    let mut group = c.benchmark_group("scene");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(3))
        .warm_up_time(Duration::from_millis(500));
    for name in scene_names() {
        let stem = name.trim_end_matches(".toml").to_string();
        let prep = prepared(&name, |_| {});
        let batch = BATCH.min(prep.substeps as usize).max(1);
        let steps = first_substeps(&prep, batch);
        eprintln!(
            "{stem}: {} particles, {} substeps per frame, passes {:?}",
            prep.model.len(),
            prep.substeps,
            prep.plan.names()
        );
        group.throughput(Throughput::Elements((prep.model.len() * batch) as u64));
        let mut cpu = None;
        group.bench_function(BenchmarkId::new("cpu", &stem), |b| {
            let cpu = cpu.get_or_insert_with(|| cpu_solver(&prep));
            b.iter(|| cpu.advance(&steps).unwrap())
        });
        if let Some(ctx) = &ctx {
            let mut gpu = None;
            group.bench_function(BenchmarkId::new("gpu", &stem), |b| {
                let gpu = gpu.get_or_insert_with(|| gpu_solver(ctx, &prep, batch));
                b.iter_custom(|iters| {
                    timed(iters, || {
                        gpu.advance(&steps).unwrap();
                        gpu.finish().unwrap();
                    })
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, scenes);
criterion_main!(benches);
