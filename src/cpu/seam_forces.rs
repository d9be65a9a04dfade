//! CPU twin of `kernels/seam_forces.wgsl`.

use super::grain;
use crate::model::layout::{Seam, SimParams, SubstepParams};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// The force on the seam vertex; the partner segment's ends get −(1 − w) and −w of it. The
/// pair's rest gap is `rest` (m): see `rest_gap`.
pub fn seam_force(s: &Seam, rest: f32, pos: &[Vec4], vel: &[Vec4]) -> Vec3 {
    let w = s.weight;
    let p = |i: u32| pos[i as usize].truncate();
    let v = |i: u32| vel[i as usize].truncate();
    let xa = p(s.v[0]);
    let va = v(s.v[0]);
    let xp = (1.0 - w) * p(s.v[1]) + w * p(s.v[2]);
    let vp = (1.0 - w) * v(s.v[1]) + w * v(s.v[2]);
    let gap = xp - xa;
    let damping = s.damping * (vp - va);
    if rest <= 0.0 {
        return s.stiffness * gap + damping;
    }
    // Pulls only: a pair closer than its rest gap feels no spring.
    let d = gap.length();
    s.stiffness * (d - rest).max(0.0) / d.max(1e-12) * gap + damping
}

/// A pair's rest gap at `time`: its open gap, shrinking to 0 at the sewing rate.
pub fn rest_gap(s: &Seam, params: &SimParams, time: f32) -> f32 {
    s.open_gap * (1.0 - params.sewing_rate * time).max(0.0)
}

/// Adds each particle's seam forces to `force`, gathered over its CSR seam refs
/// (pair index · 4 + role; role 0 is the seam vertex, 1 and 2 the partner segment's ends), in
/// parallel over particles, each in CSR order.
#[allow(clippy::too_many_arguments)] // the kernel's bindings, one argument each
pub fn seam_forces(
    params: &SimParams,
    step: &SubstepParams,
    pos: &[Vec4],
    vel: &[Vec4],
    force: &mut [Vec4],
    seam_offsets: &[u32],
    seam_refs: &[u32],
    seams: &[Seam],
) {
    let n = params.num_particles as usize;
    force[..n]
        .par_iter_mut()
        .with_min_len(grain::VERTEX)
        .enumerate()
        .for_each(|(i, force)| {
            let mut f = Vec3::ZERO;
            for k in seam_offsets[i]..seam_offsets[i + 1] {
                let r = seam_refs[k as usize];
                let s = &seams[(r / 4) as usize];
                let fa = seam_force(s, rest_gap(s, params, step.time), pos, vel);
                match r % 4 {
                    0 => f += fa,
                    1 => f -= (1.0 - s.weight) * fa,
                    _ => f -= s.weight * fa,
                }
            }
            *force += f.extend(0.0);
        });
}
