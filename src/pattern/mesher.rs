//! Panel triangulation: constrained Delaunay refinement (spade) of a sampled outline, to a
//! target edge length and a minimum angle, without adding points on the outline.

use glam::DVec2;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

/// Smallest angle the refinement aims for, in degrees.
pub const MIN_ANGLE_DEG: f64 = 20.0;

/// A triangulated panel in pattern coordinates. `points[..outline_len]` is the outline, in
/// order; triangles are counter-clockwise.
pub struct PanelMesh {
    /// Outline points followed by interior points.
    pub points: Vec<DVec2>,
    /// Counter-clockwise triangles.
    pub triangles: Vec<[u32; 3]>,
}

/// Segments `i < j` of a closed polyline that cross or touch, the first in (i, j) order, if
/// any (adjacent segments share only their common point and do not count). An R-tree over the
/// segments' bounding boxes offers each segment only the segments whose boxes meet its own, so
/// an outline of n samples costs O(n log n) plus those candidate pairs: on a sampled outline
/// the segments are no longer than the particle spacing, and only neighbours along the outline
/// (or a crossing) meet. The orientation tests are exact (Shewchuk's predicates).
pub fn first_crossing(outline: &[DVec2]) -> Option<(usize, usize)> {
    let n = outline.len();
    // A non-finite point has no place in the tree; the triangulation refuses it by name.
    if n < 4 || outline.iter().any(|p| !p.is_finite()) {
        return None;
    }
    let seg = |i: usize| (outline[i], outline[(i + 1) % n]);
    let bounds = |i: usize| {
        let (a, b) = seg(i);
        ([a.x.min(b.x), a.y.min(b.y)], [a.x.max(b.x), a.y.max(b.y)])
    };
    let boxes = (0..n)
        .map(|i| {
            let (lo, hi) = bounds(i);
            GeomWithData::new(Rectangle::from_corners(lo, hi), i)
        })
        .collect();
    let tree = RTree::bulk_load(boxes);
    let adjacent = |i: usize, j: usize| j == i + 1 || (i == 0 && j == n - 1);
    (0..n).find_map(|i| {
        let (a, b) = seg(i);
        let (lo, hi) = bounds(i);
        (tree.locate_in_envelope_intersecting(AABB::from_corners(lo, hi)))
            .map(|other| other.data)
            .filter(|&j| j > i && !adjacent(i, j))
            .filter(|&j| {
                let (c, d) = seg(j);
                segments_meet(a, b, c, d)
            })
            .min()
            .map(|j| (i, j))
    })
}

/// Whether segments ab and cd, whose bounding boxes overlap, share a point: each one's ends lie
/// on both sides of (or on) the other's line. Collinear segments meet where their boxes do.
fn segments_meet(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let orient = |p: DVec2, q: DVec2, r: DVec2| {
        let coord = |v: DVec2| robust::Coord { x: v.x, y: v.y };
        let o = robust::orient2d(coord(p), coord(q), coord(r));
        (o > 0.0) as i8 - (o < 0.0) as i8
    };
    orient(a, b, c) * orient(a, b, d) <= 0 && orient(c, d, a) * orient(c, d, b) <= 0
}

/// Outlines of this many points or more are bulk-loaded (sorted spatially, then inserted); shorter
/// ones are inserted in outline order. Inserted in order, the points of a long thin spike each
/// flip edges all along it: a 780 m needle of 19,000 samples took 5.6 s, bulk-loaded 0.6 s. The
/// two give the same triangulation up to ties between cocircular points, which a regularly
/// sampled outline has, so the shipped garments (at most about 2,500 outline points a panel at
/// the finest spacing, 1 mm) keep the meshes that their documented figures were measured on.
pub const BULK_LOAD_FROM: usize = 10_000;

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;
type Handles = Vec<spade::handles::FixedVertexHandle>;

/// The outline's points inserted one by one in order, each segment a constraint.
fn insert_in_order(outline: &[DVec2]) -> Result<(Cdt, Handles), String> {
    let mut cdt = Cdt::new();
    let mut handles = Vec::with_capacity(outline.len());
    for p in outline {
        let h = cdt
            .insert(Point2::new(p.x, p.y))
            .map_err(|e| format!("outline point {p} cannot be triangulated: {e:?}"))?;
        handles.push(h);
    }
    if cdt.num_vertices() != outline.len() {
        return Err("the outline passes through the same point twice".into());
    }
    for i in 0..handles.len() {
        let (a, b) = (handles[i], handles[(i + 1) % handles.len()]);
        if !cdt.can_add_constraint(a, b) {
            return Err(format!("outline segment {i} crosses another one"));
        }
        cdt.add_constraint(a, b);
    }
    Ok((cdt, handles))
}

/// The outline bulk-loaded with its segments as constraints (spade keeps the vertex order).
fn bulk_load(outline: &[DVec2]) -> Result<(Cdt, Handles), String> {
    let points: Vec<Point2<f64>> = outline.iter().map(|p| Point2::new(p.x, p.y)).collect();
    let n = points.len();
    let edges = (0..n).map(|i| [i, (i + 1) % n]).collect();
    let mut crossing = None;
    let cdt = Cdt::try_bulk_load_cdt(points, edges, |e| {
        crossing.get_or_insert(e[0]);
    })
    .map_err(|e| format!("its outline cannot be triangulated: {e:?}"))?;
    if cdt.num_vertices() != n {
        return Err("the outline passes through the same point twice".into());
    }
    if let Some(i) = crossing {
        return Err(format!("outline segment {i} crosses another one"));
    }
    let handles = cdt.vertices().map(|v| v.fix()).collect();
    Ok((cdt, handles))
}

/// Triangulates the region inside `outline` (a simple closed polygon, either orientation) with
/// interior points so that triangles have edges of about `target` and angles of at least
/// `MIN_ANGLE_DEG` where the outline allows it, adding at most `max_interior` points (an
/// outline much finer than `target` grades the mesh down to its segments, which can take far
/// more points than the panel's area suggests).
pub fn triangulate(
    outline: &[DVec2],
    target: f64,
    max_interior: usize,
) -> Result<PanelMesh, String> {
    let (mut cdt, handles) = if outline.len() < BULK_LOAD_FROM {
        insert_in_order(outline)?
    } else {
        bulk_load(outline)?
    };
    // An equilateral triangle with edge `target` has area √3/4·target².
    // Refinement splits until every triangle is below the limit, so triangles end up smaller
    // than it on average; 1.5× the equilateral area puts the mean edge length near the target
    // (measured on the shipped patterns: see tests/pattern.rs).
    let max_area = 1.5 * 3f64.sqrt() / 4.0 * target * target;
    let result = cdt.refine(
        RefinementParameters::new()
            .exclude_outer_faces(true)
            .keep_constraint_edges()
            .with_angle_limit(AngleLimit::from_deg(MIN_ANGLE_DEG))
            .with_max_allowed_area(max_area)
            .with_max_additional_vertices(max_interior),
    );
    if !result.refinement_complete {
        return Err(format!(
            "its mesh needs more than {max_interior} interior particles, the rest of the \
             memory budget"
        ));
    }
    let excluded: std::collections::HashSet<_> = result.excluded_faces.iter().copied().collect();
    // Outline points keep their indices: spade numbers vertices in insertion order.
    let points: Vec<DVec2> = cdt
        .vertices()
        .map(|v| DVec2::new(v.position().x, v.position().y))
        .collect();
    debug_assert!(handles.iter().enumerate().all(|(i, h)| h.index() == i));
    let triangles = cdt
        .inner_faces()
        .filter(|f| !excluded.contains(&f.fix()))
        .map(|f| f.vertices().map(|v| v.fix().index() as u32))
        .collect();
    Ok(PanelMesh { points, triangles })
}

/// The smallest interior angle of a triangle, in degrees.
pub fn min_angle_deg(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    let angle = |p: DVec2, q: DVec2, r: DVec2| (q - p).angle_to(r - p).abs().to_degrees();
    angle(a, b, c).min(angle(b, c, a)).min(angle(c, a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition `first_crossing` must agree with: every pair, in (i, j) order.
    fn brute_force(outline: &[DVec2]) -> Option<(usize, usize)> {
        let n = outline.len();
        let seg = |i: usize| (outline[i], outline[(i + 1) % n]);
        for i in 0..n {
            for j in i + 2..n {
                if i == 0 && j == n - 1 {
                    continue;
                }
                let ((a, b), (c, d)) = (seg(i), seg(j));
                let boxes_meet = a.min(b).cmple(c.max(d)).all() && c.min(d).cmple(a.max(b)).all();
                if boxes_meet && segments_meet(a, b, c, d) {
                    return Some((i, j));
                }
            }
        }
        None
    }

    fn circle(n: usize) -> Vec<DVec2> {
        (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                DVec2::new(a.cos(), a.sin())
            })
            .collect()
    }

    #[test]
    fn agrees_with_every_pair_on_random_polygons() {
        // Random star-ish and scrambled polygons: some simple, most crossing.
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut crossing, mut simple) = (0, 0);
        for trial in 0..400 {
            let n = 4 + trial % 20;
            let mut pts: Vec<DVec2> = circle(n).into_iter().map(|p| p * (0.3 + next())).collect();
            if trial % 3 == 0 {
                let (i, j) = ((next() * n as f64) as usize, (next() * n as f64) as usize);
                pts.swap(i.min(n - 1), j.min(n - 1));
            }
            if trial % 7 == 0 {
                // A vertex exactly on another segment: touching counts.
                pts[n - 1] = 0.5 * (pts[2] + pts[3]);
            }
            let expect = brute_force(&pts);
            assert_eq!(first_crossing(&pts), expect, "trial {trial}: {pts:?}");
            match expect {
                Some(_) => crossing += 1,
                None => simple += 1,
            }
        }
        assert!(
            crossing > 50 && simple > 50,
            "{crossing} crossing, {simple} simple"
        );
    }

    /// A needle: out along y = 0 and back along y = width, `n` points in all.
    fn needle(n: usize, length: f64, width: f64) -> Vec<DVec2> {
        let half = n / 2;
        let out = (0..half).map(|k| DVec2::new(length * k as f64 / half as f64, 0.0));
        let back =
            (0..n - half).map(|k| DVec2::new(length * (1.0 - k as f64 / (n - half) as f64), width));
        out.chain(back).collect()
    }

    #[test]
    fn both_ways_of_loading_an_outline_cover_it_exactly() {
        // Below and above BULK_LOAD_FROM: the triangles cover the outline's area exactly, keep
        // the outline's points first and in order, and use each outline segment.
        for n in [BULK_LOAD_FROM / 2, BULK_LOAD_FROM + 10] {
            let outline = needle(n, 100.0, 0.3);
            let mesh = triangulate(&outline, 0.2, 1_000_000).expect("a simple outline");
            assert_eq!(&mesh.points[..n], &outline[..]);
            let area: f64 = (mesh.triangles.iter())
                .map(|t| {
                    let [a, b, c] = t.map(|i| mesh.points[i as usize]);
                    0.5 * (b - a).perp_dot(c - a)
                })
                .sum();
            let shoelace: f64 = (0..n)
                .map(|i| 0.5 * outline[i].perp_dot(outline[(i + 1) % n]))
                .sum();
            // Sums of a few thousand terms of size ~1: rounding is far below 1e-9 of the area.
            assert!(
                (area - shoelace).abs() < 1e-9 * shoelace,
                "{n} points: area {area} vs {shoelace}"
            );
            let mut segments = std::collections::HashSet::new();
            for t in &mesh.triangles {
                for k in 0..3 {
                    let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
                    segments.insert((a, b));
                }
            }
            let on_outline = (0..n as u32).filter(|&i| {
                let j = (i + 1) % n as u32;
                segments.contains(&(i.min(j), i.max(j)))
            });
            assert_eq!(
                on_outline.count(),
                n,
                "{n} points: every outline segment is an edge"
            );
        }
    }

    #[test]
    fn a_long_needle_is_meshed_in_well_under_its_old_time() {
        // 20,000 points on a 100 m needle 0.3 m wide: inserting them in outline order took
        // 5.1 s here (each point flips edges along the needle); bulk-loading them, 0.05 s.
        // 3 s leaves room for a loaded test machine and still fails the old way.
        let outline = needle(20_000, 100.0, 0.3);
        let start = std::time::Instant::now();
        triangulate(&outline, 0.05, 1_000_000).expect("a simple outline");
        let elapsed = start.elapsed().as_secs_f64();
        assert!(elapsed < 3.0, "took {elapsed} s");
    }

    #[test]
    fn a_bow_tie_crosses_and_a_square_does_not() {
        let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(DVec2::from);
        assert_eq!(first_crossing(&square), None);
        let bow_tie = [(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)].map(DVec2::from);
        assert_eq!(first_crossing(&bow_tie), Some((0, 2)));
    }

    #[test]
    fn a_long_simple_outline_takes_well_under_a_second() {
        // Testing every pair of segments (the old test) took 2.4 s at 100,000 and 21 s at
        // 300,000, so about 9 s here; the R-tree
        // offers each segment its two neighbours, so this is a fraction of a second even in a
        // loaded test run. A crossing added at the end is still found.
        let mut pts = circle(200_000);
        let start = std::time::Instant::now();
        assert_eq!(first_crossing(&pts), None);
        let elapsed = start.elapsed().as_secs_f64();
        assert!(elapsed < 1.0, "took {elapsed} s");
        let last = pts.len() - 1;
        pts[last] = DVec2::new(0.5, -2.0);
        let (i, j) = first_crossing(&pts).expect("a spike through the circle crosses it");
        assert!(j >= last - 1, "({i}, {j})");
    }
}
