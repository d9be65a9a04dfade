//! CPU twin of `kernels/vbd_finish.wgsl`.

use crate::model::layout::SimParams;
use glam::Vec4;

/// The next state from the solved positions: x_{n+1} = x, v_{n+1} = (x − xₙ)/h. Pinned
/// particles keep their position and have zero velocity.
pub fn vbd_finish(params: &SimParams, x: &[Vec4], pos: &mut [Vec4], vel: &mut [Vec4]) {
    let h = params.dt;
    for i in 0..params.num_particles as usize {
        let p = pos[i];
        if p.w == 0.0 {
            vel[i] = Vec4::ZERO;
            continue;
        }
        let next = x[i].truncate();
        vel[i] = ((next - p.truncate()) / h).extend(0.0);
        pos[i] = next.extend(p.w);
    }
}
