//! Ambient occlusion per vertex, so that folds read: from each vertex, rays over the
//! hemisphere on each side of the surface, and the fraction that leave without hitting the
//! cloth or the body within `REACH`. Computed on the CPU against one BVH of every mesh in the
//! picture; the renderer darkens the ambient light by it.

use super::render::DrawMesh;
use glam::Vec3;
use parry3d::query::{Ray, RayCast};
use parry3d::shape::TriMesh as ParryMesh;
use rayon::prelude::*;

/// How far an occluder counts, in m: the depth of a garment's folds and of the gap between an
/// arm and the body, beyond which light in a room still reaches the surface.
pub const REACH: f32 = 0.08;
/// Rays per side of a vertex. With a different turn of the ray set per vertex, 16 rays give
/// a smooth result once the renderer interpolates it over the triangles.
pub const RAYS: usize = 16;
/// Rays start this far off the surface, in m, so that they do not hit their own triangles.
const LIFT: f32 = 5e-4;

/// Each vertex's unoccluded fraction on the side its normal points to and on the other side,
/// for every mesh in order (a mesh without triangles gets none). The inner side of a closed
/// mesh is never seen: it is left unshaded (1) without casting its rays.
pub fn ambient_occlusion(meshes: &[DrawMesh]) -> Vec<Vec<[f32; 2]>> {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for m in meshes {
        let base = positions.len() as u32;
        positions.extend_from_slice(&m.positions);
        triangles.extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    let Ok(scene) = ParryMesh::new(positions, triangles) else {
        return meshes
            .iter()
            .map(|m| vec![[1.0; 2]; m.positions.len()])
            .collect();
    };
    let directions = hemisphere();
    meshes
        .iter()
        .map(|m| {
            let normals = m.normals();
            (m.positions.par_iter().zip(&normals).enumerate())
                .map(|(k, (p, n))| {
                    let n = n.normalize_or_zero();
                    if n == Vec3::ZERO {
                        return [1.0; 2];
                    }
                    let inner = match m.closed {
                        true => 1.0,
                        false => open(&scene, *p, -n, k, &directions),
                    };
                    [open(&scene, *p, n, k, &directions), inner]
                })
                .collect()
        })
        .collect()
}

/// The fraction of rays from `p` over the hemisphere around `n` that escape.
fn open(scene: &ParryMesh, p: Vec3, n: Vec3, k: usize, directions: &[Vec3]) -> f32 {
    // A frame around n, turned by the golden angle per vertex so that neighbours sample
    // different directions (no banding).
    let (t, b) = n.any_orthonormal_pair();
    let (sin, cos) = (k as f32 * 2.399_963).sin_cos();
    let (t, b) = (t * cos + b * sin, b * cos - t * sin);
    let origin = p + n * LIFT;
    let free = (directions.iter())
        .filter(|d| {
            let dir = t * d.x + b * d.y + n * d.z;
            scene
                .cast_local_ray(&Ray::new(origin, dir), REACH, false)
                .is_none()
        })
        .count();
    free as f32 / directions.len() as f32
}

/// `RAYS` cosine-weighted directions over the hemisphere around +z (Hammersley points): each
/// ray stands for an equal share of the diffuse light.
fn hemisphere() -> Vec<Vec3> {
    (0..RAYS)
        .map(|i| {
            let u = (i as f32 + 0.5) / RAYS as f32;
            let v = (i as u32).reverse_bits() as f32 / 4_294_967_296.0;
            let r = u.sqrt();
            let phi = std::f32::consts::TAU * v;
            Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u).sqrt())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square of `n`×`n` quads, side 1 m, in the plane through `origin` spanned by `a`, `b`.
    fn square(origin: Vec3, a: Vec3, b: Vec3, n: u32) -> DrawMesh {
        let mut m = DrawMesh::default();
        for j in 0..=n {
            for i in 0..=n {
                m.positions
                    .push(origin + a * (i as f32 / n as f32) + b * (j as f32 / n as f32));
                m.colors.push(Vec3::ONE);
            }
        }
        for j in 0..n {
            for i in 0..n {
                let v = j * (n + 1) + i;
                m.triangles.push([v, v + 1, v + n + 2]);
                m.triangles.push([v, v + n + 2, v + n + 1]);
            }
        }
        m
    }

    #[test]
    fn an_open_sheet_is_lit_and_a_crease_is_dark() {
        // A sheet alone: nothing occludes either side.
        let flat = square(Vec3::ZERO, Vec3::X, Vec3::Y, 8);
        let ao = ambient_occlusion(std::slice::from_ref(&flat));
        assert!(ao[0].iter().all(|s| s[0] == 1.0 && s[1] == 1.0));
        // Two sheets 2 cm apart, facing each other: the sides that face are occluded by rays
        // that hit within REACH (all but the most grazing), the outer sides not at all.
        let a = square(Vec3::ZERO, Vec3::X, Vec3::Y, 8);
        let b = square(Vec3::new(0.0, 0.0, 0.02), Vec3::Y, Vec3::X, 8);
        let ao = ambient_occlusion(&[a, b]);
        // The middle vertex of the first sheet: its normal is +z (x × y), towards the other.
        let mid = 4 * 9 + 4;
        let [front, back] = ao[0][mid];
        assert!(front < 0.25 && back == 1.0, "front {front}, back {back}");
    }

    #[test]
    fn a_closed_meshs_inner_side_is_not_shaded() {
        // A sheet 2 cm behind the first: it occludes the first's back side, unless the first
        // is the outside of a closed body, whose back side nobody sees.
        let behind = square(Vec3::new(0.0, 0.0, -0.02), Vec3::X, Vec3::Y, 8);
        let mid = 4 * 9 + 4;
        for closed in [false, true] {
            let front = DrawMesh {
                closed,
                ..square(Vec3::ZERO, Vec3::X, Vec3::Y, 8)
            };
            let [outer, inner] = ambient_occlusion(&[front, behind.clone()])[0][mid];
            assert_eq!(outer, 1.0, "nothing is in front of it");
            match closed {
                true => assert_eq!(inner, 1.0),
                false => assert!(inner < 0.25, "inner {inner}"),
            }
        }
    }
}
