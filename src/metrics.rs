//! Measurements on a read-back state; the same code serves both backends.

use crate::model::{ClothModel, Spring};
use crate::pattern::garment::SeamPair;
use crate::solver::ParticleState;
use glam::Vec4;

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

/// The springs stretched by at least `strain` (0.1 = 10%).
pub fn edges_stretched_past(positions: &[Vec4], springs: &[Spring], strain: f32) -> usize {
    springs
        .iter()
        .filter(|s| {
            let [a, b] = s.ends.map(|i| positions[i as usize].truncate());
            a.distance(b) >= (1.0 + strain) * s.rest_length
        })
        .count()
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

/// The largest gap between a seam vertex and its partner point, per stitch, in m.
pub fn seam_gaps(pairs: &[SeamPair], stitches: usize, positions: &[Vec4]) -> Vec<f32> {
    let p = |i: u32| positions[i as usize].truncate();
    let mut gaps = vec![0.0f32; stitches];
    for s in pairs {
        let partner = (1.0 - s.w) * p(s.b[0]) + s.w * p(s.b[1]);
        let gap = p(s.a).distance(partner);
        gaps[s.stitch as usize] = gaps[s.stitch as usize].max(gap);
    }
    gaps
}

/// Every particle's signed distance to the body's exact surface in m (negative inside).
/// `body` is the body's pose at the state's time.
pub fn body_distances(
    collider: &crate::body::Collider,
    body: &crate::body::motion::BodyState,
    positions: &[Vec4],
) -> Vec<f32> {
    let inverse = body.rotation.inverse();
    positions
        .iter()
        .map(|p| {
            collider
                .exact
                .query(inverse * (p.truncate() - body.translation))
                .0
        })
        .collect()
}

/// The deepest any particle lies inside the body, in m (0 when none is inside).
pub fn max_penetration(distances: &[f32]) -> f32 {
    distances.iter().map(|d| -d).fold(0.0, f32::max)
}

/// Marks the particles resting on a body: outside it and within `reach` (m) of its surface.
pub fn mark_contacts(distances: &[f32], reach: f32, touching: &mut [bool]) {
    for (t, &d) in touching.iter_mut().zip(distances) {
        *t |= (0.0..=reach).contains(&d);
    }
}

/// What a user should know about a cloth mesh before trusting a run: triangles with no area
/// (they carry no mass, stretch or bending) and free particles that only such triangles touch
/// (no mass: they stay where they are, as if pinned), and, when asked (not for patterns, whose
/// panels meet only through seams), vertices at the same position (the cloth can open there).
pub fn mesh_warnings(model: &ClothModel, check_duplicates: bool) -> Vec<String> {
    let mut warnings = Vec::new();
    let area = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| model.positions[i as usize]);
        (b - a).cross(c - a).length()
    };
    let flat = model.triangles.iter().filter(|t| area(t) <= 0.0).count();
    let massless: Vec<usize> = (0..model.len())
        .filter(|&i| !model.pinned[i] && model.masses[i] <= 0.0)
        .collect();
    if flat > 0 || !massless.is_empty() {
        warnings.push(format!(
            "the cloth mesh has {flat} triangle(s) with no area; {} free particle(s) touch only \
             such triangles and have no mass, so they stay where they are{}. Repair the mesh \
             (remove degenerate faces) if that is not meant",
            massless.len(),
            massless
                .first()
                .map_or(String::new(), |i| format!(" (first: particle {i})"))
        ));
    }
    if !check_duplicates {
        return warnings;
    }
    let mut keys: Vec<[u32; 3]> = (model.positions.iter())
        .map(|p| p.to_array().map(f32::to_bits))
        .collect();
    keys.sort_unstable();
    let duplicates = keys.windows(2).filter(|w| w[0] == w[1]).count();
    if duplicates > 0 {
        warnings.push(format!(
            "the cloth mesh has {duplicates} vertex position(s) used by more than one vertex: \
             the cloth is not joined there and can open (weld the vertices in the mesh if it \
             should be one sheet; a pattern's seams do this by design)"
        ));
    }
    warnings
}
