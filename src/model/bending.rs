//! Bending by direction: a membrane fabric's hinges bend with the rigidity measured along the
//! direction they fold. A hinge folds the cloth across its edge: a hinge whose edge runs
//! across the warp bends a strip cut along the warp, one along the warp a weft strip.
//!
//! Why not each hinge at its direction's measured rigidity: a strip bent along a direction ψ
//! bends every hinge whose fold direction α is near ψ, each by the curvature cos²(α − ψ)·κ, so
//! it stores Σ k(α)·cos⁴(α − ψ)·κ² and feels a blend of the hinges' coefficients, not the one
//! at ψ. Over fold directions spread evenly (a pattern's irregular mesh) the blend passes a
//! coefficient's cos 2α part at 2/3 of its strength (∫cos 2u·cos⁴u / ∫cos⁴u = 2/3). So the
//! hinges take k(α) = k̄ + 3/2·Δ·cos 2α, with k̄ the mean of the warp and weft strips' and Δ
//! half their difference: a warp strip then bends with the warp's rigidity and a weft strip with
//! the weft's. (Each hinge at its own direction's value, as Wang et al. 2011's ARCSim
//! interpolates its hinge table, bent the presets' strips at 0.89 to 1.33 of their measured
//! warp and weft rigidities.)
//!
//! Known limits: two values per fabric, so a bias strip bends with the mean of the two; the
//! measured bias rigidity (W11's 45° rows) differs from it by up to a quarter. Past a warp/weft
//! ratio of 5 the weak direction's coefficient would be negative: it is held at 1% of the mean. The
//! compression law's Euler load (`scene::Fabric::compression_law`) keeps the fabric's one
//! bending stiffness.

use super::ClothModel;
use glam::Vec3;
use std::collections::HashMap;

/// The coefficient of a hinge whose edge runs `angle` radians from the warp, for the
/// coefficients `strips` of strips cut along the warp and along the weft: k̄ − 3/2·Δ·cos 2θ,
/// with k̄ their mean and Δ half the warp's less the weft's (the fold direction is the edge's
/// turned 90°), at least `WEAKEST_FOLD` of the mean.
pub fn hinge_coefficient(angle: f32, strips: [f32; 2]) -> f32 {
    let [warp, weft] = strips;
    let (mean, half_difference) = (0.5 * (warp + weft), 0.5 * (warp - weft));
    (mean - 1.5 * half_difference * (2.0 * angle).cos()).max(WEAKEST_FOLD * mean)
}

/// The least coefficient a hinge keeps, as a fraction of the warp and weft strips' mean: past a
/// warp/weft ratio of 5 the law would fold the weak direction for nothing (or less). A hinge
/// keeps some stiffness, so its rest weight stays tied to it.
pub const WEAKEST_FOLD: f32 = 0.01;

/// Sets each hinge of `model` whose first three vertices form one of its triangles to the
/// coefficient its edge takes from `strips` (`hinge_coefficient`), the warp of that triangle
/// the membrane's (`membrane::warp_in_plane` of its `grain`). The rest weight, linear in the
/// coefficient, follows. A hinge across a seam (`seam_sides`: its index and the other panel's
/// sewn edge, which with its fourth vertex makes the other panel's triangle) takes the mean of
/// its two panels' coefficients, each by its own edge and grain: its curvature's energy is
/// spread over both triangles (of one spacing), each bending as its panel does. A seam hinge
/// whose other side is no triangle with a warp (a degenerate one) keeps its own side's.
pub fn set_by_direction(
    model: &mut ClothModel,
    grain: &[Vec3],
    strips: [f32; 2],
    seam_sides: &[(usize, [u32; 2])],
) {
    let key = |v: [u32; 3]| {
        let mut v = v;
        v.sort_unstable();
        v
    };
    let triangles: HashMap<[u32; 3], usize> = (model.triangles.iter().enumerate())
        .map(|(t, &tri)| (key(tri), t))
        .collect();
    let other_edge: HashMap<usize, [u32; 2]> = seam_sides.iter().copied().collect();
    let p = |i: u32| model.positions[i as usize];
    // The coefficient of a fold along `edge` of triangle `corners`, by that triangle's grain.
    let side = |corners: [u32; 3], edge: [u32; 2]| {
        let &t = triangles.get(&key(corners))?;
        let [x0, x1, x2] = model.triangles[t].map(p);
        let (_, warp) = super::membrane::warp_in_plane(x0, x1, x2, grain[t])?;
        let edge = (p(edge[1]) - p(edge[0])).try_normalize()?;
        Some(hinge_coefficient(
            edge.dot(warp).abs().min(1.0).acos(),
            strips,
        ))
    };
    let coefficients: Vec<Option<f32>> = (model.hinges.iter().enumerate())
        .map(|(k, h)| {
            let own = side([h.v[0], h.v[1], h.v[2]], [h.v[0], h.v[1]])?;
            let other = (other_edge.get(&k)).and_then(|&e| side([e[0], e[1], h.v[3]], e));
            Some(other.map_or(own, |other| 0.5 * (own + other)))
        })
        .collect();
    for (h, k) in model.hinges.iter_mut().zip(coefficients) {
        let Some(k) = k else {
            continue;
        };
        if h.stiffness > 0.0 {
            h.rest_weight *= k / h.stiffness;
        }
        h.stiffness = k;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    #[test]
    fn an_even_spread_of_hinges_bends_warp_and_weft_strips_at_their_own_rigidity() {
        let strips = [4.0f32, 1.0];
        // A strip bent along ψ feels the hinges' coefficients weighted by cos⁴ of the angle
        // between its direction and theirs (fold direction = edge + 90°). Summed over 3,600
        // evenly spread hinge directions: the warp's 4 and the weft's 1 back, to the sum's
        // rounding (1e-5 relative is far more).
        let strip = |psi: f32| {
            let (mut num, mut den) = (0.0f64, 0.0f64);
            for k in 0..3600 {
                let edge = k as f32 * PI / 3600.0;
                let w = ((edge + FRAC_PI_2 - psi).cos() as f64).powi(4);
                num += w * hinge_coefficient(edge, strips) as f64;
                den += w;
            }
            (num / den) as f32
        };
        assert!((strip(0.0) - 4.0).abs() < 4e-5, "warp {}", strip(0.0));
        assert!(
            (strip(FRAC_PI_2) - 1.0).abs() < 1e-5,
            "weft {}",
            strip(FRAC_PI_2)
        );
        // The bias takes their mean.
        assert!(
            (strip(FRAC_PI_4) - 2.5).abs() < 3e-5,
            "bias {}",
            strip(FRAC_PI_4)
        );
        // An edge's direction has no sign: 180° − θ and −θ are θ.
        for a in [0.1f32, 0.7, 1.3] {
            let k = hinge_coefficient(a, strips);
            for other in [-a, PI - a, a + PI] {
                let got = hinge_coefficient(other, strips);
                assert!((got - k).abs() < 1e-5, "{a} vs {other}: {k} {got}");
            }
        }
        // Past a ratio of 5 the weak fold keeps 1% of the mean, never less.
        assert_eq!(hinge_coefficient(0.0, [6.0, 1.0]), WEAKEST_FOLD * 3.5);
    }

    #[test]
    fn a_hinge_across_a_seam_bends_by_both_panels_grain() {
        // Two panels apart in the plane z = 0, each a triangle on an edge along x: panel A
        // (0, 1, 2) with its warp along x, panel B (3, 4, 5) with its warp along y. Hinge 0
        // crosses the seam sewing A's edge 0→1 to B's 3→4; hinge 1 is the same hinge with no
        // seam side given, as a hinge inside panel A is set.
        let v = |x: f32, y: f32| Vec3::new(x, y, 0.0);
        let mut model = ClothModel {
            positions: vec![v(0.0, 0.0), v(1.0, 0.0), v(0.5, 1.0)]
                .into_iter()
                .chain([v(3.0, 0.0), v(4.0, 0.0), v(3.5, -1.0)])
                .collect(),
            triangles: vec![[0, 1, 2], [3, 4, 5]],
            ..Default::default()
        };
        let hinge = crate::model::layout::Hinge {
            v: [0, 1, 2, 5],
            stiffness: 1.0,
            rest_weight: 3.0,
            ..Default::default()
        };
        model.hinges = vec![hinge, hinge];
        let strips = [4.0f32, 1.0];
        set_by_direction(&mut model, &[Vec3::X, Vec3::Y], strips, &[(0, [3, 4])]);
        // A's edge runs along its warp (θ = 0), B's across its warp (θ = 90°).
        let (along, across) = (
            hinge_coefficient(0.0, strips),
            hinge_coefficient(FRAC_PI_2, strips),
        );
        assert!(
            across > 10.0 * along,
            "the two sides differ: {along} {across}"
        );
        let [seam, inside] = [&model.hinges[0], &model.hinges[1]];
        // The mean of two coefficients of a few ulps each: 1e-6 relative is ample.
        let mean = 0.5 * (along + across);
        assert!(
            (seam.stiffness - mean).abs() < 1e-6 * mean,
            "{} against {mean}",
            seam.stiffness
        );
        assert!(
            (inside.stiffness - along).abs() < 1e-6 * along,
            "{} against {along}",
            inside.stiffness
        );
        // The rest weight follows the coefficient.
        assert!((seam.rest_weight - 3.0 * seam.stiffness).abs() < 1e-5 * seam.rest_weight);
    }
}
