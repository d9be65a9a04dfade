//! CPU twin of `kernels/vbd_finish.wgsl`.

use super::grain;
use crate::model::layout::SimParams;
use glam::Vec4;
use rayon::prelude::*;

/// The next state from the solved displacements D: x_{n+1} = xₙ + D, v_{n+1} = D/h. Pinned
/// particles keep their position and have zero velocity. Particles run in parallel.
pub fn vbd_finish(params: &SimParams, x: &[Vec4], pos: &mut [Vec4], vel: &mut [Vec4]) {
    let h = params.dt;
    let n = params.num_particles as usize;
    let state = (&mut pos[..n], &mut vel[..n]);
    state
        .into_par_iter()
        .with_min_len(grain::ARRAY)
        .enumerate()
        .for_each(|(i, (pos, vel))| {
            let p = *pos;
            if p.w == 0.0 {
                *vel = Vec4::ZERO;
                return;
            }
            let d = x[i].truncate();
            *vel = (d / h).extend(0.0);
            *pos = (p.truncate() + d).extend(p.w);
        });
}
