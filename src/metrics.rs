//! Measurements on a read-back state; the same code serves both backends.

use crate::model::{ClothModel, Spring};
use crate::solver::ParticleState;
use glam::Vec4;

/// Kinetic energy ½·Σm·v² of the free particles, in J (summed in f64).
pub fn kinetic_energy(model: &ClothModel, state: &ParticleState) -> f64 {
    (0..model.len())
        .filter(|&i| !model.pinned[i])
        .map(|i| {
            0.5 * model.masses[i] as f64 * state.velocities[i].truncate().length_squared() as f64
        })
        .sum()
}

/// Largest relative stretch (L − L0)/L0 over all springs.
pub fn max_edge_strain(positions: &[Vec4], springs: &[Spring]) -> f32 {
    springs
        .iter()
        .map(|s| {
            let [a, b] = s.ends.map(|i| positions[i as usize].truncate());
            (a.distance(b) - s.rest_length) / s.rest_length
        })
        .fold(0.0, f32::max)
}

/// The first particle with a non-finite position or velocity, and which of the two.
pub fn first_non_finite(state: &ParticleState) -> Option<(usize, &'static str)> {
    for i in 0..state.positions.len() {
        if !state.positions[i].truncate().is_finite() {
            return Some((i, "position"));
        }
        if !state.velocities[i].truncate().is_finite() {
            return Some((i, "velocity"));
        }
    }
    None
}
