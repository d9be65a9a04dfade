//! The coarse start: a garment sewn and draped at a coarse spacing, carried onto the full
//! mesh through the pattern coordinates. A Gauss–Seidel sweep carries load about one ring of
//! vertices, so relaxing a mode N rings across takes about N² sweeps: 16× as many at 5 mm as at
//! 2 cm. The coarse garment does the long-range sewing and draping; the full mesh continues
//! from its rest shape and only has the short-range work left.

use super::Prepared;
use crate::pattern::transfer::Transfer;
use crate::solver::ParticleState;
use glam::Vec4;
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
    let mapped = carried(&transfer, state, &super::packed_at(fine, frame));
    Some((mapped, transfer.max_gap_m))
}

/// `state` carried through `transfer` onto the particles of the meshing whose packed positions
/// are `packed` (`packed_at` the state's frame): each position and velocity blended, with the
/// particle's inverse mass; held particles (w = 0) where the model puts them, at rest.
pub fn carried(transfer: &Transfer, state: &ParticleState, packed: &[Vec4]) -> ParticleState {
    let (positions, velocities) = (
        transfer.apply(&state.positions),
        transfer.apply(&state.velocities),
    );
    let pinned = |q: &Vec4| q.w == 0.0;
    ParticleState {
        positions: (positions.iter().zip(packed))
            .map(|(p, q)| if pinned(q) { *q } else { p.extend(q.w) })
            .collect(),
        velocities: (velocities.iter().zip(packed))
            .map(|(v, q)| if pinned(q) { Vec4::ZERO } else { v.extend(0.0) })
            .collect(),
    }
}
