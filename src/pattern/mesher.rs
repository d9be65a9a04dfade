//! Panel triangulation: constrained Delaunay refinement (spade) of a sampled outline, to a
//! target edge length and a minimum angle, without adding points on the outline.

use glam::DVec2;
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

/// Segments `i` and `j` of a closed polyline that cross, if any (adjacent segments share only
/// their common point and do not count).
pub fn first_crossing(outline: &[DVec2]) -> Option<(usize, usize)> {
    let n = outline.len();
    let seg = |i: usize| (outline[i], outline[(i + 1) % n]);
    let orient = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    for i in 0..n {
        let (a, b) = seg(i);
        let (lo_a, hi_a) = (a.min(b), a.max(b));
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue; // the closing segment is adjacent to the first
            }
            let (c, d) = seg(j);
            if hi_a.x < c.x.min(d.x)
                || lo_a.x > c.x.max(d.x)
                || hi_a.y < c.y.min(d.y)
                || lo_a.y > c.y.max(d.y)
            {
                continue;
            }
            let (d1, d2) = (orient(a, b, c), orient(a, b, d));
            let (d3, d4) = (orient(c, d, a), orient(c, d, b));
            if d1 * d2 <= 0.0 && d3 * d4 <= 0.0 {
                return Some((i, j));
            }
        }
    }
    None
}

/// Triangulates the region inside `outline` (a simple closed polygon, either orientation) with
/// interior points so that triangles have edges of about `target` and angles of at least
/// `MIN_ANGLE_DEG` where the outline allows it.
pub fn triangulate(outline: &[DVec2], target: f64) -> Result<PanelMesh, String> {
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
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
            .with_max_additional_vertices(10_000_000),
    );
    if !result.refinement_complete {
        return Err("mesh refinement did not finish".into());
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
