//! CPU twin of `kernels/wind_forces.wgsl`.

use super::grain;
use crate::model::layout::{SimParams, SubstepParams};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// Adds each particle's share of wind drag on its incident triangles to `force` (in parallel
/// over particles, each summing its triangles in CSR order).
#[allow(clippy::too_many_arguments)] // mirrors the kernel's bindings one to one
pub fn wind_forces(
    params: &SimParams,
    step: &SubstepParams,
    pos: &[Vec4],
    vel: &[Vec4],
    force: &mut [Vec4],
    triangle_offsets: &[u32],
    triangle_refs: &[u32],
    triangles: &[[u32; 4]],
) {
    let wind = Vec4::from(step.wind).truncate();
    let n = params.num_particles as usize;
    force[..n]
        .par_iter_mut()
        .with_min_len(grain::VERTEX)
        .enumerate()
        .for_each(|(i, force)| {
            let mut f = Vec3::ZERO;
            for k in triangle_offsets[i]..triangle_offsets[i + 1] {
                let t = triangles[triangle_refs[k as usize] as usize];
                let x = |j: usize| pos[t[j] as usize].truncate();
                let v = |j: usize| vel[t[j] as usize].truncate();
                let c = (x(1) - x(0)).cross(x(2) - x(0));
                let twice_area = c.length();
                if twice_area > 1e-12 {
                    let n = c / twice_area;
                    let v_mean = (v(0) + v(1) + v(2)) / 3.0;
                    let vn = (wind - v_mean).dot(n);
                    let drag = 0.5
                        * params.air_density
                        * params.drag_coefficient
                        * (0.5 * twice_area)
                        * vn
                        * vn.abs();
                    f += (drag / 3.0) * n;
                }
            }
            *force += f.extend(0.0);
        });
}
