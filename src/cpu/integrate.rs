//! CPU twin of `kernels/integrate.wgsl`.

use crate::model::layout::{SimParams, INTEGRATOR_EXPLICIT};
use glam::Vec4;
use rayon::prelude::*;

/// Advances every free particle by one Euler step and clears the force accumulator. (The kernel
/// writes the next state to the other texture of a ping-pong pair and needs no clearing: the
/// first force stage of the next substep overwrites its forces. The arithmetic is the same.)
/// Particles are independent and run in parallel.
pub fn integrate(params: &SimParams, pos: &mut [Vec4], vel: &mut [Vec4], force: &mut [Vec4]) {
    let gravity = Vec4::from(params.gravity).truncate();
    let n = params.num_particles as usize;
    let state = (&mut pos[..n], &mut vel[..n], &mut force[..n]);
    state.into_par_iter().for_each(|(pos, vel, force)| {
        let p = *pos;
        let inv_mass = p.w;
        let f = force.truncate();
        *force = Vec4::ZERO;
        if inv_mass == 0.0 {
            *vel = Vec4::ZERO;
            return;
        }
        let v = vel.truncate();
        let a = f * inv_mass + gravity - params.air_damping * v;
        let (x_new, v_new) = if params.integrator == INTEGRATOR_EXPLICIT {
            // explicit: position from the old velocity
            (p.truncate() + params.dt * v, v + params.dt * a)
        } else {
            // semi-implicit: position from the new velocity
            let v_new = v + params.dt * a;
            (p.truncate() + params.dt * v_new, v_new)
        };
        *pos = x_new.extend(inv_mass);
        *vel = v_new.extend(0.0);
    });
}
