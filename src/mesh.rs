//! Triangle meshes for cloth: a rectangular grid generator, OBJ loading, and the topology the
//! model needs (unique edges, the vertices opposite each edge, per-vertex area shares).

use crate::error::InputError;
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// An indexed triangle mesh in metres.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions in m.
    pub positions: Vec<Vec3>,
    /// Triangles as vertex indices, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
}

/// Which world plane a grid lies in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridPlane {
    /// Vertical: columns along +x, rows along +y ("top" is highest).
    Xy,
    /// Horizontal: columns along +x, rows along −z ("top" is farthest, at the most negative z).
    Xz,
}

/// A mesh edge with the vertices opposite it in its one or two triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    /// Endpoints, smaller index first.
    pub v: [u32; 2],
    /// Opposite vertex in the first and (for interior edges) the second triangle.
    pub opposite: [Option<u32>; 2],
}

impl TriMesh {
    /// A `columns × rows` particle grid of `width × height` metres centred on `center`.
    /// Cell diagonals alternate so that the grid has no preferred shear direction.
    pub fn grid(
        width: f32,
        height: f32,
        columns: u32,
        rows: u32,
        center: Vec3,
        plane: GridPlane,
    ) -> Self {
        let mut positions = Vec::with_capacity((columns * rows) as usize);
        for r in 0..rows {
            for c in 0..columns {
                let u = (c as f32 / (columns - 1) as f32 - 0.5) * width;
                let v = (r as f32 / (rows - 1) as f32 - 0.5) * height;
                let offset = match plane {
                    GridPlane::Xy => Vec3::new(u, v, 0.0),
                    GridPlane::Xz => Vec3::new(u, 0.0, -v),
                };
                positions.push(center + offset);
            }
        }
        let id = |r: u32, c: u32| r * columns + c;
        let mut triangles = Vec::with_capacity(2 * ((columns - 1) * (rows - 1)) as usize);
        for r in 0..rows - 1 {
            for c in 0..columns - 1 {
                let (a, b, cc, d) = (id(r, c), id(r, c + 1), id(r + 1, c + 1), id(r + 1, c));
                if (r + c) % 2 == 0 {
                    triangles.push([a, b, cc]);
                    triangles.push([a, cc, d]);
                } else {
                    triangles.push([a, b, d]);
                    triangles.push([b, cc, d]);
                }
            }
        }
        TriMesh {
            positions,
            triangles,
        }
    }

    /// Loads a triangulated (or polygonal) OBJ, scaling coordinates by `scale` to metres.
    pub fn load_obj(path: &Path, scale: f32, key: &str) -> Result<Self, InputError> {
        let (models, _materials) = tobj::load_obj(path, &Self::obj_options()).map_err(|e| {
            InputError::new(
                path,
                key,
                format!("cannot read the mesh: {e}"),
                "check that the path exists (it is relative to the scene file) and is a text OBJ",
            )
        })?;
        Self::from_obj_models(&models, path, scale, key)
    }

    /// Parses OBJ text held in memory (`name` stands for its path in errors).
    pub fn parse_obj(text: &str, name: &Path, scale: f32, key: &str) -> Result<Self, InputError> {
        let mut reader = std::io::BufReader::new(text.as_bytes());
        let (models, _materials) =
            tobj::load_obj_buf(
                &mut reader,
                &Self::obj_options(),
                |_| Ok(Default::default()),
            )
            .map_err(|e| {
                InputError::new(
                    name,
                    key,
                    format!("cannot parse the mesh: {e}"),
                    "give a text OBJ",
                )
            })?;
        Self::from_obj_models(&models, name, scale, key)
    }

    fn obj_options() -> tobj::LoadOptions {
        tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        }
    }

    fn from_obj_models(
        models: &[tobj::Model],
        path: &Path,
        scale: f32,
        key: &str,
    ) -> Result<Self, InputError> {
        let mut mesh = TriMesh::default();
        for model in models {
            let base = mesh.positions.len() as u32;
            for p in model.mesh.positions.chunks_exact(3) {
                mesh.positions.push(Vec3::new(p[0], p[1], p[2]) * scale);
            }
            for t in model.mesh.indices.chunks_exact(3) {
                mesh.triangles.push([base + t[0], base + t[1], base + t[2]]);
            }
        }
        if mesh.triangles.is_empty() {
            return Err(InputError::new(
                path,
                key,
                "the mesh has no faces",
                "export the cloth as a triangle or polygon mesh with `f` records",
            ));
        }
        if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
            return Err(InputError::new(
                path,
                key,
                format!("vertex {} has a non-finite coordinate", i + 1),
                "repair the mesh: every coordinate must be a finite number",
            ));
        }
        Ok(mesh)
    }

    /// Merges vertices at exactly the same position into the first of them, keeping the order
    /// of first appearance, and returns how many were merged. OBJ exporters split a vertex
    /// wherever its texture coordinate or normal changes (and between objects), which would
    /// make a closed body look open along every UV seam.
    pub fn weld_coincident(&mut self) -> usize {
        let before = self.positions.len();
        self.weld_map();
        before - self.positions.len()
    }

    /// `weld_coincident`, returning for each old vertex its new index (what per-vertex data
    /// such as skin weights needs to follow the weld).
    pub fn weld_map(&mut self) -> Vec<u32> {
        let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(self.positions.len());
        let mut positions = Vec::with_capacity(self.positions.len());
        let remap: Vec<u32> = self
            .positions
            .iter()
            .map(|p| {
                // Adding +0 turns −0 into +0, so that the two weld.
                let key = (*p + Vec3::ZERO).to_array().map(f32::to_bits);
                *first.entry(key).or_insert_with(|| {
                    positions.push(*p);
                    positions.len() as u32 - 1
                })
            })
            .collect();
        for t in &mut self.triangles {
            *t = t.map(|i| remap[i as usize]);
        }
        self.positions = positions;
        remap
    }

    /// Unique edges with their opposite vertices, sorted by endpoints for determinism.
    /// An edge shared by more than two triangles (non-manifold) keeps only the first two.
    pub fn edges(&self) -> Vec<Edge> {
        self.edges_with_areas()
            .into_iter()
            .map(|(e, _)| e)
            .collect()
    }

    /// `edges`, each with the summed area of the triangles on it (in triangle order). Linear in
    /// the mesh: the triangle sides are bucketed by their lower vertex (a counting sort) and
    /// each bucket of a few sides is sorted by the upper one; a hash map here made 4M-particle
    /// models take 25 s through cache misses.
    pub fn edges_with_areas(&self) -> Vec<(Edge, f32)> {
        let n = self.positions.len();
        let mut start = vec![0u32; n + 1];
        for t in &self.triangles {
            for k in 0..3 {
                start[t[k].min(t[(k + 1) % 3]) as usize + 1] += 1;
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        // (upper vertex, opposite vertex, triangle area), grouped by lower vertex.
        let mut sides = vec![(0u32, 0u32, 0.0f32); 3 * self.triangles.len()];
        let mut cursor = start.clone();
        for &t in &self.triangles {
            let area = self.triangle_area(t);
            for k in 0..3 {
                let (a, b, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let slot = &mut cursor[a.min(b) as usize];
                sides[*slot as usize] = (a.max(b), o, area);
                *slot += 1;
            }
        }
        let mut edges = Vec::with_capacity(sides.len() / 2 + n);
        for v in 0..n {
            let bucket = &mut sides[start[v] as usize..start[v + 1] as usize];
            // Stable: sides of one edge keep triangle order (first two opposites, area sum).
            bucket.sort_by_key(|s| s.0);
            let mut k = 0;
            while k < bucket.len() {
                let upper = bucket[k].0;
                let mut edge = Edge {
                    v: [v as u32, upper],
                    opposite: [Some(bucket[k].1), None],
                };
                let mut area = bucket[k].2;
                k += 1;
                while k < bucket.len() && bucket[k].0 == upper {
                    if edge.opposite[1].is_none() {
                        edge.opposite[1] = Some(bucket[k].1);
                    }
                    area += bucket[k].2;
                    k += 1;
                }
                edges.push((edge, area));
            }
        }
        edges
    }

    /// Area of triangle `t` in m².
    pub fn triangle_area(&self, t: [u32; 3]) -> f32 {
        let [a, b, c] = t.map(|i| self.positions[i as usize]);
        0.5 * (b - a).cross(c - a).length()
    }

    /// Each vertex's share of the surface: a third of each incident triangle's area.
    pub fn vertex_areas(&self) -> Vec<f32> {
        let mut areas = vec![0.0; self.positions.len()];
        for &t in &self.triangles {
            let share = self.triangle_area(t) / 3.0;
            for v in t {
                areas[v as usize] += share;
            }
        }
        areas
    }
}

/// Area-weighted vertex normals: each vertex sums the cross products of its triangles, so a
/// larger triangle weighs more. Unnormalised (a vertex of no triangle gets zero); callers that
/// need unit normals normalise.
pub fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let face = (b - a).cross(c - a);
        for &i in t {
            n[i as usize] += face;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_counts_and_area() {
        let m = TriMesh::grid(2.0, 1.0, 5, 3, Vec3::ZERO, GridPlane::Xy);
        assert_eq!(m.positions.len(), 15);
        assert_eq!(m.triangles.len(), 2 * 4 * 2);
        let total: f32 = m.vertex_areas().iter().sum();
        // Exact area 2 m²; f32 sums of 24 terms are good to ~1e-6 relative.
        assert!((total - 2.0).abs() < 1e-5, "{total}");
        let edges = m.edges();
        // Euler: E = V + F - 1 for a disc.
        assert_eq!(edges.len(), 15 + 16 - 1);
        let interior = edges.iter().filter(|e| e.opposite[1].is_some()).count();
        // Interior edges = (3F - boundary)/2, boundary = 2(4+2) = 12.
        assert_eq!(interior, (3 * 16 - 12) / 2);
    }
}

/// A triangle mesh with 2D chart coordinates: a garment's panels in pattern space, or a grid
/// in its plane. Two meshings of the same charts can exchange values through them.
#[derive(Clone, Debug, Default)]
pub struct Charted {
    /// Each particle's 2D chart coordinate, in m.
    pub uv: Vec<Vec2>,
    /// The triangles.
    pub triangles: Vec<[u32; 3]>,
    /// The chart (panel) of each triangle.
    pub triangle_chart: Vec<u32>,
    /// Number of charts.
    pub charts: usize,
}

impl Charted {
    /// A `columns` × `rows` grid of `width` × `height` m as `TriMesh::grid` builds it (the
    /// same particle order and triangles), in its own plane.
    pub fn grid(width: f32, height: f32, columns: u32, rows: u32) -> Charted {
        let mesh = TriMesh::grid(width, height, columns, rows, Vec3::ZERO, GridPlane::Xy);
        Charted {
            uv: mesh.positions.iter().map(|p| p.truncate()).collect(),
            triangle_chart: vec![0; mesh.triangles.len()],
            triangles: mesh.triangles,
            charts: 1,
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.uv.len()
    }

    /// Whether the mesh has no particles.
    pub fn is_empty(&self) -> bool {
        self.uv.is_empty()
    }
}
