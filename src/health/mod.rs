//! Whether a run can be trusted: its inputs' plausibility before it starts, its result's
//! (seams, the body, settling) when it ends, and the short block that reports both.

mod block;
pub mod inputs;
pub mod result;

pub use crate::metrics::ShowThrough;
pub use block::block;
pub use inputs::{input_warnings, scene_warnings};
pub use result::{last_frame, result_warnings, show_through};
