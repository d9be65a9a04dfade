//! CPU twin of `kernels/vbd_init.wgsl`.

use super::grain;
use crate::model::layout::SimParams;
use glam::Vec4;
use rayon::prelude::*;

/// The inertial target of every particle, Y = h·vₙ + h²·a with a = g + f/m (f: the external
/// forces the force stages summed, i.e. wind), and the starting guess of the solve,
/// D⁰ = h·vₙ: where momentum alone takes the particle. Both are displacements from xₙ (see
/// `implicit_terms`); w keeps the inverse mass. (Starting at Y makes the sweeps carry the
/// whole weight of a hanging cloth back up, which they do too slowly: the cloth stretches.
/// Vertex Block Descent's adaptive guess, which adds the part of the last step's acceleration
/// along a, let a stiff hanging cloth gain energy between frames in our tests.) Pinned
/// particles do not move: both are zero. Clears the force accumulator, as `integrate` does,
/// and the largest Newton step of every iteration (`steps`). Particles are independent and run
/// in parallel.
pub fn vbd_init(
    params: &SimParams,
    pos: &[Vec4],
    vel: &[Vec4],
    force: &mut [Vec4],
    x: &mut [Vec4],
    y: &mut [Vec4],
    steps: &mut [f32],
) {
    steps.fill(0.0);
    let h = params.dt;
    let gravity = Vec4::from(params.gravity).truncate();
    let n = params.num_particles as usize;
    let out = (&mut force[..n], &mut x[..n], &mut y[..n]);
    out.into_par_iter()
        .with_min_len(grain::ARRAY)
        .enumerate()
        .for_each(|(i, (force, x, y))| {
            let p = pos[i];
            let f = force.truncate();
            *force = Vec4::ZERO;
            if p.w == 0.0 {
                *y = Vec4::ZERO;
                *x = Vec4::ZERO;
                return;
            }
            let a = f * p.w + gravity;
            let start = h * vel[i].truncate();
            *y = (start + h * h * a).extend(p.w);
            *x = start.extend(p.w);
        });
}
