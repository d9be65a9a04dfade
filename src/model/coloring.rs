//! Greedy vertex colouring for Vertex Block Descent: no two vertices that share a spring, a
//! hinge or a seam pair get the same colour, so all vertices of one colour can take their
//! Newton step at once without reading each other's new positions.

use super::layout::Sweep;
use super::ClothModel;

/// Vertices grouped by colour: `order[offsets[c]..offsets[c + 1]]` are the vertices of colour
/// `c`, in increasing index order. Both backends sweep the colours in this order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Coloring {
    /// The colour of each vertex.
    pub color_of: Vec<u32>,
    /// Vertex indices sorted by (colour, index).
    pub order: Vec<u32>,
    /// `colors + 1` offsets into `order`.
    pub offsets: Vec<u32>,
}

impl Coloring {
    /// Number of colours.
    pub fn colors(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The sweeps of one implicit substep: every colour in order, `iterations` times.
    pub fn sweeps(&self, iterations: u32) -> Vec<Sweep> {
        let mut out = Vec::new();
        for it in 0..iterations {
            for c in 0..self.colors() {
                out.push(Sweep {
                    first: self.offsets[c],
                    count: self.offsets[c + 1] - self.offsets[c],
                    iteration: it,
                    _pad0: 0,
                });
            }
        }
        out
    }
}

impl ClothModel {
    /// Colours the vertex adjacency of the springs, hinges (all four vertices pairwise) and
    /// seam pairs (vertex and both partner ends pairwise) greedily in index order: each vertex
    /// takes the smallest colour none of its lower-indexed neighbours has. Linear in the number
    /// of adjacency entries; deterministic.
    pub fn vertex_coloring(&self) -> Coloring {
        let n = self.len();
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut clique = |vs: &[u32]| {
            for (k, &a) in vs.iter().enumerate() {
                for &b in &vs[k + 1..] {
                    if a != b {
                        pairs.push((a, b));
                        pairs.push((b, a));
                    }
                }
            }
        };
        for s in &self.springs {
            clique(&s.ends);
        }
        for h in &self.hinges {
            clique(&h.v);
        }
        for s in &self.seams {
            clique(&s.v[..3]);
        }
        let adjacency = super::Csr::from_pairs(n, &pairs);
        let color_of = greedy_colors(n, &adjacency.offsets, &adjacency.items);
        let (order, offsets) = sort_by_color(&color_of);
        Coloring {
            color_of,
            order,
            offsets,
        }
    }
}

/// Each vertex's colour: the smallest none of its lower-indexed neighbours has (neighbours of
/// v: `neighbours[offsets[v]..offsets[v + 1]]`; v itself may be among them).
fn greedy_colors(n: usize, offsets: &[u32], neighbours: &[u32]) -> Vec<u32> {
    let mut color_of = vec![u32::MAX; n];
    // `seen[c] == v` marks colour c as taken by a neighbour of v.
    let mut seen: Vec<usize> = Vec::new();
    for v in 0..n {
        let (start, end) = (offsets[v], offsets[v + 1]);
        for &w in &neighbours[start as usize..end as usize] {
            let c = color_of[w as usize];
            if c != u32::MAX && w as usize != v {
                if seen.len() <= c as usize {
                    seen.resize(c as usize + 1, usize::MAX);
                }
                seen[c as usize] = v;
            }
        }
        let c = (0..)
            .find(|&c| seen.get(c).is_none_or(|&s| s != v))
            .unwrap_or(0);
        color_of[v] = c as u32;
    }
    color_of
}

/// Vertices sorted by (colour, index), and the `colours + 1` offsets of each colour.
fn sort_by_color(color_of: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let colors = color_of.iter().map(|&c| c as usize + 1).max().unwrap_or(0);
    let mut offsets = vec![0u32; colors + 1];
    for &c in color_of {
        offsets[c as usize + 1] += 1;
    }
    for c in 0..colors {
        offsets[c + 1] += offsets[c];
    }
    let mut cursor = offsets.clone();
    let mut order = vec![0u32; color_of.len()];
    for (v, &c) in color_of.iter().enumerate() {
        order[cursor[c as usize] as usize] = v as u32;
        cursor[c as usize] += 1;
    }
    (order, offsets)
}

/// A greedy colouring of a block-sparse matrix's graph (rows joined by a block): the rows by
/// colour and the colours' offsets, as `Coloring::order` and `Coloring::offsets`.
pub(super) fn greedy_coloring(n: usize, offsets: &[u32], columns: &[u32]) -> (Vec<u32>, Vec<u32>) {
    sort_by_color(&greedy_colors(n, offsets, columns))
}

#[cfg(test)]
mod tests {
    use crate::mesh::{GridPlane, TriMesh};
    use crate::model::ClothModel;
    use crate::scene::Fabric;
    use glam::Vec3;

    #[test]
    fn no_element_joins_two_vertices_of_one_colour() {
        let mesh = TriMesh::grid(1.0, 1.0, 9, 7, Vec3::ZERO, GridPlane::Xy);
        let fabric = Fabric::linear(100.0);
        let model = ClothModel::from_mesh(&mesh, &fabric, &[]);
        let coloring = model.vertex_coloring();
        let c = |v: u32| coloring.color_of[v as usize];
        for s in &model.springs {
            assert_ne!(c(s.ends[0]), c(s.ends[1]));
        }
        for h in &model.hinges {
            for a in 0..4 {
                for b in a + 1..4 {
                    assert_ne!(c(h.v[a]), c(h.v[b]), "hinge {:?}", h.v);
                }
            }
        }
        // Every vertex appears once in the order, under its own colour.
        let mut sorted = coloring.order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..model.len() as u32).collect::<Vec<_>>());
        for col in 0..coloring.colors() {
            let range = coloring.offsets[col]..coloring.offsets[col + 1];
            for k in range {
                assert_eq!(c(coloring.order[k as usize]), col as u32);
            }
        }
        // A grid with hinges: each vertex touches at most 12 others (6 by edges, 6 across
        // hinges), so greedy colouring needs at most 13 colours.
        assert!(coloring.colors() <= 13, "{} colours", coloring.colors());
    }
}
