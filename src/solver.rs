//! What both backends offer the run loop: advance a batch of substeps, read the state back.

use crate::error::Error;
use crate::model::layout::SubstepParams;
use glam::{Vec2, Vec4};
use serde::Serialize;

/// Particle positions (w = inverse mass) and velocities, as read back at an output frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParticleState {
    /// xyz in m, w = inverse mass.
    pub positions: Vec<Vec4>,
    /// xyz in m/s.
    pub velocities: Vec<Vec4>,
}

/// Which device ran a simulation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AdapterReport {
    /// Adapter name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    pub name: String,
    /// Driver name.
    pub driver: String,
    /// Graphics API backend, e.g. "vulkan".
    pub backend: String,
    /// "cpu", "discrete_gpu", …
    pub device_type: String,
}

/// A simulation backend: the CPU reference path or the wgpu path.
pub trait Solver {
    /// "cpu" or "gpu".
    fn backend_name(&self) -> &'static str;
    /// The GPU adapter, if any.
    fn adapter(&self) -> Option<AdapterReport>;
    /// Runs one substep per entry of `steps`, in order (one submission on the GPU).
    fn advance(&mut self, steps: &[SubstepParams]) -> Result<(), Error>;
    /// Reads positions and velocities back.
    fn state(&mut self) -> Result<ParticleState, Error>;
    /// Replaces positions (w = inverse mass) and velocities, e.g. to release attachments.
    fn set_state(&mut self, state: &ParticleState);
    /// Replaces the run-constant parameters between frames (e.g. to switch gravity on).
    fn set_params(&mut self, params: &crate::model::layout::SimParams);
    /// Implicit Euler's relative residual in the last substep: the unbalanced force entering
    /// the last sweep over the cloth's weight (`None` for the explicit integrators).
    fn residual(&mut self) -> Result<Option<f32>, Error> {
        Ok(None)
    }
    /// Waits until submitted work has finished, without reading anything back (for timing).
    fn finish(&mut self) -> Result<(), Error> {
        Ok(())
    }
}

/// The relative residual of an implicit step from per-vertex (m²g², |f|²) pairs: the unbalanced
/// force entering the last sweep over the cloth's weight, ‖f‖/‖m·g‖ (0 without free vertices).
pub fn relative_residual(residual: &[Vec2]) -> f32 {
    let (weight, force) = residual.iter().fold((0.0f64, 0.0f64), |(w, f), r| {
        (w + r.x as f64, f + r.y as f64)
    });
    if weight > 0.0 {
        (force / weight).sqrt() as f32
    } else {
        0.0
    }
}
