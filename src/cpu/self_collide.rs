//! CPU twin of `kernels/self_collide.wgsl`.

use super::grain;
use super::hash_count::{hash_bucket, hash_cell_of};
use crate::model::layout::{SimParams, SpringRef};
use glam::{IVec3, Vec3, Vec4};
use rayon::prelude::*;

fn is_neighbour(i: usize, j: u32, spring_offsets: &[u32], springs: &[SpringRef]) -> bool {
    (spring_offsets[i]..spring_offsets[i + 1]).any(|k| springs[k as usize].other == j)
}

/// Particle-particle repulsion through the spatial hash (`starts`, `sorted`). Reads `pos`,
/// `vel` and writes `pos_out`, `vel_out`, as the kernel does with its ping-pong textures, so
/// particles run in parallel.
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
    let n = params.num_particles as usize;
    let out = (&mut pos_out[..n], &mut vel_out[..n]);
    out.into_par_iter()
        .with_min_len(grain::VERTEX)
        .enumerate()
        .for_each(|(i, (pos_out, vel_out))| {
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
            *pos_out = (xi + dx).extend(p.w);
            *vel_out = (vi + dv).extend(0.0);
        });
}

/// The CPU-only reference for self-collision: inelastic point–triangle impulses (after Bridson,
/// Fedkiw & Anderson 2002). For every particle closer than the thickness to a triangle it does
/// not belong to and approaching it, an impulse I along the contact normal stops the approach;
/// the particle gets +I and each triangle vertex −w_i·I (w: barycentric weights of the closest
/// point), each divided by its own mass, so momentum is conserved exactly. Applied
/// Gauss–Seidel, particle by particle, to `vel` in place.
pub fn point_triangle_impulses(
    params: &SimParams,
    pos: &[Vec4],
    vel: &mut [Vec4],
    triangles: &[[u32; 3]],
) {
    use glam::DVec3;
    use std::collections::HashMap;
    let h = params.self_thickness;
    let cell = |x: Vec3| (x / h).floor().as_ivec3();
    // Each triangle goes into every cell its bounding box, grown by h, overlaps: a particle
    // within h of a triangle then finds it in its own cell.
    let mut grid: HashMap<IVec3, Vec<u32>> = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        let p = tri.map(|i| pos[i as usize].truncate());
        let lo = cell(p[0].min(p[1]).min(p[2]) - Vec3::splat(h));
        let hi = cell(p[0].max(p[1]).max(p[2]) + Vec3::splat(h));
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    grid.entry(IVec3::new(x, y, z)).or_default().push(t as u32);
                }
            }
        }
    }
    let inv_mass = |i: u32| pos[i as usize].w as f64;
    for i in 0..params.num_particles as usize {
        if pos[i].w == 0.0 {
            continue;
        }
        let xi = pos[i].truncate();
        let Some(candidates) = grid.get(&cell(xi)) else {
            continue;
        };
        for &t in candidates {
            let tri = triangles[t as usize];
            if tri.contains(&(i as u32)) {
                continue;
            }
            let [a, b, c] = tri.map(|v| pos[v as usize].truncate().as_dvec3());
            let p = xi.as_dvec3();
            let q = crate::body::closest_point_on_triangle(p, a, b, c);
            let d = p.distance(q);
            if d >= h as f64 || d < 1e-9 {
                continue;
            }
            let n = (p - q) / d;
            let area2 = (b - a).cross(c - a).length();
            if area2 <= 0.0 {
                continue;
            }
            let w = [
                (b - q).cross(c - q).length() / area2,
                (c - q).cross(a - q).length() / area2,
                (a - q).cross(b - q).length() / area2,
            ];
            let v = |k: u32| vel[k as usize].truncate().as_dvec3();
            let v_tri: DVec3 = (0..3).map(|k| w[k] * v(tri[k])).sum();
            let vn = (v(i as u32) - v_tri).dot(n);
            if vn >= 0.0 {
                continue;
            }
            let denominator: f64 =
                inv_mass(i as u32) + (0..3).map(|k| w[k] * w[k] * inv_mass(tri[k])).sum::<f64>();
            let impulse = -vn / denominator;
            let bump = |vel: &mut [Vec4], k: u32, dv: DVec3| {
                vel[k as usize] += dv.as_vec3().extend(0.0);
            };
            bump(vel, i as u32, impulse * inv_mass(i as u32) * n);
            for k in 0..3 {
                bump(vel, tri[k], -w[k] * impulse * inv_mass(tri[k]) * n);
            }
        }
    }
}
