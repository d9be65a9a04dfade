//! CPU twin of `kernels/hinge_forces.wgsl`, and the hinge geometry that `vbd_solve` shares.

use super::grain;
use crate::model::layout::Hinge;
use glam::{Vec3, Vec3A, Vec4};
use rayon::prelude::*;

/// Force on vertex `role` of hinge `h` (roles 0, 1: shared edge; 2, 3: opposite vertices).
pub fn hinge_force(pos: &[Vec4], h: &Hinge, role: u32) -> Vec3 {
    match hinge_frame(pos, h) {
        Some(t) => t.weight * (t.sin_half - h.rest_sin_half) * t.direction(role),
        None => Vec3::ZERO,
    }
}

/// A hinge's terms shared by its four vertices (Bridson, Marino & Fedkiw 2003): the force on
/// vertex `role` is weight · (sin(θ/2) − sin(θ0/2)) · `direction(role)`. In `Vec3A`: the same
/// IEEE operations lane by lane as `Vec3` (the same bits), with one SIMD divide per vector.
pub struct HingeFrame {
    x: [Vec3A; 4],
    e_hat: Vec3A,
    e_len: f32,
    /// n1 / |n1|².
    a: Vec3A,
    /// n2 / |n2|².
    b: Vec3A,
    /// k·|E|²/(|N1| + |N2|), in N·m.
    pub weight: f32,
    /// sin(θ/2) of the signed dihedral angle.
    pub sin_half: f32,
}

impl HingeFrame {
    /// The direction u of vertex `role` (the gradient of θ up to sign), in 1/m.
    #[inline]
    pub fn direction(&self, role: u32) -> Vec3 {
        self.direction_a(role).into()
    }

    #[inline]
    fn direction_a(&self, role: u32) -> Vec3A {
        let [x3, x4, x1, x2] = self.x;
        let (a, b, e_hat) = (self.a, self.b, self.e_hat);
        match role {
            0 => (x1 - x4).dot(e_hat) * a + (x2 - x4).dot(e_hat) * b,
            1 => -(x1 - x3).dot(e_hat) * a - (x2 - x3).dot(e_hat) * b,
            2 => self.e_len * a,
            _ => self.e_len * b,
        }
    }
}

/// The hinge's weight, angle and directions; `None` for a degenerate hinge.
#[inline]
pub fn hinge_frame(pos: &[Vec4], h: &Hinge) -> Option<HingeFrame> {
    let p = |i: u32| Vec3A::from_vec4(pos[i as usize]);
    HingeFrame::at([p(h.v[0]), p(h.v[1]), p(h.v[2]), p(h.v[3])], h.stiffness)
}

impl HingeFrame {
    /// The frame of a hinge of `stiffness` with shared edge x3→x4 and opposite vertices x1, x2
    /// (`[x3, x4, x1, x2]`, the order of `Hinge::v`); `None` for a degenerate hinge.
    #[inline]
    pub fn at(x: [Vec3A; 4], stiffness: f32) -> Option<HingeFrame> {
        let [x3, x4, x1, x2] = x;
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
        // sin(θ/2) = |n̂1 − n̂2|/2: √(½(1 − cos θ)) would cancel at small θ, turning one
        // rounding of cos θ into a relative error of 2⁻²⁴/θ² (1e-4 of the force on a sheet
        // bent by a few milliradians, and backends that round cos θ differently disagree).
        let mut sin_half = (0.5 * (n1_hat - n2_hat).length()).min(1.0);
        if n1_hat.cross(n2_hat).dot(e) < 0.0 {
            sin_half = -sin_half;
        }
        Some(HingeFrame {
            x,
            e_hat: e / e_len,
            e_len,
            a: n1 / n1_sq,
            b: n2 / n2_sq,
            weight: stiffness * e_len * e_len / (n1_len + n2_len),
            sin_half,
        })
    }
}

/// Evaluates every hinge once and writes its forces on its four vertices to
/// `forces[4·h + role]`, the index each vertex's hinge ref (h·4 + role) names. Hinges run in
/// parallel, each writing only its own four entries.
pub fn hinge_forces(pos: &[Vec4], hinges: &[Hinge], forces: &mut [Vec4]) {
    forces
        .par_chunks_mut(4)
        .zip(hinges)
        .with_min_len(grain::ROW)
        .for_each(|(out, h)| match hinge_frame(pos, h) {
            Some(t) => {
                let c = t.weight * (t.sin_half - h.rest_sin_half);
                for (role, f) in out.iter_mut().enumerate() {
                    *f = (c * t.direction_a(role as u32)).extend(0.0);
                }
            }
            None => out.fill(Vec4::ZERO),
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
    fn a_nearly_flat_hinge_has_its_angle_to_a_few_roundings() {
        // The bent hinge lifts x1 by `lift` over a 1 m lever: θ = atan(lift), so sin(θ/2) in
        // f64 is the reference. The unit normals each carry a few roundings (about 4·2⁻²⁴ =
        // 2.4e-7 absolute), so |n̂1 − n̂2|/2 is off by at most about that much: a relative
        // 2.4e-7/θ, 2.4e-4 at θ = 1e-3. √(½(1 − cos θ)) would be off by 2⁻²⁴/θ² relative
        // (6e-2 at θ = 1e-3), so this bound fails for the cancelling formula.
        for lift in [1e-2f32, 1e-3, -1e-3] {
            let (pos, hinge) = bent_hinge(lift);
            let t = hinge_frame(&pos, &hinge).unwrap();
            let theta = (lift as f64).atan();
            let exact = (0.5 * theta).sin();
            let error = ((t.sin_half.abs() as f64) - exact.abs()).abs() / exact.abs();
            let bound = 2.4e-7 / theta.abs();
            assert!(
                error <= bound,
                "θ = {theta}: relative error {error:e} > {bound:e}"
            );
        }
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

    #[test]
    fn each_hinge_once_gives_every_vertex_its_per_vertex_force_bit_for_bit() {
        let (mut pos, mut hinge) = bent_hinge(0.3);
        hinge.rest_sin_half = 0.05;
        // A second, degenerate hinge (its edge has zero length) gets zero forces.
        pos.push(pos[0]);
        let degenerate = Hinge {
            v: [0, 4, 2, 3],
            ..hinge
        };
        let mut forces = vec![Vec4::splat(9.0); 8];
        hinge_forces(&pos, &[hinge, degenerate], &mut forces);
        for role in 0..4 {
            let per_vertex = hinge_force(&pos, &hinge, role).extend(0.0);
            assert_eq!(forces[role as usize], per_vertex, "role {role}");
            assert_ne!(per_vertex, Vec4::ZERO);
            assert_eq!(forces[4 + role as usize], Vec4::ZERO);
        }
    }
}
