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
use crate::model::layout::{Hinge, Seam, SimParams, SpringRef, SubstepParams, Sweep, MAX_BODIES};
use crate::solver::converged_before;
use glam::{Mat3, Vec3, Vec4};
use rayon::prelude::*;

/// The elements a vertex gathers over, as CSR lists (the same arrays the force stages use).
pub struct VbdElements<'a> {
    /// Spring offsets per particle and incident springs.
    pub springs: (&'a [u32], &'a [SpringRef]),
    /// Hinge offsets, hinge refs (index · 4 + role) and hinges, when bending is on.
    pub hinges: Option<(&'a [u32], &'a [u32], &'a [Hinge])>,
    /// Seam offsets, seam refs (index · 4 + role) and seam pairs, when the cloth is sewn.
    pub seams: Option<(&'a [u32], &'a [u32], &'a [Seam])>,
    /// Each body's SDF nodes (grids in `SimParams::bodies`); empty without a body.
    pub sdfs: &'a [&'a [f32]],
}

/// Contact is this many times stiffer than the mean diagonal of everything else acting on the
/// vertex, whatever the fabric and step.
pub const CONTACT_RATIO: f32 = 100.0;

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
/// - contact with each body, at its pose at the end of the step: a penalty ½k_c(thickness − φ)²
///   where φ < thickness, Hessian k_c·n̂n̂ᵀ, k_c = `CONTACT_RATIO` × the mean diagonal of the
///   rest; and Coulomb friction lagged on the penalty's normal force λ = k_c(thickness − φ):
///   −μλ·u/max(|u|, ε_v·h) on the slip u (the tangential displacement over the
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
) -> (Vec3, Mat3, Surfaces) {
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

    // Every body's contact stiffness comes from the same (contact-free) diagonal.
    let k_c = CONTACT_RATIO * (hess.x_axis.x + hess.y_axis.y + hess.z_axis.z) / 3.0;
    let mut surfaces = Surfaces::default();
    for (b, sdf) in el.sdfs.iter().enumerate().take(params.num_bodies as usize) {
        let (body, pose) = (&params.bodies[b], &step.bodies[b]);
        let (xb, d) = to_body_frame(pose, xi);
        let s = sample_body_sdf(body, sdf, xb);
        let g = to_world(pose, s.truncate());
        let len = g.length();
        let n = if len > 1e-12 { g / len } else { Vec3::ZERO };
        surfaces[b] = Some((s.w, n));
        if s.w < body.thickness {
            let lambda = k_c * (body.thickness - s.w);
            f += lambda * n;
            hess += k_c * outer(n, n);
            let v_body = body_velocity_at(pose, d);
            let slip = moved(i) - h * v_body;
            let u = slip - slip.dot(n) * n;
            let scale = body.friction * lambda / u.length().max(body.friction_slip_speed * h);
            f -= scale * u;
            hess += scale * (Mat3::IDENTITY - outer(n, n));
        }
    }
    (f, hess, surfaces)
}

/// Each body's signed distance φ and outward normal at a vertex (`None` past the scene's bodies).
pub type Surfaces = [Option<(f32, Vec3)>; MAX_BODIES];

/// How far inside the contact layer, as a fraction of the thickness, a vertex that reaches it
/// from outside stops (`newton_step`).
pub const CONTACT_ENTRY: f32 = 1e-2;

/// The vertex's Newton step H⁻¹f, stopped where it would enter a body's contact layer from
/// outside: at `CONTACT_ENTRY` of the thickness inside it (φ linearised along the step), body
/// by body in scene order.
/// Outside the layer the contact has no force and no stiffness, so an unstopped step lands as
/// deep as the pull takes it (millimetres); the next sweep's stiff penalty throws it back out,
/// and a resting vertex alternated between the two on every sweep (the largest step of every
/// sweep stayed at ~2 mm). Stopped just inside, the next sweep sees the contact and settles it.
pub fn newton_step(params: &SimParams, f: Vec3, hess: Mat3, surfaces: &Surfaces) -> Vec3 {
    let mut delta = solve3(hess, f);
    for (body, surface) in params.bodies.iter().zip(surfaces) {
        if let Some((phi, n)) = *surface {
            if phi >= body.thickness {
                let entry = body.thickness * (1.0 - CONTACT_ENTRY);
                let landing = phi + n.dot(delta);
                if landing < entry {
                    delta += (entry - landing) * n;
                }
            }
        }
    }
    delta
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

/// One sweep: every free vertex of the colour takes its Newton step, in place, and the
/// sweep's iteration records the largest step length in `steps` (m). Skipped (returning
/// false) once the tolerance says the substep has converged (`converged_before`).
///
/// A vertex's system reads only itself and vertices of other colours, so the colour's steps
/// are computed in parallel from the same `x` and then written: the same numbers as one
/// vertex after another, on any number of threads (the largest of them too).
#[allow(clippy::too_many_arguments)] // the kernel's bindings, one argument each
pub fn vbd_solve(
    params: &SimParams,
    step: &SubstepParams,
    sweep: &Sweep,
    order: &[u32],
    prev: &[Vec4],
    y: &[Vec4],
    x: &mut [Vec4],
    steps: &mut [f32],
    el: &VbdElements,
) -> bool {
    let iteration = sweep.iteration as usize;
    if converged_before(steps, iteration, params.tolerance) {
        return false;
    }
    let colour = &order[sweep.first as usize..(sweep.first + sweep.count) as usize];
    let x_now: &[Vec4] = x;
    let updates: Vec<(usize, Vec4, f32)> = colour
        .par_iter()
        .filter_map(|&i| {
            let i = i as usize;
            if prev[i].w == 0.0 {
                return None;
            }
            let (f, hess, surfaces) = vertex_system(params, step, i, x_now, prev, y, el);
            let delta = newton_step(params, f, hess, &surfaces);
            let next = (x_now[i].truncate() + delta).extend(prev[i].w);
            Some((i, next, delta.length()))
        })
        .collect();
    for (i, next, len) in updates {
        x[i] = next;
        steps[iteration] = steps[iteration].max(len);
    }
    true
}
