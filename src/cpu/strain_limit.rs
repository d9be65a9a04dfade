//! CPU twin of `kernels/strain_limit.wgsl`.

use super::grain;
use crate::model::layout::{SimParams, SpringRef};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// One Jacobi iteration of strain limiting from (`pos`, `vel`) into (`pos_out`, `vel_out`):
/// every edge longer than (1 + strain_limit) × rest is pulled back to that length, each end
/// taking its inverse-mass share; a particle moves by the mean correction of its violated
/// edges, and its velocity by that displacement over the step. Particles run in parallel: each
/// reads only the old state and writes only its own new one.
#[allow(clippy::too_many_arguments)] // the kernel's bindings, one argument each
pub fn strain_limit(
    params: &SimParams,
    pos: &[Vec4],
    vel: &[Vec4],
    offsets: &[u32],
    springs: &[SpringRef],
    pos_out: &mut [Vec4],
    vel_out: &mut [Vec4],
) {
    let n = params.num_particles as usize;
    let out = (&mut pos_out[..n], &mut vel_out[..n]);
    out.into_par_iter()
        .with_min_len(grain::VERTEX)
        .enumerate()
        .for_each(|(i, (pos_out, vel_out))| {
            let p = pos[i];
            let wi = p.w;
            let mut delta = Vec3::ZERO;
            let mut violated = 0u32;
            if wi > 0.0 {
                for s in &springs[offsets[i] as usize..offsets[i + 1] as usize] {
                    let q = pos[s.other as usize];
                    let d = q.truncate() - p.truncate();
                    let len = d.length();
                    let longest = (1.0 + params.strain_limit) * s.rest_length;
                    if len > longest {
                        let share = wi / (wi + q.w);
                        delta += (share * (len - longest) / len) * d;
                        violated += 1;
                    }
                }
            }
            if violated > 0 {
                delta /= violated as f32;
            }
            *pos_out = (p.truncate() + delta).extend(wi);
            *vel_out = (vel[i].truncate() + delta / params.dt).extend(0.0);
        });
}
