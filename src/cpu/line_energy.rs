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
    energy_partials(s, d, c, [0, 1, 2], partials);
}

/// `line_energy` then `line_search` as the CPU solve runs them: G's change at the full step
/// first, and at the shorter ones only when the full step raises G. Each step length's change
/// is computed and summed on its own, so the step it chooses is `line_search`'s after
/// `line_energy` to the bit, as are the partials it sums: the full step's always, the shorter
/// steps' only when the full step is rejected (else `partials` keeps whatever it held in those
/// components). A full step that is taken costs one evaluation of each element at the step
/// instead of three.
pub fn line_search_from_full_step(
    s: &Implicit,
    d: &[Vec4],
    c: &[Vec4],
    partials: &mut [Vec4],
) -> f32 {
    energy_partials(s, d, c, [0], partials);
    let alpha = line_search(partials);
    if alpha == LINE_ALPHAS[0] {
        return alpha;
    }
    energy_partials(s, d, c, [1, 2], partials);
    line_search(partials)
}

/// `line_energy` for the step lengths `LINE_ALPHAS[k]`, k in `which`: each block's sum of
/// each of them written to its component k, the other components left as they are.
fn energy_partials<const N: usize>(
    s: &Implicit,
    d: &[Vec4],
    c: &[Vec4],
    which: [usize; N],
    partials: &mut [Vec4],
) {
    let n = s.params.num_particles as usize;
    let group = WORKGROUP_SIZE as usize;
    let alphas = which.map(|k| LINE_ALPHAS[k]);
    (partials
        .par_iter_mut()
        .with_min_len(grain::blocks(grain::VERTEX)))
    .enumerate()
    .for_each(|(g, out)| {
        let mut lanes = [Vec4::ZERO; WORKGROUP_SIZE as usize];
        for (k, lane) in lanes.iter_mut().enumerate() {
            let i = g * group + k;
            if i < n {
                let e = s.energy_change(i, d, c, alphas);
                for (&component, value) in which.iter().zip(e) {
                    lane[component] = value;
                }
            }
        }
        let sum = tree_sum(&mut lanes);
        for &component in &which {
            out[component] = sum[component];
        }
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
