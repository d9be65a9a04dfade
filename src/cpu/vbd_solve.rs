//! CPU twin of `kernels/vbd_solve.wgsl`: one Vertex Block Descent sweep (Chen, Macklin et al.,
//! SIGGRAPH 2024) over the vertices of one colour.
//!
//! Backward Euler is the minimisation x_{n+1} = argmin ½‖x − y‖²_M / h² + E(x). Each vertex
//! takes one Newton step on that objective with every other vertex held fixed: with f the
//! vertex's force (−gradient) and H its 3×3 Hessian block, x += H⁻¹f. Vertices of one colour
//! share no element, so they update at once (one dispatch) without reading each other.

use super::collide_body::{body_velocity_at, sample_body_sdf, to_body_frame, to_world};
use super::hinge_forces::hinge_geometry;
use super::seam_forces::rest_gap;
use crate::model::layout::{Hinge, Seam, SimParams, SpringRef, SubstepParams, Sweep, SWEEP_LAST};
use glam::{Mat3, Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// The elements a vertex gathers over, as CSR lists (the same arrays the force stages use).
pub struct VbdElements<'a> {
    /// Spring offsets per particle and incident springs.
    pub springs: (&'a [u32], &'a [SpringRef]),
    /// Hinge offsets, hinge refs (index · 4 + role) and hinges, when bending is on.
    pub hinges: Option<(&'a [u32], &'a [u32], &'a [Hinge])>,
    /// Seam offsets, seam refs (index · 4 + role) and seam pairs, when the cloth is sewn.
    pub seams: Option<(&'a [u32], &'a [u32], &'a [Seam])>,
    /// The body's SDF values (grid in `SimParams`), when the scene has a body.
    pub sdf: Option<&'a [f32]>,
}

/// Contact is this many times stiffer than the mean diagonal of everything else acting on the
/// vertex, whatever the fabric and step.
pub const CONTACT_RATIO: f32 = 100.0;

/// Friction reaches its Coulomb bound μλ at this slip speed relative to the body, in m/s;
/// below it friction grows in proportion to the slip (the smoothing of IPC's friction). At
/// 0.01 m/s the cotton T-shirt's seams could not close against it while it was sewn on the
/// body (4 of 12); at 1 m/s all close and the shirt still hangs where it is sewn.
pub const FRICTION_SLIP_SPEED: f32 = 1.0;

fn outer(a: Vec3, b: Vec3) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Hessian of ½k(|d| − L)² in d, made positive semi-definite: k·(n̂n̂ᵀ + max(0, 1 − L/|d|)·
/// (I − n̂n̂ᵀ)). The transverse term is negative for a compressed spring; it is dropped.
fn spring_hessian(k: f32, rest: f32, d: Vec3, len: f32) -> Mat3 {
    let n = d / len;
    let nn = outer(n, n);
    let transverse = (1.0 - rest / len).max(0.0);
    k * nn + (k * transverse) * (Mat3::IDENTITY - nn)
}

/// Vertex `i`'s force f = −∇G and Hessian block H of the incremental potential
/// G(x) = ½‖x − y‖²_M / h² + E(x) + damping, at the iterate `x` (xₙ in `prev`).
///
/// - inertia: −(m/h²)(x − y), Hessian (m/h²)·I;
/// - air damping as mass-proportional Rayleigh damping: −(c·m/h)(x − xₙ), Hessian (c·m/h)·I;
/// - springs: −k(l − L)n̂ and the projected Hessian above; spring damping along n̂ on the
///   relative displacement over h, Hessian (c/h)·n̂n̂ᵀ;
/// - hinges: the explicit bending force, Hessian ½cos(θ/2)·weight·uuᵀ (Gauss–Newton: the
///   derivative of sin(θ/2) times the outer product of the angle's direction; PSD);
/// - seam pairs: zero-rest (or shrinking-rest, pull-only) springs to the partner point, the
///   partner's ends taking −(1 − w) and −w of the force and (1 − w)² and w² of the Hessian;
/// - body contact, at the body's pose at the end of the step: a penalty ½k_c(thickness − φ)²
///   where φ < thickness, Hessian k_c·n̂n̂ᵀ, k_c = `CONTACT_RATIO` × the mean diagonal of the
///   rest; and Coulomb friction lagged on the penalty's normal force λ = k_c(thickness − φ):
///   −μλ·u/max(|u|, `FRICTION_SLIP_SPEED`·h) on the slip u (the tangential displacement over the
///   step relative to the body), Hessian μλ/max(…)·(I − n̂n̂ᵀ). Without friction here (contact
///   resolved in the solve leaves `collide_body` nothing to do), draped cloth slid up the body.
#[allow(clippy::too_many_arguments)] // the kernel's inputs, one argument each
pub fn vertex_system(
    params: &SimParams,
    step: &SubstepParams,
    i: usize,
    x: &[Vec4],
    prev: &[Vec4],
    y: &[Vec4],
    el: &VbdElements,
) -> (Vec3, Mat3) {
    let h = params.dt;
    let inv_mass = prev[i].w;
    let mass = 1.0 / inv_mass;
    let xi = x[i].truncate();
    let moved = |j: usize| x[j].truncate() - prev[j].truncate();
    let inertia = mass / (h * h);
    let air = params.air_damping * mass / h;
    let mut f = -inertia * (xi - y[i].truncate()) - air * moved(i);
    let mut hess = Mat3::from_diagonal(Vec3::splat(inertia + air));

    let (offsets, springs) = el.springs;
    for k in offsets[i]..offsets[i + 1] {
        let s = springs[k as usize];
        let j = s.other as usize;
        let d = xi - x[j].truncate();
        let len = d.length();
        if len > 1e-12 {
            let n = d / len;
            let closing = n.dot(moved(i) - moved(j));
            f -= (s.stiffness * (len - s.rest_length) + s.damping / h * closing) * n;
            hess +=
                spring_hessian(s.stiffness, s.rest_length, d, len) + (s.damping / h) * outer(n, n);
        }
    }

    if let Some((offsets, refs, hinges)) = el.hinges {
        for k in offsets[i]..offsets[i + 1] {
            let r = refs[k as usize];
            let hinge = &hinges[(r / 4) as usize];
            if let Some(g) = hinge_geometry(x, hinge, r % 4) {
                f += g.weight * (g.sin_half - hinge.rest_sin_half) * g.u;
                let cos_half = (1.0 - g.sin_half * g.sin_half).max(0.0).sqrt();
                hess += (0.5 * cos_half * g.weight) * outer(g.u, g.u);
            }
        }
    }

    if let Some((offsets, refs, seams)) = el.seams {
        for k in offsets[i]..offsets[i + 1] {
            let r = refs[k as usize];
            let s = &seams[(r / 4) as usize];
            let w = s.weight;
            let [a, b0, b1] = [s.v[0], s.v[1], s.v[2]].map(|v| v as usize);
            let xa = x[a].truncate();
            let gap = (1.0 - w) * x[b0].truncate() + w * x[b1].truncate() - xa;
            let opening = (1.0 - w) * moved(b0) + w * moved(b1) - moved(a);
            let rest = rest_gap(s, params, step.time);
            // Force and Hessian on the seam vertex a; its partner's ends get shares of them.
            let mut fa = s.damping / h * opening;
            let mut ha = Mat3::from_diagonal(Vec3::splat(s.damping / h));
            if rest <= 0.0 {
                fa += s.stiffness * gap;
                ha += Mat3::from_diagonal(Vec3::splat(s.stiffness));
            } else {
                let d = gap.length();
                if d > rest {
                    fa += s.stiffness * (d - rest) / d * gap;
                    ha += spring_hessian(s.stiffness, rest, gap, d);
                }
            }
            let share = match r % 4 {
                0 => 1.0,
                1 => -(1.0 - w),
                _ => -w,
            };
            f += share * fa;
            hess += (share * share) * ha;
        }
    }

    if let Some(sdf) = el.sdf {
        let (xb, d) = to_body_frame(step, xi);
        let s = sample_body_sdf(params, sdf, xb);
        if s.w < params.thickness {
            let g = to_world(step, s.truncate());
            let len = g.length();
            let n = if len > 1e-12 { g / len } else { Vec3::ZERO };
            let k_c = CONTACT_RATIO * (hess.x_axis.x + hess.y_axis.y + hess.z_axis.z) / 3.0;
            let lambda = k_c * (params.thickness - s.w);
            f += lambda * n;
            hess += k_c * outer(n, n);
            let v_body = body_velocity_at(step, d);
            let slip = moved(i) - h * v_body;
            let u = slip - slip.dot(n) * n;
            let scale = params.friction * lambda / u.length().max(FRICTION_SLIP_SPEED * h);
            f -= scale * u;
            hess += scale * (Mat3::IDENTITY - outer(n, n));
        }
    }
    (f, hess)
}

/// H⁻¹f through the adjugate (as the kernel, which has no matrix inverse); zero when H is
/// singular, which a positive mass rules out.
pub fn solve3(hess: Mat3, f: Vec3) -> Vec3 {
    let (c0, c1, c2) = (hess.x_axis, hess.y_axis, hess.z_axis);
    let r0 = c1.cross(c2);
    let r1 = c2.cross(c0);
    let r2 = c0.cross(c1);
    let det = c0.dot(r0);
    if det.abs() < 1e-30 {
        return Vec3::ZERO;
    }
    // Rows of the adjugate are the cross products of the columns.
    Vec3::new(r0.dot(f), r1.dot(f), r2.dot(f)) / det
}

/// The weight scale of the residual when gravity is off (a zero-gravity sewing phase), m/s².
pub const STANDARD_GRAVITY: f32 = 9.80665;

/// One sweep: every free vertex of the colour takes its Newton step, in place. The last
/// iteration records, before the step, the vertex's squared weight m²g² (x) and squared
/// unbalanced force |f|² (y) in `residual`.
///
/// A vertex's system reads only itself and vertices of other colours, so the colour's steps
/// are computed in parallel from the same `x` and then written: the same numbers as one
/// vertex after another, on any number of threads.
#[allow(clippy::too_many_arguments)] // the kernel's bindings, one argument each
pub fn vbd_solve(
    params: &SimParams,
    step: &SubstepParams,
    sweep: &Sweep,
    order: &[u32],
    prev: &[Vec4],
    y: &[Vec4],
    x: &mut [Vec4],
    residual: &mut [Vec2],
    el: &VbdElements,
) {
    let colour = &order[sweep.first as usize..(sweep.first + sweep.count) as usize];
    let x_now: &[Vec4] = x;
    let updates: Vec<(usize, Vec4, Option<Vec2>)> = colour
        .par_iter()
        .filter_map(|&i| {
            let i = i as usize;
            if prev[i].w == 0.0 {
                return None;
            }
            let (f, hess) = vertex_system(params, step, i, x_now, prev, y, el);
            // The last sweep records the unbalanced force against the vertex's weight.
            let r = (sweep.flags & SWEEP_LAST != 0).then(|| {
                let g = Vec4::from(params.gravity).truncate().length();
                let weight = (1.0 / prev[i].w) * if g > 0.0 { g } else { STANDARD_GRAVITY };
                Vec2::new(weight * weight, f.dot(f))
            });
            let next = (x_now[i].truncate() + solve3(hess, f)).extend(prev[i].w);
            Some((i, next, r))
        })
        .collect();
    for (i, next, r) in updates {
        x[i] = next;
        if let Some(r) = r {
            residual[i] = r;
        }
    }
}
