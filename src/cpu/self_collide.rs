//! CPU twin of `kernels/self_collide.wgsl`.

use super::hash_count::{hash_bucket, hash_cell_of};
use crate::gpu::layout::{SimParams, SpringRef};
use glam::{IVec3, Vec3, Vec4};

fn is_neighbour(i: usize, j: u32, spring_offsets: &[u32], springs: &[SpringRef]) -> bool {
    (spring_offsets[i]..spring_offsets[i + 1]).any(|k| springs[k as usize].other == j)
}

/// Particle-particle repulsion through the spatial hash (`starts`, `sorted`). Reads `pos`,
/// `vel` and writes `pos_out`, `vel_out`, as the kernel does with its ping-pong textures.
#[allow(clippy::too_many_arguments)]
pub fn self_collide(
    params: &SimParams,
    pos: &[Vec4],
    vel: &[Vec4],
    starts: &[u32],
    sorted: &[u32],
    spring_offsets: &[u32],
    springs: &[SpringRef],
    pos_out: &mut [Vec4],
    vel_out: &mut [Vec4],
) {
    for i in 0..params.num_particles as usize {
        let p = pos[i];
        let xi = p.truncate();
        let vi = vel[i].truncate();
        let mut dx = Vec3::ZERO;
        let mut dv = Vec3::ZERO;
        if p.w != 0.0 {
            let h = params.self_thickness;
            let c = hash_cell_of(params, xi);
            // Two of the 27 cells may share a bucket; visit each bucket once.
            let mut seen = Vec::with_capacity(27);
            for oz in -1..=1 {
                for oy in -1..=1 {
                    for ox in -1..=1 {
                        let b = hash_bucket(params, c + IVec3::new(ox, oy, oz));
                        if seen.contains(&b) {
                            continue;
                        }
                        seen.push(b);
                        for k in starts[b as usize]..starts[b as usize + 1] {
                            let j = sorted[k as usize];
                            if j as usize == i {
                                continue;
                            }
                            let d = xi - pos[j as usize].truncate();
                            let dist = d.length();
                            if dist >= h
                                || dist < 1e-9
                                || is_neighbour(i, j, spring_offsets, springs)
                            {
                                continue;
                            }
                            let n = d / dist;
                            dx += 0.5 * (h - dist) * n;
                            let vn = (vi - vel[j as usize].truncate()).dot(n);
                            if vn < 0.0 {
                                dv -= 0.5 * vn * n;
                            }
                        }
                    }
                }
            }
        }
        pos_out[i] = (xi + dx).extend(p.w);
        vel_out[i] = (vi + dv).extend(0.0);
    }
}
