//! CPU time per particle-substep of each stage and of whole substeps, for both ways of
//! evaluating hinges on both backends: `cargo bench --bench cpu_time [-- SIZE ...]`.
//!
//! Criterion's wall-clock figures swing by 2× on a machine shared with other builds; the CPU
//! time a process spends (the CPU twin on one thread, or lavapipe's worker threads) swings far
//! less, so this is what decides which way each backend evaluates hinges. It is read from
//! `/proc/self/task/*/schedstat` (Linux; nanoseconds on a CPU, summed over the process's
//! threads). The kernel brings a running thread's figure up to date at each scheduler tick (a
//! few ms), so each timed window repeats the batch for at least `WINDOW_S`, and each figure is
//! the minimum over `REPEATS` windows.

use drapekit::bench::{bench_model, bench_steps, cpu_description};
use drapekit::cpu::CpuSolver;
use drapekit::gpu::{AdapterChoice, GpuContext, GpuSolver};
use drapekit::plan::{HingeEvaluation, Pass, PassPlan};
use drapekit::solver::Solver;
use std::time::Instant;

/// Substeps per batch, the shortest timed window (a tick is at most 10 ms: at most 2.5% of the
/// window per thread), and windows (the minimum is kept).
const BATCH: u32 = 10;
const WINDOW_S: f64 = 0.4;
const REPEATS: usize = 5;

/// Nanoseconds this process's threads have run on a CPU.
fn process_cpu_ns() -> u64 {
    let tasks = std::fs::read_dir("/proc/self/task").expect("/proc/self/task (Linux only)");
    tasks
        .filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .sum()
}

/// (CPU ns, wall ns) per particle-substep of the fastest of `REPEATS` windows of `work`.
fn measure(particle_substeps: f64, mut work: impl FnMut()) -> (f64, f64) {
    // Warm caches and pipelines, and find how many batches fill a window.
    let start = Instant::now();
    work();
    let batches = (WINDOW_S / start.elapsed().as_secs_f64()).ceil().max(1.0) as usize;
    let (mut cpu, mut wall) = (f64::MAX, f64::MAX);
    for _ in 0..REPEATS {
        let (c, w) = (process_cpu_ns(), Instant::now());
        (0..batches).for_each(|_| work());
        let w = w.elapsed().as_nanos() as f64;
        let c = (process_cpu_ns() - c) as f64;
        let work = particle_substeps * batches as f64;
        cpu = cpu.min(c / work);
        wall = wall.min(w / work);
    }
    (cpu, wall)
}

/// The stages of `plan` alone, then whole substeps, on `solver`; one table row each.
fn rows(
    n: u32,
    backend: &str,
    how: HingeEvaluation,
    plan: &PassPlan,
    run: &mut dyn FnMut(Option<Pass>),
    particles: usize,
) {
    let work = particles as f64 * BATCH as f64;
    let stages = plan.passes.iter().map(|&p| Some(p)).chain([None]);
    for pass in stages {
        let (cpu, wall) = measure(work, || run(pass));
        let name = pass.map_or("whole substep", |p| p.name());
        println!("| {n}² | {backend} | {how:?} | {name} | {cpu:.1} | {wall:.1} |");
    }
}

fn main() {
    let sizes: Vec<u32> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let sizes = if sizes.is_empty() {
        vec![64, 128, 256]
    } else {
        sizes
    };
    let ctx = GpuContext::new(&AdapterChoice::Fallback).ok();
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    println!("CPU: {}; CPU twin on 1 thread", cpu_description());
    match &ctx {
        Some(ctx) => {
            let a = ctx.report();
            println!(
                "GPU: {} ({}, {}, {})",
                a.name, a.driver, a.backend, a.device_type
            );
        }
        None => println!("GPU: no fallback adapter, CPU only"),
    }
    println!(
        "\nns per particle-substep, minimum of {REPEATS} windows of at least {WINDOW_S} s \
         (batches of {BATCH} substeps)"
    );
    println!("\n| grid | backend | hinges | stage | CPU time | wall |\n|---|---|---|---|---|---|");
    for n in sizes {
        let (model, params, plan) = bench_model(n);
        let steps = bench_steps(BATCH, params.dt);
        for how in [HingeEvaluation::Once, HingeEvaluation::PerVertex] {
            let plan = plan.with_hinges(how);
            let mut cpu = CpuSolver::new(&model, params, &plan);
            one_thread.install(|| {
                let mut run = |pass: Option<Pass>| match pass {
                    Some(p) => steps.iter().for_each(|s| cpu.run_pass(p, s)),
                    None => cpu.advance(&steps).expect("CPU substeps"),
                };
                rows(n, "cpu", how, &plan, &mut run, model.len());
            });
            if let Some(ctx) = &ctx {
                let mut gpu =
                    GpuSolver::new(ctx, &model, params, &plan, BATCH as usize).expect("GPU solver");
                let mut run = |pass: Option<Pass>| {
                    match pass {
                        Some(p) => gpu.run_passes(&[p], &steps),
                        None => gpu.advance(&steps),
                    }
                    .and_then(|_| gpu.finish())
                    .expect("GPU substeps")
                };
                rows(n, "gpu", how, &plan, &mut run, model.len());
            }
        }
    }
}
