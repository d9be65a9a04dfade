//! The orthotropic membrane (CPU twin of `kernels/membrane_forces.wgsl` and of the membrane
//! terms in `kernels/implicit_terms.wgsl`).
//!
//! Baraff and Witkin 1998's conditions on the deformation gradient F = [w_u w_v] in the
//! fabric's warp/weft frame: energy A·(½k_u(|w_u| − 1)² + ½k_v(|w_v| − 1)² + ½k_s(w_u·w_v)²).
//! At small strain |w_u| − 1 is the warp strain, |w_v| − 1 the weft strain and w_u·w_v the
//! engineering shear strain γ, so k_u, k_v and k_s are the uniaxial warp and weft stiffness
//! (lateral edges free: the model has no Poisson coupling) and the shear stiffness τ/γ, in N/m.
//! The Hessian is made positive semi-definite as the springs' is (a compressed condition's
//! transverse term dropped) and the shear condition's curvature term is left out
//! (Gauss–Newton). Damping is stiffness-proportional with each triangle's time constant τ
//! (`model::membrane`), along the conditions' gradients.
//!
//! With `compression = "buckling"` each stretch condition takes compression by
//! `stretch_law` (its strip's Euler strain, then a small fraction of its stiffness).
//!
//! With `tension = "stiffening"` each stretch condition's tangent stiffness rises with its
//! strain (`stretch_law`), as the measured curves do (Wang et al. 2011).
//!
//! Known limits: the shear condition is linear; buckling acts on the warp and the weft
//! conditions each, not on the principal compression; large shear couples with stretch through
//! w_u·w_v = |w_u||w_v|cos.

use super::grain;
use super::stretch_law::StretchLaw;
use crate::model::layout::{Membrane, SimParams};
use glam::{Mat3, Vec3, Vec4};
use rayon::prelude::*;

fn v3(v: Vec4) -> Vec3 {
    v.truncate()
}

/// Σ_r c_r·values[v_r] written as c₁(v₁ − v₀) + c₂(v₂ − v₀): differences of nearby values.
pub fn image(m: &Membrane, c: &[f32; 3], values: &[Vec4]) -> Vec3 {
    let x = |r: usize| v3(values[m.v[r] as usize]);
    let x0 = x(0);
    c[1] * (x(1) - x0) + c[2] * (x(2) - x0)
}

/// The force of membrane `m` on its vertex `role` at positions `pos` and velocities `vel`.
pub fn membrane_force(
    p: &SimParams,
    m: &Membrane,
    role: usize,
    pos: &[Vec4],
    vel: &[Vec4],
) -> Vec3 {
    let (a, b) = m.coefficients();
    let [ku, kv, ks, tau] = m.stiffness;
    let (wu, wv) = (image(m, &a, pos), image(m, &b, pos));
    let (du, dv) = (image(m, &a, vel), image(m, &b, vel));
    let g = a[role] * wv + b[role] * wu;
    let mut f = -ks * wu.dot(wv) * g - tau * ks * (du.dot(wv) + wu.dot(dv)) * g;
    for (condition, (w, dw, k, c)) in [(wu, du, ku, a[role]), (wv, dv, kv, b[role])]
        .into_iter()
        .enumerate()
    {
        let len = w.length();
        if len > 1e-12 {
            let n = w / len;
            // The law's tension per unit stiffness: the strain itself when linear.
            let strain = StretchLaw::membrane(p, k, condition).tension(1.0, len - 1.0);
            f -= k * c * (strain + tau * n.dot(dw)) * n;
        }
    }
    f
}

/// Adds each particle's membrane forces to `force`, gathered over its CSR membrane refs
/// (triangle · 4 + role). Particles run in parallel, each summing its own triangles in CSR
/// order: the same result on any number of threads.
pub fn membrane_forces(
    params: &SimParams,
    pos: &[Vec4],
    vel: &[Vec4],
    force: &mut [Vec4],
    offsets: &[u32],
    refs: &[u32],
    membranes: &[Membrane],
) {
    let n = params.num_particles as usize;
    force[..n]
        .par_iter_mut()
        .with_min_len(grain::VERTEX)
        .enumerate()
        .for_each(|(i, force)| {
            let mut f = Vec3::ZERO;
            for &r in &refs[offsets[i] as usize..offsets[i + 1] as usize] {
                let m = &membranes[(r / 4) as usize];
                f += membrane_force(params, m, (r % 4) as usize, pos, vel);
            }
            *force += f.extend(0.0);
        });
}

/// Hessian of a stretch condition's energy per unit stiffness in w, made positive
/// semi-definite: `axial`·n̂n̂ᵀ + max(0, 1 − 1/|w|)·`secant`·(I − n̂n̂ᵀ), `axial` the law's axial
/// stiffness and `secant` its tension over the linear one (both 1 when linear): the transverse
/// term is the tension over |w|.
pub fn stretch_hessian(axial: f32, secant: f32, n: Vec3, len: f32) -> Mat3 {
    let nn = super::implicit_terms::outer(n, n);
    axial * nn + ((1.0 - 1.0 / len).max(0.0) * secant) * (Mat3::IDENTITY - nn)
}

/// One membrane in implicit Euler's step: its conditions at the start of the step and at
/// displacements D (edge images split as start + change, as the springs' are).
pub struct MembraneStep {
    /// Per-vertex coefficients of w_u and w_v.
    pub a: [f32; 3],
    /// β.
    pub b: [f32; 3],
    /// w_u, w_v at the start of the step.
    pub start: [Vec3; 2],
    /// Their changes over the step so far.
    pub change: [Vec3; 2],
}

impl MembraneStep {
    /// The membrane at start positions `prev` and displacements `d`.
    pub fn at(m: &Membrane, prev: &[Vec4], d: &[Vec4]) -> MembraneStep {
        let (a, b) = m.coefficients();
        MembraneStep {
            start: [image(m, &a, prev), image(m, &b, prev)],
            change: [image(m, &a, d), image(m, &b, d)],
            a,
            b,
        }
    }

    /// w_u and w_v now.
    pub fn images(&self) -> [Vec3; 2] {
        [
            self.start[0] + self.change[0],
            self.start[1] + self.change[1],
        ]
    }

    /// |w| − 1 of condition `c` (0: warp, 1: weft), split as (|start| − 1) plus the change's
    /// share, smooth in the change down to its own rounding (see `implicit_terms::stretch`).
    pub fn stretch(&self, c: usize) -> f32 {
        let (s, dw) = (self.start[c], self.change[c]);
        super::implicit_terms::stretch(s, s.length(), dw, (s + dw).length(), 1.0)
    }

    /// The coefficient of vertex `role` in condition `c`'s image.
    pub fn coefficient(&self, c: usize, role: usize) -> f32 {
        if c == 0 {
            self.a[role]
        } else {
            self.b[role]
        }
    }

    /// The shear condition's gradient at vertex `role` for images `w`: α_r·w_v + β_r·w_u.
    pub fn shear_gradient(&self, w: [Vec3; 2], role: usize) -> Vec3 {
        self.a[role] * w[1] + self.b[role] * w[0]
    }
}

impl MembraneStep {
    /// The force −∇G on vertex `role` and the Hessian blocks (`role`, s) for s = 0, 1, 2 of
    /// membrane `m` in a step of `h` s: the elastic conditions at the iterate, and damping
    /// ½(τ/h)·k·q² on each condition's change q over the step, linearised at the step's start
    /// (a quadratic in D, as the springs' damping is).
    pub fn system(&self, p: &SimParams, m: &Membrane, role: usize, h: f32) -> (Vec3, [Mat3; 3]) {
        let [ku, kv, ks, tau] = m.stiffness;
        let damp = tau / h;
        let w = self.images();
        let mut f = Vec3::ZERO;
        let mut blocks = [Mat3::ZERO; 3];
        for (c, k) in [(0, ku), (1, kv)] {
            let len = w[c].length();
            let cr = self.coefficient(c, role);
            if len > 1e-12 {
                let n = w[c] / len;
                let (law, s) = (StretchLaw::membrane(p, k, c), self.stretch(c));
                f -= k * cr * law.tension(1.0, s) * n;
                let hess = k * stretch_hessian(law.axial(1.0, s), law.secant_ratio(s), n, len);
                for (s, block) in blocks.iter_mut().enumerate() {
                    *block += (cr * self.coefficient(c, s)) * hess;
                }
            }
            let start_len = self.start[c].length();
            if start_len > 1e-12 {
                let n = self.start[c] / start_len;
                f -= damp * k * cr * n.dot(self.change[c]) * n;
                let nn = super::implicit_terms::outer(n, n);
                for (s, block) in blocks.iter_mut().enumerate() {
                    *block += (damp * k * cr * self.coefficient(c, s)) * nn;
                }
            }
        }
        let g = self.shear_gradient(w, role);
        f -= ks * w[0].dot(w[1]) * g;
        let g0 = self.shear_gradient(self.start, role);
        let q = self.start[1].dot(self.change[0]) + self.start[0].dot(self.change[1]);
        f -= damp * ks * q * g0;
        for (s, block) in blocks.iter_mut().enumerate() {
            let outer = super::implicit_terms::outer;
            *block += ks * outer(g, self.shear_gradient(w, s))
                + (damp * ks) * outer(g0, self.shear_gradient(self.start, s));
        }
        (f, blocks)
    }

    /// The change of the membrane's energy (elastic and damping) when its images change by
    /// `dw` (the correction's images times the step length), as differences of nearby
    /// quantities.
    pub fn energy_change(&self, p: &SimParams, m: &Membrane, dw: [Vec3; 2], h: f32) -> f32 {
        let [ku, kv, ks, tau] = m.stiffness;
        let damp = tau / h;
        let w = self.images();
        let mut e = 0.0;
        for (c, k) in [(0, ku), (1, kv)] {
            let (len, len2) = (w[c].length(), (w[c] + dw[c]).length());
            let grow = 2.0 * w[c].dot(dw[c]) + dw[c].length_squared();
            // (|w'| − 1)² − (|w| − 1)² = ds·(2s + ds), ds = |w'| − |w| without cancellation.
            let ds = if len + len2 > 0.0 {
                grow / (len + len2)
            } else {
                0.0
            };
            let s = self.stretch(c);
            e += StretchLaw::membrane(p, k, c).energy_change(k, s, s + ds, 2.0 * s + ds, ds);
            let start_len = self.start[c].length();
            if start_len > 1e-12 {
                let n = self.start[c] / start_len;
                let (q, dq) = (n.dot(self.change[c]), n.dot(dw[c]));
                e += 0.5 * damp * k * dq * (2.0 * q + dq);
            }
        }
        let shear = w[0].dot(w[1]);
        let d_shear = dw[0].dot(w[1]) + w[0].dot(dw[1]) + dw[0].dot(dw[1]);
        e += 0.5 * ks * d_shear * (2.0 * shear + d_shear);
        let q = self.start[1].dot(self.change[0]) + self.start[0].dot(self.change[1]);
        let dq = self.start[1].dot(dw[0]) + self.start[0].dot(dw[1]);
        e + 0.5 * damp * ks * dq * (2.0 * q + dq)
    }

    /// The mean diagonal of the part of vertex `role`'s block that does not depend on the
    /// state (for `Implicit::contact_stiffness`): each condition's k·c_r²·(1 + τ/h), |w| ≈ 1.
    pub fn constant_stiffness(m: &Membrane, role: usize, h: f32) -> f32 {
        let (a, b) = m.coefficients();
        let [ku, kv, ks, tau] = m.stiffness;
        let (ar, br) = (a[role], b[role]);
        (1.0 + tau / h) * (ku * ar * ar + kv * br * br + ks * (ar * ar + br * br)) / 3.0
    }
}
