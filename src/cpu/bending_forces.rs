//! CPU twin of `kernels/bending_forces.wgsl`.

use crate::model::layout::{Hinge, SimParams};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// Force on vertex `role` of hinge `h` (roles 0, 1: shared edge; 2, 3: opposite vertices).
pub fn hinge_force(pos: &[Vec4], h: &Hinge, role: u32) -> Vec3 {
    match hinge_geometry(pos, h, role) {
        Some(g) => g.weight * (g.sin_half - h.rest_sin_half) * g.u,
        None => Vec3::ZERO,
    }
}

/// What a hinge's force on one vertex is made of: f = weight · (sin(θ/2) − sin(θ0/2)) · u,
/// with u the Bridson et al. (2003) direction of that vertex (the gradient of θ up to sign).
pub struct HingeGeometry {
    /// k·|E|²/(|N1| + |N2|), in N·m.
    pub weight: f32,
    /// sin(θ/2) of the signed dihedral angle.
    pub sin_half: f32,
    /// The vertex's direction, in 1/m.
    pub u: Vec3,
}

/// The hinge's weight, angle and direction at vertex `role`; `None` for a degenerate hinge.
pub fn hinge_geometry(pos: &[Vec4], h: &Hinge, role: u32) -> Option<HingeGeometry> {
    let p = |i: u32| pos[i as usize].truncate();
    let (x3, x4, x1, x2) = (p(h.v[0]), p(h.v[1]), p(h.v[2]), p(h.v[3]));
    let e = x4 - x3;
    let n1 = (x1 - x3).cross(x1 - x4);
    let n2 = (x2 - x4).cross(x2 - x3);
    let e_len = e.length();
    let n1_sq = n1.dot(n1);
    let n2_sq = n2.dot(n2);
    // Degenerate triangles have no defined angle; they get no bending force.
    if e_len < 1e-12 || n1_sq < 1e-24 || n2_sq < 1e-24 {
        return None;
    }
    let n1_len = n1_sq.sqrt();
    let n2_len = n2_sq.sqrt();
    let n1_hat = n1 / n1_len;
    let n2_hat = n2 / n2_len;
    let cos_theta = n1_hat.dot(n2_hat).clamp(-1.0, 1.0);
    let mut sin_half = (0.5 * (1.0 - cos_theta)).max(0.0).sqrt();
    if n1_hat.cross(n2_hat).dot(e) < 0.0 {
        sin_half = -sin_half;
    }
    let weight = h.stiffness * e_len * e_len / (n1_len + n2_len);
    let e_hat = e / e_len;
    let a = n1 / n1_sq;
    let b = n2 / n2_sq;
    let u = match role {
        0 => (x1 - x4).dot(e_hat) * a + (x2 - x4).dot(e_hat) * b,
        1 => -(x1 - x3).dot(e_hat) * a - (x2 - x3).dot(e_hat) * b,
        2 => e_len * a,
        _ => e_len * b,
    };
    Some(HingeGeometry {
        weight,
        sin_half,
        u,
    })
}

/// Adds each particle's bending forces to `force`, gathered over its CSR hinge references (in
/// parallel over particles, each in its own fixed order: thread-count independent).
pub fn bending_forces(
    params: &SimParams,
    pos: &[Vec4],
    force: &mut [Vec4],
    hinge_offsets: &[u32],
    hinge_refs: &[u32],
    hinges: &[Hinge],
) {
    let n = params.num_particles as usize;
    force[..n]
        .par_iter_mut()
        .enumerate()
        .for_each(|(i, force)| {
            let mut f = Vec3::ZERO;
            for k in hinge_offsets[i]..hinge_offsets[i + 1] {
                let r = hinge_refs[k as usize];
                f += hinge_force(pos, &hinges[(r / 4) as usize], r % 4);
            }
            *force += f.extend(0.0);
        });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::hinge_sin_half;

    fn bent_hinge(lift: f32) -> (Vec<Vec4>, Hinge) {
        // Edge along x; opposite vertices at ±y, the first lifted by `lift` in z.
        let pos = vec![
            Vec4::new(0.0, 0.0, 0.0, 1.0),
            Vec4::new(1.0, 0.0, 0.0, 1.0),
            Vec4::new(0.5, 1.0, lift, 1.0),
            Vec4::new(0.5, -1.0, 0.0, 1.0),
        ];
        let hinge = Hinge {
            v: [0, 1, 2, 3],
            stiffness: 1.0,
            rest_sin_half: 0.0,
            ..Default::default()
        };
        (pos, hinge)
    }

    #[test]
    fn bending_force_restores_flat_rest_shape() {
        for lift in [0.2f32, -0.2] {
            let (pos, hinge) = bent_hinge(lift);
            let f = hinge_force(&pos, &hinge, 2);
            // The lifted vertex is pushed back towards the plane.
            assert!(f.z * lift < 0.0, "lift {lift}: force {f}");
        }
    }

    #[test]
    fn bending_forces_sum_to_zero_and_vanish_at_rest() {
        let (pos, mut hinge) = bent_hinge(0.3);
        let total: Vec3 = (0..4).map(|r| hinge_force(&pos, &hinge, r)).sum();
        // u1+u2+u3+u4 = 0 analytically; f32 cancellation of O(1) terms leaves ~1e-7.
        assert!(total.length() < 1e-5, "{total}");
        let p = |i: usize| pos[i].truncate();
        hinge.rest_sin_half = hinge_sin_half(p(0), p(1), p(2), p(3));
        for r in 0..4 {
            assert!(hinge_force(&pos, &hinge, r).length() < 1e-6);
        }
    }
}
