//! CPU twins of `kernels/smooth.wgsl` and `kernels/level_residual.wgsl`.

use super::colour_run::{colour_after_colour, colour_of_each, Cells};
use super::grain;
use super::vbd_solve::solve3;
use crate::model::multigrid::BlockPattern;
use glam::{Mat3, Mat3A, Vec3, Vec3A, Vec4};
use rayon::prelude::*;
use std::ops::Range;

/// A level's matrix with the rows of each colour side by side, for its Gauss–Seidel sweeps.
///
/// A level's blocks are stored row after row in particle order, as assembly, the Galerkin
/// products and the matrix-vector products read them. A sweep visits one colour at a time, a
/// row here and there across the whole matrix, so on a large mesh each row starts with a cache
/// miss (the 5 mm T-shirt's fine matrix is 25 MB). A copy in colour order, refreshed once per
/// assembly (`fill`), lets each colour read one contiguous run. It changes no number: the same
/// blocks meet the same vectors in the same order.
pub struct ColourRows {
    /// The level's particles by colour: row s of the copy is particle `order[s]`.
    order: Vec<u32>,
    /// Each row's first block in the copy (rows + 1 entries).
    offsets: Vec<u32>,
    /// Each block's column (a particle).
    columns: Vec<u32>,
    /// Each block's index in the level's own blocks.
    source: Vec<u32>,
    /// The copy, diagonal block first in each row.
    blocks: Vec<Mat3>,
    /// Each colour's rows, first colour first.
    forward: Vec<Range<usize>>,
    /// The same, last colour first.
    backward: Vec<Range<usize>>,
}

impl ColourRows {
    /// The copy's structure for the level of block pattern `pattern`, whose particles `order`
    /// lists colour after colour, colour k from `colour_offsets[k]`.
    ///
    /// Panics unless `order` lists every row once in colours that cover it, each row's first
    /// block is its diagonal, and
    /// no row has a block in a column of its own colour: what lets `smooth` update a colour's
    /// rows at once, in place, on any number of threads.
    pub fn new(pattern: &BlockPattern, order: &[u32], colour_offsets: &[u32]) -> ColourRows {
        let rows = pattern.offsets.len() - 1;
        let colour = colour_of_each(order, colour_offsets, rows);
        // With the colours covering all of `order`, `colour_of_each` has checked that it names
        // each row once: what lets `residual` and `product` write each row's particle at once.
        assert_eq!(order.len(), rows, "every row is listed once");
        assert!(
            colour_offsets.first() == Some(&0) && colour_offsets.last() == Some(&(rows as u32)),
            "the colours cover every row"
        );
        for r in 0..rows {
            let blocks =
                &pattern.columns[pattern.offsets[r] as usize..pattern.offsets[r + 1] as usize];
            assert_eq!(
                blocks.first(),
                Some(&(r as u32)),
                "row {r} starts with its diagonal"
            );
            assert!(
                (blocks[1..].iter()).all(|&c| colour[c as usize] != colour[r]),
                "row {r} has a block in its own colour"
            );
        }
        let (mut offsets, mut columns, mut source) = (vec![0u32], Vec::new(), Vec::new());
        for &r in order {
            let (start, end) = (pattern.offsets[r as usize], pattern.offsets[r as usize + 1]);
            columns.extend(&pattern.columns[start as usize..end as usize]);
            source.extend(start..end);
            offsets.push(columns.len() as u32);
        }
        let forward: Vec<Range<usize>> = (colour_offsets.windows(2))
            .map(|w| w[0] as usize..w[1] as usize)
            .collect();
        ColourRows {
            backward: forward.iter().rev().cloned().collect(),
            forward,
            order: order.to_vec(),
            offsets,
            columns,
            blocks: vec![Mat3::ZERO; source.len()],
            source,
        }
    }

    /// Copies the level's `blocks` (in its pattern's order) into colour order.
    pub fn fill(&mut self, blocks: &[Mat3]) {
        (self.blocks.par_iter_mut().zip(&self.source))
            .with_min_len(grain::ARRAY)
            .for_each(|(b, &s)| *b = blocks[s as usize]);
    }

    /// The rows of every colour, first colour first: a forward sweep.
    pub fn forward(&self) -> &[Range<usize>] {
        &self.forward
    }

    /// The rows of every colour, last colour first: a backward sweep.
    pub fn backward(&self) -> &[Range<usize>] {
        &self.backward
    }

    /// The rows of colour `k` alone.
    pub fn colour(&self, k: usize) -> &[Range<usize>] {
        &self.forward[k..k + 1]
    }

    /// The residual rhs − A·e into `out`, as `level_residual` computes it (the same bits),
    /// reading the copy: between two assemblies the smoothing sweeps, residuals and products
    /// then stream one copy of the matrix instead of two (the 5 mm T-shirt's two are 50 MB,
    /// more than the 2-core machine's last-level cache).
    pub fn residual(&self, rhs: &[Vec4], e: &[Vec4], out: &mut [Vec4]) {
        self.each_row(out, |row, i| {
            row_residual(rhs[i], &self.blocks[row.clone()], &self.columns[row], e)
        });
    }

    /// The product A·v into `out`, as `pcg_matvec` computes it (the same bits), reading the
    /// copy (see `residual`).
    pub fn product(&self, v: &[Vec4], out: &mut [Vec4]) {
        self.each_row(out, |row, _| {
            row_product(&self.blocks[row.clone()], &self.columns[row], v)
        });
    }

    /// `out[i] = value(blocks of the row, i)` for every row, rows in parallel in the copy's
    /// order, each written to its particle i.
    fn each_row(&self, out: &mut [Vec4], value: impl Fn(Range<usize>, usize) -> Vec4 + Sync) {
        assert_eq!(out.len(), self.order.len(), "one value per row");
        let out = Cells::new(out);
        (0..self.order.len())
            .into_par_iter()
            .with_min_len(grain::ROW)
            .for_each(|s| {
                let row = self.offsets[s] as usize..self.offsets[s + 1] as usize;
                let i = self.order[s] as usize;
                // SAFETY: `order` names every particle once (`new`), so each is written by
                // one row alone, and nothing reads `out` during the loop.
                unsafe { out.set(i, value(row, i)) };
            });
    }
}

/// Block Gauss–Seidel updates of a level's system A·e = r, colour after colour of `colours`
/// (rows of the colour-ordered copy: `ColourRows::forward`, `backward` or `colour`):
/// e_I = A_II⁻¹(r_I − Σ_J≠I A_IJ·e_J). Rows of one colour share no block, so they update at
/// once from the same `e`, in place, split across the pool (`colour_after_colour`). A row whose
/// diagonal is singular (a pinned particle, or a coarse one whose children are all pinned) gets
/// e = 0.
pub fn smooth(m: &ColourRows, colours: &[Range<usize>], rhs: &[Vec4], e: &mut [Vec4]) {
    let e = Cells::new(e);
    colour_after_colour(colours, |_, rows| {
        for s in rows {
            let (start, end) = (m.offsets[s] as usize, m.offsets[s + 1] as usize);
            let mut sum = Vec3A::from_vec4(rhs[m.order[s] as usize]);
            for b in start + 1..end {
                // SAFETY: column b is a particle of another colour (a colour's rows share no
                // block), which no thread writes while this colour runs.
                let other = unsafe { e.get(m.columns[b] as usize) };
                sum -= block_times(m.blocks[b], other);
            }
            let update = solve3(m.blocks[start], sum.into()).extend(0.0);
            // SAFETY: row s is written by this iteration alone, and read by no row of its
            // colour.
            unsafe { e.set(m.order[s] as usize, update) };
        }
    });
}

/// A 3×3 block times a particle's vector, in SIMD lanes: the same products and sums in the same
/// order as `Mat3 * Vec3` (column by column, no fused multiply-add), so the same bits, at about
/// half the instructions.
pub fn block_times(block: Mat3, v: Vec4) -> Vec3A {
    Mat3A::from(block) * Vec3A::from_vec4(v)
}

/// Block-Jacobi preconditioning: each row's e = D⁻¹·rhs with D its diagonal block (the first
/// of the row). Rows run in parallel.
pub fn block_jacobi(pattern: &BlockPattern, blocks: &[Mat3], rhs: &[Vec4], e: &mut [Vec4]) {
    (e.par_iter_mut().with_min_len(grain::ROW))
        .enumerate()
        .for_each(|(r, e)| {
            let diagonal = blocks[pattern.offsets[r] as usize];
            *e = solve3(diagonal, rhs[r].truncate()).extend(0.0);
        });
}

/// The residual r − A·e of a level, row by row in parallel.
pub fn level_residual(
    pattern: &BlockPattern,
    blocks: &[Mat3],
    rhs: &[Vec4],
    e: &[Vec4],
    out: &mut [Vec4],
) {
    (out.par_iter_mut().with_min_len(grain::ROW))
        .enumerate()
        .for_each(|(r, out)| {
            let row = pattern.offsets[r] as usize..pattern.offsets[r + 1] as usize;
            *out = row_residual(rhs[r], &blocks[row.clone()], &pattern.columns[row], e);
        });
}

/// A row's rhs − Σ A_b·e[column b], its blocks in the order given.
#[inline]
fn row_residual(rhs: Vec4, blocks: &[Mat3], columns: &[u32], e: &[Vec4]) -> Vec4 {
    let mut sum = Vec3A::from_vec4(rhs);
    for (&block, &c) in blocks.iter().zip(columns) {
        sum -= block_times(block, e[c as usize]);
    }
    Vec3::from(sum).extend(0.0)
}

/// A row's Σ A_b·v[column b], its blocks in the order given.
#[inline]
pub fn row_product(blocks: &[Mat3], columns: &[u32], v: &[Vec4]) -> Vec4 {
    let mut sum = Vec3A::ZERO;
    for (&block, &c) in blocks.iter().zip(columns) {
        sum += block_times(block, v[c as usize]);
    }
    sum.extend(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every component's bits, for comparing vectors to the bit.
    fn bits(v: &[Vec4]) -> Vec<u32> {
        v.iter()
            .flat_map(|x| x.to_array())
            .map(f32::to_bits)
            .collect()
    }

    /// A chain of `n` particles, each coupled to its two neighbours: rows alternate between two
    /// colours, and the blocks are diagonally dominant with varied entries.
    fn chain(n: usize) -> (BlockPattern, Vec<Mat3>, Vec<Vec4>) {
        let (mut offsets, mut columns, mut blocks) = (vec![0u32], Vec::new(), Vec::new());
        let wobble = |k: usize| ((k * 7919) % 101) as f32 / 101.0;
        for i in 0..n {
            columns.push(i as u32);
            blocks.push(Mat3::from_diagonal(Vec3::splat(4.0 + wobble(i))));
            for j in [i.wrapping_sub(1), i + 1] {
                if j < n {
                    columns.push(j as u32);
                    blocks.push(Mat3::from_cols_array(&[-0.5 - 0.1 * wobble(i + j); 9]));
                }
            }
            offsets.push(columns.len() as u32);
        }
        let rhs = (0..n)
            .map(|i| Vec4::new(wobble(i), -wobble(i + 1), 1.0, 0.0))
            .collect();
        (BlockPattern { offsets, columns }, blocks, rhs)
    }

    #[test]
    fn the_colour_copy_s_residual_and_product_are_the_pattern_s_to_the_bit() {
        // The solve takes its residuals and products from the colour-ordered copy; the kernels'
        // twins take them from the pattern's order. Long enough that the rows split across
        // threads.
        let n = 4 * grain::ROW + 1;
        let (pattern, blocks, rhs) = chain(n);
        // Every entry of every block its own, so that a block read transposed or from the
        // mirrored row shows.
        let blocks: Vec<Mat3> = (blocks.iter().enumerate())
            .map(|(k, b)| {
                *b + Mat3::from_cols_array(&std::array::from_fn(|e| (k * 9 + e) as f32 / 64.0))
            })
            .collect();
        let order: Vec<u32> = (0..2).flat_map(|c| (c..n as u32).step_by(2)).collect();
        let mut rows = ColourRows::new(&pattern, &order, &[0, n.div_ceil(2) as u32, n as u32]);
        rows.fill(&blocks);
        let e: Vec<Vec4> = (0..n)
            .map(|i| Vec4::new(0.3, -(i as f32), 0.01 * i as f32, 0.0))
            .collect();
        let (mut want, mut got) = (vec![Vec4::ZERO; n], vec![Vec4::NAN; n]);
        level_residual(&pattern, &blocks, &rhs, &e, &mut want);
        rows.residual(&rhs, &e, &mut got);
        assert_eq!(bits(&got), bits(&want), "residual");
        let mut scalars = crate::cpu::PcgScalars::default();
        crate::cpu::pcg_matvec(&pattern, &blocks, &e, &mut want, &mut scalars);
        got.fill(Vec4::NAN);
        rows.product(&e, &mut got);
        assert_eq!(bits(&got), bits(&want), "product");
    }

    #[test]
    #[should_panic(expected = "has a block in its own colour")]
    fn a_colour_whose_rows_read_each_other_is_refused() {
        // A chain coloured in two halves: neighbours inside each half share a colour, so an
        // update in place would read a row that another thread is writing.
        let n = 8;
        let (pattern, _, _) = chain(n);
        let order: Vec<u32> = (0..n as u32).collect();
        ColourRows::new(&pattern, &order, &[0, 4, 8]);
    }

    #[test]
    fn a_split_colour_updates_as_one_row_after_another_on_any_thread_count() {
        // Colours long enough that the sweep splits them (the path that a fine level of a
        // large garment takes); the reference updates row after row in place.
        let n = 4 * grain::ROW + 1;
        let (pattern, blocks, rhs) = chain(n);
        let colours: Vec<Vec<u32>> = (0..2).map(|c| (c..n as u32).step_by(2).collect()).collect();
        let order: Vec<u32> = colours.concat();
        let mut rows = ColourRows::new(&pattern, &order, &[0, colours[0].len() as u32, n as u32]);
        rows.fill(&blocks);
        let mut reference = vec![Vec4::ZERO; n];
        for _ in 0..2 {
            for colour in &colours {
                for &r in colour {
                    let r = r as usize;
                    let (start, end) =
                        (pattern.offsets[r] as usize, pattern.offsets[r + 1] as usize);
                    let mut sum = rhs[r].truncate();
                    for b in start + 1..end {
                        sum -= blocks[b] * reference[pattern.columns[b] as usize].truncate();
                    }
                    reference[r] = solve3(blocks[start], sum).extend(0.0);
                }
            }
        }
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut e = vec![Vec4::ZERO; n];
            pool.install(|| {
                for _ in 0..2 {
                    smooth(&rows, rows.forward(), &rhs, &mut e);
                }
            });
            assert_eq!(bits(&e), bits(&reference), "{threads} threads");
        }
    }
}
