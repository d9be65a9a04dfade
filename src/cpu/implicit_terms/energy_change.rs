//! The change of implicit Euler's incremental potential G along a correction, counted vertex by
//! vertex, for the line search (`line_energy`); GPU twin: `kernels/line_energy.wgsl`
//! (`hinge_psi`: `kernels/implicit_terms.wgsl`). A child of `implicit_terms`, whose terms it
//! shares.

use super::{seam_combination, v3, Implicit};
use crate::cpu::hinge_forces::HingeFrame;
use crate::cpu::membrane::{self, MembraneStep};
use crate::cpu::seam_forces::rest_gap;
use crate::cpu::stretch_law::StretchLaw;
use crate::model::layout::Hinge;
use glam::{Vec3, Vec4};

impl Implicit<'_> {
    /// The change of G along the correction `c` (m per vertex) for each step length in
    /// `alphas`, counted at vertex `i`: its own terms (inertia, air damping, contact,
    /// friction) and the elements it owns (a spring at its lower-numbered end, a hinge and a
    /// seam pair at its first vertex), so that every element counts once. Each change is
    /// computed as a difference of nearby quantities (d·Δ and |Δ|², not G(x + αc) − G(x)), so
    /// it keeps its own precision however large G is.
    pub fn energy_change<const N: usize>(
        &self,
        i: usize,
        d: &[Vec4],
        c: &[Vec4],
        alphas: [f32; N],
    ) -> [f32; N] {
        self.energy_change_and_scale(i, d, c, alphas).0
    }

    /// `energy_change`, and the size of what its first step length's change adds up: each
    /// term's change, except where a term is a difference of two values that are not nearby
    /// (a hinge's energies, friction's potentials), whose two values count. Each term rounds
    /// a few times relative to its share of that size, so the sum of the sizes bounds the
    /// change's rounding (`line_search`).
    pub fn energy_change_and_scale<const N: usize>(
        &self,
        i: usize,
        d: &[Vec4],
        c: &[Vec4],
        alphas: [f32; N],
    ) -> ([f32; N], f32) {
        let p = self.params;
        let mut scale = 0.0f32;
        let h = p.dt;
        let mut out = [0.0f32; N];
        let di = v3(d[i]);
        let ci = v3(c[i]);
        if self.prev[i].w != 0.0 {
            let mass = 1.0 / self.prev[i].w;
            let inertia = mass / (h * h);
            let air = p.air_damping * mass / h;
            let to_target = di - v3(self.target[i]);
            for (k, (o, &a)) in out.iter_mut().zip(&alphas).enumerate() {
                let sq = a * a * ci.length_squared();
                let v = inertia * (a * ci.dot(to_target) + 0.5 * sq)
                    + air * (a * ci.dot(di) + 0.5 * sq);
                *o += v;
                scale += if k == 0 { v.abs() } else { 0.0 };
            }
            self.contact_change(i, di, ci, alphas, (&mut out, &mut scale));
        }

        let (offsets, springs) = self.el.springs;
        for s in &springs[self.el.span(offsets, i)] {
            let j = s.other as usize;
            if j < i {
                continue;
            }
            let start = v3(self.prev[i]) - v3(self.prev[j]);
            let change = di - v3(d[j]);
            let e = start + change;
            let dc = ci - v3(c[j]);
            let len = e.length();
            let start_len = start.length();
            let n = if start_len > 1e-12 {
                start / start_len
            } else {
                Vec3::ZERO
            };
            let rest = s.rest_length;
            let law = StretchLaw::spring(p, rest);
            for (k, (o, &a)) in out.iter_mut().zip(&alphas).enumerate() {
                let grow = 2.0 * a * e.dot(dc) + a * a * dc.length_squared();
                let len2 = (e + a * dc).length();
                // l' − l = (|e'|² − |e|²)/(l' + l): no cancellation of two lengths.
                let dl = if len + len2 > 0.0 {
                    grow / (len + len2)
                } else {
                    0.0
                };
                let sum = len + len2 - 2.0 * rest;
                let stretch = law.energy_change(s.stiffness, len - rest, len2 - rest, sum, dl);
                let dn = a * n.dot(dc);
                let v = stretch + 0.5 * s.damping / h * dn * (2.0 * n.dot(change) + dn);
                *o += v;
                scale += if k == 0 { v.abs() } else { 0.0 };
            }
        }

        if let Some((offsets, refs, hinges)) = self.el.hinges {
            let range = self.el.span(offsets, i);
            for (&r, hinge) in refs[range.clone()].iter().zip(&hinges[range]) {
                if r % 4 != 0 {
                    continue;
                }
                let before = self.hinge_energy(hinge, d, c, 0.0);
                for (k, (o, &a)) in out.iter_mut().zip(&alphas).enumerate() {
                    let after = self.hinge_energy(hinge, d, c, a);
                    *o += after - before;
                    scale += if k == 0 {
                        after.abs() + before.abs()
                    } else {
                        0.0
                    };
                }
            }
        }

        if let Some((offsets, refs, membranes)) = self.el.membranes {
            let range = self.el.span(offsets, i);
            for (&r, m) in refs[range.clone()].iter().zip(&membranes[range]) {
                if r % 4 != 0 {
                    continue;
                }
                let step = MembraneStep::at(m, self.prev, d);
                let dw = [
                    membrane::image(m, &step.a, c),
                    membrane::image(m, &step.b, c),
                ];
                for (k, (o, &a)) in out.iter_mut().zip(&alphas).enumerate() {
                    let v = step.energy_change(p, m, [a * dw[0], a * dw[1]], h);
                    *o += v;
                    scale += if k == 0 { v.abs() } else { 0.0 };
                }
            }
        }

        if let Some((offsets, refs, seams)) = self.el.seams {
            let range = self.el.span(offsets, i);
            for (&r, s) in refs[range.clone()].iter().zip(&seams[range]) {
                if r % 4 != 0 {
                    continue;
                }
                let (gap, opening) = self.seam_gap(s, d);
                let dg = seam_combination(s, c);
                let rest = rest_gap(s, p, self.step.time);
                for (k, (o, &a)) in out.iter_mut().zip(&alphas).enumerate() {
                    let damping = 0.5 * s.damping / h
                        * (2.0 * a * opening.dot(dg) + a * a * dg.length_squared());
                    let spring = if rest <= 0.0 {
                        0.5 * s.stiffness * (2.0 * a * gap.dot(dg) + a * a * dg.length_squared())
                    } else {
                        let over = |g: Vec3| (g.length() - rest).max(0.0);
                        let (o0, o1) = (over(gap), over(gap + a * dg));
                        0.5 * s.stiffness * (o1 - o0) * (o1 + o0)
                    };
                    *o += damping + spring;
                    scale += if k == 0 {
                        damping.abs() + spring.abs()
                    } else {
                        0.0
                    };
                }
            }
        }
        (out, scale)
    }

    /// Contact and friction's share of `energy_change` at free vertex `i`.
    fn contact_change<const N: usize>(
        &self,
        i: usize,
        di: Vec3,
        ci: Vec3,
        alphas: [f32; N],
        (out, scale): (&mut [f32; N], &mut f32),
    ) {
        let p = self.params;
        if p.num_bodies == 0 {
            return;
        }
        let k_c = self.contact_stiffness(i);
        for b in 0..p.num_bodies as usize {
            let body = &p.bodies[b];
            let plane = self.plane(b, i);
            let n = v3(plane);
            let depth = body.thickness - (plane.w + n.dot(di));
            let lambda = self.lambdas[i][b];
            let eps = body.friction_slip_speed * p.dt;
            let slip = self.slip(b, i, di, n);
            let dslip = ci - ci.dot(n) * n;
            for (k, (o, &a)) in out.iter_mut().zip(&alphas).enumerate() {
                let depth2 = depth - a * n.dot(ci);
                let (p0, p1) = (depth.max(0.0), depth2.max(0.0));
                let v = 0.5 * k_c * (p1 - p0) * (p1 + p0);
                *o += v;
                *scale += if k == 0 { v.abs() } else { 0.0 };
                if lambda > 0.0 && body.friction > 0.0 {
                    let f0 = |s: f32| {
                        if s < eps {
                            s * s / (2.0 * eps)
                        } else {
                            s - 0.5 * eps
                        }
                    };
                    let (s0, s1) = (slip.length(), (slip + a * dslip).length());
                    let (e0, e1) = (
                        body.friction * lambda * f0(s0),
                        body.friction * lambda * f0(s1),
                    );
                    *o += body.friction * lambda * (f0(s1) - f0(s0));
                    *scale += if k == 0 { e0 + e1 } else { 0.0 };
                }
            }
        }
    }

    /// Hinge energy w₀·ψ(θ) at displacements d + a·c (0 for a degenerate hinge).
    fn hinge_energy(&self, hinge: &Hinge, d: &[Vec4], c: &[Vec4], a: f32) -> f32 {
        let corners = self.hinge_corners(hinge, |v| v3(d[v]) + a * v3(c[v]));
        match HingeFrame::at(corners, hinge.stiffness) {
            Some(t) => hinge.rest_weight * hinge_psi(t.sin_half, hinge.rest_sin_half),
            None => 0.0,
        }
    }
}

/// ψ(θ) = −2cos(θ/2) − sin(θ₀/2)·θ from s = sin(θ/2) and s₀ = sin(θ₀/2): dψ/dθ = s − s₀.
pub fn hinge_psi(s: f32, s0: f32) -> f32 {
    let s = s.clamp(-1.0, 1.0);
    -2.0 * (1.0 - s * s).max(0.0).sqrt() - 2.0 * s0 * s.asin()
}
