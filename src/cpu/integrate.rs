//! CPU twin of `kernels/integrate.wgsl`.

use super::grain;
use crate::model::layout::{SimParams, INTEGRATOR_EXPLICIT};
use glam::Vec4;
use rayon::prelude::*;

/// What `hinge_forces` wrote (four entries per hinge, at the refs' indices `h·4 + role`) and
/// each particle's hinge refs, for `integrate` to gather.
#[derive(Clone, Copy)]
pub struct HingeGather<'a> {
    /// `n + 1` offsets into `refs`.
    pub offsets: &'a [u32],
    /// Each particle's hinge refs, in CSR order.
    pub refs: &'a [u32],
    /// The per-hinge forces.
    pub forces: &'a [Vec4],
}

/// Advances every free particle by one Euler step under the forces the force stages summed plus
/// its bending forces (gathered from `hinges` in CSR order, when the scene bends), and clears
/// the force accumulator. (The kernel writes the next state to the other texture of a
/// ping-pong pair and needs no clearing: the first force stage of the next substep overwrites
/// its forces. The arithmetic is the same.) Particles are independent and run in parallel.
pub fn integrate(
    params: &SimParams,
    pos: &mut [Vec4],
    vel: &mut [Vec4],
    force: &mut [Vec4],
    hinges: Option<HingeGather>,
) {
    let gravity = Vec4::from(params.gravity).truncate();
    let n = params.num_particles as usize;
    let state = (&mut pos[..n], &mut vel[..n], &mut force[..n]);
    state
        .into_par_iter()
        .with_min_len(grain::ROW)
        .enumerate()
        .for_each(|(i, (pos, vel, force))| {
            let p = *pos;
            let inv_mass = p.w;
            let summed = *force;
            *force = Vec4::ZERO;
            if inv_mass == 0.0 {
                *vel = Vec4::ZERO;
                return;
            }
            // w is 0 in every entry, so whole-vector sums give xyz the bits of Vec3 sums.
            let mut bending = Vec4::ZERO;
            if let Some(h) = hinges {
                for k in h.offsets[i]..h.offsets[i + 1] {
                    bending += h.forces[h.refs[k as usize] as usize];
                }
            }
            let f = summed.truncate() + bending.truncate();
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
