//! The coarse start: a garment sewn and draped at a coarse spacing, carried onto the full
//! mesh through the pattern coordinates. A Gauss–Seidel sweep carries load about one ring of
//! vertices, so relaxing a mode N rings across takes about N² sweeps: 16× as many at 5 mm as at
//! 2 cm. The coarse garment does the long-range sewing and draping; the full mesh continues
//! from its rest shape and only has the short-range work left.

use super::Prepared;
use crate::pattern::transfer::Transfer;
use crate::solver::ParticleState;
use serde::{Deserialize, Serialize};

/// What the coarse start did, for the summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CoarseStart {
    /// Its particle spacing, in m.
    pub particle_distance_m: f32,
    /// Its particles.
    pub particles: usize,
    /// The frame it ended at, from which the full mesh continues.
    pub frame: u32,
    /// The frame its settle rule fired (`None`: it ran to the last frame without settling).
    pub settled_frame: Option<u32>,
    /// The first frame at which all its seams were closed.
    pub seams_closed_frame: Option<u32>,
    /// Its largest spring strain at any frame.
    pub max_edge_strain: f32,
    /// Seconds it took, with the mapping onto the full mesh.
    pub wall_seconds: f64,
    /// The largest distance in the pattern from a full-mesh particle to its panel's coarse
    /// triangles, in m (curved edges' chords); such particles take the nearest coarse point.
    pub max_pattern_gap_m: f32,
}

/// The state of `fine`'s particles at the end of output frame `frame`, blended from the
/// `coarse` run's `state` through the pattern coordinates (positions and velocities), with
/// `fine`'s inverse masses: its pins held, its attached particles held until their release.
/// Returns the state and the largest pattern gap (see `CoarseStart`); `None` unless both runs
/// are garments.
pub fn map_state(
    coarse: &Prepared,
    state: &ParticleState,
    fine: &Prepared,
    frame: u32,
) -> Option<(ParticleState, f32)> {
    let transfer = Transfer::new(coarse.garment.as_ref()?, fine.garment.as_ref()?);
    let positions = transfer.apply(&state.positions);
    let velocities = transfer.apply(&state.velocities);
    let model = &fine.model;
    let mut held: Vec<bool> = model.masses.iter().map(|&m| m <= 0.0).collect();
    let attached = (frame < fine.attach_frames).then_some(&fine.attached[..]);
    for &i in fine.scene_pins.iter().chain(attached.unwrap_or(&[])) {
        held[i as usize] = true;
    }
    let mut mapped = ParticleState {
        positions: Vec::with_capacity(positions.len()),
        velocities: Vec::with_capacity(positions.len()),
    };
    for (i, (p, v)) in positions.into_iter().zip(velocities).enumerate() {
        if held[i] {
            // Held particles keep their own place: a pin is where the scene put it.
            mapped.positions.push(model.positions[i].extend(0.0));
            mapped.velocities.push(glam::Vec4::ZERO);
        } else {
            mapped.positions.push(p.extend(1.0 / model.masses[i]));
            mapped.velocities.push(v.extend(0.0));
        }
    }
    Some((mapped, transfer.max_gap_m))
}
