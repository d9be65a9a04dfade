//! CPU twin of `kernels/bending_forces.wgsl`: bending with each hinge evaluated from each of its
//! four vertices (the way lavapipe runs faster; `hinge_forces` is the CPU's own way).

use super::grain;
use super::hinge_forces::hinge_force;
use crate::model::layout::{Hinge, SimParams};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// Adds each particle's bending forces to `force`, gathered over its CSR hinge references (in
/// parallel over particles, each in its own fixed order: thread-count independent).
pub fn bending_forces(
    params: &SimParams,
    pos: &[Vec4],
    force: &mut [Vec4],
    hinge_offsets: &[u32],
    hinge_refs: &[u32],
    hinges: &[Hinge],
) {
    let n = params.num_particles as usize;
    force[..n]
        .par_iter_mut()
        .with_min_len(grain::VERTEX)
        .enumerate()
        .for_each(|(i, force)| {
            let mut f = Vec3::ZERO;
            for k in hinge_offsets[i]..hinge_offsets[i + 1] {
                let r = hinge_refs[k as usize];
                f += hinge_force(pos, &hinges[(r / 4) as usize], r % 4);
            }
            *force += f.extend(0.0);
        });
}
