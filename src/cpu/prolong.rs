//! CPU twin of `kernels/prolong.wgsl`.

use super::grain;
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// Prolongation P between two coarse levels: each finer particle adds the weighted sum of its
/// three parents' `coarse` corrections to its own. Particles run in parallel.
pub fn prolong(parents: &[[u32; 3]], weights: &[[f32; 3]], coarse: &[Vec4], finer: &mut [Vec4]) {
    (finer.par_iter_mut().with_min_len(grain::ARRAY))
        .enumerate()
        .for_each(|(i, e)| {
            *e += blend(parents[i], weights[i], coarse).extend(0.0);
        });
}

/// The weighted sum of three parents' values.
pub(super) fn blend(parents: [u32; 3], weights: [f32; 3], coarse: &[Vec4]) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for k in 0..3 {
        sum += weights[k] * coarse[parents[k] as usize].truncate();
    }
    sum
}

/// The Newton correction c filtered before the line search: zero at pinned vertices; at a
/// vertex touching a body (`Implicit::touching`), without its component into the body
/// (Tamstorf et al. 2015's prefiltering; the linear solve left the normal out already, up to
/// the coarse levels' share); elsewhere stopped at the layer where it would enter it, as a
/// sweep's step is. Particles run in parallel.
pub fn correction_filter(s: &super::implicit_terms::Implicit, d: &[Vec4], c: &mut [Vec4]) {
    let n = s.params.num_particles as usize;
    (c[..n].par_iter_mut().with_min_len(grain::ARRAY))
        .enumerate()
        .for_each(|(i, c)| {
            if s.prev[i].w == 0.0 {
                *c = Vec4::ZERO;
                return;
            }
            let mut v = c.truncate();
            for b in 0..s.params.num_bodies as usize {
                let plane = s.plane(b, i);
                let normal = plane.truncate();
                let phi = plane.w + normal.dot(d[i].truncate());
                let thickness = s.params.bodies[b].thickness;
                let inward = v.dot(normal);
                if s.touching(b, i, d[i].truncate()) {
                    if inward < 0.0 {
                        v -= inward * normal;
                    }
                } else {
                    let landing = phi + inward;
                    if landing < thickness {
                        v += (thickness - landing) * normal;
                    }
                }
            }
            *c = v.extend(0.0);
        });
}
