//! CPU twin of `kernels/spring_forces.wgsl`.

use super::grain;
use super::stretch_law::StretchLaw;
use crate::model::layout::{SimParams, SpringRef};
use glam::{Vec3A, Vec4};
use rayon::prelude::*;

/// Adds each particle's spring forces to `force`, gathered over its CSR springs. Particles run
/// in parallel; each sums its own springs in CSR order, so the result is the same on any
/// number of threads. `Vec3A` runs the same IEEE operations lane by lane as `Vec3` would (the
/// same bits), with one SIMD divide per direction.
pub fn spring_forces(
    params: &SimParams,
    pos: &[Vec4],
    vel: &[Vec4],
    force: &mut [Vec4],
    spring_offsets: &[u32],
    springs: &[SpringRef],
) {
    let n = params.num_particles as usize;
    force[..n]
        .par_iter_mut()
        .with_min_len(grain::VERTEX)
        .enumerate()
        .for_each(|(i, force)| {
            let xi = Vec3A::from_vec4(pos[i]);
            let vi = Vec3A::from_vec4(vel[i]);
            let mut f = Vec3A::ZERO;
            for k in spring_offsets[i]..spring_offsets[i + 1] {
                let s = springs[k as usize];
                let d = Vec3A::from_vec4(pos[s.other as usize]) - xi;
                let len = d.length();
                if len > 1e-12 {
                    let dir = d / len;
                    let stretch = len - s.rest_length;
                    let closing_speed = (Vec3A::from_vec4(vel[s.other as usize]) - vi).dot(dir);
                    let law = StretchLaw::spring(params, s.rest_length);
                    let tension = law.tension(s.stiffness, stretch);
                    f += (tension + s.damping * closing_speed) * dir;
                }
            }
            *force += f.extend(0.0);
        });
}
