//! From a pattern to a cloth: edges sampled by arc length, panels triangulated and placed in
//! 3D, and seam pairs matched by arc-length fraction.

use super::mesher::{first_crossing, triangulate};
use super::{EdgeRef, Pattern};
use crate::error::InputError;
use crate::mesh::TriMesh;
use glam::{DVec2, DVec3, Vec2};
use std::collections::HashMap;

/// A panel placement in pattern units and Euler degrees (as the spec's own).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Translation, pattern units.
    pub translation: DVec3,
    /// Rotation, Euler degrees, R = Rz·Ry·Rx.
    pub rotation_deg: DVec3,
}

/// How to build the cloth.
#[derive(Clone, Debug, PartialEq)]
pub struct GarmentOptions {
    /// Target particle spacing in m.
    pub particle_distance: f64,
    /// Placements that replace the spec's, by panel name.
    pub placement: HashMap<String, Placement>,
}

/// A seam vertex and its partner point on the other edge: `(1 − w)·x[b[0]] + w·x[b[1]]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeamPair {
    /// The seam vertex.
    pub a: u32,
    /// The partner segment's ends.
    pub b: [u32; 2],
    /// Weight of `b[1]`.
    pub w: f32,
    /// Which stitch of the pattern.
    pub stitch: u32,
}

/// A bending hinge across a seam: edge `v[0]`→`v[1]` on the first panel, `v[2]` the opposite
/// vertex of its boundary triangle there, `v[3]` the opposite vertex on the other panel. Its
/// layout matches `Hinge::v`, so that a positive angle folds convex outward.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SeamHinge {
    /// Shared edge (first panel) and the two opposite vertices.
    pub v: [u32; 4],
    /// The edge on the other panel that the first panel's is sewn to: with `v[3]`, the other
    /// panel's boundary triangle.
    pub other_edge: [u32; 2],
    /// Which stitch of the pattern.
    pub stitch: u32,
}

/// The assembled cloth.
#[derive(Clone, Debug)]
pub struct Garment {
    /// Particles in m and triangles facing outward.
    pub mesh: TriMesh,
    /// Each particle's 2D pattern coordinate, in m.
    pub uv: Vec<Vec2>,
    /// The particles along each edge, per panel, in edge direction (ends included).
    pub edge_particles: Vec<Vec<Vec<u32>>>,
    /// Seam pairs of all stitches.
    pub seam_pairs: Vec<SeamPair>,
    /// Number of stitches (seams).
    pub stitches: usize,
    /// Hinges across every seam segment.
    pub seam_hinges: Vec<SeamHinge>,
    /// Each edge's label, per panel.
    pub edge_labels: Vec<Vec<Option<String>>>,
    /// The panels' names, in pattern order.
    pub panel_names: Vec<String>,
    /// The panel (index into `panel_names`) of each triangle of `mesh`.
    pub triangle_panel: Vec<u32>,
}

impl Garment {
    /// The garment's panels in pattern coordinates, one chart per panel.
    pub fn charted(&self) -> crate::mesh::Charted {
        crate::mesh::Charted {
            uv: self.uv.clone(),
            triangles: self.mesh.triangles.clone(),
            triangle_chart: self.triangle_panel.clone(),
            charts: self.panel_names.len(),
        }
    }

    /// The particles on edges labelled with any of `labels`, sorted and unique.
    pub fn particles_on_labelled_edges(&self, labels: &[String]) -> Vec<u32> {
        let mut ids: Vec<u32> = (self.edge_labels.iter().zip(&self.edge_particles))
            .flat_map(|(panel_labels, panel_edges)| panel_labels.iter().zip(panel_edges))
            .filter(|(label, _)| label.as_ref().is_some_and(|l| labels.contains(l)))
            .flat_map(|(_, ids)| ids.iter().copied())
            .collect();
        ids.sort_unstable();
        ids.dedup();
        ids
    }
}

/// The most particles all panel outlines together may take: 4 million (a 2000×2000 grid's
/// worth, beyond which the particle budget refuses any garment anyway).
pub const MAX_OUTLINE_PARTICLES: usize = 4_000_000;

impl Garment {
    /// Builds the cloth for `pattern`.
    pub fn build(pattern: &Pattern, options: &GarmentOptions) -> Result<Garment, InputError> {
        Self::build_within(pattern, options, usize::MAX)
    }

    /// Builds the cloth for `pattern` with at most `max_particles` particles: a panel whose
    /// mesh would take more is refused as it is meshed, before the memory is spent.
    pub fn build_within(
        pattern: &Pattern,
        options: &GarmentOptions,
        max_particles: usize,
    ) -> Result<Garment, InputError> {
        let unit = pattern.units_in_meter;
        let spacing = options.particle_distance * unit; // in pattern units
        let err = |loc: String, problem: String, fix: &str| {
            InputError::new(&pattern.path, loc, problem, fix)
        };
        // Segments per edge at the particle distance; both edges of a stitch take the larger.
        let mut segments: Vec<Vec<usize>> = pattern
            .panels
            .iter()
            .map(|p| {
                p.edges
                    .iter()
                    // `as` saturates: an infinite or NaN length becomes usize::MAX or 0 here and
                    // is refused below (NaN lengths are refused when the pattern loads).
                    .map(|e| ((e.curve.length() / spacing).round() as usize).max(1))
                    .collect()
            })
            .collect();
        for s in &pattern.stitches {
            let [a, b] = s.sides;
            let n = segments[a.panel][a.edge].max(segments[b.panel][b.edge]);
            segments[a.panel][a.edge] = n;
            segments[b.panel][b.edge] = n;
        }
        // An outline this long is a mistake (a stray control point, a unit slip), and sampling
        // it would exhaust memory before the particle budget, which counts area, could object.
        let total = (segments.iter().flatten()).fold(0usize, |a, &b| a.saturating_add(b));
        if total > MAX_OUTLINE_PARTICLES {
            let (pi, ei) = (0..pattern.panels.len())
                .flat_map(|p| (0..segments[p].len()).map(move |e| (p, e)))
                .max_by_key(|&(p, e)| segments[p][e])
                .expect("a pattern with panels");
            let panel = &pattern.panels[pi];
            return Err(err(
                format!("panel '{}', edge {ei}", panel.name),
                format!(
                    "the outlines need {total} particles at particle_distance_m = {:.4} (this \
                     edge is {:.3e} m long), more than {MAX_OUTLINE_PARTICLES}",
                    options.particle_distance,
                    panel.edges[ei].curve.length() / unit
                ),
                &format!(
                    "check the edge's vertices and curvature control points, and the \
                     pattern's units_in_meter, or use particle_distance_m = {:.4} or more \
                     (outline particles fall in proportion)",
                    options.particle_distance * total as f64 / MAX_OUTLINE_PARTICLES as f64
                ),
            ));
        }
        let mut positions = Vec::new();
        let mut uv = Vec::new();
        let mut triangles = Vec::new();
        let mut triangle_panel = Vec::new();
        let mut edge_particles: Vec<Vec<Vec<u32>>> = Vec::new();
        for (pi, panel) in pattern.panels.iter().enumerate() {
            let mut outline: Vec<DVec2> = Vec::new();
            let mut edge_start = Vec::new();
            for (ei, e) in panel.edges.iter().enumerate() {
                edge_start.push(outline.len());
                let pts = e.curve.sample(segments[pi][ei]);
                outline.extend_from_slice(&pts[..pts.len() - 1]);
            }
            let edge_of = |seg: usize| edge_start.iter().rposition(|&s| s <= seg).unwrap_or(0);
            if let Some((i, j)) = first_crossing(&outline) {
                return Err(err(
                    format!("panel '{}'", panel.name),
                    format!(
                        "outline intersects itself: edge {} crosses edge {}",
                        edge_of(i),
                        edge_of(j)
                    ),
                    "fix the vertices or curvature so that the outline is a simple loop",
                ));
            }
            let room = max_particles.saturating_sub(positions.len() + outline.len());
            let mesh = triangulate(&outline, spacing, room).map_err(|m| {
                let finest = (0..panel.edges.len())
                    .map(|e| panel.edges[e].curve.length() / unit / segments[pi][e] as f64)
                    .fold(f64::INFINITY, f64::min);
                err(
                    format!("panel '{}'", panel.name),
                    format!(
                        "cannot be triangulated: {m} (its outline's finest segments are \
                         {finest:.2e} m at particle_distance_m = {}: an edge sewn to a much \
                         longer one takes that edge's particle count)",
                        options.particle_distance as f32
                    ),
                    "check the outline and the lengths of the stitched edges, use a coarser \
                     particle_distance_m, or raise solver.max_memory_mb",
                )
            })?;
            let base = positions.len() as u32;
            let place = options
                .placement
                .get(&panel.name)
                .copied()
                .unwrap_or(Placement {
                    translation: panel.translation,
                    rotation_deg: panel.rotation_deg,
                });
            let mut placed = panel.clone();
            placed.rotation_deg = place.rotation_deg;
            let rotation = placed.rotation();
            for p in &mesh.points {
                let world = (rotation * DVec3::new(p.x, p.y, 0.0) + place.translation) / unit;
                positions.push(world.as_vec3());
                uv.push((*p / unit).as_vec2());
            }
            // Spade's triangles are counter-clockwise in the panel plane (normal +z there). A
            // counter-clockwise loop faces +z (away from the body); a clockwise one faces −z.
            let flip = panel.signed_area2() < 0.0;
            for t in &mesh.triangles {
                let t = t.map(|v| v + base);
                triangles.push(if flip { [t[0], t[2], t[1]] } else { t });
                triangle_panel.push(pi as u32);
            }
            let n = outline.len();
            edge_particles.push(
                (0..panel.edges.len())
                    .map(|ei| {
                        (0..=segments[pi][ei])
                            .map(|k| base + ((edge_start[ei] + k) % n) as u32)
                            .collect()
                    })
                    .collect(),
            );
        }
        // Each directed boundary edge (a→b in its triangle's winding) and its opposite vertex.
        let mut opposite: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &triangles {
            for k in 0..3 {
                opposite.insert((t[k], t[(k + 1) % 3]), t[(k + 2) % 3]);
            }
        }
        let mut seam_pairs = Vec::new();
        let mut seam_hinges = Vec::new();
        for (k, s) in pattern.stitches.iter().enumerate() {
            let along = |e: EdgeRef| edge_particles[e.panel][e.edge].clone();
            let mut first = along(s.sides[0]);
            if !s.right_wrong {
                first.reverse();
            }
            let second = along(s.sides[1]);
            seam_pairs.extend(pair_edges(&first, &second, &uv, k as u32));
            // Both edges have the same count, so segment j of one faces segment j of the other.
            for j in 0..first
                .len()
                .saturating_sub(1)
                .min(second.len().saturating_sub(1))
            {
                let (a0, a1, b0, b1) = (first[j], first[j + 1], second[j], second[j + 1]);
                let hinge = match (opposite.get(&(a0, a1)), opposite.get(&(a1, a0))) {
                    (Some(&o1), _) => opposite
                        .get(&(b1, b0))
                        .or(opposite.get(&(b0, b1)))
                        .map(|&o2| [a0, a1, o1, o2]),
                    (None, Some(&o1)) => opposite
                        .get(&(b0, b1))
                        .or(opposite.get(&(b1, b0)))
                        .map(|&o2| [a1, a0, o1, o2]),
                    _ => None,
                };
                if let Some(v) = hinge {
                    seam_hinges.push(SeamHinge {
                        v,
                        other_edge: [b0, b1],
                        stitch: k as u32,
                    });
                }
            }
        }
        Ok(Garment {
            mesh: TriMesh {
                positions,
                triangles,
            },
            uv,
            edge_particles,
            seam_pairs,
            stitches: pattern.stitches.len(),
            seam_hinges,
            edge_labels: (pattern.panels.iter())
                .map(|p| p.edges.iter().map(|e| e.label.clone()).collect())
                .collect(),
            panel_names: pattern.panels.iter().map(|p| p.name.clone()).collect(),
            triangle_panel,
        })
    }
}

/// Arc-length fraction of each point of a polyline (0 at the start, 1 at the end).
fn fractions(ids: &[u32], uv: &[Vec2]) -> Vec<f32> {
    let mut acc = vec![0.0f32];
    for w in ids.windows(2) {
        acc.push(acc.last().unwrap() + uv[w[0] as usize].distance(uv[w[1] as usize]));
    }
    let total = acc.last().copied().unwrap_or(0.0).max(f32::MIN_POSITIVE);
    acc.iter().map(|a| a / total).collect()
}

/// The point at fraction `f` of a polyline, as (segment ends, weight of the second end).
fn locate(ids: &[u32], fr: &[f32], f: f32) -> ([u32; 2], f32) {
    let k = fr.partition_point(|&x| x <= f).clamp(1, ids.len() - 1) - 1;
    let span = fr[k + 1] - fr[k];
    let w = if span > 0.0 {
        ((f - fr[k]) / span).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ([ids[k], ids[k + 1]], w)
}

/// Seam pairs between two edges given in sewing order (`first[0]` meets `second[0]`): every
/// vertex of `first` pairs with the point at the same arc-length fraction of `second`; every
/// vertex of `second` that does not already coincide with such a point pairs with `first`.
pub fn pair_edges(first: &[u32], second: &[u32], uv: &[Vec2], stitch: u32) -> Vec<SeamPair> {
    // Fractions closer than this name the same point (f32 rounding of sums of ~100 lengths).
    const SAME: f32 = 1e-5;
    let (fa, fb) = (fractions(first, uv), fractions(second, uv));
    let mut pairs: Vec<SeamPair> = first
        .iter()
        .zip(&fa)
        .map(|(&a, &f)| {
            let (b, w) = locate(second, &fb, f);
            SeamPair { a, b, w, stitch }
        })
        .collect();
    for (&b, &f) in second.iter().zip(&fb) {
        if fa.iter().any(|&x| (x - f).abs() < SAME) {
            continue;
        }
        let (a_seg, w) = locate(first, &fa, f);
        pairs.push(SeamPair {
            a: b,
            b: a_seg,
            w,
            stitch,
        });
    }
    pairs
}
