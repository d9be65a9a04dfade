//! CPU twin of `kernels/integrate.wgsl`.

use crate::model::layout::{SimParams, INTEGRATOR_EXPLICIT};
use glam::Vec4;

/// Advances every free particle by one Euler step and clears the force accumulator. (The kernel
/// writes the next state to the other texture of a ping-pong pair and needs no clearing: the
/// first force stage of the next substep overwrites its forces. The arithmetic is the same.)
pub fn integrate(params: &SimParams, pos: &mut [Vec4], vel: &mut [Vec4], force: &mut [Vec4]) {
    let gravity = Vec4::from(params.gravity).truncate();
    for i in 0..params.num_particles as usize {
        let p = pos[i];
        let inv_mass = p.w;
        let f = force[i].truncate();
        force[i] = Vec4::ZERO;
        if inv_mass == 0.0 {
            vel[i] = Vec4::ZERO;
            continue;
        }
        let v = vel[i].truncate();
        let a = f * inv_mass + gravity - params.air_damping * v;
        let (x_new, v_new) = if params.integrator == INTEGRATOR_EXPLICIT {
            // explicit: position from the old velocity
            (p.truncate() + params.dt * v, v + params.dt * a)
        } else {
            // semi-implicit: position from the new velocity
            let v_new = v + params.dt * a;
            (p.truncate() + params.dt * v_new, v_new)
        };
        pos[i] = x_new.extend(inv_mass);
        vel[i] = v_new.extend(0.0);
    }
}
