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
    /// The current state's health (the `monitor` stage): kinetic energy, largest speed and
    /// strain, non-finite particles. Reads back 32 bytes per 64 particles.
    fn health(&mut self) -> Result<Health, Error>;
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

/// One workgroup's (or block's) share of a frame's health.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HealthPartial {
    /// Σ ½m|v|² over free finite particles, in J.
    pub kinetic_energy: f32,
    /// Σ −m·g·x over free finite particles (gravity as set now), in J.
    pub gravity_energy: f32,
    /// Σ ½k(l − L)² of the springs, each seen from both ends at a half share, in J.
    pub elastic_energy: f32,
    /// Largest |v| in m/s.
    pub max_speed: f32,
    /// Largest (|d| − L)/L of the particles' springs (−1 with no springs).
    pub max_strain: f32,
    /// The particle with that strain.
    pub worst: u32,
    /// Particles with a non-finite position or velocity.
    pub non_finite: u32,
    /// The first of them (`u32::MAX` when none).
    pub first_non_finite: u32,
}

/// A frame's health: the partials reduced over blocks (in f64 for the energy).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Health {
    /// Kinetic energy of the free particles, in J.
    pub kinetic_energy: f64,
    /// Gravitational energy −Σ m·g·x of the free particles, in J (zero while gravity is off).
    pub gravity_energy: f64,
    /// Elastic energy of the stretch springs, in J.
    pub elastic_energy: f64,
    /// Largest particle speed, in m/s.
    pub max_speed: f32,
    /// Largest spring strain (0.1 = 10%).
    pub max_strain: f32,
    /// The particle with the largest strain.
    pub worst: u32,
    /// Particles with a non-finite position or velocity.
    pub non_finite: u32,
    /// The first of them.
    pub first_non_finite: Option<u32>,
}

impl Health {
    /// Finishes the reduction on the host, as both backends do.
    pub fn from_partials(partials: &[HealthPartial]) -> Health {
        let mut h = Health {
            kinetic_energy: 0.0,
            gravity_energy: 0.0,
            elastic_energy: 0.0,
            max_speed: 0.0,
            max_strain: -1.0,
            worst: 0,
            non_finite: 0,
            first_non_finite: None,
        };
        for p in partials {
            h.kinetic_energy += p.kinetic_energy as f64;
            h.gravity_energy += p.gravity_energy as f64;
            h.elastic_energy += p.elastic_energy as f64;
            h.max_speed = h.max_speed.max(p.max_speed);
            if p.max_strain > h.max_strain {
                h.max_strain = p.max_strain;
                h.worst = p.worst;
            }
            h.non_finite += p.non_finite;
            if p.first_non_finite != u32::MAX {
                let f = h
                    .first_non_finite
                    .map_or(p.first_non_finite, |f| f.min(p.first_non_finite));
                h.first_non_finite = Some(f);
            }
        }
        h
    }
}
