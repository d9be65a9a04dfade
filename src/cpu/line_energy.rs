//! CPU twin of `kernels/line_energy.wgsl`.

use super::grain;
use super::implicit_terms::Implicit;
use crate::model::layout::WORKGROUP_SIZE;
use glam::Vec4;
use rayon::prelude::*;

/// The step lengths the line search tries, in order.
pub const LINE_ALPHAS: [f32; 3] = [1.0, 0.5, 0.25];

/// The change of G along the correction `c` at each of `LINE_ALPHAS`, summed per block of
/// `WORKGROUP_SIZE` vertices (one workgroup's share, xyz; w unused) by `tree_sum`, the
/// workgroup's own order. Blocks run in parallel.
pub fn line_energy(s: &Implicit, d: &[Vec4], c: &[Vec4], partials: &mut [Vec4]) {
    let n = s.params.num_particles as usize;
    let group = WORKGROUP_SIZE as usize;
    (partials
        .par_iter_mut()
        .with_min_len(grain::blocks(grain::VERTEX)))
    .enumerate()
    .for_each(|(g, out)| {
        let mut lanes = [Vec4::ZERO; WORKGROUP_SIZE as usize];
        for (k, lane) in lanes.iter_mut().enumerate() {
            let i = g * group + k;
            if i < n {
                let e = s.energy_change(i, d, c, LINE_ALPHAS);
                *lane = Vec4::new(e[0], e[1], e[2], 0.0);
            }
        }
        *out = tree_sum(&mut lanes);
    });
}

/// The sum of a workgroup's lanes as the kernels reduce them: lane k adds lane k + stride for
/// stride = 32, 16, …, 1 (64 lanes).
pub fn tree_sum(lanes: &mut [Vec4; WORKGROUP_SIZE as usize]) -> Vec4 {
    let mut stride = lanes.len() / 2;
    while stride > 0 {
        for k in 0..stride {
            lanes[k] += lanes[k + stride];
        }
        stride /= 2;
    }
    lanes[0]
}

/// The line search: the first step length of `LINE_ALPHAS` whose change of G (the workgroup
/// partials summed in order) does not raise it, or 0 when each does. A cycle is then never
/// worse than the sweeps alone.
pub fn line_search(partials: &[Vec4]) -> f32 {
    let mut total = Vec4::ZERO;
    for p in partials {
        total += *p;
    }
    for (k, &alpha) in LINE_ALPHAS.iter().enumerate() {
        if total[k] <= 0.0 {
            return alpha;
        }
    }
    0.0
}

/// D += α·c for every particle (the correction is zero at pins). Particles run in parallel.
pub fn apply_correction(alpha: f32, c: &[Vec4], d: &mut [Vec4]) {
    if alpha == 0.0 {
        return;
    }
    (d.par_iter_mut().zip(c).with_min_len(grain::ARRAY)).for_each(|(d, c)| {
        *d = (d.truncate() + alpha * c.truncate()).extend(d.w);
    });
}
