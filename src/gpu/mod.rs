//! The wgpu path: adapter choice, kernel composition and the solver.

mod array_layout;
mod context;
mod elements;
mod encode;
pub mod implicit;
pub mod kernels;
mod pipelines;
pub mod profile;
mod readback;
mod solver;
mod texels;

pub use array_layout::ArrayLayout;
pub use context::{adapters, AdapterChoice, AdapterList, GpuContext};
pub use readback::HashTables;
pub use solver::GpuSolver;
