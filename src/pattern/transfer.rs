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

    /// Locates each particle of `target` in a triangle of the same chart of `source`: the
    /// triangle closest to it in the pattern (0 inside), the first in `source`'s order of
    /// equally close ones.
    pub fn between(source: &Charted, target: &Charted) -> Transfer {
        let target_chart = particle_charts(target);
        let by_chart = chart_triangles(source);
        let grids: Vec<ChartGrid> = by_chart.iter().map(|tris| ChartGrid::new(tris)).collect();
        let everywhere: Vec<&([u32; 3], [Vec2; 3])> = by_chart.iter().flatten().collect();
        let corners: Vec<(([u32; 3], Vec3), f32)> = (0..target.uv.len())
            .into_par_iter()
            .map(|i| {
                let uv = target.uv[i];
                // A particle in no triangle (none in a meshed pattern) searches every chart.
                let own = target_chart[i].and_then(|p| grids.get(p as usize));
                let (t, w, d) = match own {
                    Some(grid) if !grid.triangles.is_empty() => grid.closest(uv),
                    _ => closest_of(uv, everywhere.iter().copied()),
                };
                ((t, w), d)
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

/// The triangle of `candidates` closest to `p`, its corners' weights and the distance: the
/// first in order of the equally close ones (a point on an edge shared by two triangles takes
/// the earlier).
fn closest_of<'a>(
    p: Vec2,
    candidates: impl Iterator<Item = &'a ([u32; 3], [Vec2; 3])>,
) -> ([u32; 3], Vec3, f32) {
    let mut best = ([0u32; 3], Vec3::X, f32::INFINITY);
    for (t, c) in candidates {
        let (w, d) = closest_in_triangle(p, c);
        if d < best.2 {
            best = (*t, w, d);
            if d == 0.0 {
                break;
            }
        }
    }
    best
}

/// One chart's source triangles bucketed by a uniform grid of cells about a triangle across,
/// each triangle in every cell its bounding box touches, so that a particle tests the
/// triangles around it instead of every triangle of its chart (a 5 mm T-shirt's particles
/// against its 1 cm level: thousands of triangles a panel).
struct ChartGrid<'a> {
    triangles: &'a [([u32; 3], [Vec2; 3])],
    origin: Vec2,
    cell: f32,
    dims: [usize; 2],
    /// Cell (x, y)'s triangles, ascending: `cells[y·dims[0] + x]`.
    cells: Vec<Vec<u32>>,
}

impl<'a> ChartGrid<'a> {
    fn new(triangles: &'a [([u32; 3], [Vec2; 3])]) -> ChartGrid<'a> {
        let boxes: Vec<(Vec2, Vec2)> = (triangles.iter())
            .map(|(_, c)| (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2])))
            .collect();
        let (lo, hi) = (boxes.iter()).fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(lo, hi), b| {
            (lo.min(b.0), hi.max(b.1))
        });
        let mean_side = (boxes.iter())
            .map(|(l, h)| (*h - *l).max_element())
            .sum::<f32>()
            / boxes.len().max(1) as f32;
        let extent = (hi - lo).max(Vec2::ZERO);
        let cell = mean_side
            .max(extent.max_element() / 1024.0)
            .max(f32::MIN_POSITIVE);
        let dims = if boxes.is_empty() {
            [0, 0]
        } else {
            [0, 1].map(|a| ((extent[a] / cell) as usize + 1).min(1024))
        };
        let mut grid = ChartGrid {
            triangles,
            origin: lo,
            cell,
            dims,
            cells: vec![Vec::new(); dims[0] * dims[1]],
        };
        // Each box grown by a thousandth of a cell: a point that rounds into a triangle lies
        // an ulp or so outside it at most, and a cell index rounds by less than that margin.
        let margin = Vec2::splat(BOX_MARGIN * cell);
        for (t, (l, h)) in boxes.iter().enumerate() {
            let ([x0, y0], [x1, y1]) = (grid.cell_of(*l - margin), grid.cell_of(*h + margin));
            for y in y0..=y1 {
                for x in x0..=x1 {
                    grid.cells[y * dims[0] + x].push(t as u32);
                }
            }
        }
        grid
    }

    /// The cell holding `p`, or the nearest one to it.
    fn cell_of(&self, p: Vec2) -> [usize; 2] {
        let at = (p - self.origin) / self.cell;
        [0, 1].map(|a| (at[a].max(0.0) as usize).min(self.dims[a] - 1))
    }

    /// `closest_of` over every triangle of the chart, testing the cells in square rings around
    /// `p`'s cell until the closest found is nearer than any triangle outside them can be: a
    /// triangle not in rings 0..=r touches no cell of them, so it lies at least r cells from
    /// `p` (p is in, or outside the grid beyond, the centre cell), and one that holds `p` is
    /// in ring 0. Equally close triangles go to the first in chart order, as `closest_of`.
    fn closest(&self, p: Vec2) -> ([u32; 3], Vec3, f32) {
        let [cx, cy] = self.cell_of(p);
        let mut best = (usize::MAX, Vec3::X, f32::INFINITY);
        for r in 0..self.dims[0].max(self.dims[1]) {
            for (x, y) in ring(cx, cy, r, self.dims) {
                for &t in &self.cells[y * self.dims[0] + x] {
                    let t = t as usize;
                    let (w, d) = closest_in_triangle(p, &self.triangles[t].1);
                    if d < best.2 || (d == best.2 && t < best.0) {
                        best = (t, w, d);
                    }
                }
            }
            // A triangle that holds p (distance 0) is in p's own cell.
            if best.2 == 0.0 || best.2 < (r as f32 - BOX_MARGIN) * self.cell {
                break;
            }
        }
        match self.triangles.get(best.0) {
            Some(t) => (t.0, best.1, best.2),
            // No triangle at a finite distance (non-finite corners): as `closest_of`.
            None => ([0u32; 3], Vec3::X, f32::INFINITY),
        }
    }
}

/// How far each triangle's box is grown when it is bucketed, in cells.
const BOX_MARGIN: f32 = 1e-3;

/// The cells of a `dims` grid at Chebyshev distance `r` from cell (cx, cy): its rows at
/// cy ± r whole, and its columns at cx ± r between them.
fn ring(cx: usize, cy: usize, r: usize, dims: [usize; 2]) -> impl Iterator<Item = (usize, usize)> {
    let span = |c: usize, n: usize| c.saturating_sub(r)..=(c + r).min(n - 1);
    let (xs, ys) = (span(cx, dims[0]), span(cy, dims[1]));
    let edge = move |c: usize, n: usize| {
        let below = c.checked_sub(r);
        let above = (r > 0 && c + r < n).then_some(c + r);
        below.into_iter().chain(above)
    };
    let rows = edge(cy, dims[1]).flat_map(move |y| xs.clone().map(move |x| (x, y)));
    let inner = (ys.clone()).filter(move |y| y.abs_diff(cy) != r);
    let columns = inner.flat_map(move |y| edge(cx, dims[0]).map(move |x| (x, y)));
    rows.chain(columns)
}

/// The triangles of each chart, in order, with their chart corners.
fn chart_triangles(g: &Charted) -> Vec<Vec<([u32; 3], [Vec2; 3])>> {
    let mut by_chart = vec![Vec::new(); g.charts];
    for (t, &p) in g.triangles.iter().zip(&g.triangle_chart) {
        by_chart[p as usize].push((*t, t.map(|i| g.uv[i as usize])));
    }
    by_chart
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

    /// Two charts meshed as grids, the second beside the first.
    fn two_charts(columns: u32, rows: u32) -> Charted {
        let mut a = Charted::grid(0.6, 0.4, columns, rows);
        let b = Charted::grid(0.3, 0.5, columns, rows);
        let shift = a.uv.len() as u32;
        a.uv.extend(b.uv.iter().map(|p| *p + Vec2::new(1.0, 0.0)));
        a.triangles
            .extend(b.triangles.iter().map(|t| t.map(|i| i + shift)));
        a.triangle_chart.extend(b.triangle_chart.iter().map(|_| 1));
        a.charts = 2;
        a
    }

    #[test]
    fn the_grid_finds_what_testing_every_triangle_finds() {
        let mut source = two_charts(13, 9);
        // A hole in the first chart, some cells across: its middle's closest triangles lie
        // rings away from its own (empty) cell.
        let centre = |t: &[u32; 3]| t.iter().map(|&i| source.uv[i as usize]).sum::<Vec2>() / 3.0;
        let keep: Vec<bool> = (source.triangles.iter())
            .map(|t| (centre(t) - Vec2::new(0.3, 0.2)).abs().max_element() > 0.11)
            .collect();
        let mut kept = keep.iter();
        source.triangle_chart.retain(|_| *kept.next().unwrap());
        let mut kept = keep.iter();
        source.triangles.retain(|_| *kept.next().unwrap());
        // Turned, so that its edges and the hole's run across the cells.
        let turn = Vec2::from_angle(0.5);
        for p in &mut source.uv {
            *p = turn.rotate(*p);
        }
        let (mut outside, mut on_corners) = (0, 0);
        for (chart, tris) in chart_triangles(&source).iter().enumerate() {
            let grid = ChartGrid::new(tris);
            // A lattice over the chart's box grown by 40% (inside, and outside by up to a few
            // cells), and the source's corners, each in up to six triangles: the first wins.
            let corners = tris.iter().flat_map(|(_, c)| *c);
            let (lo, hi) = (corners.clone()).fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |b, c| {
                (b.0.min(c), b.1.max(c))
            });
            let lattice = (0..=60).flat_map(|i| {
                (0..=50).map(move |j| {
                    let f = Vec2::new(i as f32 / 60.0, j as f32 / 50.0) * 1.4 - 0.2;
                    lo + f * (hi - lo)
                })
            });
            for p in lattice.chain(corners) {
                let (t, w, d) = closest_of(p, tris.iter());
                let (gt, gw, gd) = grid.closest(p);
                let bits = |w: Vec3| w.to_array().map(f32::to_bits);
                assert_eq!((t, bits(w), d), (gt, bits(gw), gd), "chart {chart} at {p}");
                outside += usize::from(d > 0.0);
                on_corners += usize::from(source.uv.contains(&p));
            }
        }
        assert!(
            outside > 1000 && on_corners > 100,
            "{outside} outside, {on_corners} on corners"
        );
        // Through `between`: the same source with a finer meshing of the same charts, the
        // hole's particles outside.
        let (target, mut unturned) = (two_charts(37, 23), source.clone());
        for p in unturned.uv.iter_mut() {
            *p = Vec2::from_angle(-0.5).rotate(*p);
        }
        let transfer = Transfer::between(&unturned, &target);
        let (charts, by_chart) = (particle_charts(&target), chart_triangles(&unturned));
        for (i, got) in transfer.corners().iter().enumerate() {
            let tris = &by_chart[charts[i].unwrap() as usize];
            let (t, w, _) = closest_of(target.uv[i], tris.iter());
            assert_eq!(
                (t, w.to_array().map(f32::to_bits)),
                (got.0, got.1.to_array().map(f32::to_bits))
            );
        }
        assert!(
            transfer.max_gap_m > 0.01,
            "the hole's particles lie outside"
        );
    }

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
