//! drapekit: a cloth and garment solver whose simulation runs as WGSL compute passes on wgpu,
//! with a plain-Rust twin of every pass as the reference.
//!
//! The data path: [`scene::Scene`] → [`model::ClothModel`] → [`plan::PassPlan`] →
//! a [`solver::Solver`] ([`gpu::GpuSolver`] or [`cpu::CpuSolver`]) → frames and a summary.
//!
//! Modules form layers that import only downward (docs/src/architecture.md): ground
//! (`error`, `check`, `atomic_file`, `suggest`, `toml_message`, `progress`) → geometry (`mesh`, `pattern`, `body`) → `scene` →
//! `model` → `plan` and `solver` → backends (`cpu`, `gpu`) and `metrics` → `sim` → outputs
//! (`run`, `run_folder`, `output`, `health`, `export`, `bench`, `plot`, `batch`) → the CLI.
#![warn(missing_docs)]

pub mod atomic_file;
pub mod batch;
pub mod bench;
pub mod body;
pub mod check;
pub mod checkpoint;
pub mod cpu;
pub mod error;
pub mod export;
pub mod glb;
pub mod gpu;
pub mod health;
pub mod mesh;
pub mod metrics;
pub mod model;
pub mod notice;
pub mod output;
pub mod pattern;
pub mod plan;
pub mod plot;
pub mod preview;
pub mod progress;
pub mod run;
pub mod run_folder;
pub mod scene;
pub mod sim;
pub mod solver;
pub mod suggest;
pub mod toml_message;

pub use error::{Error, InputError};
