//! CPU twin of `kernels/vbd_init.wgsl`.

use crate::model::layout::SimParams;
use glam::Vec4;

/// The inertial target y = xₙ + h·vₙ + h²·a of every particle, with a = g + f/m (f: the
/// external forces the force stages summed, i.e. wind), and the starting guess of the solve,
/// x⁰ = xₙ + h·vₙ: where momentum alone takes the particle. (Starting at y makes the sweeps
/// carry the whole weight of a hanging cloth back up, which they do too slowly: the cloth
/// stretches. Vertex Block Descent's adaptive guess, which adds the part of the last step's
/// acceleration along a, let a stiff hanging cloth gain energy between frames in our tests.)
/// Pinned particles stay where they are. Clears the force accumulator, as `integrate` does.
pub fn vbd_init(
    params: &SimParams,
    pos: &[Vec4],
    vel: &[Vec4],
    force: &mut [Vec4],
    x: &mut [Vec4],
    y: &mut [Vec4],
) {
    let h = params.dt;
    let gravity = Vec4::from(params.gravity).truncate();
    for i in 0..params.num_particles as usize {
        let p = pos[i];
        let f = force[i].truncate();
        force[i] = Vec4::ZERO;
        if p.w == 0.0 {
            y[i] = p;
            x[i] = p;
            continue;
        }
        let a = f * p.w + gravity;
        let start = p.truncate() + h * vel[i].truncate();
        y[i] = (start + h * h * a).extend(p.w);
        x[i] = start.extend(p.w);
    }
}
