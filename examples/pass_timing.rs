use drapekit::bench::{bench_model, bench_steps};
use drapekit::cpu::CpuSolver;
use drapekit::gpu::{AdapterChoice, GpuContext, GpuSolver};
use drapekit::solver::Solver;
use std::time::Instant;
fn main() {
    let n: u32 = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(128);
    let ctx = GpuContext::new(&AdapterChoice::Fallback).unwrap();
    let (model, params, plan) = bench_model(n);
    let steps = bench_steps(50, params.dt);
    let mut gpu = GpuSolver::new(&ctx, &model, params, &plan, 50).unwrap();
    let mut cpu = CpuSolver::new(&model, params, &plan);
    for &pass in &plan.passes {
        gpu.run_passes(&[pass], &steps).unwrap();
        gpu.finish().unwrap();
        let t = Instant::now();
        gpu.run_passes(&[pass], &steps).unwrap();
        gpu.finish().unwrap();
        let g = t.elapsed().as_secs_f64() / 50.0;
        let t = Instant::now();
        for s in &steps {
            cpu.run_pass(pass, s);
        }
        let c = t.elapsed().as_secs_f64() / 50.0;
        println!(
            "{:>15}: gpu {:8.3} ms  cpu {:8.3} ms",
            pass.name(),
            g * 1e3,
            c * 1e3
        );
    }
}
