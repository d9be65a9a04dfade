//! CPU twin of `kernels/contact_planes.wgsl`.

use super::collide_body::{body_velocity_at, sample_body_sdf, to_body_frame, to_world};
use super::deformed_body::deformed_sample;
use super::grain;
use super::implicit_terms::{Implicit, CONTACT_SLACK_FRACTION};
use crate::model::layout::SimParams;
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// Linearises each body's contact at every free vertex for the step: the SDF sampled once at
/// the starting guess xₙ + D⁰ gives a plane φ ≈ c + n̂·D (`planes[b·n + i]` = (n̂, c)), which
/// the step's sweeps, assembly and line search all use. The plane has no rounding noise in D:
/// its force resolves the contact's normal balance to ~1e-10 m, where the SDF sampled at
/// world positions would move by 1.2e-7 m steps, 100 times a particle's weight at the
/// contact's stiffness. A vertex in contact (within `CONTACT_SLACK_FRACTION` of the layer)
/// gets friction's normal force λ from its load at the guess: the inward component of
/// everything but contact (its weight and the pull of its springs and seams), in
/// `lambdas[i][b]`; others get 0 and no friction this step. Far from a body (outside its
/// grid) the plane is (0, SDF_FAR). After the planes, each body's surface velocity at the
/// vertex's start of step `planes[(bodies + b)·n + i]` (xyz, m/s) is what friction's slip is
/// measured against: a rigid body's at xₙ, a deforming body's from the same query as its plane
/// (its skin's velocity field around xₙ + D⁰, at xₙ).
pub fn contact_planes(
    s: &Implicit,
    guess: &[Vec4],
    sdfs: &[&[f32]],
    planes: &mut [Vec4],
    lambdas: &mut [Vec4],
) {
    let p = s.params;
    let n = p.num_particles as usize;
    let bodies = p.num_bodies as usize;
    let free_params = SimParams {
        num_bodies: 0,
        ..*p
    };
    let without_contact = Implicit {
        params: &free_params,
        ..*s
    };
    type PerBody = [Vec4; crate::model::layout::MAX_BODIES];
    let results: Vec<(PerBody, PerBody, Vec4)> = (0..n)
        .into_par_iter()
        .with_min_len(grain::VERTEX)
        .map(|i| {
            let mut out = [Vec4::ZERO; crate::model::layout::MAX_BODIES];
            let mut surface = [Vec4::ZERO; crate::model::layout::MAX_BODIES];
            let mut lambda = Vec4::ZERO;
            if s.prev[i].w == 0.0 {
                return (out, surface, lambda);
            }
            let d0 = guess[i].truncate();
            let x = s.prev[i].truncate() + d0;
            let mut load: Option<Vec3> = None;
            for b in 0..bodies {
                let (pose, body) = (&s.step.bodies[b], &p.bodies[b]);
                let start = s.prev[i].truncate();
                let (phi, normal, velocity) = if body.parts > 0 {
                    // A deforming body: its parts posed at the substep's end.
                    let parts = &s.step.parts[body.first_part as usize..];
                    let d = deformed_sample(body, parts, sdfs[b], x);
                    (d.phi, d.normal, d.velocity_at(start))
                } else {
                    let (xb, _) = to_body_frame(pose, x);
                    let sample = sample_body_sdf(body, sdfs[b], xb);
                    let g = to_world(pose, sample.truncate());
                    let len = g.length();
                    let normal = if len > 1e-12 { g / len } else { Vec3::ZERO };
                    let (_, offset) = to_body_frame(pose, start);
                    (sample.w, normal, body_velocity_at(pose, offset))
                };
                out[b] = normal.extend(phi - normal.dot(d0));
                surface[b] = velocity.extend(0.0);
                if phi < body.thickness * (1.0 + CONTACT_SLACK_FRACTION) {
                    let f = *load.get_or_insert_with(|| {
                        without_contact
                            .vertex_system(i, guess, None, &mut |_, _| {})
                            .force
                    });
                    lambda[b] = (-normal.dot(f)).max(0.0);
                }
            }
            (out, surface, lambda)
        })
        .collect();
    for (i, (out, surface, lambda)) in results.into_iter().enumerate() {
        for (b, plane) in out.iter().enumerate().take(bodies) {
            planes[b * n + i] = *plane;
            planes[(bodies + b) * n + i] = surface[b];
        }
        lambdas[i] = lambda;
    }
}
