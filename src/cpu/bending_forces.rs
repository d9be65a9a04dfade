//! CPU twin of `kernels/bending_forces.wgsl`.

use crate::model::layout::SimParams;
use glam::Vec4;
use rayon::prelude::*;

/// Adds each particle's bending forces to `force`: the sum, in CSR order, of the entries of
/// `hinge_forces` (written by `hinge_forces`) that its hinge refs name. In parallel over
/// particles, each in its own fixed order: thread-count independent.
pub fn bending_forces(
    params: &SimParams,
    force: &mut [Vec4],
    hinge_offsets: &[u32],
    hinge_refs: &[u32],
    hinge_forces: &[Vec4],
) {
    let n = params.num_particles as usize;
    force[..n]
        .par_iter_mut()
        .enumerate()
        .for_each(|(i, force)| {
            // w is 0 in every entry, so whole-vector sums give xyz's bits as Vec3 sums would.
            let mut f = Vec4::ZERO;
            for k in hinge_offsets[i]..hinge_offsets[i + 1] {
                f += hinge_forces[hinge_refs[k as usize] as usize];
            }
            *force += f;
        });
}
