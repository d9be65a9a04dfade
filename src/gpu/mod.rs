//! The wgpu path: shared layouts, adapter choice, kernel composition and the solver.

mod context;
pub mod kernels;
pub mod layout;
mod solver;
mod texels;

pub use context::{AdapterChoice, GpuContext};
pub use solver::GpuSolver;
