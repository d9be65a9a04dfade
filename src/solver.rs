//! What both backends offer the run loop: advance a batch of substeps, read the state back.

use crate::error::Error;
use crate::model::layout::SubstepParams;
use crate::model::layout::VBD_STEP_FLOOR;
use glam::Vec4;
use serde::Serialize;

/// Particle positions (w = inverse mass) and velocities, as read back at an output frame.
///
/// ```
/// use drapekit::solver::ParticleState;
/// use glam::Vec4;
///
/// // Two particles: a free one of 0.5 kg (w = 1/m = 2) moving at 3 m/s, and a pinned one (w = 0).
/// let state = ParticleState {
///     positions: vec![Vec4::new(0.0, 1.0, 0.0, 2.0), Vec4::new(0.1, 1.0, 0.0, 0.0)],
///     velocities: vec![Vec4::new(0.0, -3.0, 0.0, 0.0), Vec4::ZERO],
/// };
/// let kinetic: f32 = (state.positions.iter().zip(&state.velocities))
///     .filter(|(p, _)| p.w > 0.0)
///     .map(|(p, v)| 0.5 / p.w * v.truncate().length_squared())
///     .sum();
/// assert_eq!(kinetic, 2.25); // ½ · 0.5 kg · (3 m/s)²
/// ```
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
    /// Where the kernels' arrays live on an opened device: "textures" or "buffers".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub array_layout: Option<String>,
}

impl AdapterReport {
    /// One line for reports: name, driver, API backend, device type and array layout.
    pub fn describe(&self) -> String {
        let layout = (self.array_layout.as_ref()).map_or(String::new(), |l| format!(", {l}"));
        format!(
            "{} (driver {}, {}, device type {}{layout})",
            self.name, self.driver, self.backend, self.device_type
        )
    }
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
    /// Reads the positions back (w = inverse mass), without the velocities.
    fn positions(&mut self) -> Result<Vec<glam::Vec4>, Error> {
        Ok(self.state()?.positions)
    }
    /// Replaces positions (w = inverse mass) and velocities, e.g. to release attachments.
    fn set_state(&mut self, state: &ParticleState);
    /// Replaces the run-constant parameters between frames (e.g. to switch gravity on).
    fn set_params(&mut self, params: &crate::model::layout::SimParams);
    /// The current state's health (the `monitor` stage): kinetic energy, largest speed and
    /// strain, non-finite particles. Reads back 32 bytes per 64 particles.
    fn health(&mut self) -> Result<Health, Error>;
    /// What implicit Euler's solve did: its relative residual in the last substep, and the
    /// iterations it ran since the last call (`None` for the explicit integrators).
    fn residual(&mut self) -> Result<Option<SolveProgress>, Error> {
        Ok(None)
    }
    /// Waits until submitted work has finished, without reading anything back (for timing).
    fn finish(&mut self) -> Result<(), Error> {
        Ok(())
    }
}

/// What implicit Euler's solve did, as `Solver::residual` reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveProgress {
    /// The last substep's relative residual (see `relative_residual`).
    pub relative_residual: f32,
    /// Iterations (sweeps over every colour) run since the previous report.
    pub iterations: u64,
    /// Newton steps run since the previous report (0 without coarse levels).
    pub newton_steps: u64,
    /// The last substep's force residual |f|/(m·g) over the free particles at its end:
    /// largest and RMS.
    pub force_residual: (f32, f32),
}

/// The relative residual of a substep from the largest Newton step of each sweep: that of the
/// last sweep run over that of the first (a step under `VBD_STEP_FLOOR` counts as the floor,
/// so a cloth at rest reads ≈ 0, not 0/0). The Newton step is the residual force
/// preconditioned by each vertex's Hessian, so it is in metres whatever the stiffness. Sweeps
/// a converged substep skipped record nothing and do not count.
pub fn relative_residual(steps: &[f32]) -> f32 {
    let Some(last) = steps.iter().rposition(|&s| s > 0.0) else {
        return 0.0;
    };
    steps[last].max(VBD_STEP_FLOOR) / steps[0].max(VBD_STEP_FLOOR)
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
