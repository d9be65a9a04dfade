//! CPU twin of `kernels/monitor.wgsl`: the same per-block partials, reduced in the same tree.

use super::grain;
use crate::model::layout::{SimParams, SpringRef, WORKGROUP_SIZE};
use crate::solver::HealthPartial;
use glam::Vec4;
use rayon::prelude::*;

/// The kernel's partials, one per block of `WORKGROUP_SIZE` particles. Blocks run in parallel;
/// each reduces its own tree, and they are collected in block order.
pub fn monitor(
    params: &SimParams,
    pos: &[Vec4],
    vel: &[Vec4],
    offsets: &[u32],
    springs: &[SpringRef],
) -> Vec<HealthPartial> {
    let n = params.num_particles as usize;
    let size = WORKGROUP_SIZE as usize;
    (0..n.div_ceil(size).max(1))
        .into_par_iter()
        .with_min_len(grain::blocks(grain::ROW))
        .map(|group| {
            let mut slots: Vec<HealthPartial> = (0..size)
                .map(|local| {
                    let i = group * size + local;
                    particle_health(params, i, pos, vel, offsets, springs)
                })
                .collect();
            let mut half = size / 2;
            while half > 0 {
                for local in 0..half {
                    let o = slots[local + half];
                    let a = &mut slots[local];
                    a.kinetic_energy += o.kinetic_energy;
                    a.gravity_energy += o.gravity_energy;
                    a.elastic_energy += o.elastic_energy;
                    a.max_speed = a.max_speed.max(o.max_speed);
                    if o.max_strain > a.max_strain {
                        a.max_strain = o.max_strain;
                        a.worst = o.worst;
                    }
                    a.non_finite += o.non_finite;
                    a.first_non_finite = a.first_non_finite.min(o.first_non_finite);
                }
                half /= 2;
            }
            slots[0]
        })
        .collect()
}

/// One thread's values before the reduction.
fn particle_health(
    params: &SimParams,
    i: usize,
    pos: &[Vec4],
    vel: &[Vec4],
    offsets: &[u32],
    springs: &[SpringRef],
) -> HealthPartial {
    let mut h = HealthPartial {
        kinetic_energy: 0.0,
        gravity_energy: 0.0,
        elastic_energy: 0.0,
        max_speed: 0.0,
        max_strain: -1.0,
        worst: i as u32,
        non_finite: 0,
        first_non_finite: u32::MAX,
    };
    if i >= params.num_particles as usize {
        return h;
    }
    let p = pos[i];
    let v = vel[i].truncate();
    if !(p.truncate().is_finite() && v.is_finite()) {
        h.non_finite = 1;
        h.first_non_finite = i as u32;
        return h;
    }
    if p.w > 0.0 {
        h.kinetic_energy = 0.5 * v.dot(v) / p.w;
        h.gravity_energy = -Vec4::from(params.gravity).truncate().dot(p.truncate()) / p.w;
    }
    h.max_speed = v.length();
    for s in &springs[offsets[i] as usize..offsets[i + 1] as usize] {
        let q = pos[s.other as usize].truncate();
        // A non-finite neighbour is counted where it lies, not here.
        if !q.is_finite() {
            continue;
        }
        let stretch = q.distance(p.truncate()) - s.rest_length;
        h.max_strain = h.max_strain.max(stretch / s.rest_length);
        h.elastic_energy += 0.25 * s.stiffness * stretch * stretch;
    }
    h
}
