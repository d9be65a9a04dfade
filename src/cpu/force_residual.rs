//! CPU twin of `kernels/force_residual.wgsl`.

use super::grain;
use super::implicit_terms::Implicit;
use super::line_energy::tree_sum;
use crate::model::layout::WORKGROUP_SIZE;
use glam::Vec4;
use rayon::prelude::*;

/// Gravity's magnitude that weighs the residual: the scene's, or standard gravity when it is
/// off (zero-gravity sewing), in m/s².
pub fn residual_gravity(gravity: [f32; 4]) -> f32 {
    let g = glam::Vec3::new(gravity[0], gravity[1], gravity[2]).length();
    if g > 0.0 {
        g
    } else {
        9.80665
    }
}

/// The force residual |fᵢ|/(mᵢ·g) of the free vertices at displacements `d`, per block of
/// `WORKGROUP_SIZE` vertices: its largest value (x), the sum of its squares (y) and the free
/// vertices counted (z). Blocks run in parallel.
pub fn force_residual(s: &Implicit, d: &[Vec4], partials: &mut [Vec4]) {
    let n = s.params.num_particles as usize;
    let g = residual_gravity(s.params.gravity);
    let group = WORKGROUP_SIZE as usize;
    (partials
        .par_iter_mut()
        .with_min_len(grain::blocks(grain::VERTEX)))
    .enumerate()
    .for_each(|(b, out)| {
        let mut sums = [Vec4::ZERO; WORKGROUP_SIZE as usize];
        let mut largest = 0.0f32;
        for (k, lane) in sums.iter_mut().enumerate() {
            let i = b * group + k;
            if i < n && s.prev[i].w != 0.0 {
                let r = s.force_residual(i, d, g);
                largest = largest.max(r);
                *lane = Vec4::new(0.0, r * r, 1.0, 0.0);
            }
        }
        let total = tree_sum(&mut sums);
        *out = Vec4::new(largest, total.y, total.z, 0.0);
    });
}

/// The largest and RMS force residual of all free vertices from `force_residual`'s partials.
pub fn reduce_residual(partials: &[Vec4]) -> (f32, f32) {
    let mut largest = 0.0f32;
    let (mut sum_sq, mut count) = (0.0f32, 0.0f32);
    for p in partials {
        largest = largest.max(p.x);
        sum_sq += p.y;
        count += p.z;
    }
    (
        largest,
        if count > 0.0 {
            (sum_sq / count).sqrt()
        } else {
            0.0
        },
    )
}
