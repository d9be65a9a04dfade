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

/// `line_energy`, `line_slopes` and `line_search` as the CPU solve runs them: G's change at
/// the full step first, at the shorter ones only when the full step is not taken, and the
/// slopes only when a change is within its rounding. Each is computed and summed on its own,
/// so the step it chooses is `line_search`'s after `line_energy` and `line_slopes` to the bit,
/// as are the partials it sums: the full step's change and the scale always, the shorter
/// steps' and the slopes only when needed (else they keep whatever they held). A full step
/// that is taken costs one evaluation of each element at the step instead of three.
pub fn line_search_from_full_step(
    s: &Implicit,
    d: &[Vec4],
    c: &[Vec4],
    force: &[Vec4],
    (partials, slope_partials): (&mut [Vec4], &mut [Vec4]),
) -> f32 {
    energy_partials(s, d, c, [0], partials);
    let mut slopes = None;
    let mut slopes_once = || {
        *slopes.get_or_insert_with(|| {
            line_slopes(s, d, c, force, slope_partials);
            in_order_sum(slope_partials)
        })
    };
    if takes(0, in_order_sum(partials), &mut slopes_once) {
        return LINE_ALPHAS[0];
    }
    energy_partials(s, d, c, [1, 2], partials);
    choose(in_order_sum(partials), slopes_once)
}

/// `line_energy` for the step lengths `LINE_ALPHAS[k]`, k in `which`: each block's sum of
/// each of them written to its component k, the other components left as they are; with the
/// full step (k = 0) among them, the sum of its scale (`energy_change_and_scale`) to w.
fn energy_partials<const N: usize>(
    s: &Implicit,
    d: &[Vec4],
    c: &[Vec4],
    which: [usize; N],
    partials: &mut [Vec4],
) {
    let alphas = which.map(|k| LINE_ALPHAS[k]);
    let lane = |i: usize| {
        let (e, scale) = s.energy_change_and_scale(i, d, c, alphas);
        let mut lane = Vec4::new(0.0, 0.0, 0.0, scale);
        for (&component, value) in which.iter().zip(e) {
            lane[component] = value;
        }
        lane
    };
    block_sums(
        s.params.num_particles as usize,
        lane,
        partials,
        |out, sum| {
            for &component in &which {
                out[component] = sum[component];
            }
            if which[0] == 0 {
                out.w = sum.w;
            }
        },
    );
}

/// Each block of `WORKGROUP_SIZE` vertices' values `lane(i)` (i < n) summed by `tree_sum` and
/// handed to `write` with the block's partial. Blocks run in parallel.
fn block_sums(
    n: usize,
    lane: impl Fn(usize) -> Vec4 + Sync,
    partials: &mut [Vec4],
    write: impl Fn(&mut Vec4, Vec4) + Sync,
) {
    let group = WORKGROUP_SIZE as usize;
    (partials
        .par_iter_mut()
        .with_min_len(grain::blocks(grain::VERTEX)))
    .enumerate()
    .for_each(|(g, out)| {
        let mut lanes = [Vec4::ZERO; WORKGROUP_SIZE as usize];
        for (k, value) in lanes.iter_mut().enumerate() {
            let i = g * group + k;
            if i < n {
                *value = lane(i);
            }
        }
        write(out, tree_sum(&mut lanes));
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

/// G's slopes along the correction `c` (G′ = −f·c), at the iterate (x: from `force`, the
/// assembled force, filtered as `c` is, which leaves the product as it is) and at the full
/// step d + c (y: the force there, computed as `vertex_system` computes it), summed per block
/// of `WORKGROUP_SIZE` vertices by `tree_sum`. Pinned vertices add nothing.
pub fn line_slopes(s: &Implicit, d: &[Vec4], c: &[Vec4], force: &[Vec4], partials: &mut [Vec4]) {
    // The full step's displacements, as `apply_correction` would leave them with α = 1.
    let full: Vec<Vec4> = (d.iter().zip(c))
        .map(|(d, c)| (d.truncate() + c.truncate()).extend(d.w))
        .collect();
    let lane = |i: usize| {
        if s.prev[i].w == 0.0 {
            return Vec4::ZERO;
        }
        let ci = c[i].truncate();
        let at_full = s.vertex_system(i, &full, None, &mut |_, _| {}).force;
        Vec4::new(-force[i].truncate().dot(ci), -at_full.dot(ci), 0.0, 0.0)
    };
    block_sums(
        s.params.num_particles as usize,
        lane,
        partials,
        |out, sum| *out = sum,
    );
}

/// The rounding of G's change as `line_energy` sums it, per unit of its scale (its partials'
/// w): each term rounds a few times relative to its share of the scale, and ~10⁵ of them are
/// added by blocks of 64 and then in order.
pub const LINE_ROUNDING: f32 = 32.0 * f32::EPSILON;

/// The line search from `line_energy`'s and `line_slopes`' partials, each summed in order: the
/// first step length of `LINE_ALPHAS` that does not raise G, or 0 when each does. A step whose
/// change of G is not above zero is taken. A step whose change is above zero by less than its
/// rounding (`LINE_ROUNDING` times the scale) is taken when G falls by its slopes: G′(0)
/// and G′(1) from `line_slopes`, G quadratic along c between them. Near a converged step the
/// change of G is far smaller than the energies it is summed from, and its rounding would
/// refuse every step. A cycle is then never worse than the sweeps alone, up to G's rounding.
pub fn line_search(partials: &[Vec4], slope_partials: &[Vec4]) -> f32 {
    let slopes = in_order_sum(slope_partials);
    choose(in_order_sum(partials), || slopes)
}

/// The partials' sum, in order, as the kernels add them.
fn in_order_sum(partials: &[Vec4]) -> Vec4 {
    let mut total = Vec4::ZERO;
    for p in partials {
        total += *p;
    }
    total
}

/// `line_search`'s choice from the energy total and (called only when a change is within its
/// rounding) the slopes' total.
fn choose(energy: Vec4, mut slopes: impl FnMut() -> Vec4) -> f32 {
    for (k, &alpha) in LINE_ALPHAS.iter().enumerate() {
        if takes(k, energy, &mut slopes) {
            return alpha;
        }
    }
    0.0
}

/// Whether `line_search` takes step length `LINE_ALPHAS[k]`.
fn takes(k: usize, energy: Vec4, slopes: &mut impl FnMut() -> Vec4) -> bool {
    let change = energy[k];
    change <= 0.0
        || (change <= LINE_ROUNDING * energy.w && slope_change(LINE_ALPHAS[k], slopes()) <= 0.0)
}

/// G's change at step length α from its slopes at 0 and 1 (x, y), G quadratic along the
/// correction between them: α·G′(0) + ½α²·(G′(1) − G′(0)).
pub fn slope_change(alpha: f32, slopes: Vec4) -> f32 {
    alpha * slopes.x + 0.5 * alpha * alpha * (slopes.y - slopes.x)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Energy partials (one block) with changes `e` at the three step lengths and scale `w`.
    fn energy(e: [f32; 3], w: f32) -> Vec<Vec4> {
        vec![Vec4::new(e[0], e[1], e[2], w)]
    }

    /// Slope partials (one block): G′(0) and G′(1).
    fn slopes(at_start: f32, at_full: f32) -> Vec<Vec4> {
        vec![Vec4::new(at_start, at_full, 0.0, 0.0)]
    }

    #[test]
    fn a_change_that_does_not_raise_g_is_taken_whatever_the_slopes() {
        let rising = slopes(1.0, 2.0);
        assert_eq!(line_search(&energy([-1e-3, 1.0, 1.0], 1.0), &rising), 1.0);
        assert_eq!(line_search(&energy([1.0, 0.0, 1.0], 1.0), &rising), 0.5);
    }

    #[test]
    fn a_rise_above_its_rounding_is_refused_whatever_the_slopes() {
        // Scale 1 J: rounding 32ε ≈ 3.8e-6 J; rises of 1e-5 J are G's own.
        let falling = slopes(-1.0, -1.0);
        let rise = 1e-5;
        assert!(rise > LINE_ROUNDING);
        assert_eq!(line_search(&energy([rise; 3], 1.0), &falling), 0.0);
    }

    #[test]
    fn a_rise_within_its_rounding_is_decided_by_the_slopes() {
        // Below the rounding the sign of the change is noise: the slopes decide. With G′(0) =
        // −1 and G′(1) = 3, G along c is −α + 2α²: up at α = 1 (+1), level at ½ (0), down at
        // ¼ (−⅛). The first step that does not raise it is ½.
        let within = LINE_ROUNDING / 2.0;
        let partials = energy([within; 3], 1.0);
        assert_eq!(line_search(&partials, &slopes(-1.0, 3.0)), 0.5);
        assert_eq!(line_search(&partials, &slopes(-1.0, 0.5)), 1.0);
        // G rising from the start along c: no step.
        assert_eq!(line_search(&partials, &slopes(1e-9, 1.0)), 0.0);
        assert_eq!(slope_change(0.25, slopes(-1.0, 3.0)[0]), -0.125);
    }
}
