//! Moves per-particle values between two meshings of one pattern (say at 2 cm and at 5 mm)
//! through the pattern coordinates: each particle of the target lies in a triangle of the same
//! panel in the source, and takes the barycentric blend of that triangle's values. Blending
//! reproduces any field that is affine over a source triangle exactly.

use super::garment::Garment;
pub use crate::mesh::Charted;
use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// Where every particle of the target meshing lies in the source meshing.
#[derive(Clone, Debug)]
pub struct Transfer {
    /// The source triangle of each target particle and the weights of its three corners.
    corners: Vec<([u32; 3], Vec3)>,
    /// The largest distance in the pattern from a target particle to its panel's source
    /// triangles, in m: 0 inside them; a curved edge's chords at the source's spacing leave
    /// points of the finer outline slightly outside.
    pub max_gap_m: f32,
}

impl Transfer {
    /// Locates each particle of `target` in `source`, which must be the same pattern meshed
    /// at another spacing (the same panels, in the same order).
    pub fn new(source: &Garment, target: &Garment) -> Transfer {
        Transfer::between(&source.charted(), &target.charted())
    }

    /// Locates each particle of `target` in a triangle of the same chart of `source`.
    pub fn between(source: &Charted, target: &Charted) -> Transfer {
        let target_chart = particle_charts(target);
        // The source triangles of each chart, with their chart corners.
        let mut by_chart: Vec<Vec<([u32; 3], [Vec2; 3])>> = vec![Vec::new(); source.charts];
        for (t, &p) in source.triangles.iter().zip(&source.triangle_chart) {
            let uv = t.map(|i| source.uv[i as usize]);
            by_chart[p as usize].push((*t, uv));
        }
        let corners: Vec<(([u32; 3], Vec3), f32)> = (0..target.uv.len())
            .into_par_iter()
            .map(|i| {
                let uv = target.uv[i];
                // A particle in no triangle (none in a meshed pattern) searches every chart.
                let own = target_chart[i].and_then(|p| by_chart.get(p as usize));
                let candidates: Vec<&([u32; 3], [Vec2; 3])> = match own {
                    Some(tris) if !tris.is_empty() => tris.iter().collect(),
                    _ => by_chart.iter().flatten().collect(),
                };
                let mut best = ([0u32; 3], Vec3::X, f32::INFINITY);
                for (t, c) in candidates {
                    let (w, d) = closest_in_triangle(uv, c);
                    if d < best.2 {
                        best = (*t, w, d);
                        if d == 0.0 {
                            break;
                        }
                    }
                }
                ((best.0, best.1), best.2)
            })
            .collect();
        Transfer {
            max_gap_m: corners.iter().map(|c| c.1).fold(0.0, f32::max),
            corners: corners.into_iter().map(|c| c.0).collect(),
        }
    }

    /// The target particles' blend of the source's `values` (xyz; w is ignored).
    pub fn apply(&self, values: &[Vec4]) -> Vec<Vec3> {
        (self.corners.iter())
            .map(|(t, w)| {
                let v = t.map(|i| values[i as usize].truncate());
                w.x * v[0] + w.y * v[1] + w.z * v[2]
            })
            .collect()
    }

    /// Each target particle's source triangle and the weights of its corners.
    pub fn corners(&self) -> &[([u32; 3], Vec3)] {
        &self.corners
    }
}

/// Each particle's chart: the chart of any triangle that uses it (`None` for none).
fn particle_charts(g: &Charted) -> Vec<Option<u32>> {
    let mut chart = vec![None; g.uv.len()];
    for (t, &p) in g.triangles.iter().zip(&g.triangle_chart) {
        for &i in t {
            chart[i as usize].get_or_insert(p);
        }
    }
    chart
}

/// The barycentric weights of the point of triangle `c` closest to `p`, and its distance.
fn closest_in_triangle(p: Vec2, c: &[Vec2; 3]) -> (Vec3, f32) {
    let (e1, e2, d) = (c[1] - c[0], c[2] - c[0], p - c[0]);
    let det = e1.perp_dot(e2);
    if det.abs() > f32::MIN_POSITIVE {
        let b1 = d.perp_dot(e2) / det;
        let b2 = e1.perp_dot(d) / det;
        if b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 {
            return (Vec3::new(1.0 - b1 - b2, b1, b2), 0.0);
        }
    }
    // Outside (or degenerate): the closest point of the three edges.
    let mut best = (Vec3::X, f32::INFINITY);
    for k in 0..3 {
        let (a, b) = (c[k], c[(k + 1) % 3]);
        let ab = b - a;
        let s = ((p - a).dot(ab) / ab.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
        let dist = p.distance(a + s * ab);
        if dist < best.1 {
            let mut w = Vec3::ZERO;
            w[k] = 1.0 - s;
            w[(k + 1) % 3] = s;
            best = (w, dist);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inside_a_triangle_the_weights_reproduce_the_point() {
        let c = [Vec2::ZERO, Vec2::new(2.0, 0.0), Vec2::new(0.0, 1.0)];
        let p = Vec2::new(0.5, 0.25);
        let (w, d) = closest_in_triangle(p, &c);
        assert_eq!(d, 0.0);
        let back = w.x * c[0] + w.y * c[1] + w.z * c[2];
        // Three products of numbers below 2: a few ulps of 1.
        assert!(back.distance(p) < 1e-6, "{back} against {p}");
    }

    #[test]
    fn outside_a_triangle_the_closest_edge_point_is_taken() {
        let c = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)];
        // Below the edge from corner 0 to corner 1, a quarter of the way along.
        let (w, d) = closest_in_triangle(Vec2::new(0.25, -0.1), &c);
        assert!((d - 0.1).abs() < 1e-6, "{d}");
        assert!(
            (w - Vec3::new(0.75, 0.25, 0.0)).abs().max_element() < 1e-6,
            "{w}"
        );
        // Beyond corner 2.
        let (w, d) = closest_in_triangle(Vec2::new(-0.3, 1.4), &c);
        assert!((d - 0.5).abs() < 1e-6, "{d}");
        assert!((w - Vec3::Z).abs().max_element() < 1e-6, "{w}");
    }
}
