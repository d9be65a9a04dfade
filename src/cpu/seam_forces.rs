//! CPU twin of `kernels/seam_forces.wgsl`.

use crate::gpu::layout::{Seam, SimParams};
use glam::{Vec3, Vec4};

/// The force on the seam vertex; the partner segment's ends get −(1 − w) and −w of it.
pub fn seam_force(s: &Seam, pos: &[Vec4], vel: &[Vec4]) -> Vec3 {
    let w = s.weight;
    let p = |i: u32| pos[i as usize].truncate();
    let v = |i: u32| vel[i as usize].truncate();
    let xa = p(s.v[0]);
    let va = v(s.v[0]);
    let xp = (1.0 - w) * p(s.v[1]) + w * p(s.v[2]);
    let vp = (1.0 - w) * v(s.v[1]) + w * v(s.v[2]);
    s.stiffness * (xp - xa) + s.damping * (vp - va)
}

/// Adds each particle's seam forces to `force`, gathered over its CSR seam refs
/// (pair index · 4 + role; role 0 is the seam vertex, 1 and 2 the partner segment's ends).
pub fn seam_forces(
    params: &SimParams,
    pos: &[Vec4],
    vel: &[Vec4],
    force: &mut [Vec4],
    seam_offsets: &[u32],
    seam_refs: &[u32],
    seams: &[Seam],
) {
    for i in 0..params.num_particles as usize {
        let mut f = Vec3::ZERO;
        for k in seam_offsets[i]..seam_offsets[i + 1] {
            let r = seam_refs[k as usize];
            let s = &seams[(r / 4) as usize];
            let fa = seam_force(s, pos, vel);
            match r % 4 {
                0 => f += fa,
                1 => f -= (1.0 - s.weight) * fa,
                _ => f -= s.weight * fa,
            }
        }
        force[i] += f.extend(0.0);
    }
}
