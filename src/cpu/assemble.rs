//! CPU twin of `kernels/assemble.wgsl`.

use super::grain;
use super::implicit_terms::{Implicit, CONTACT_RATIO};
use crate::model::multigrid::{BlockPattern, ElementBlocks};
use glam::{Mat3, Vec4};
use rayon::prelude::*;

/// The fine level's linear system at displacements `d`: every vertex's force f = −∇G into
/// `force` and its Hessian row (diagonal block first, then a block per neighbour, in
/// `pattern`'s order) into `blocks`, gathered over its elements, both filtered by the contact
/// projections S (`Implicit::contact_filter`): f ← Sᵢf, H_ij ← Sᵢ·H_ij·Sⱼ, and the diagonal
/// block gets the vertex's constant stiffness in its filtered directions, so that it stays
/// invertible while the system leaves them alone. A pinned vertex's row and force are zero,
/// and no row has a block towards a pinned vertex: the correction never moves one. Rows are
/// independent and run in parallel.
pub fn assemble(
    s: &Implicit,
    d: &[Vec4],
    pattern: &BlockPattern,
    element_blocks: &ElementBlocks,
    force: &mut [Vec4],
    blocks: &mut [Mat3],
) {
    let n = s.params.num_particles as usize;
    // Each vertex's filter, once: every neighbour's row needs it.
    let filters: Vec<Mat3> = (0..n)
        .into_par_iter()
        .with_min_len(grain::ROW)
        .map(|i| s.contact_filter(i, d))
        .collect();
    let rows: Vec<&mut [Mat3]> = split_rows(blocks, &pattern.offsets);
    (force[..n].par_iter_mut().zip(rows))
        .with_min_len(grain::VERTEX)
        .enumerate()
        .for_each(|(i, (f, row))| {
            row.fill(Mat3::ZERO);
            let start = pattern.offsets[i];
            let sys = s.vertex_system(i, d, Some(element_blocks), &mut |b, m| {
                row[(b - start) as usize] += m;
            });
            let si = filters[i];
            let touching = si != Mat3::IDENTITY;
            if touching {
                let fixed = s.contact_stiffness(i) / CONTACT_RATIO;
                row[0] = si * sys.hessian * si + fixed * (Mat3::IDENTITY - si);
            } else {
                row[0] = sys.hessian;
            }
            for (k, block) in row.iter_mut().enumerate().skip(1) {
                let sj = filters[pattern.columns[start as usize + k] as usize];
                // Most rows meet no body: I·H·I is H (up to the sign of a zero), so it is
                // skipped, as in the kernel.
                if touching || sj != Mat3::IDENTITY {
                    *block = si * *block * sj;
                }
            }
            *f = (si * sys.force).extend(0.0);
        });
}

/// `blocks` cut into the rows of a block pattern (`offsets`: rows + 1 entries).
pub(super) fn split_rows<'a, T>(mut blocks: &'a mut [T], offsets: &[u32]) -> Vec<&'a mut [T]> {
    let mut rows = Vec::with_capacity(offsets.len() - 1);
    for w in offsets.windows(2) {
        let (row, rest) = blocks.split_at_mut((w[1] - w[0]) as usize);
        rows.push(row);
        blocks = rest;
    }
    rows
}
