//! Measurements on a read-back state; the same code serves both backends.

use crate::model::layout::Membrane;
use crate::model::{ClothModel, Spring};
use crate::pattern::garment::SeamPair;
use crate::solver::ParticleState;
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// The bodies farther from the cloth than the cloth can travel in the run, which touch
/// nothing: each one's index and its distance from the cloth's box, in m. The cloth's reach is
/// its box grown by `REACH_MARGIN_M` all round, and along each axis by the distance a free fall
/// covers in `run_s` and the distances the wind (`wind`: its mean velocity and gust amplitude)
/// carries it downwind at its strongest gust and upwind when a gust reverses it. Each drift
/// counts on its own, so that a wind against gravity still reaches everything in between.
/// Only bodies that stay where they are (no motion, no animation) are judged.
pub fn unreachable_bodies(
    model: &ClothModel,
    gravity: Vec3,
    wind: (Vec3, f32),
    run_s: f32,
) -> Vec<(usize, f32)> {
    let (cloth_lo, cloth_hi) = bounds(model.positions.iter().copied());
    let margin = Vec3::splat(REACH_MARGIN_M);
    let (velocity, gust) = wind;
    let drifts = [
        0.5 * gravity * run_s * run_s,
        (1.0 + gust) * velocity * run_s,
        -(gust - 1.0).max(0.0) * velocity * run_s,
    ];
    let (mut reach_lo, mut reach_hi) = (cloth_lo - margin, cloth_hi + margin);
    for d in drifts {
        reach_lo += d.min(Vec3::ZERO);
        reach_hi += d.max(Vec3::ZERO);
    }
    let apart = |(a_lo, a_hi): (Vec3, Vec3), (b_lo, b_hi): (Vec3, Vec3)| {
        (b_lo - a_hi).max(a_lo - b_hi).max(Vec3::ZERO).length()
    };
    (model.colliders.iter().enumerate())
        .filter(|(_, c)| !c.motion.moves() && c.deformed.is_none())
        .filter_map(|(i, c)| {
            let pose = c.motion.at(0.0);
            let world =
                (c.body.mesh.positions.iter()).map(|&p| pose.rotation * p + pose.translation);
            let body = bounds(world);
            (apart((reach_lo, reach_hi), body) > 0.0)
                .then(|| (i, apart((cloth_lo, cloth_hi), body)))
        })
        .collect()
}

/// How far, in m, beyond its box and its fall the cloth is taken to reach: a swing, a
/// billow, a sleeve thrown out.
pub const REACH_MARGIN_M: f32 = 1.0;

/// The box around `points`.
pub fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    })
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

/// The `q`-quantile (0.99 = 99th percentile) of the springs' relative stretch (L − L0)/L0:
/// the strain most of the cloth rests at, which one pinched edge at a seam junction or an
/// armpit cannot move the way it moves the largest.
pub fn edge_strain_quantile(positions: &[Vec4], springs: &[Spring], q: f32) -> f32 {
    let mut strains: Vec<f32> = springs
        .iter()
        .map(|s| {
            let [a, b] = s.ends.map(|i| positions[i as usize].truncate());
            (a.distance(b) - s.rest_length) / s.rest_length
        })
        .collect();
    quantile(&mut strains, q)
}

/// The `q`-quantile of `values` (reordered); 0 when there are none.
fn quantile(values: &mut [f32], q: f32) -> f32 {
    if values.is_empty() {
        return 0.0;
    }
    let k = ((q.clamp(0.0, 1.0) * values.len() as f32).ceil() as usize).clamp(1, values.len());
    *values.select_nth_unstable_by(k - 1, f32::total_cmp).1
}

/// A membrane's strain at the last frame, per triangle along its threads and in shear.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ThreadStrain {
    /// The largest thread strain (|w_u| − 1 or |w_v| − 1 of any triangle).
    pub max: f32,
    /// Its 99th percentile over the triangles (each triangle's larger of the two).
    pub p99: f32,
    /// The 99th percentile of the shear angle between warp and weft, in degrees.
    pub shear_p99_deg: f32,
}

/// The membrane's thread strain and shear angle at `positions` (`None` without a membrane):
/// what a designer reads as how much the fabric stretches. Edge strain mixes in shear, which a
/// woven takes easily.
pub fn thread_strain(positions: &[Vec4], membranes: &[Membrane]) -> Option<ThreadStrain> {
    if membranes.is_empty() {
        return None;
    }
    let (mut threads, mut shears) = (Vec::new(), Vec::new());
    for m in membranes {
        let x = |r: usize| positions[m.v[r] as usize].truncate();
        let [a1, a2, b1, b2] = m.shape;
        let (e1, e2) = (x(1) - x(0), x(2) - x(0));
        let (wu, wv) = (a1 * e1 + a2 * e2, b1 * e1 + b2 * e2);
        let (lu, lv) = (wu.length(), wv.length());
        threads.push((lu - 1.0).max(lv - 1.0));
        let cos = wu.dot(wv) / (lu * lv).max(f32::MIN_POSITIVE);
        shears.push(cos.clamp(-1.0, 1.0).asin().abs().to_degrees());
    }
    Some(ThreadStrain {
        max: threads.iter().copied().fold(f32::MIN, f32::max),
        p99: quantile(&mut threads, 0.99),
        shear_p99_deg: quantile(&mut shears, 0.99),
    })
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
    // Every frame, for every particle: about a microsecond a query, tens of ms a frame on one
    // core for the 5 mm shirt, so it runs on the pool.
    positions
        .par_iter()
        .map(|p| {
            collider
                .exact
                .query(inverse * (p.truncate() - body.translation))
                .0
        })
        .collect()
}

/// Each particle's signed distance (negative inside) to a deforming body's exact mesh as it is
/// deformed at time `t`, in m (the exact queries rebuilt over the deformed vertices).
pub fn deformed_distances(
    collider: &crate::body::Collider,
    t: f32,
    positions: &[Vec4],
) -> Result<Vec<f32>, String> {
    let mesh = crate::mesh::TriMesh {
        positions: collider.world_positions(t),
        triangles: collider.body.mesh.triangles.clone(),
    };
    let exact = crate::body::exact::ExactBody::new(&mesh)?;
    Ok(positions
        .par_iter()
        .map(|p| exact.query(p.truncate()).0)
        .collect())
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
    // A pattern's size is checked against a garment's when it loads; a mesh or grid here.
    let (lo, hi) = bounds(model.positions.iter().copied());
    let span = (hi - lo).max_element();
    if span.is_finite() && !(0.01..=10.0).contains(&span) {
        warnings.push(format!(
            "the cloth spans {span} m, {} any garment, curtain or test swatch (1 cm to 10 m): \
             check its size, or a mesh's units ([cloth.mesh] units)",
            if span > 10.0 {
                "larger than"
            } else {
                "smaller than"
            }
        ));
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

/// Where a body shows through the cloth at the last frame: cloth that lies inside a body, at
/// its particles or at its triangles' centres (a triangle can cut into the body between
/// particles that are all outside it).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShowThrough {
    /// Particles inside a body.
    pub particles: usize,
    /// Triangles whose centre is inside a body (by any depth).
    pub triangles: usize,
    /// The cloth's triangles.
    pub of_triangles: usize,
    /// The deepest of those points inside a body, in m.
    pub deepest_m: f32,
}

#[cfg(test)]
mod quantile_tests {
    use super::*;

    #[test]
    fn the_99th_percentile_is_the_nearest_rank() {
        // 100 springs of rest length 1 stretched by 0, 0.001, …, 0.099 (in shuffled order): the
        // 99th smallest strain is 0.098, to the rounding of an f32 length near 1 (1e-7).
        let mut positions = Vec::new();
        let mut springs = Vec::new();
        for i in 0..100u32 {
            let strain = ((i * 37) % 100) as f32 / 1000.0;
            positions.push(Vec4::new(0.0, 0.0, i as f32, 0.0));
            positions.push(Vec4::new(1.0 + strain, 0.0, i as f32, 0.0));
            springs.push(Spring {
                ends: [2 * i, 2 * i + 1],
                rest_length: 1.0,
                stiffness: 1.0,
                damping: 0.0,
            });
        }
        let p99 = edge_strain_quantile(&positions, &springs, 0.99);
        assert!((p99 - 0.098).abs() < 1e-6, "{p99}");
        let max = edge_strain_quantile(&positions, &springs, 1.0);
        assert!((max - max_edge_strain(&positions, &springs)).abs() == 0.0);
        assert_eq!(edge_strain_quantile(&positions, &[], 0.99), 0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{GridPlane, TriMesh};
    use crate::scene::Fabric;

    #[test]
    fn a_cloth_larger_than_any_garment_or_smaller_than_a_swatch_is_warned() {
        let fabric = Fabric::linear(100.0);
        let spans = |side: f32| {
            let mesh = TriMesh::grid(side, side, 4, 4, Vec3::ZERO, GridPlane::Xy);
            let model = ClothModel::from_mesh(&mesh, &fabric, &[]);
            let warned = mesh_warnings(&model, true);
            warned.iter().any(|w| w.contains("the cloth spans"))
        };
        // A cm-modelled 40 cm strip read in metres is 40 m; one in mm read as m is 0.4 mm.
        assert!(spans(40.0) && spans(0.004));
        assert!(!spans(1.0) && !spans(0.02) && !spans(9.0));
    }
}
