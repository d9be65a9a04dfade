//! The multigrid hierarchy of implicit Euler's solve: the same cloth meshed at twice, four times,
//! … the particle spacing (the coarse levels), how values move between neighbouring levels
//! (barycentric prolongation P in the charts' 2D coordinates, and its transpose), and the
//! block-sparse structure of each level's matrix.
//!
//! The fine level's matrix is the Hessian of the incremental potential, assembled per vertex
//! from its elements; each coarse level's is the Galerkin product PᵀAP of the level below,
//! gathered block by block from a list built here once. Seams, pins, contact and friction
//! reach the coarse levels through the fine Hessian: no coarse level models them itself.

use super::coloring::greedy_coloring;
use super::{ClothModel, Csr};
use crate::mesh::Charted;
use crate::pattern::transfer::Transfer;

/// Where a block-sparse matrix keeps its 3×3 blocks: row i's are `offsets[i]..offsets[i + 1]`,
/// the first the diagonal, then the row's other columns in increasing order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BlockPattern {
    /// `rows + 1` offsets into `columns`.
    pub offsets: Vec<u32>,
    /// The column (particle) of every block.
    pub columns: Vec<u32>,
}

impl BlockPattern {
    /// The pattern with the diagonal and every `(row, column)` pair given (duplicates merged).
    fn from_pairs(rows: usize, pairs: &[(u32, u32)]) -> BlockPattern {
        // Bucketed by row in one pass, then each row's few columns sorted on their own: a
        // coarse level's millions of pairs fall into rows of tens.
        let by_row = Csr::from_pairs(rows, pairs);
        let mut offsets = Vec::with_capacity(rows + 1);
        offsets.push(0u32);
        let mut columns = Vec::with_capacity(by_row.items.len());
        let mut row = Vec::new();
        for i in 0..rows {
            let range = by_row.offsets[i] as usize..by_row.offsets[i + 1] as usize;
            row.clear();
            row.push(i as u32);
            row.extend_from_slice(&by_row.items[range]);
            // The diagonal sorts first in its row.
            row.sort_unstable_by_key(|&j| (j != i as u32, j));
            row.dedup();
            columns.extend_from_slice(&row);
            offsets.push(columns.len() as u32);
        }
        BlockPattern { offsets, columns }
    }

    /// Number of rows (particles).
    pub fn rows(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of blocks.
    pub fn blocks(&self) -> usize {
        self.columns.len()
    }

    /// The block at (`row`, `column`), if the pattern has it.
    pub fn find(&self, row: u32, column: u32) -> Option<u32> {
        let (start, end) = (self.offsets[row as usize], self.offsets[row as usize + 1]);
        if column == row {
            return Some(start);
        }
        let others = &self.columns[start as usize + 1..end as usize];
        others
            .binary_search(&column)
            .ok()
            .map(|k| start + 1 + k as u32)
    }
}

/// Where the fine Hessian's element blocks go: for each entry of the model's incidence lists
/// (`spring_csr`, `hinge_csr`, `seam_csr`), the blocks of the entry's particle's row that the
/// element's vertices occupy.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ElementBlocks {
    /// Per spring entry: the block of the spring's other end.
    pub springs: Vec<u32>,
    /// Per hinge entry: the blocks of the hinge's four vertices, in hinge order (the entry's
    /// own role holds its diagonal).
    pub hinges: Vec<[u32; 4]>,
    /// Per seam entry: the blocks of the pair's seam vertex and partner ends; w unused.
    pub seams: Vec<[u32; 4]>,
    /// Per membrane entry: the blocks of the triangle's three vertices; w unused.
    pub membranes: Vec<[u32; 4]>,
}

/// One coarse level and its link to the level below it (the next finer one).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Level {
    /// The level's particle spacing, in m.
    pub spacing_m: f32,
    /// The structure of the level's matrix.
    pub pattern: BlockPattern,
    /// Particles by colour, for Gauss–Seidel smoothing: no block joins two of one colour.
    pub order: Vec<u32>,
    /// `colours + 1` offsets into `order`.
    pub color_offsets: Vec<u32>,
    /// Prolongation: for each particle of the finer level, its three parents on this level
    /// and their weights (a finer value is Σ weight·parent).
    pub parents: Vec<[u32; 3]>,
    /// The weights of `parents`.
    pub weights: Vec<[f32; 3]>,
    /// Restriction (Pᵀ): for each particle of this level, its finer children and weights.
    pub children: Csr<(u32, f32)>,
    /// The Galerkin product: for each block of this level, the finer blocks and the weights
    /// P_iI·P_jJ it sums.
    pub galerkin: Csr<(u32, f32)>,
}

impl Level {
    /// Particles on this level.
    pub fn len(&self) -> usize {
        self.pattern.rows()
    }

    /// Whether the level is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of colours.
    pub fn colors(&self) -> usize {
        self.color_offsets.len() - 1
    }

    /// The particles of colour `k`.
    pub fn color_rows(&self, k: usize) -> &[u32] {
        &self.order[self.color_offsets[k] as usize..self.color_offsets[k + 1] as usize]
    }
}

/// The fine level's structure and the coarse levels, finest first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Multigrid {
    /// The fine (model) level's matrix structure.
    pub fine: BlockPattern,
    /// Where each element's Hessian blocks go in the fine matrix.
    pub element_blocks: ElementBlocks,
    /// The coarse levels, finest first.
    pub levels: Vec<Level>,
}

impl Multigrid {
    /// The hierarchy for `model`, whose particles are those of `fine`, over the coarser
    /// meshings of the same charts in `coarser` (finest first).
    pub fn build(model: &ClothModel, fine: &Charted, coarser: &[Charted]) -> Multigrid {
        let (pattern, element_blocks) = fine_structure(model);
        let mut levels: Vec<Level> = Vec::new();
        let mut finer_chart = fine;
        for chart in coarser {
            let finer_pattern = levels.last().map_or(&pattern, |l| &l.pattern);
            let transfer = Transfer::between(chart, finer_chart);
            let mut level = coarse_level(chart.len(), finer_pattern, &transfer);
            level.spacing_m = mean_edge(chart);
            levels.push(level);
            finer_chart = chart;
        }
        Multigrid {
            fine: pattern,
            element_blocks,
            levels,
        }
    }

    /// Particles on each level, the fine level first.
    pub fn sizes(&self) -> Vec<usize> {
        std::iter::once(self.fine.rows())
            .chain(self.levels.iter().map(Level::len))
            .collect()
    }
}

/// The mean edge length of a charted mesh, in m.
fn mean_edge(chart: &Charted) -> f32 {
    let mut sum = 0.0f64;
    for t in &chart.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            sum += chart.uv[a].distance(chart.uv[b]) as f64;
        }
    }
    (sum / (3 * chart.triangles.len()).max(1) as f64) as f32
}

/// The fine matrix's structure (every pair of particles that share a spring, a hinge or a
/// seam pair) and where each element entry's blocks go.
fn fine_structure(model: &ClothModel) -> (BlockPattern, ElementBlocks) {
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    let mut clique = |vs: &[u32]| {
        for &a in vs {
            for &b in vs {
                if a != b {
                    pairs.push((a, b));
                }
            }
        }
    };
    for s in &model.springs {
        clique(&s.ends);
    }
    for h in &model.hinges {
        clique(&h.v);
    }
    for s in &model.seams {
        clique(&s.v[..3]);
    }
    for m in &model.membranes {
        clique(&m.v[..3]);
    }
    let pattern = BlockPattern::from_pairs(model.len(), &pairs);
    let block = |row: u32, column: u32| pattern.find(row, column).expect("in the pattern");
    let springs = model.spring_csr();
    let hinges = model.hinge_csr();
    let seams = model.seam_csr();
    let membranes = model.membrane_csr();
    let mut blocks = ElementBlocks::default();
    for i in 0..model.len() {
        let row = i as u32;
        for k in springs.offsets[i]..springs.offsets[i + 1] {
            let other = springs.items[k as usize].other;
            blocks.springs.push(block(row, other));
        }
        for k in hinges.offsets[i]..hinges.offsets[i + 1] {
            let h = &model.hinges[(hinges.items[k as usize] / 4) as usize];
            blocks.hinges.push(h.v.map(|v| block(row, v)));
        }
        for k in seams.offsets[i]..seams.offsets[i + 1] {
            let s = &model.seams[(seams.items[k as usize] / 4) as usize];
            let b = |r: usize| block(row, s.v[r]);
            blocks.seams.push([b(0), b(1), b(2), 0]);
        }
        for k in membranes.offsets[i]..membranes.offsets[i + 1] {
            let m = &model.membranes[(membranes.items[k as usize] / 4) as usize];
            let b = |r: usize| block(row, m.v[r]);
            blocks.membranes.push([b(0), b(1), b(2), 0]);
        }
    }
    (pattern, blocks)
}

/// A coarse level of `len` particles over the finer level's `finer` pattern, linked by
/// `transfer` (which locates every finer particle in the coarse mesh).
fn coarse_level(len: usize, finer: &BlockPattern, transfer: &Transfer) -> Level {
    let parents: Vec<[u32; 3]> = transfer.corners().iter().map(|(t, _)| *t).collect();
    let weights: Vec<[f32; 3]> = transfer
        .corners()
        .iter()
        .map(|(_, w)| w.to_array())
        .collect();
    // A finer particle's parents with non-zero weight.
    let (p, w) = (&parents, &weights);
    let links = |i: usize| {
        (0..3)
            .filter(move |&k| w[i][k] != 0.0)
            .map(move |k| (p[i][k], w[i][k]))
    };
    let mut child_pairs = Vec::new();
    for i in 0..finer.rows() {
        for (parent, w) in links(i) {
            child_pairs.push((parent, (i as u32, w)));
        }
    }
    let children = Csr::from_pairs(len, &child_pairs);
    // Every finer block (i, j) adds P_iI·P_jJ·A_ij to the coarse block (I, J).
    let mut terms: Vec<(u32, u32, u32, f32)> = Vec::new();
    for i in 0..finer.rows() {
        for b in finer.offsets[i]..finer.offsets[i + 1] {
            let j = finer.columns[b as usize] as usize;
            for (ci, wi) in links(i) {
                for (cj, wj) in links(j) {
                    terms.push((ci, cj, b, wi * wj));
                }
            }
        }
    }
    let pairs: Vec<(u32, u32)> = terms.iter().map(|t| (t.0, t.1)).collect();
    let pattern = BlockPattern::from_pairs(len, &pairs);
    // Each coarse block sums its terms in finer-block order, the same on every backend: the
    // terms come in finer-block order, and `Csr::from_pairs` keeps it within each coarse block.
    let galerkin_pairs: Vec<(u32, (u32, f32))> = terms
        .iter()
        .map(|&(ci, cj, b, w)| (pattern.find(ci, cj).expect("in the pattern"), (b, w)))
        .collect();
    let galerkin = Csr::from_pairs(pattern.blocks(), &galerkin_pairs);
    let (order, color_offsets) = greedy_coloring(len, &pattern.offsets, &pattern.columns);
    Level {
        spacing_m: 0.0,
        pattern,
        order,
        color_offsets,
        parents,
        weights,
        children,
        galerkin,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{GridPlane, TriMesh};
    use crate::scene::Fabric;
    use glam::Vec3;

    fn sheet(columns: u32) -> (ClothModel, Charted) {
        let mesh = TriMesh::grid(1.0, 1.0, columns, columns, Vec3::ZERO, GridPlane::Xy);
        let fabric = Fabric::linear(100.0);
        let model = ClothModel::from_mesh(&mesh, &fabric, &[]);
        (model, Charted::grid(1.0, 1.0, columns, columns))
    }

    #[test]
    fn prolongation_reproduces_affine_fields_and_weights_sum_to_one() {
        let (model, fine) = sheet(9);
        let coarse = [Charted::grid(1.0, 1.0, 5, 5), Charted::grid(1.0, 1.0, 3, 3)];
        let mg = Multigrid::build(&model, &fine, &coarse);
        assert_eq!(mg.sizes(), vec![81, 25, 9]);
        let field = |p: glam::Vec2| 2.0 * p.x - 3.0 * p.y + 0.5;
        for (level, (finer, chart)) in mg
            .levels
            .iter()
            .zip([(&fine, &coarse[0]), (&coarse[0], &coarse[1])])
        {
            for (i, (parents, w)) in level.parents.iter().zip(&level.weights).enumerate() {
                let sum: f32 = w.iter().sum();
                // Barycentric weights of f32 pattern points: a few ulps of 1.
                assert!((sum - 1.0).abs() < 1e-5, "{sum}");
                let blended: f32 = (0..3)
                    .map(|k| w[k] * field(chart.uv[parents[k] as usize]))
                    .sum();
                assert!((blended - field(finer.uv[i])).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn galerkin_terms_reproduce_the_dense_triple_product() {
        // With every fine block the identity, PᵀAP over the sparse lists equals the dense
        // product ΣᵢΣⱼ P_iI·A_ij·P_jJ computed from the parents directly.
        let (model, fine) = sheet(7);
        let mg = Multigrid::build(&model, &fine, &[Charted::grid(1.0, 1.0, 4, 4)]);
        let level = &mg.levels[0];
        let n = level.len();
        let mut dense = vec![vec![0.0f64; n]; n];
        let p = |i: usize| {
            (0..3).map(move |k| (level.parents[i][k] as usize, level.weights[i][k] as f64))
        };
        for i in 0..mg.fine.rows() {
            for b in mg.fine.offsets[i]..mg.fine.offsets[i + 1] {
                let j = mg.fine.columns[b as usize] as usize;
                for (ci, wi) in p(i) {
                    for (cj, wj) in p(j) {
                        dense[ci][cj] += wi * wj;
                    }
                }
            }
        }
        for (ci, row) in dense.iter_mut().enumerate().take(n) {
            for b in level.pattern.offsets[ci]..level.pattern.offsets[ci + 1] {
                let cj = level.pattern.columns[b as usize] as usize;
                let (s, e) = (
                    level.galerkin.offsets[b as usize],
                    level.galerkin.offsets[b as usize + 1],
                );
                let sum: f64 = level.galerkin.items[s as usize..e as usize]
                    .iter()
                    .map(|t| t.1 as f64)
                    .sum();
                // f32 weight products summed in f64: 1e-6 relative.
                assert!(
                    (sum - row[cj]).abs() < 1e-6 * (1.0 + row[cj].abs()),
                    "({ci}, {cj})"
                );
                row[cj] = 0.0;
            }
        }
        // Nothing of the product lies outside the coarse pattern.
        assert!(dense.iter().flatten().all(|&v| v.abs() < 1e-9));
    }

    #[test]
    fn coarse_rows_are_sorted_and_sum_their_terms_in_finer_block_order() {
        let (model, fine) = sheet(9);
        let mg = Multigrid::build(&model, &fine, &[Charted::grid(1.0, 1.0, 5, 5)]);
        let level = &mg.levels[0];
        for r in 0..level.len() {
            let row = &level.pattern.columns
                [level.pattern.offsets[r] as usize..level.pattern.offsets[r + 1] as usize];
            assert_eq!(row[0], r as u32, "row {r}: the diagonal first");
            assert!(row[1..].windows(2).all(|w| w[0] < w[1]), "row {r}: {row:?}");
            assert!(
                !row[1..].contains(&(r as u32)),
                "row {r}: the diagonal twice"
            );
        }
        // The summation order the backends share: each coarse block's terms by finer block.
        let g = &level.galerkin;
        for c in 0..level.pattern.blocks() {
            let terms = &g.items[g.offsets[c] as usize..g.offsets[c + 1] as usize];
            assert!(terms.windows(2).all(|w| w[0].0 <= w[1].0), "block {c}");
        }
    }

    #[test]
    fn every_element_block_is_in_its_row() {
        let (model, fine) = sheet(5);
        let mg = Multigrid::build(&model, &fine, &[]);
        let csr = model.spring_csr();
        for i in 0..model.len() {
            let (s, e) = (mg.fine.offsets[i], mg.fine.offsets[i + 1]);
            assert_eq!(mg.fine.columns[s as usize], i as u32, "diagonal first");
            for k in csr.offsets[i]..csr.offsets[i + 1] {
                let b = mg.element_blocks.springs[k as usize];
                assert!(b > s && b < e);
                assert_eq!(mg.fine.columns[b as usize], csr.items[k as usize].other);
            }
        }
    }
}
