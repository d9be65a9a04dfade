//! A deforming body in `bench collision` (a skinned or cached body, e.g. the rigged mannequin
//! walking). Structures built once in the rest pose no longer describe it, so:
//!
//! - `gpu-sdf` and `sdf` run the deformed-body path the solver uses (each point mapped back to
//!   the rest pose by inverse skinning and looked up in the rest-pose SDF), through the same
//!   solver machinery as on a rigid body;
//! - `exact` (parry) and `bvh-aabb` are rebuilt over the deformed triangle mesh at each substep
//!   (the time the collision stage sees, the substep's end) and queried once per particle:
//!   their stage is the rebuild plus the queries, timed together. `exact` is the reference
//!   for contacts (particles within the thickness of the deformed surface) and for the deepest
//!   penetration;
//! - the other BVHs answer the same question as `bvh-aabb` at a higher build cost, and
//!   `exact+edges` and `brute` are rigid-body references: they do not apply.

use super::{CollisionRow, Contender};
use crate::body::bvh::{BodyBvh, VolumeKind};
use crate::body::exact::ExactBody;
use crate::body::{Collider, Strategy};
use crate::error::Error;
use crate::mesh::TriMesh;
use crate::model::layout::SubstepParams;
use glam::{Vec3, Vec4};
use rayon::prelude::*;
use std::time::Instant;

/// The contenders rebuilt over the deformed mesh each substep, in table order.
pub const REBUILT: [Contender; 2] = [
    Contender::Cpu(Strategy::BvhAabb),
    Contender::Cpu(Strategy::Exact),
];

/// Whether `c` applies to a deforming body (run by the solver or rebuilt per substep).
pub fn applies(c: Contender) -> bool {
    matches!(c, Contender::GpuSdf | Contender::Cpu(Strategy::Sdf)) || REBUILT.contains(&c)
}

/// The deformed mesh in the world when `step`'s collision stage runs (at its end: the parts'
/// poses are taken there too).
pub fn mesh_at(collider: &Collider, step: &SubstepParams, dt: f32) -> TriMesh {
    TriMesh {
        positions: collider.world_positions(step.time + dt),
        triangles: collider.body.mesh.triangles.clone(),
    }
}

/// parry's exact body over `mesh`.
pub fn exact(mesh: &TriMesh) -> Result<ExactBody, Error> {
    ExactBody::new(mesh).map_err(|e| Error::Unstable(format!("the exact deformed body mesh: {e}")))
}

/// The free particles within `thickness` of the surface `query` answers for: those a
/// collision stage moves.
fn within(query: impl Fn(Vec3) -> f32 + Sync, pos: &[Vec4], thickness: f32) -> Vec<bool> {
    pos.par_iter()
        .map(|p| p.w != 0.0 && query(p.truncate()) < thickness)
        .collect()
}

/// The particles within the thickness of the exact deformed surface: the reference contacts.
pub fn truth(exact: &ExactBody, pos: &[Vec4], thickness: f32) -> Vec<bool> {
    within(|x| exact.query(x).0, pos, thickness)
}

/// One rebuilt stage: (seconds for rebuild and queries, seconds for the rebuild alone, the
/// structure's bytes, the particles it finds in contact).
pub fn rebuilt_stage(
    contender: Contender,
    mesh: &TriMesh,
    pos: &[Vec4],
    thickness: f32,
) -> Result<(f64, f64, usize, Vec<bool>), Error> {
    let start = Instant::now();
    let (build_s, bytes, found) = match contender {
        Contender::Cpu(Strategy::Exact) => {
            let e = exact(mesh)?;
            let build_s = start.elapsed().as_secs_f64();
            (
                build_s,
                e.heap_bytes(),
                within(|x| e.query(x).0, pos, thickness),
            )
        }
        _ => {
            let b = BodyBvh::new(mesh, VolumeKind::Aabb);
            let build_s = start.elapsed().as_secs_f64();
            (
                build_s,
                b.heap_bytes(),
                within(|x| b.query(x).0, pos, thickness),
            )
        }
    };
    Ok((start.elapsed().as_secs_f64(), build_s, bytes, found))
}

/// An empty row for a rebuilt contender (figures summed over the samples by the caller).
pub fn row(
    contender: Contender,
    particles: usize,
    triangles: usize,
    samples: usize,
    repeats: usize,
) -> CollisionRow {
    let note = "deforming body: rebuilt over the deformed mesh each substep; timed: rebuild and \
                a query per particle (the response is not run: substep = the plan less collision \
                plus this)";
    CollisionRow {
        samples,
        repeats,
        // Not run through a solver: what its response leaves inside is not measured.
        max_penetration: f32::NAN,
        max_edge_penetration: f32::NAN,
        ..CollisionRow::new(contender, particles, triangles, note.into())
    }
}
