//! CPU twin of `kernels/collide_body.wgsl`, plus the same response driven by other contact
//! queries (the CPU collision strategies).

use super::deformed_body::deformed_sample;
use super::grain;
use crate::body::sdf::sdf_sample;
use crate::model::layout::{BodyParams, BodyPose, SimParams, SubstepParams};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

fn v3(a: [f32; 4]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// World point `x` in the body frame of `pose` (`d` is `x` − the body's origin).
pub fn to_body_frame(pose: &BodyPose, x: Vec3) -> (Vec3, Vec3) {
    let (bx, by, bz) = (v3(pose.x), v3(pose.y), v3(pose.z));
    let d = x - v3(pose.translation);
    (Vec3::new(bx.dot(d), by.dot(d), bz.dot(d)), d)
}

/// A body-frame direction (an SDF gradient) in the world.
pub fn to_world(pose: &BodyPose, g: Vec3) -> Vec3 {
    v3(pose.x) * g.x + v3(pose.y) * g.y + v3(pose.z) * g.z
}

/// The velocity of the body's surface at offset `d` from its origin.
pub fn body_velocity_at(pose: &BodyPose, d: Vec3) -> Vec3 {
    v3(pose.velocity) + v3(pose.angular_velocity).cross(d)
}

/// φ (w) and ∇φ (xyz) of a body's SDF (grid in `body`, nodes in `sdf`, the body's own) at
/// body-frame point `p`.
pub fn sample_body_sdf(body: &BodyParams, sdf: &[f32], p: Vec3) -> Vec4 {
    let dims = [body.sdf_dims[0], body.sdf_dims[1], body.sdf_dims[2]];
    sdf_sample(sdf, dims, v3(body.sdf_origin), body.sdf_origin[3], p)
}

/// One body's collision response to a particle at `x` with velocity `v`. `query` gives φ (w)
/// and ∇φ (xyz) at a body-frame point.
pub fn collide_particle(
    body: &BodyParams,
    pose: &BodyPose,
    x: Vec3,
    v: Vec3,
    query: impl Fn(Vec3) -> Vec4,
) -> (Vec3, Vec3) {
    let (xb, _) = to_body_frame(pose, x);
    let s = query(xb);
    if s.w >= body.thickness {
        return (x, v);
    }
    let n = safe_normalize(to_world(pose, s.truncate()));
    respond(body, x, v, s.w, n, |p| {
        body_velocity_at(pose, p - v3(pose.translation))
    })
}

/// A deforming body's response to a particle at `x` with velocity `v`: its parts' poses are
/// `parts` (from its first), its words `words` (`cpu::deformed_sample`).
pub fn collide_deformed(
    body: &BodyParams,
    parts: &[BodyPose],
    words: &[f32],
    x: Vec3,
    v: Vec3,
) -> (Vec3, Vec3) {
    let s = deformed_sample(body, parts, words, x);
    if s.phi >= body.thickness {
        return (x, v);
    }
    respond(body, x, v, s.phi, s.normal, |p| s.velocity_at(p))
}

/// The response to a contact at distance `phi` along unit normal `n` (zero: none): the particle
/// moves out to the thickness, its inward velocity relative to the surface (`v_body` at the
/// new position) is cancelled and Coulomb friction acts on the rest.
fn respond(
    body: &BodyParams,
    x: Vec3,
    v: Vec3,
    phi: f32,
    n: Vec3,
    v_body: impl Fn(Vec3) -> Vec3,
) -> (Vec3, Vec3) {
    if n.dot(n) == 0.0 {
        return (x, v);
    }
    let x = x + (body.thickness - phi) * n;
    let v_body = v_body(x);
    let v_rel = v - v_body;
    let mut vn = v_rel.dot(n);
    let mut vt = v_rel - vn * n;
    if vn < 0.0 {
        // Coulomb: tangential speed drops by μ times the normal speed taken away.
        let vt_len = vt.length();
        if vt_len > 0.0 {
            vt *= (1.0 - body.friction * (-vn) / vt_len).max(0.0);
        }
        vn = 0.0;
    } else {
        vn *= 1.0 - body.normal_loss;
    }
    vt *= 1.0 - body.tangential_loss;
    (x, v_body + vt + vn * n)
}

fn safe_normalize(v: Vec3) -> Vec3 {
    let len = v.length();
    if len > 1e-12 {
        v / len
    } else {
        Vec3::ZERO
    }
}

/// Collides every particle with the first `bodies` bodies, in scene order (in place: each
/// particle reads and writes only its own state, so particles run in parallel). `query(b, p)`
/// gives rigid body b's φ (w) and ∇φ (xyz) at body-frame point p: its SDF sampled as the kernel
/// samples it (`sample_body_sdf`), or another CPU strategy's answer. A deforming body (one
/// with parts) is sampled from its words in `words`, as the kernel does.
#[allow(clippy::too_many_arguments)]
pub fn collide_body(
    params: &SimParams,
    step: &SubstepParams,
    pos: &mut [Vec4],
    vel: &mut [Vec4],
    bodies: usize,
    words: &[&[f32]],
    query: impl Fn(usize, Vec3) -> Vec4 + Sync,
) {
    let n = params.num_particles as usize;
    let state = (&mut pos[..n], &mut vel[..n]);
    (state.into_par_iter().with_min_len(grain::VERTEX)).for_each(|(pos, vel)| {
        if pos.w == 0.0 {
            return;
        }
        let (mut x, mut v) = (pos.truncate(), vel.truncate());
        for (b, body_words) in words.iter().enumerate().take(bodies) {
            let body = &params.bodies[b];
            (x, v) = if body.parts > 0 {
                let parts = &step.parts[body.first_part as usize..];
                collide_deformed(body, parts, body_words, x, v)
            } else {
                collide_particle(body, &step.bodies[b], x, v, |p| query(b, p))
            };
        }
        *pos = x.extend(pos.w);
        *vel = v.extend(0.0);
    });
}

/// The CPU-only edge response for cloth edge `e` in contact `c` (body frame), the edge
/// counterpart of `collide_particle`: the contact point moves out to the thickness and its
/// velocity relative to the body is treated as a particle's. Both corrections are shared
/// between the edge's ends with weights (1 − s) and s over their inverse masses, the smallest
/// change that moves the contact point by the full amount.
pub fn collide_edge(
    body: &BodyParams,
    pose: &BodyPose,
    pos: &mut [Vec4],
    vel: &mut [Vec4],
    e: [u32; 2],
    c: &crate::body::edges::EdgeContact,
) {
    let (i, j) = (e[0] as usize, e[1] as usize);
    let w = [1.0 - c.s, c.s];
    let inv_mass = [pos[i].w, pos[j].w];
    let denom = w[0] * w[0] * inv_mass[0] + w[1] * w[1] * inv_mass[1];
    if denom <= 0.0 || c.distance >= body.thickness {
        return;
    }
    let share = [w[0] * inv_mass[0] / denom, w[1] * inv_mass[1] / denom];
    let n = to_world(pose, c.normal);
    let push = (body.thickness - c.distance) * n;
    for (k, &p) in [i, j].iter().enumerate() {
        pos[p] += (share[k] * push).extend(0.0);
    }
    let x = pos[i].truncate().lerp(pos[j].truncate(), c.s);
    let v = vel[i].truncate().lerp(vel[j].truncate(), c.s);
    let v_body = body_velocity_at(pose, x - v3(pose.translation));
    let v_rel = v - v_body;
    let vn = v_rel.dot(n);
    let mut vt = v_rel - vn * n;
    let vn_new = if vn < 0.0 {
        let vt_len = vt.length();
        if vt_len > 0.0 {
            vt *= (1.0 - body.friction * (-vn) / vt_len).max(0.0);
        }
        0.0
    } else {
        vn * (1.0 - body.normal_loss)
    };
    vt *= 1.0 - body.tangential_loss;
    let change = vt + vn_new * n - v_rel;
    for (k, &p) in [i, j].iter().enumerate() {
        vel[p] += (share[k] * change).extend(0.0);
    }
}

/// Every cloth edge against a body's edges (CPU only; after the particle pass), one contact per
/// edge: its deepest. Does nothing unless the collider carries its edges.
pub fn collide_edges(
    body: &BodyParams,
    pose: &BodyPose,
    pos: &mut [Vec4],
    vel: &mut [Vec4],
    cloth_edges: &[[u32; 2]],
    collider: &crate::body::Collider,
) {
    let Some(edges) = &collider.edges else { return };
    let to_body = |x: Vec4| to_body_frame(pose, x.truncate()).0;
    let inside = |x: Vec3| collider.exact.query(x).0 < 0.0;
    for &e in cloth_edges {
        let (a, b) = (to_body(pos[e[0] as usize]), to_body(pos[e[1] as usize]));
        if let Some(contact) = edges.deepest(a, b, body.thickness, inside) {
            collide_edge(body, pose, pos, vel, e, &contact);
        }
    }
}
