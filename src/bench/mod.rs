//! `drapekit bench …`: what drapekit costs, measured by drapekit itself, as CSV and Markdown
//! tables and SVG plots that anyone reproduces with one command.
//!
//! - [`grid`]: whole substeps of the benchmark cloth at several sizes, on both backends;
//! - [`integrators`]: one scene under symplectic and implicit Euler, on both backends;
//! - [`accuracy`]: what accuracy costs in time, knob by knob, against a fine reference;
//! - [`collision`]: every contact strategy on a skirt on a turning body, at three sizes;
//! - [`convergence`]: implicit Euler's force residual against cost, plain sweeps against
//!   Newton steps with a multigrid preconditioner, at three particle spacings;
//!   [`fas`] is the nonlinear multigrid (FAS) it measures beside them;
//! - [`effects`]: what each optional effect costs per substep, on both backends;
//! - [`fabric`]: the fabric presets in the Cusick drape and cantilever bending tests, against
//!   published values;
//! - [`profile`]: where a substep's GPU time goes, stage by stage, from GPU timestamps;
//! - [`peer`]: drapekit beside NVIDIA Warp's cloth benchmark and Newton's cloth solvers, on
//!   Warp's benchmark cloth ([`warp_cloth`]), through a Python driver ([`python_peer`]).

pub mod accuracy;
pub mod collision;
pub mod convergence;
pub mod effects;
pub mod fabric;
pub mod fas;
mod fas_levels;
pub mod grid;
pub mod integrators;
mod measured_state;
pub mod peer;
mod peer_report;
pub mod profile;
pub mod python_peer;
pub mod warp_cloth;

pub use peer_report::CSV_HEADER as PEER_CSV_HEADER;

pub use grid::{bench_model, bench_steps, BenchRow};

use crate::error::Error;
use crate::gpu::{AdapterChoice, GpuContext};
use crate::run::BackendChoice;

/// The CPU's model name and core count, from /proc/cpuinfo where available.
pub fn cpu_description() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    format!("{model}, {cores} cores")
}

/// The path a benchmark runs on, from `--backend` and `--adapter` as `drapekit run` reads them
/// (auto: a hardware GPU if there is one, a software adapter only when asked for by name, else
/// the CPU), and its description for the report.
pub fn choose_device(
    choice: BackendChoice,
    adapter: &AdapterChoice,
) -> Result<(Option<GpuContext>, String), Error> {
    let cpu = |why: &str| {
        (
            None,
            format!("the CPU twin ({}){why}", cpu_threads_description()),
        )
    };
    let gpu = |ctx: GpuContext| {
        let d = ctx.report().describe();
        (Some(ctx), d)
    };
    Ok(match choice {
        BackendChoice::Cpu => cpu(""),
        BackendChoice::Gpu => gpu(GpuContext::new(adapter)?),
        BackendChoice::Auto => match GpuContext::new(adapter) {
            Ok(ctx) if !ctx.is_software() || crate::run::adapter_named(adapter) => gpu(ctx),
            // Said in the report, so that a misspelt adapter is not a silent CPU run.
            Ok(ctx) => cpu(&format!(
                " (--backend auto: {} is a software adapter; name it with --adapter to use it)",
                ctx.report().describe()
            )),
            Err(e) => cpu(&format!(" (--backend auto: no GPU: {e})")),
        },
    })
}

/// The CPU and the rayon threads the CPU twin runs on (`--threads`).
pub fn cpu_threads_description() -> String {
    let n = rayon::current_num_threads();
    format!(
        "{}, {n} thread{}",
        cpu_description(),
        if n == 1 { "" } else { "s" }
    )
}
