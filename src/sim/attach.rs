//! Attachments: particles on labelled pattern edges held in place for the scene's first
//! `attach_frames` output frames, then let go.

use super::Prepared;
use crate::solver::{ParticleState, Solver};
use glam::Vec4;

/// Which of `prep`'s particles are held at the end of output frame `frame`: the scene's pins
/// always, the attached particles until they are let go after frame `attach_frames`.
fn held_at(prep: &Prepared, frame: u32) -> Vec<bool> {
    let mut held = vec![false; prep.model.len()];
    let attached = (frame < prep.attach_frames).then_some(&prep.attached[..]);
    for &i in prep.scene_pins.iter().chain(attached.unwrap_or(&[])) {
        held[i as usize] = true;
    }
    held
}

/// `ClothModel::packed_positions` of `prep` as they stand at the end of output frame `frame`:
/// each particle's place in the model, and its inverse mass then (0 while it is held, or
/// without mass). A state carried onto this meshing at that frame holds the particles with
/// w = 0 at these places.
pub fn packed_at(prep: &Prepared, frame: u32) -> Vec<Vec4> {
    let model = &prep.model;
    let held = held_at(prep, frame);
    (0..model.len())
        .map(|i| {
            let mass = model.masses[i];
            let inverse_mass = if held[i] || mass <= 0.0 {
                0.0
            } else {
                1.0 / mass
            };
            model.positions[i].extend(inverse_mass)
        })
        .collect()
}

/// Gives attached particles their inverse mass back (pins from the scene stay pinned), as
/// after their last frame.
pub(crate) fn release(prep: &Prepared, solver: &mut dyn Solver, mut state: ParticleState) {
    let packed = packed_at(prep, prep.attach_frames);
    for &i in &prep.attached {
        state.positions[i as usize].w = packed[i as usize].w;
    }
    solver.set_state(&state);
}
