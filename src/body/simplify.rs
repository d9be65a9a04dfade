//! Body simplification: fewer triangles through meshoptimizer's edge-collapse simplifier
//! (quadric error metrics), checked to be a closed two-manifold again before it is used.

use super::Body;
use crate::mesh::TriMesh;
use glam::Vec3;

/// A simplified body and what the simplifier reports.
pub struct Simplified {
    /// The body, closed and outward-oriented (checked by `Body::from_mesh`).
    pub body: Body,
    /// The simplifier's own bound on the geometric deviation from the original surface, in m.
    pub error_m: f32,
}

/// Simplifies `body` towards `target_triangles` triangles (the simplifier may stop above it where
/// collapsing more would break the topology). Fails, saying why, when the result is not closed
/// and two-manifold (the check the body loader applies).
pub fn simplify(body: &Body, target_triangles: usize) -> Result<Simplified, String> {
    let mesh = &body.mesh;
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let positions: Vec<[f32; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
    let mut relative_error = 0.0f32;
    // No error bound (1.0 = the whole mesh extent): the triangle count is the knob.
    let kept = meshopt::simplify_decoder(
        &indices,
        &positions,
        3 * target_triangles,
        1.0,
        meshopt::SimplifyOptions::None,
        Some(&mut relative_error),
    );
    let scale = meshopt::simplify_scale_decoder(&positions);
    // Keep only the vertices the simplified triangles use, in their original order.
    let mut remap = vec![u32::MAX; positions.len()];
    let mut kept_positions: Vec<Vec3> = Vec::new();
    for &i in &kept {
        if remap[i as usize] == u32::MAX {
            remap[i as usize] = kept_positions.len() as u32;
            kept_positions.push(mesh.positions[i as usize]);
        }
    }
    let triangles: Vec<[u32; 3]> = kept
        .chunks_exact(3)
        .map(|t| {
            [
                remap[t[0] as usize],
                remap[t[1] as usize],
                remap[t[2] as usize],
            ]
        })
        .collect();
    if triangles.len() < 4 {
        return Err(format!(
            "simplified to {} triangles: too few for a closed body",
            triangles.len()
        ));
    }
    let simplified = TriMesh {
        positions: kept_positions,
        triangles,
    };
    let body = Body::from_mesh(simplified)
        .map_err(|e| format!("the simplified body is not a closed two-manifold: {e}"))?;
    Ok(Simplified {
        body,
        error_m: relative_error * scale,
    })
}

/// Writes a mesh as OBJ text (positions in m, shortest round-trip digits, 1-based faces).
pub fn to_obj(mesh: &TriMesh) -> String {
    use std::fmt::Write as _;
    let mut s = String::with_capacity(40 * (mesh.positions.len() + mesh.triangles.len()));
    for p in &mesh.positions {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_simplified_sphere_is_closed_smaller_and_close_to_the_original() {
        let body = Body::from_mesh(super::super::shapes::sphere(Vec3::ZERO, 0.3, 48)).unwrap();
        let full = body.mesh.triangles.len();
        let s = simplify(&body, full / 10).unwrap();
        let n = s.body.mesh.triangles.len();
        assert!(n < full / 5, "{n} of {full} triangles kept");
        // Every kept vertex is an original vertex, on the sphere up to f32 rounding.
        for p in &s.body.mesh.positions {
            assert!((p.length() - 0.3).abs() < 1e-6, "{p}");
        }
        // ~460 triangles over 4π(0.3 m)² have edges of about 7.6 cm, whose facets sag
        // e²/(8r) ≈ 2.4 mm below the sphere; 1 cm allows for uneven triangles.
        let sag = (body.mesh.positions.iter())
            .map(|&p| super::super::brute_query(&s.body.mesh, p).0.abs())
            .fold(0.0f32, f32::max);
        assert!(
            sag < 0.01,
            "original vertices lie up to {sag} m from the simplified surface"
        );
        assert!(s.error_m > 0.0 && s.error_m < 0.01, "{}", s.error_m);
        assert!(super::super::signed_volume(&s.body.mesh) > 0.0);
    }

    #[test]
    fn obj_text_round_trips_exactly() {
        let mesh = super::super::shapes::sphere(Vec3::new(0.1, 0.2, 0.3), 0.25, 8);
        let back =
            TriMesh::parse_obj(&to_obj(&mesh), std::path::Path::new("x.obj"), 1.0, "k").unwrap();
        // The OBJ reader numbers vertices in order of first use: compare the triangles' corners.
        let corners = |m: &TriMesh| -> Vec<[Vec3; 3]> {
            (m.triangles.iter())
                .map(|t| t.map(|i| m.positions[i as usize]))
                .collect()
        };
        assert_eq!(corners(&back), corners(&mesh));
    }
}
