//! Generated bodies as closed, outward-oriented triangle meshes: analytic shapes for tests, and
//! the shipped mannequin.

use crate::mesh::TriMesh;
use glam::Vec3;

/// A UV sphere of `radius` about `center` with `rings` latitude bands (≥ 3).
pub fn sphere(center: Vec3, radius: f32, rings: u32) -> TriMesh {
    capsule_like(center, radius, 0.0, rings)
}

/// A capsule along y: two hemispheres of `radius` joined by a cylinder of `half_height`.
pub fn capsule(center: Vec3, radius: f32, half_height: f32, rings: u32) -> TriMesh {
    capsule_like(center, radius, half_height, rings)
}

fn capsule_like(center: Vec3, radius: f32, half_height: f32, rings: u32) -> TriMesh {
    let rings = rings.max(3) | 1; // odd, so the equator splits between the two caps
    let segments = 2 * rings;
    let mut positions = vec![center + Vec3::new(0.0, radius + half_height, 0.0)];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        let shift = if theta < std::f32::consts::FRAC_PI_2 {
            half_height
        } else {
            -half_height
        };
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            let dir = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            positions.push(center + radius * dir + Vec3::new(0.0, shift, 0.0));
        }
    }
    positions.push(center - Vec3::new(0.0, radius + half_height, 0.0));
    let bottom = positions.len() as u32 - 1;
    let ring = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
    let mut triangles = Vec::new();
    for s in 0..segments {
        triangles.push([0, ring(1, s), ring(1, s + 1)]);
        triangles.push([bottom, ring(rings - 1, s + 1), ring(rings - 1, s)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (
                ring(r, s),
                ring(r, s + 1),
                ring(r + 1, s + 1),
                ring(r + 1, s),
            );
            triangles.push([a, d, c]);
            triangles.push([a, c, b]);
        }
    }
    TriMesh {
        positions,
        triangles,
    }
}

/// An axis-aligned box with half extents `half` about `center`.
pub fn cuboid(center: Vec3, half: Vec3) -> TriMesh {
    let corner = |i: u32| {
        center
            + half
                * Vec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                )
    };
    let positions = (0..8).map(corner).collect();
    // Two triangles per face, counter-clockwise seen from outside.
    let triangles = vec![
        [0, 2, 3],
        [0, 3, 1], // -z
        [4, 5, 7],
        [4, 7, 6], // +z
        [0, 1, 5],
        [0, 5, 4], // -y
        [2, 6, 7],
        [2, 7, 3], // +y
        [0, 4, 6],
        [0, 6, 2], // -x
        [1, 3, 7],
        [1, 7, 5], // +x
    ];
    TriMesh {
        positions,
        triangles,
    }
}

/// The shipped CC0 MakeHuman mannequin (`fixtures/bodies/mannequin.obj`, built into the
/// binary so that scenes anywhere can use it), standing with its lowest point at `feet`'s
/// height and its axis through `feet`'s x and z.
pub fn mannequin(feet: Vec3) -> TriMesh {
    const OBJ: &str = include_str!("../../fixtures/bodies/mannequin.obj");
    let name = std::path::Path::new("fixtures/bodies/mannequin.obj");
    let mut mesh = TriMesh::parse_obj(OBJ, name, 1.0, "body.shape")
        .expect("the shipped mannequin parses (tested)");
    let lowest = mesh
        .positions
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min);
    for p in &mut mesh.positions {
        *p += feet - Vec3::new(0.0, lowest, 0.0);
    }
    mesh
}
